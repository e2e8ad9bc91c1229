//! The shortest path of the hull centre through the corridor, a lower bound on the distance any valid
//! path travels (docs/physics.md section 6: the greedy speed profile over this distance bounds the time).
//!
//! The hull may not overlap any wall, solid or rule, so its centre must stay out of the interior of every
//! wall segment grown by the box (a convex hexagon). The shortest path among polygonal obstacles is a
//! polyline whose corners are obstacle vertices; to a target segment, its last leg ends at an end of a
//! reachable stretch of the target or meets the target at a right angle. So a visibility graph over the
//! grown vertices, the start and the ends of the reachable stretches, with perpendicular last legs, and
//! Dijkstra over it, is exact.
//!
//! Lower bound: visibility is tested against the grown segments shrunk by [`PATH_SHRINK_UNITS`], so a leg
//! that runs along a grown wall (as shortest paths do) is never blocked by rounding. Shrinking only removes
//! obstacles, so the reported length never exceeds the length of any valid path.
//!
//! Performance: `O(V^2 S)` for `V` grown vertices (6 per segment) and `S` segments: about a millisecond for
//! the shipped scenes.

use super::corridor::Corridor;
use super::grown::GrownSegment;
use super::PATH_SHRINK_UNITS;
use crate::physics::Vec2;

impl Corridor {
    /// The shortest path for the hull centre from `from` to any point of the segment `to_segment`
    /// (units), around every wall (solid and rule) grown by the hull half-width: its length (units) and its
    /// corners, starting at `from` and ending on the segment. `None` when no path exists (the segment is
    /// walled off, lies wholly inside grown walls, or `from` is inside one).
    pub fn shortest_path(&self, from: Vec2, to_segment: (Vec2, Vec2)) -> Option<(f64, Vec<Vec2>)> {
        let obstacles: Vec<&GrownSegment> = self.pieces.iter().map(|p| &p.grown).collect();
        let blocked = |p: Vec2, q: Vec2| {
            obstacles.iter().any(|g| {
                g.open_interval(p, q - p, PATH_SHRINK_UNITS)
                    .is_some_and(|iv| iv.meets_unit_open())
            })
        };
        let inside_any = |p: Vec2| obstacles.iter().any(|g| g.max_side(p) < -PATH_SHRINK_UNITS);

        let targets = reachable_stretches(&obstacles, to_segment);
        if targets.is_empty() || !from.is_finite() {
            return None;
        }

        // Nodes: the start, the grown vertices outside every grown wall, the ends of the target stretches.
        let mut nodes = vec![from];
        for g in &obstacles {
            nodes.extend(g.vertices().iter().copied().filter(|&v| !inside_any(v)));
        }
        let (ta, te) = (to_segment.0, to_segment.1 - to_segment.0);
        for &(s0, s1) in &targets {
            nodes.push(ta + te * s0);
            nodes.push(ta + te * s1);
        }

        // Dense Dijkstra; node `n` is the virtual terminal, reached from any node by its best last leg.
        let n = nodes.len();
        let terminal = n;
        let mut dist = vec![f64::INFINITY; n + 1];
        let mut prev = vec![usize::MAX; n + 1];
        let mut done = vec![false; n + 1];
        let mut terminal_point = from;
        dist[0] = 0.0;
        loop {
            let u = (0..=n)
                .filter(|&i| !done[i] && dist[i].is_finite())
                .min_by(|&i, &j| dist[i].total_cmp(&dist[j]))?;
            if u == terminal {
                break;
            }
            done[u] = true;
            let pu = nodes[u];
            // Best last leg from u: the nearest point of each stretch, if in sight.
            for &(s0, s1) in &targets {
                let foot = ta + te * closest_parameter(pu, ta, te).max(s0).min(s1);
                let d = dist[u] + (foot - pu).length();
                if d < dist[terminal] && !blocked(pu, foot) {
                    dist[terminal] = d;
                    prev[terminal] = u;
                    terminal_point = foot;
                }
            }
            for v in 0..n {
                if done[v] {
                    continue;
                }
                let d = dist[u] + (nodes[v] - pu).length();
                if d < dist[v] && !blocked(pu, nodes[v]) {
                    dist[v] = d;
                    prev[v] = u;
                }
            }
        }

        let mut path = vec![terminal_point];
        let mut at = prev[terminal];
        while at != usize::MAX {
            path.push(nodes[at]);
            at = prev[at];
        }
        path.reverse();
        Some((dist[terminal], path))
    }
}

/// The parameter `t` of the point `a + t e` nearest to `p` on the line through `a` along `e` (0 when `e`
/// is zero). Measured on the whole target segment, not on a stretch of it, so that a foot in the middle of
/// a stretch is not moved by the rounding of the stretch's ends.
fn closest_parameter(p: Vec2, a: Vec2, e: Vec2) -> f64 {
    let len2 = e.length_squared();
    if len2 == 0.0 {
        return 0.0;
    }
    (p - a).dot(e) / len2
}

/// How far the grown walls are shrunk when the reachable stretches of the target are found, units: half
/// as far as visibility shrinks them ([`PATH_SHRINK_UNITS`]). A stretch's end then lies just outside every
/// wall the visibility test knows, so a last leg that runs along a grown wall to the end of a stretch (the
/// finish line leaving the wall at a slanted corner) is not blocked by rounding at its very end; shrunk
/// alike, the end lay on the shrunk wall and the path went round the wall's far corner and back, longer
/// than the true shortest path and so no longer a lower bound. Some shrink is kept so that a corridor
/// exactly one hull wide still has its single point on the line.
const STRETCH_SHRINK_UNITS: f64 = 0.5 * PATH_SHRINK_UNITS;

/// The parts of the segment `(a, b)` outside every (shrunk) grown wall, as closed parameter intervals
/// `[s0, s1]` of `a + s (b - a)`.
fn reachable_stretches(obstacles: &[&GrownSegment], (a, b): (Vec2, Vec2)) -> Vec<(f64, f64)> {
    if !(a.is_finite() && b.is_finite()) {
        return Vec::new();
    }
    let e = b - a;
    if e == Vec2::ZERO {
        let outside = obstacles
            .iter()
            .all(|g| g.max_side(a) >= -PATH_SHRINK_UNITS);
        return if outside {
            vec![(0.0, 0.0)]
        } else {
            Vec::new()
        };
    }
    // Open intervals of the parameter in (0, 1) covered by grown walls.
    let mut covered: Vec<(f64, f64)> = obstacles
        .iter()
        .filter_map(|g| g.open_interval(a, e, STRETCH_SHRINK_UNITS))
        .filter(|iv| iv.meets_unit_open())
        .map(|iv| (iv.lo.max(0.0), iv.hi.min(1.0)))
        .collect();
    covered.sort_by(|x, y| x.0.total_cmp(&y.0));
    // The complement in [0, 1]; a single uncovered point between two touching walls is dropped (a
    // measure-zero gap no hull centre can use to make a path shorter).
    let mut free = Vec::new();
    let mut t = 0.0;
    for &(lo, hi) in &covered {
        if lo > t {
            free.push((t, lo));
        }
        t = f64::max(t, hi);
    }
    if t < 1.0 {
        free.push((t, 1.0));
    }
    free
}
