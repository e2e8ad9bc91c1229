//! The racing line: the line through the corridor that bends least (docs/physics.md section 9: the
//! tighter a strafer turns, the slower it must go, so a line with gentle curves keeps its speed).
//!
//! The line is the centre line moved sideways: each point `p_i = c_i + alpha_i n_i` of the centre line
//! resampled at even steps `c_i`, moved by `alpha_i` along its normal `n_i`. Its bending is the sum of the
//! squared second differences, `sum |p_(i-1) - 2 p_i + p_(i+1)|^2` (the discrete `integral kappa^2 ds`
//! at an even step), a convex quadratic in the offsets; each offset is bounded by how far the hull can
//! move off the centre line along its normal and keep `margin_units` off every wall. Clarabel solves
//! that quadratic programme. The first point is the start and stays put.
//!
//! Each point keeps the margin by its bounds. The chords between points can cut a corner: where a chord's
//! middle comes closer than half the margin, the bounds of its ends are halved and the programme solved
//! again, a few times at most (a chord of the reference itself that cuts a sharp corner stays). The line
//! is a guide for a strafer, whose runs are simulated and judged on their own.

use super::Corridor;
use crate::physics::Vec2;
use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus,
    SupportedConeT, ZeroConeT,
};

/// The line's points are about this far apart along the centre line, units, unless that makes more
/// than [`MAX_POINTS`].
const STEP_UNITS: f64 = 24.0;

/// The most points a line has (its step grows on long corridors).
const MAX_POINTS: usize = 600;

/// How far along a normal the bound of an offset is looked for, units.
const MAX_OFFSET_UNITS: f64 = 1024.0;

/// Steps of the search for an offset's bound along its normal, units (then bisected).
const OFFSET_SCAN_UNITS: f64 = 2.0;

/// Times the bounds of the ends of chords that came too close to a wall are halved and the line solved
/// again.
const MAX_TIGHTENINGS: usize = 6;

/// Passes of the programme, each moving the line found by the one before sideways along its own normals:
/// the centre line's normals fan out at its corners, where the first pass's points can only move along
/// them, and the passes after it, along a line that already bends smoothly, take those kinks out.
const PASSES: usize = 3;

/// A line through the corridor, its points in order from the start.
#[derive(Clone, Debug, PartialEq)]
pub struct RacingLine {
    /// The points, units.
    pub points: Vec<Vec2>,
}

impl RacingLine {
    /// The line that bends least through `corridor` along `centre` (a polyline from the start to the
    /// finish, kept off the walls), each point at least `margin_units` off every wall; `None` when the
    /// centre line has no length or the programme has no solution.
    pub fn through(corridor: &Corridor, centre: &[Vec2], margin_units: f64) -> Option<Self> {
        let mut line = Self::moved_from(corridor, centre, margin_units)?;
        for _ in 1..PASSES {
            match Self::moved_from(corridor, &line.points, margin_units) {
                Some(next) => line = next,
                None => break,
            }
        }
        Some(line)
    }

    /// The line that bends least among those moved sideways from `reference` (one pass).
    fn moved_from(corridor: &Corridor, reference: &[Vec2], margin_units: f64) -> Option<Self> {
        let samples = resampled(reference)?;
        let normals = normals_of(&samples);
        let mut bounds: Vec<(f64, f64)> = samples
            .iter()
            .zip(&normals)
            .map(|(&c, &n)| offset_bounds(corridor, c, n, margin_units))
            .collect();
        // The start stays where it is.
        bounds[0] = (0.0, 0.0);
        let mut tightenings = 0;
        loop {
            let offsets = least_bending_offsets(&samples, &normals, &bounds)?;
            let points: Vec<Vec2> = samples
                .iter()
                .zip(&normals)
                .zip(&offsets)
                .map(|((&c, &n), &a)| c + n * a)
                .collect();
            let close = too_close(corridor, &points, 0.5 * margin_units);
            if close.is_empty() || tightenings == MAX_TIGHTENINGS {
                return Some(RacingLine { points });
            }
            // Halved towards the reference, whose chords are clear where its points are well inside.
            for i in close {
                if bounds[i].0 <= 0.0 && bounds[i].1 >= 0.0 {
                    bounds[i] = (0.5 * bounds[i].0, 0.5 * bounds[i].1);
                }
            }
            tightenings += 1;
        }
    }
}

/// The polyline `path` resampled at even steps of arc length (about [`STEP_UNITS`]), its ends kept;
/// `None` for a path of no length.
fn resampled(path: &[Vec2]) -> Option<Vec<Vec2>> {
    let mut cumulative = vec![0.0];
    for w in path.windows(2) {
        let last = cumulative.last().copied().unwrap_or(0.0);
        cumulative.push(last + (w[1] - w[0]).length());
    }
    let total = cumulative.last().copied().unwrap_or(0.0);
    // A path of no length (or not finite) has no direction to resample along.
    if total.is_nan() || total <= 0.0 {
        return None;
    }
    let steps = ((total / STEP_UNITS).ceil() as usize).clamp(2, MAX_POINTS - 1);
    let mut points = Vec::with_capacity(steps + 1);
    let mut seg = 1;
    for k in 0..=steps {
        let s = total * k as f64 / steps as f64;
        while seg < path.len() - 1 && cumulative[seg] < s {
            seg += 1;
        }
        let (a, b) = (path[seg - 1], path[seg]);
        let len = cumulative[seg] - cumulative[seg - 1];
        let t = if len > 0.0 {
            ((s - cumulative[seg - 1]) / len).clamp(0.0, 1.0)
        } else {
            0.0
        };
        points.push(a + (b - a) * t);
    }
    Some(points)
}

/// The unit normals (to the left) of `points`, each from the chord between its neighbours.
fn normals_of(points: &[Vec2]) -> Vec<Vec2> {
    let n = points.len();
    (0..n)
        .map(|i| {
            let (a, b) = (points[i.saturating_sub(1)], points[(i + 1).min(n - 1)]);
            (b - a).perp().normalized().unwrap_or(Vec2::new(0.0, 1.0))
        })
        .collect()
}

/// The offsets along the unit normal `n` from `c` that keep the hull `margin_units` off every wall: the
/// stretch through `c` where it keeps that margin, else (a point of the reference on a chord that cuts
/// a corner) the nearest such stretch on either side within [`MAX_OFFSET_UNITS`], else none (`(0, 0)`).
fn offset_bounds(corridor: &Corridor, c: Vec2, n: Vec2, margin_units: f64) -> (f64, f64) {
    let clear = |t: f64| corridor.clearance(c + n * t) >= margin_units;
    if clear(0.0) {
        return (
            -offset_bound(corridor, c, -n, margin_units),
            offset_bound(corridor, c, n, margin_units),
        );
    }
    let mut t = OFFSET_SCAN_UNITS;
    while t <= MAX_OFFSET_UNITS {
        for dir in [1.0, -1.0] {
            if clear(dir * t) {
                let from = c + n * (dir * t);
                let far = t + offset_bound(corridor, from, n * dir, margin_units);
                return if dir > 0.0 { (t, far) } else { (-far, -t) };
            }
        }
        t += OFFSET_SCAN_UNITS;
    }
    (0.0, 0.0)
}

/// How far the hull can move from `from` along the unit vector `dir` keeping `margin_units` off every
/// wall, units (0 when it cannot move at all).
fn offset_bound(corridor: &Corridor, from: Vec2, dir: Vec2, margin_units: f64) -> f64 {
    let clear = |t: f64| corridor.clearance(from + dir * t) >= margin_units;
    if !clear(0.0) {
        return 0.0;
    }
    let mut t = 0.0;
    while t < MAX_OFFSET_UNITS && clear(t + OFFSET_SCAN_UNITS) {
        t += OFFSET_SCAN_UNITS;
    }
    let (mut lo, mut hi) = (t, t + OFFSET_SCAN_UNITS);
    for _ in 0..8 {
        let mid = 0.5 * (lo + hi);
        if clear(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// The indices of the points of `points` (and of both ends of each chord) that come closer than
/// `min_units` to a wall, the start excepted.
fn too_close(corridor: &Corridor, points: &[Vec2], min_units: f64) -> Vec<usize> {
    let mut close = Vec::new();
    for i in 1..points.len() {
        let mid = (points[i - 1] + points[i]) * 0.5;
        if corridor.clearance(points[i]) < min_units || corridor.clearance(mid) < min_units {
            if i > 1 {
                close.push(i - 1);
            }
            close.push(i);
        }
    }
    close.dedup();
    close
}

/// The offsets `alpha` within `bounds` that minimise `sum |D_i|^2`, `D_i = p_(i-1) - 2 p_i + p_(i+1)`
/// with `p_i = c_i + alpha_i n_i`: a convex quadratic programme ([`bending_objective`],
/// [`offset_constraints`]) that Clarabel solves.
fn least_bending_offsets(
    centre: &[Vec2],
    normals: &[Vec2],
    bounds: &[(f64, f64)],
) -> Option<Vec<f64>> {
    let (p, q) = bending_objective(centre, normals);
    let (a, b, cones, fixed) = offset_constraints(bounds);
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .max_iter(200)
        .build()
        .ok()?;
    let mut solver = DefaultSolver::new(&p, &q, &a, &b, &cones, settings).ok()?;
    solver.solve();
    match solver.solution.status {
        SolverStatus::Solved | SolverStatus::AlmostSolved => {}
        _ => return None,
    }
    let mut x = std::mem::take(&mut solver.solution.x);
    // The fixed offsets exactly, not to the solver's tolerance.
    for &i in &fixed {
        x[i] = 0.5 * (bounds[i].0 + bounds[i].1);
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// The bending as Clarabel's objective `1/2 x'Px + q'x` in the offsets: `P = 2 sum J_i'J_i`,
/// `q = 2 sum J_i'd_i`, where `J_i` holds `n_(i-1), -2 n_i, n_(i+1)` in the columns of its three points
/// and `d_i` is the centre line's own second difference. `P` is banded: its upper triangle is three
/// diagonals.
fn bending_objective(centre: &[Vec2], normals: &[Vec2]) -> (CscMatrix<f64>, Vec<f64>) {
    let n = centre.len();
    let mut upper_diagonals = vec![[0.0; 3]; n];
    let mut q = vec![0.0; n];
    for i in 1..n.saturating_sub(1) {
        let d = centre[i - 1] - centre[i] * 2.0 + centre[i + 1];
        let cols = [
            (i - 1, normals[i - 1]),
            (i, normals[i] * -2.0),
            (i + 1, normals[i + 1]),
        ];
        for &(a, ja) in &cols {
            q[a] += 2.0 * ja.dot(d);
            for &(b, jb) in &cols {
                if b >= a {
                    upper_diagonals[a][b - a] += 2.0 * ja.dot(jb);
                }
            }
        }
    }
    let (mut pr, mut pc, mut pv) = (Vec::new(), Vec::new(), Vec::new());
    for (a, diagonals) in upper_diagonals.iter().enumerate() {
        for (k, &v) in diagonals.iter().enumerate() {
            // Entries no term reached stay out of the sparse matrix (a structural zero is exactly 0).
            if a + k < n && v != 0.0 {
                pr.push(a);
                pc.push(a + k);
                pv.push(v);
            }
        }
    }
    (CscMatrix::new_from_triplets(n, n, pr, pc, pv), q)
}

/// Clarabel's constraints `Ax + s = b` (`A`, `b` and the cones of the rows), and the indices of the
/// offsets they fix.
type Constraints = (
    CscMatrix<f64>,
    Vec<f64>,
    Vec<SupportedConeT<f64>>,
    Vec<usize>,
);

/// The offsets' bounds as constraints: the offsets fixed (no room: the start, or a point with no
/// stretch off the walls) in a zero cone, then `alpha <= hi` and `-alpha <= -lo` in a nonnegative cone.
fn offset_constraints(bounds: &[(f64, f64)]) -> Constraints {
    let n = bounds.len();
    let fixed: Vec<usize> = (0..n)
        .filter(|&i| bounds[i].1 - bounds[i].0 <= 0.0)
        .collect();
    let free: Vec<usize> = (0..n)
        .filter(|&i| bounds[i].1 - bounds[i].0 > 0.0)
        .collect();
    let (mut ar, mut ac, mut av, mut b) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for &i in &fixed {
        ar.push(b.len());
        ac.push(i);
        av.push(1.0);
        b.push(0.5 * (bounds[i].0 + bounds[i].1));
    }
    for &i in &free {
        for (sign, limit) in [(1.0, bounds[i].1), (-1.0, -bounds[i].0)] {
            ar.push(b.len());
            ac.push(i);
            av.push(sign);
            b.push(limit);
        }
    }
    let a = CscMatrix::new_from_triplets(b.len(), n, ar, ac, av);
    let mut cones: Vec<SupportedConeT<f64>> = Vec::new();
    if !fixed.is_empty() {
        cones.push(ZeroConeT(fixed.len()));
    }
    if !free.is_empty() {
        cones.push(NonnegativeConeT(2 * free.len()));
    }
    (a, b, cones, fixed)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::HULL_HALF_WIDTH_UNITS;
    use crate::scene::generate::{generate, GeneratorSettings};

    /// `sum |D_i|^2` of `points` resampled at the line's step: the bending the programme lowers.
    fn bending(points: &[Vec2]) -> f64 {
        let p = resampled(points).unwrap_or_else(|| panic!("no length"));
        p.windows(3)
            .map(|w| (w[0] - w[1] * 2.0 + w[2]).length_squared())
            .sum()
    }

    #[test]
    fn the_racing_line_keeps_off_the_walls_from_the_start_and_bends_less_than_its_reference() {
        // Generated corridors of every width, turn and frame rate; the reference is the shortest path
        // kept a unit further off the walls than the margin (as the centre line is, and more).
        let margin = 4.0;
        let settings = GeneratorSettings::default();
        let mut lines = 0;
        for index in 0..12 {
            let scene = generate(7, index, &settings)
                .unwrap_or_else(|e| panic!("{e}"))
                .scene;
            let corridor = Corridor::new(&scene.walls).unwrap_or_else(|e| panic!("{e}"));
            let kept =
                Corridor::with_half_width(&scene.walls, HULL_HALF_WIDTH_UNITS + margin + 1.0)
                    .unwrap_or_else(|e| panic!("{e}"));
            let Some((_, reference)) =
                kept.shortest_path(scene.start.pos, (scene.finish.a, scene.finish.b))
            else {
                continue;
            };
            let line = RacingLine::through(&corridor, &reference, margin)
                .unwrap_or_else(|| panic!("scene {index}: no line"));
            lines += 1;
            assert_eq!(line.points[0], scene.start.pos, "scene {index}");
            for &p in &line.points {
                let clearance = corridor.clearance(p);
                assert!(clearance >= margin, "scene {index}: {p:?} {clearance}");
            }
            let (ours, theirs) = (bending(&line.points), bending(&reference));
            assert!(ours < theirs, "scene {index}: {ours} against {theirs}");
        }
        assert!(lines >= 10, "{lines}");
    }
}
