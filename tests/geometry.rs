//! Corridor queries against brute force: the swept hull (cast and sweep), clearances, rule boundaries,
//! finish crossings and the shortest path (docs/physics.md section 10). Seeds are fixed.

use strafeopt::geometry::{
    BoundaryKind, Cast, Corridor, FinishLine, FinishPoint, SweepStatus, Wall, CONTACT_TOL_UNITS,
    DIST_EPSILON_UNITS, HULL_HALF_WIDTH_UNITS,
};
use strafeopt::physics::Vec2;

const H: f64 = HULL_HALF_WIDTH_UNITS;

/// A tiny deterministic generator (64-bit LCG, Knuth's MMIX constants), uniform in [0, 1).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
    fn pick<T: Copy>(&mut self, items: &[T]) -> T {
        items[((self.next() * items.len() as f64) as usize).min(items.len() - 1)]
    }
}

fn v(x: f64, y: f64) -> Vec2 {
    Vec2::new(x, y)
}

fn wall(kind: BoundaryKind, closed: bool, pts: &[(f64, f64)]) -> Wall {
    Wall {
        points: pts.iter().map(|&(x, y)| v(x, y)).collect(),
        closed,
        kind,
    }
}

/// A test room: a box 0..400 x 0..300, a diagonal wall, a thin vertical wall and a triangle.
fn room(kind: BoundaryKind) -> Vec<Wall> {
    vec![
        wall(
            kind,
            true,
            &[(0.0, 0.0), (400.0, 0.0), (400.0, 300.0), (0.0, 300.0)],
        ),
        wall(kind, false, &[(100.0, 60.0), (180.0, 140.0)]),
        wall(kind, false, &[(260.0, 0.0), (260.0, 120.0)]),
        wall(
            kind,
            true,
            &[(120.0, 200.0), (200.0, 230.0), (150.0, 260.0)],
        ),
    ]
}

/// Exact distance from the box centred at `c` to the point `p` (0 inside).
fn box_point_distance(c: Vec2, p: Vec2) -> f64 {
    let dx = ((p.x - c.x).abs() - H).max(0.0);
    let dy = ((p.y - c.y).abs() - H).max(0.0);
    dx.hypot(dy)
}

/// Brute force: the smallest distance from the box to points sampled along every wall segment, and
/// whether any sample lies strictly inside the box.
fn sampled_clearance(walls: &[Wall], c: Vec2, spacing: f64) -> (f64, bool) {
    let mut best = f64::INFINITY;
    let mut inside = false;
    for w in walls {
        for (a, b) in w.segments() {
            let n = ((b - a).length() / spacing).ceil().max(1.0) as usize;
            for i in 0..=n {
                let p = a + (b - a) * (i as f64 / n as f64);
                best = best.min(box_point_distance(c, p));
                if (p.x - c.x).abs() < H && (p.y - c.y).abs() < H {
                    inside = true;
                }
            }
        }
    }
    (best, inside)
}

#[test]
fn clearance_matches_point_sampling() {
    let walls = room(BoundaryKind::Solid);
    let corridor = Corridor::new(&walls).unwrap();
    let mut rng = Lcg(0x5eed_0001);
    let spacing = 0.01;
    for _ in 0..3000 {
        let c = v(rng.range(-20.0, 420.0), rng.range(-20.0, 320.0));
        let clearance = corridor.clearance(c);
        let (sampled, inside) = sampled_clearance(&walls, c, spacing);
        if clearance > 0.0 {
            // Sampling can only overestimate a gap, by at most half a spacing.
            assert!(
                sampled >= clearance - 1e-9 && sampled <= clearance + spacing,
                "at {c:?}: clearance {clearance}, sampled {sampled}"
            );
            assert!(!inside);
        } else {
            assert_eq!(
                sampled, 0.0,
                "at {c:?}: clearance {clearance} but no sample touches"
            );
            if clearance < -spacing {
                assert!(
                    inside,
                    "at {c:?}: clearance {clearance} but no sample inside"
                );
            }
        }
    }
}

#[test]
fn clearance_penetration_depth_is_the_separating_distance() {
    let walls = vec![wall(
        BoundaryKind::Solid,
        false,
        &[(0.0, 0.0), (100.0, 0.0)],
    )];
    let corridor = Corridor::new(&walls).unwrap();
    assert!((corridor.clearance(v(50.0, 20.0)) - 4.0).abs() < 1e-12);
    assert_eq!(corridor.clearance(v(50.0, 16.0)), 0.0);
    assert!((corridor.clearance(v(50.0, 10.0)) + 6.0).abs() < 1e-12);
    // Past the end: the nearer of the end (x) and the face (y).
    assert!((corridor.clearance(v(110.0, 5.0)) + 6.0).abs() < 1e-12);
    // Diagonally off the end: corner to endpoint.
    assert!((corridor.clearance(v(119.0, 20.0)) - 5.0).abs() < 1e-12);
}

/// Brute-force check of one cast: sub-step the move and compare with the reported contact.
/// Returns whether brute force saw the penetration (false for windows narrower than a sub-step).
fn check_cast(corridor: &Corridor, pos: Vec2, delta: Vec2, steps: usize) -> bool {
    let clear = |t: f64| corridor.clearance_of(pos + delta * t, Some(BoundaryKind::Solid));
    let first_deep = (0..=steps)
        .map(|i| i as f64 / steps as f64)
        .find(|&t| clear(t) < -CONTACT_TOL_UNITS);
    match corridor.cast(pos, delta) {
        Cast::StartedInside { .. } => panic!("start {pos:?} was checked clear"),
        Cast::Free => {
            assert!(
                first_deep.is_none(),
                "free move {pos:?} + {delta:?} penetrates at t = {first_deep:?}"
            );
            true
        }
        Cast::Hit(c) => {
            assert!((0.0..=1.0).contains(&c.fraction));
            let at = clear(c.fraction);
            assert!(
                at.abs() <= 1e-8,
                "contact of {pos:?} + {delta:?} at {} has clearance {at}",
                c.fraction
            );
            // Nothing before the contact goes deeper than the tolerance.
            for i in 0..=steps {
                let t = c.fraction * i as f64 / steps as f64;
                assert!(
                    clear(t) >= -CONTACT_TOL_UNITS - 1e-12,
                    "penetrates before contact"
                );
            }
            // The normal points out of the wall.
            let out = pos + delta * c.fraction + c.normal * 1e-6;
            assert!(corridor.clearance_of(out, Some(BoundaryKind::Solid)) >= -1e-9);
            assert!((c.normal.length() - 1.0).abs() < 1e-12);
            assert!(
                c.normal.dot(delta) <= 0.0,
                "contact normal faces along the move"
            );
            match first_deep {
                Some(t) => {
                    assert!(
                        c.fraction <= t + 1e-12 && c.fraction >= t - 1.0 / steps as f64 - 1e-9,
                        "contact at {} but brute force penetrates first at {t}",
                        c.fraction
                    );
                    true
                }
                None => false,
            }
        }
    }
}

#[test]
fn cast_matches_substepping_on_random_moves() {
    let corridor = Corridor::new(&room(BoundaryKind::Solid)).unwrap();
    let mut rng = Lcg(0x5eed_0002);
    let mut checked = 0;
    let mut unseen = 0;
    let mut hits = 0;
    while checked < 4000 {
        let pos = v(rng.range(10.0, 390.0), rng.range(10.0, 290.0));
        if corridor.clearance(pos) < 0.0 {
            continue;
        }
        let len = rng.pick(&[1.0, 10.0, 60.0, 200.0]);
        let delta = Vec2::from_angle(rng.range(0.0, std::f64::consts::TAU)) * len;
        if matches!(corridor.cast(pos, delta), Cast::Hit(_)) {
            hits += 1;
        }
        if !check_cast(&corridor, pos, delta, 2000) {
            unseen += 1;
        }
        checked += 1;
    }
    assert!(
        hits > 500,
        "only {hits} hits: the test does not probe walls"
    );
    assert!(
        unseen * 100 < checked,
        "{unseen} contacts brute force could not confirm"
    );
}

#[test]
fn cast_grazing_corner_and_parallel_moves() {
    let corridor = Corridor::new(&room(BoundaryKind::Solid)).unwrap();
    // Along the floor at clearance 0 (parallel, distance 0): free, both directions.
    assert_eq!(corridor.cast(v(40.0, H), v(150.0, 0.0)), Cast::Free);
    assert_eq!(corridor.cast(v(200.0, H), v(-150.0, 0.0)), Cast::Free);
    // Along the grown diagonal wall's face, exactly: free.
    let n = Vec2::new(-1.0, 1.0) * (1.0 / 2f64.sqrt());
    let face_offset = n.dot(v(100.0, 60.0)) + H * (n.x.abs() + n.y.abs());
    let on_face = v(140.0, 100.0) + n * (face_offset - n.dot(v(140.0, 100.0)));
    assert_eq!(
        corridor.cast(on_face, v(20.0, 20.0)),
        Cast::Free,
        "sliding along a diagonal face"
    );
    // Exactly through the grown corner of the thin wall's top (276, 136): grazing, free.
    let corner = v(260.0 + H, 120.0 + H);
    assert_eq!(
        corridor.cast(corner - v(30.0, -30.0), v(60.0, -60.0)),
        Cast::Free
    );
    // Aimed at that corner from directly above, 1e-6 inside it: a hit on the top face.
    match corridor.cast(v(276.0 - 1e-6, 200.0), v(0.0, -100.0)) {
        Cast::Hit(c) => {
            assert!((c.fraction - (200.0 - 136.0) / 100.0).abs() < 1e-12);
            assert_eq!(c.normal, v(0.0, 1.0));
        }
        other => panic!("expected a hit, got {other:?}"),
    }
    // Random grazing moves: start on a grown face, move parallel to it.
    let mut rng = Lcg(0x5eed_0003);
    for _ in 0..1000 {
        let x = rng.range(50.0, 200.0);
        let pos = v(x, H);
        let delta = v(rng.range(-30.0, 30.0), 0.0);
        assert_eq!(
            corridor.cast(pos, delta),
            Cast::Free,
            "grazing {pos:?} {delta:?}"
        );
        assert!(check_cast(&corridor, pos, delta, 500));
    }
    // Moves that start touching and head into the wall: contact at once.
    match corridor.cast(v(50.0, H), v(10.0, -10.0)) {
        Cast::Hit(c) => {
            assert_eq!(c.fraction, 0.0);
            assert_eq!(c.normal, v(0.0, 1.0));
        }
        other => panic!("expected a hit at 0, got {other:?}"),
    }
    // Starting inside is its own status.
    assert!(matches!(
        corridor.cast(v(50.0, 10.0), v(10.0, 0.0)),
        Cast::StartedInside { wall: 0, depth_units } if (depth_units - 6.0).abs() < 1e-12
    ));
}

#[test]
fn sweep_slides_along_walls_and_stops_in_corners() {
    let corridor = Corridor::new(&room(BoundaryKind::Solid)).unwrap();
    let tau = 0.01;
    // Diagonally into the floor: stop at y = 16, keep the x velocity, use the whole frame.
    let r = corridor.sweep(v(50.0, 26.0), v(1000.0, -2000.0), tau);
    assert_eq!(r.status, SweepStatus::Clipped { contacts: 1 });
    assert!((r.pos.y - H).abs() < 1e-12);
    assert!((r.pos.x - (50.0 + 10.0 * 0.5 + 10.0 * 0.5)).abs() < 1e-9);
    assert_eq!(r.vel, v(1000.0, 0.0));
    // Head-on into the floor: stopped, velocity zero.
    let r = corridor.sweep(v(50.0, 26.0), v(0.0, -2000.0), tau);
    assert_eq!(r.status, SweepStatus::Clipped { contacts: 1 });
    assert_eq!(r.vel, Vec2::ZERO);
    // Into the concave corner at (0, 0): both walls hit, velocity zero, resting in the corner.
    let r = corridor.sweep(v(20.0, 20.0), v(-1000.0, -1000.0), tau);
    assert_eq!(r.vel, Vec2::ZERO);
    assert!((r.pos - v(H, H)).length() < 1e-9, "{:?}", r.pos);
    assert_eq!(r.status.contacts(), 2);
    // No wall in reach: free, full move.
    let r = corridor.sweep(v(60.0, 150.0), v(100.0, 50.0), tau);
    assert_eq!(r.status, SweepStatus::Free);
    assert_eq!(r.pos, v(61.0, 150.5));
    // Started inside: not moved, velocity zeroed.
    let r = corridor.sweep(v(50.0, 10.0), v(100.0, 0.0), tau);
    assert!(matches!(r.status, SweepStatus::StartedInside { .. }));
    assert_eq!((r.pos, r.vel), (v(50.0, 10.0), Vec2::ZERO));
}

#[test]
fn the_games_sweep_stops_a_32nd_of_a_unit_short_of_the_wall() {
    let corridor = Corridor::new(&room(BoundaryKind::Solid)).unwrap();
    let tau = 0.01;
    let stand_off = DIST_EPSILON_UNITS;
    // Diagonally into the floor, 20 units into its plane over the frame: the hit comes
    // `stand_off / 20` of the move early, and the slide uses the time left, so x ends where it would
    // without the stand-off.
    let r = corridor.sweep_standing_off(v(50.0, 26.0), v(1000.0, -2000.0), tau, stand_off);
    assert_eq!(r.status, SweepStatus::Clipped { contacts: 1 });
    assert!((r.pos.y - (H + stand_off)).abs() < 1e-12, "{:?}", r.pos);
    assert!((r.pos.x - 60.0).abs() < 1e-9, "{:?}", r.pos);
    assert_eq!(r.vel, v(1000.0, 0.0));
    // Starting within the stand-off and moving in: not moved into the wall, the velocity clipped and
    // the slide taking the whole frame.
    let r = corridor.sweep_standing_off(v(50.0, H + 0.01), v(1000.0, -500.0), tau, stand_off);
    assert_eq!(r.status, SweepStatus::Clipped { contacts: 1 });
    assert_eq!(r.pos, v(60.0, H + 0.01));
    // Into the concave corner at (0, 0): held a 32nd off both walls.
    let r = corridor.sweep_standing_off(v(20.0, 20.0), v(-1000.0, -1000.0), tau, stand_off);
    assert_eq!(r.vel, Vec2::ZERO);
    assert!(
        (r.pos - v(H + stand_off, H + stand_off)).length() < 1e-9,
        "{:?}",
        r.pos
    );
}

#[test]
fn sweep_never_ends_inside_a_wall() {
    let corridor = Corridor::new(&room(BoundaryKind::Solid)).unwrap();
    let mut rng = Lcg(0x5eed_0004);
    let mut count = 0;
    let mut clipped = 0;
    while count < 5000 {
        let pos = v(rng.range(10.0, 390.0), rng.range(10.0, 290.0));
        if corridor.clearance(pos) < 0.0 {
            continue;
        }
        let speed = rng.pick(&[300.0, 2000.0, 20000.0]);
        let vel = Vec2::from_angle(rng.range(0.0, std::f64::consts::TAU)) * speed;
        let r = corridor.sweep(pos, vel, 0.01);
        assert!(
            corridor.clearance(r.pos) >= -CONTACT_TOL_UNITS,
            "sweep from {pos:?} at {vel:?} ends at {:?} with clearance {}",
            r.pos,
            corridor.clearance(r.pos)
        );
        assert!(r.vel.length() <= vel.length() * (1.0 + 1e-12));
        assert!((r.pos - pos).length() <= vel.length() * 0.01 * (1.0 + 1e-12) + 1e-9);
        match r.status {
            SweepStatus::Free => assert!((r.pos - (pos + vel * 0.01)).length() < 1e-9),
            SweepStatus::StartedInside { .. } => panic!("start was clear"),
            _ => clipped += 1,
        }
        // The hull can continue from where it stopped.
        assert!(!matches!(
            corridor.sweep(r.pos, r.vel, 0.01).status,
            SweepStatus::StartedInside { .. }
        ));
        count += 1;
    }
    assert!(clipped > 500);
}

#[test]
fn rule_lines_allow_touching_but_not_overlap() {
    let corridor = Corridor::new(&[
        wall(BoundaryKind::Rule, false, &[(0.0, 0.0), (1000.0, 0.0)]),
        wall(BoundaryKind::Rule, false, &[(500.0, 40.0), (500.0, 100.0)]),
    ])
    .unwrap();
    // Exactly along the line: clearance 0, allowed, also swept along it.
    assert_eq!(corridor.clearance(v(300.0, H)), 0.0);
    assert!(!corridor.rule_violation(v(300.0, H)));
    assert!(!corridor.rule_violation_swept(v(100.0, H), v(400.0, H)));
    // 1e-6 inside: a violation.
    assert!(corridor.rule_violation(v(300.0, H - 1e-6)));
    assert!(corridor.rule_violation_swept(v(100.0, H), v(400.0, H - 1e-6)));
    // Within the tolerance: still touching.
    assert!(!corridor.rule_violation(v(300.0, H - 0.5 * CONTACT_TOL_UNITS)));
    // A thin line crossed between two frame positions that are both clear of it.
    let (p0, p1) = (v(470.0, 70.0), v(530.0, 70.0));
    assert!(!corridor.rule_violation(p0) && !corridor.rule_violation(p1));
    assert!(corridor.rule_violation_swept(p0, p1));
    // Passing just over its end (the grown end is at y = 116): fine; just under it: not.
    assert!(!corridor.rule_violation_swept(v(470.0, 116.0), v(530.0, 116.0)));
    assert!(corridor.rule_violation_swept(v(470.0, 115.9), v(530.0, 115.9)));
    // Rules do not stop a move: the sweep ignores them.
    assert_eq!(corridor.cast(p0, p1 - p0), Cast::Free);
}

#[test]
fn finish_crossing_fractions() {
    let line = FinishLine {
        a: v(100.0, 0.0),
        b: v(100.0, 50.0),
        point: FinishPoint::Centre,
    };
    assert_eq!(
        line.crossing_fraction(v(90.0, 10.0), v(110.0, 10.0)),
        Some(0.5)
    );
    assert_eq!(line.crossing_fraction(v(90.0, 10.0), v(99.0, 10.0)), None);
    assert_eq!(
        line.crossing_fraction(v(90.0, 10.0), v(100.0, 10.0)),
        Some(1.0)
    );
    assert_eq!(line.crossing_fraction(v(90.0, 60.0), v(110.0, 60.0)), None);
    assert_eq!(
        line.crossing_fraction(v(100.0, 10.0), v(110.0, 10.0)),
        Some(0.0)
    );
    // Along the line: the moment it reaches the segment.
    assert_eq!(
        line.crossing_fraction(v(100.0, -50.0), v(100.0, 50.0)),
        Some(0.5)
    );
    // Diagonal crossing.
    let t = line
        .crossing_fraction(v(80.0, 0.0), v(120.0, 40.0))
        .unwrap();
    assert!((t - 0.5).abs() < 1e-15);
    // The hull reaches it 16 units earlier, and also past the segment's end.
    let hull = FinishLine {
        point: FinishPoint::Hull,
        ..line
    };
    assert_eq!(
        hull.crossing_fraction(v(60.0, 10.0), v(100.0, 10.0)),
        Some(0.6)
    );
    assert_eq!(
        hull.crossing_fraction(v(60.0, 60.0), v(100.0, 60.0)),
        Some(0.6)
    );
    assert_eq!(hull.crossing_fraction(v(60.0, 70.0), v(100.0, 70.0)), None);
    assert_eq!(
        line.crossing_fraction_with(v(60.0, 10.0), v(100.0, 10.0), FinishPoint::Hull, 8.0),
        Some(0.8)
    );
}

/// The bend90 of `hl-bend90-100fps`: width 160, legs 1200.
fn bend90(d: f64, l1: f64, l2: f64, kind: BoundaryKind) -> Vec<Wall> {
    vec![wall(
        kind,
        false,
        &[
            (l1 - d, l2),
            (l1 - d, d),
            (0.0, d),
            (0.0, 0.0),
            (l1, 0.0),
            (l1, l2),
        ],
    )]
}

#[test]
fn shortest_path_on_bend90_matches_hand_value() {
    let (d, l1, l2) = (160.0, 1200.0, 1200.0);
    let corridor = Corridor::new(&bend90(d, l1, l2, BoundaryKind::Rule)).unwrap();
    let from = v(40.0, d / 2.0);
    let (len, path) = corridor
        .shortest_path(from, (v(l1 - d, l2), v(l1, l2)))
        .unwrap();
    // Straight to the grown inner corner (l1 - d + 16, d - 16), then straight up to the finish.
    let corner = v(l1 - d + H, d - H);
    let expected = (corner - from).length() + (l2 - corner.y);
    assert!((expected - 2_074.013_752_363).abs() < 1e-6, "{expected}");
    assert!(
        len <= expected + 1e-9 && len >= expected - 1e-5,
        "{len} vs {expected}"
    );
    assert_eq!(path.len(), 3);
    assert!((path[1] - corner).length() < 1e-9);
    assert!((path[2] - v(corner.x, l2)).length() < 1e-9);
    // A valid path (the centreline) is longer.
    let centreline = (l1 - d / 2.0 - 40.0) + (l2 - d / 2.0);
    assert!(len < centreline);
}

#[test]
fn shortest_path_is_a_lower_bound_on_grid_paths() {
    // Random obstacles in a box; a grid path over clear cells (8-neighbour moves that never overlap a
    // wall) is a valid path, so it can never be shorter than the reported shortest path.
    let mut rng = Lcg(0x5eed_0005);
    let mut compared = 0;
    for case in 0..6 {
        let mut walls = vec![wall(
            BoundaryKind::Solid,
            true,
            &[(0.0, 0.0), (300.0, 0.0), (300.0, 200.0), (0.0, 200.0)],
        )];
        for _ in 0..4 {
            let a = v(rng.range(60.0, 240.0), rng.range(20.0, 180.0));
            let b = a + Vec2::from_angle(rng.range(0.0, 6.3)) * rng.range(20.0, 80.0);
            walls.push(wall(BoundaryKind::Solid, false, &[(a.x, a.y), (b.x, b.y)]));
        }
        let corridor = Corridor::new(&walls).unwrap();
        let from = v(20.0, 100.0);
        if corridor.clearance(from) < 0.0 {
            continue;
        }
        // The line the hull centre reaches when the hull touches the far wall.
        let target = (v(284.0, 0.0), v(284.0, 200.0));
        let best = corridor.shortest_path(from, target);
        let grid = grid_path(&corridor, from, 284.0, 2.0);
        match (best, grid) {
            (Some((len, path)), Some(g)) => {
                compared += 1;
                assert!(len <= g + 1e-9, "case {case}: {len} > grid {g}");
                // An 8-neighbour grid is at most 8.25 % longer than the true path, plus a cell or two.
                assert!(
                    g <= len * 1.0824 + 8.0,
                    "case {case}: grid {g} far above {len}"
                );
                // The path's legs never overlap a wall by more than the shrink.
                for leg in path.windows(2) {
                    for i in 0..=200 {
                        let p = leg[0] + (leg[1] - leg[0]) * (i as f64 / 200.0);
                        assert!(corridor.clearance(p) > -1e-6);
                    }
                }
            }
            (None, Some(g)) => panic!("case {case}: no path but the grid found {g}"),
            _ => {}
        }
    }
    assert!(compared >= 4, "only {compared} cases compared");
}

/// Dijkstra over a grid of hull centres (spacing `step`) from `from` to any cell with x >= `goal_x`.
fn grid_path(corridor: &Corridor, from: Vec2, goal_x: f64, step: f64) -> Option<f64> {
    let (nx, ny) = ((300.0 / step) as i64, (200.0 / step) as i64);
    let idx = |i: i64, j: i64| (i * ny + j) as usize;
    let pt = |i: i64, j: i64| v(i as f64 * step, j as f64 * step);
    let mut dist = vec![f64::INFINITY; (nx * ny) as usize];
    let mut done = vec![false; (nx * ny) as usize];
    let (si, sj) = (
        (from.x / step).round() as i64,
        (from.y / step).round() as i64,
    );
    let start = pt(si, sj);
    if corridor.rule_violation_swept(from, start) || corridor.cast(from, start - from) != Cast::Free
    {
        return None;
    }
    dist[idx(si, sj)] = (start - from).length();
    let mut heap = std::collections::BinaryHeap::new();
    heap.push((std::cmp::Reverse(ordered(dist[idx(si, sj)])), si, sj));
    while let Some((std::cmp::Reverse(d), i, j)) = heap.pop() {
        let d = d as f64 / 1e9;
        if done[idx(i, j)] {
            continue;
        }
        done[idx(i, j)] = true;
        if pt(i, j).x >= goal_x {
            return Some(d);
        }
        for (di, dj) in [
            (1, 0),
            (-1, 0),
            (0, 1),
            (0, -1),
            (1, 1),
            (1, -1),
            (-1, 1),
            (-1, -1),
        ] {
            let (a, b) = (i + di, j + dj);
            if a < 0 || b < 0 || a >= nx || b >= ny || done[idx(a, b)] {
                continue;
            }
            let (p, q) = (pt(i, j), pt(a, b));
            if corridor.cast(p, q - p) != Cast::Free || corridor.clearance(q) < 0.0 {
                continue;
            }
            let nd = d + (q - p).length();
            if nd < dist[idx(a, b)] {
                dist[idx(a, b)] = nd;
                heap.push((std::cmp::Reverse(ordered(nd)), a, b));
            }
        }
    }
    None
}

/// Distances as integers (nano-units) for the heap.
fn ordered(d: f64) -> u64 {
    (d * 1e9) as u64
}

#[test]
fn shortest_path_straight_lane_and_blocked() {
    let lane = vec![wall(
        BoundaryKind::Rule,
        false,
        &[(2000.0, 0.0), (0.0, 0.0), (0.0, 256.0), (2000.0, 256.0)],
    )];
    let corridor = Corridor::new(&lane).unwrap();
    let (len, path) = corridor
        .shortest_path(v(40.0, 128.0), (v(2000.0, 0.0), v(2000.0, 256.0)))
        .unwrap();
    assert!((len - 1960.0).abs() < 1e-9);
    assert_eq!(path, vec![v(40.0, 128.0), v(2000.0, 128.0)]);
    // A wall across with a 20-unit gap: no way through for the 32-unit hull.
    let mut blocked = lane.clone();
    blocked.push(wall(
        BoundaryKind::Solid,
        false,
        &[(1000.0, 0.0), (1000.0, 236.0)],
    ));
    let corridor = Corridor::new(&blocked).unwrap();
    assert!(corridor
        .shortest_path(v(40.0, 128.0), (v(2000.0, 0.0), v(2000.0, 256.0)))
        .is_none());
    // A 32-unit gap: the hull just fits, touching both sides.
    let mut tight = lane;
    tight.push(wall(
        BoundaryKind::Solid,
        false,
        &[(1000.0, 0.0), (1000.0, 224.0)],
    ));
    let corridor = Corridor::new(&tight).unwrap();
    let (len, _) = corridor
        .shortest_path(v(40.0, 128.0), (v(2000.0, 0.0), v(2000.0, 256.0)))
        .unwrap();
    assert!(len > 1960.0);
}

#[test]
fn corridor_refuses_bad_walls() {
    let bad = [
        wall(BoundaryKind::Rule, false, &[(0.0, 0.0)]),
        wall(BoundaryKind::Rule, false, &[(0.0, 0.0), (0.0, 0.0)]),
        wall(BoundaryKind::Rule, true, &[(0.0, 0.0), (10.0, 0.0)]),
        wall(
            BoundaryKind::Rule,
            false,
            &[(0.0, 0.0), (10.0, 0.0), (5.0, 0.0)],
        ),
        wall(
            BoundaryKind::Rule,
            false,
            &[(0.0, 0.0), (10.0, 10.0), (10.0, 0.0), (0.0, 10.0)],
        ),
        wall(BoundaryKind::Rule, false, &[(0.0, f64::NAN), (1.0, 0.0)]),
    ];
    for w in bad {
        assert!(w.defect().is_some(), "{w:?}");
        assert!(Corridor::new(&[w]).is_err());
    }
    // A square, closed; an L; a U: all fine.
    let good = [
        wall(
            BoundaryKind::Solid,
            true,
            &[(0.0, 0.0), (10.0, 0.0), (10.0, 10.0), (0.0, 10.0)],
        ),
        wall(
            BoundaryKind::Solid,
            false,
            &[(0.0, 0.0), (10.0, 0.0), (10.0, 10.0)],
        ),
    ];
    for w in good {
        assert_eq!(w.defect(), None, "{w:?}");
    }
}

/// A reference `PM_FlyMove` built only on `clearance`: contacts found by sub-stepping and bisection, the
/// contact normal from the clearance gradient (central differences) of the segment penetrated, just before
/// contact. Returns (position, velocity).
fn reference_sweep(corridor: &Corridor, pos: Vec2, vel: Vec2, tau: f64) -> (Vec2, Vec2) {
    // Looser than the corridor's tolerance: finite-difference normals are good to about 1e-10.
    const DEEP_UNITS: f64 = 1e-7;
    let clear = |p: Vec2| corridor.clearance_of(p, Some(BoundaryKind::Solid));
    let (mut pos, mut vel, mut time_left) = (pos, vel, tau);
    for _ in 0..strafeopt::geometry::MAX_BUMPS_PER_FRAME {
        if vel == Vec2::ZERO {
            break;
        }
        let delta = vel * time_left;
        let steps = 4000;
        let deep = (1..=steps)
            .map(|i| i as f64 / steps as f64)
            .find(|&t| clear(pos + delta * t) < -DEEP_UNITS);
        let Some(t_deep) = deep else {
            pos += delta;
            break;
        };
        // Bisect for clearance 0 between the last clear sub-step and the first deep one.
        let (mut lo, mut hi) = ((t_deep - 1.0 / steps as f64).max(0.0), t_deep);
        if clear(pos + delta * lo) < 0.0 {
            lo = 0.0;
        }
        for _ in 0..80 {
            let mid = 0.5 * (lo + hi);
            if clear(pos + delta * mid) >= 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let f = lo;
        // The segment penetrated, alone, and its clearance gradient a little way back along the move.
        let hit = corridor
            .nearest(pos + delta * t_deep, Some(BoundaryKind::Solid))
            .unwrap();
        let (a, b) = corridor.walls()[hit.wall].segment(hit.segment);
        let alone =
            Corridor::new(&[wall(BoundaryKind::Solid, false, &[(a.x, a.y), (b.x, b.y)])]).unwrap();
        let back = delta.normalized().unwrap_or(Vec2::ZERO) * -1e-3;
        let probe = pos + delta * f + back;
        let e = 1e-4;
        let g = Vec2::new(
            alone.clearance(probe + v(e, 0.0)) - alone.clearance(probe - v(e, 0.0)),
            alone.clearance(probe + v(0.0, e)) - alone.clearance(probe - v(0.0, e)),
        );
        let n = g.normalized().unwrap_or(Vec2::ZERO);
        pos += delta * f;
        time_left -= time_left * f;
        vel = vel - n * vel.dot(n);
    }
    (pos, vel)
}

#[test]
fn sweep_matches_a_brute_force_reference() {
    let corridor = Corridor::new(&room(BoundaryKind::Solid)).unwrap();
    let mut rng = Lcg(0x5eed_0006);
    let (mut cases, mut agree, mut contacts) = (0, 0, 0);
    while cases < 1500 {
        let pos = v(rng.range(10.0, 390.0), rng.range(10.0, 290.0));
        if corridor.clearance(pos) <= 1e-3 {
            continue;
        }
        let speed = rng.pick(&[2000.0, 8000.0]);
        let vel = Vec2::from_angle(rng.range(0.0, std::f64::consts::TAU)) * speed;
        let r = corridor.sweep(pos, vel, 0.01);
        let (p, w) = reference_sweep(&corridor, pos, vel, 0.01);
        contacts += r.status.contacts();
        if (r.pos - p).length() < 1e-5 && (r.vel - w).length() < 1e-3 {
            agree += 1;
        } else if cases - agree < 40 {
            eprintln!(
                "pos {pos:?} vel {vel:?}: sweep {:?} {:?} {:?} ref {p:?} {w:?}",
                r.pos, r.vel, r.status
            );
        }
        cases += 1;
    }
    assert!(contacts > 300, "only {contacts} contacts");
    // Disagreements can only come from hits exactly on a grown corner, where the normal is a choice.
    eprintln!("{agree} of {cases} agree, {contacts} contacts");
    assert!(agree * 1000 >= cases * 995, "{agree} of {cases} agree");
}
