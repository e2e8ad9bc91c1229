//! What accuracy costs in time: one scene measured at every accuracy level, from the analytic
//! lower bound through the greedy strafer and `solve` at each quality to the engine-exact replay, each
//! with its wall time, frames, game time and gap to the lower bound; beside each solve, the hill-climbing
//! baseline ([`crate::optimise::hillclimb`]) given the same wall time. [`measure_scaling`] runs the same
//! scene at two frame rates. [`write_accuracy_svg`] draws gap against wall time.
//!
//! Nothing here prints or opens files; `strafeopt bench` ([`crate::cli::bench`]) does.
//!
//! Wall times are measured around each call with [`Instant`], on whatever machine runs it: they are
//! measurements, not targets (speed targets live in `benches/`).
//!
//! [`generated`] solves generated scenes and gives the distribution of their results.

use crate::error::{Error, Result};
use crate::geometry::HULL_HALF_WIDTH_UNITS;
use crate::optimise::hillclimb::{hill_climb, HillClimbSettings};
use crate::optimise::{lower_bound, solve, LowerBound, Outcome, Quality, SearchSettings};
use crate::physics::curvature::{bend_arc_radius, speed_for_radius};
use crate::physics::Control;
use crate::scene::Scene;
use crate::sim::controllers::{best_capped_greedy, best_greedy, GREEDY_LOOKAHEADS_UNITS};
use crate::sim::{Crossing, Simulation, Trace};
use serde::Serialize;
use std::time::{Duration, Instant};

pub mod generated;

/// Which part of the table a row belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Section {
    /// One scene at every accuracy level.
    Accuracy,
    /// The same scene solved at two frame rates.
    Scaling,
}

/// How a row's run was made.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// The analytic lower bound (shortest path at the greedy speed profile).
    LowerBound,
    /// The greedy autostrafer, best of its look-aheads.
    Greedy,
    /// `solve` at the row's quality.
    Solve,
    /// Random-mutation hill climbing with the wall time of the solve at the row's quality.
    HillClimb,
    /// The most exact plan replayed in the engine-exact mode (f32 state, anglemod).
    EngineExact,
}

impl Method {
    /// The name printed in tables.
    pub fn name(self) -> &'static str {
        match self {
            Method::LowerBound => "lower bound",
            Method::Greedy => "greedy",
            Method::Solve => "solve",
            Method::HillClimb => "hill climb",
            Method::EngineExact => "engine-exact",
        }
    }
}

/// The name of a quality level.
pub fn quality_name(q: Quality) -> &'static str {
    match q {
        Quality::Fast => "fast",
        Quality::Balanced => "balanced",
        Quality::Exact => "exact",
    }
}

/// One measured row.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BenchRow {
    /// Part of the table.
    pub section: Section,
    /// Scene name.
    pub scene: String,
    /// Frames per second of the scene as run.
    pub fps: f64,
    /// How the run was made.
    pub method: Method,
    /// The solve quality (for hill climbing: whose wall time it was given).
    pub quality: Option<Quality>,
    /// Accuracy rank, cheapest first: 0 lower bound, 1 greedy, 2 fast, 3 balanced, 4 exact, 5 the
    /// engine-exact replay. Rows of a scene come in rank order.
    pub rank: u8,
    /// Wall-clock time of the row's computation, seconds.
    pub wall_seconds: f64,
    /// Frame in which the line is crossed.
    pub frames: Option<u64>,
    /// Fractional crossing time, game seconds.
    pub time: Option<f64>,
    /// Reached the line without breaking a rule (`None` for the bound).
    pub feasible: Option<bool>,
    /// The lower bound's time, game seconds.
    pub bound_time: f64,
    /// `(time - bound_time) / bound_time`.
    pub gap: Option<f64>,
    /// Iterations (SCP sub-steps for solve, mutations for hill climbing).
    pub iterations: Option<u64>,
    /// Evaluations: Clarabel sub-problems for solve, simulations for hill climbing.
    pub evaluations: Option<u64>,
    /// Why it stopped, or other detail.
    pub status: Option<String>,
    /// The radius-speed corner limit of a 90-degree bend (docs/physics.md section 9), ups.
    pub corner_speed_ups: Option<f64>,
    /// Scaling rows after the first: this row's wall time over the first row's.
    pub wall_ratio: Option<f64>,
    /// Scaling rows after the first: this row's frames over the first row's.
    pub frames_ratio: Option<f64>,
}

impl BenchRow {
    fn new(section: Section, scene: &Scene, method: Method, rank: u8, bound_time: f64) -> Self {
        BenchRow {
            section,
            scene: scene.name.clone(),
            fps: scene.vars.fps,
            method,
            quality: None,
            rank,
            wall_seconds: 0.0,
            frames: None,
            time: None,
            feasible: None,
            bound_time,
            gap: None,
            iterations: None,
            evaluations: None,
            status: None,
            corner_speed_ups: None,
            wall_ratio: None,
            frames_ratio: None,
        }
    }

    fn crossing(mut self, c: Option<Crossing>) -> Self {
        self.frames = c.map(|c| c.frames);
        self.time = c.map(|c| c.time);
        self.gap = c.map(|c| (c.time - self.bound_time) / self.bound_time.max(f64::MIN_POSITIVE));
        self
    }
}

/// What to measure.
#[derive(Clone, Debug, PartialEq)]
pub struct BenchSettings {
    /// Solve qualities, cheapest first. Default all three.
    pub levels: Vec<Quality>,
    /// Run the hill-climbing baseline beside each solve. Default true.
    pub hill_climb: bool,
    /// Seed of the hill climber. Default that of [`HillClimbSettings::default`].
    pub seed: u64,
    /// Time limit of each solve. Default none.
    pub time_limit: Option<Duration>,
    /// Most frames planned (see [`SearchSettings::max_frames`]): a scene whose lower bound needs more is
    /// refused before anything is measured, and no run goes further.
    pub max_frames: u64,
}

impl Default for BenchSettings {
    fn default() -> Self {
        BenchSettings {
            levels: vec![Quality::Fast, Quality::Balanced, Quality::Exact],
            hill_climb: true,
            seed: HillClimbSettings::default().seed,
            time_limit: None,
            max_frames: crate::budget::DEFAULT_MAX_PLANNED_FRAMES,
        }
    }
}

/// Rank of a quality level in [`BenchRow::rank`].
fn quality_rank(q: Quality) -> u8 {
    match q {
        Quality::Fast => 2,
        Quality::Balanced => 3,
        Quality::Exact => 4,
    }
}

/// The speeds tried as greedy caps where the greedy speed cannot take a corner: those whose measured turn
/// radius fits the largest arc through bends of these widths for the hull centre (as `solve` seeds).
const CAP_BEND_WIDTHS_UNITS: [f64; 5] = [16.0, 32.0, 64.0, 128.0, 256.0];

/// The radius-speed corner limit of a 90-degree bend `width_units` wide (the hull's width taken off for
/// its centre): the speed whose measured maximum-acceleration radius is the largest arc through it.
/// `None` when no speed up to `sv_maxvelocity` draws that radius or the bend is narrower than the hull.
pub fn corner_speed_ups(scene: &Scene, width_units: f64) -> Option<f64> {
    let centre = width_units - 2.0 * HULL_HALF_WIDTH_UNITS;
    (centre > 0.0)
        .then(|| speed_for_radius(&scene.vars, bend_arc_radius(centre)).ok())
        .flatten()
}

/// Every accuracy level of `scene` (see the module documentation). `bend_width_units`, when the scene is
/// a 90-degree bend, adds the radius-speed corner limit to the lower bound's row. Errors only for a scene
/// with no path; the rows are in rank order.
pub fn measure_scene(
    scene: &Scene,
    bend_width_units: Option<f64>,
    settings: &BenchSettings,
) -> Result<Vec<BenchRow>> {
    let t = Instant::now();
    let bound = lower_bound(scene, &scene.corridor()?)?;
    let scene = &crate::optimise::bound::frame_limited_scene(scene, &bound, settings.max_frames)?;
    let sim = Simulation::new(scene)?;
    let mut rows = vec![lower_bound_row(scene, &bound, bend_width_units, t)];
    let bt = bound.crossing.time;
    let (greedy, greedy_row) = greedy_row(scene, &sim, &bound, bt);
    rows.push(greedy_row);
    let (start, start_seconds) = hill_climb_start(scene, &sim, &bound, greedy);
    let mut last_plan = None;
    for &q in &settings.levels {
        let (row, out) = solve_row(scene, settings, q, bt)?;
        let wall = row.wall_seconds;
        rows.push(row);
        if settings.hill_climb {
            // The same wall time in total: the start's cost plus the climb.
            let budget = Duration::from_secs_f64((wall - start_seconds).max(0.0));
            let climb = (&start, start_seconds, budget);
            rows.push(hill_climb_row(scene, &sim, settings, q, bt, climb));
        }
        last_plan = Some((q, out.controls));
    }
    if let Some((q, controls)) = last_plan {
        rows.push(engine_exact_row(scene, &sim, q, &controls, bt));
    }
    Ok(rows)
}

/// The lower bound's row, timed from `t`, with the corner speed of a bend `bend_width_units` wide.
fn lower_bound_row(
    scene: &Scene,
    bound: &LowerBound,
    bend_width_units: Option<f64>,
    t: Instant,
) -> BenchRow {
    let mut row = BenchRow::new(
        Section::Accuracy,
        scene,
        Method::LowerBound,
        0,
        bound.crossing.time,
    )
    .crossing(Some(bound.crossing));
    row.wall_seconds = t.elapsed().as_secs_f64();
    row.corner_speed_ups = bend_width_units.and_then(|w| corner_speed_ups(scene, w));
    row.status = Some(format!("shortest path {:.1} units", bound.path_length));
    row
}

/// The best greedy run along the shortest path over the look-aheads, and its row (`bt`: the bound's
/// crossing time, seconds).
fn greedy_row(scene: &Scene, sim: &Simulation, bound: &LowerBound, bt: f64) -> (Trace, BenchRow) {
    let t = Instant::now();
    let (greedy, lookahead) = best_greedy(sim, &bound.path, &GREEDY_LOOKAHEADS_UNITS);
    let mut row =
        BenchRow::new(Section::Accuracy, scene, Method::Greedy, 1, bt).crossing(greedy.crossing);
    row.wall_seconds = t.elapsed().as_secs_f64();
    row.feasible = Some(greedy.feasible());
    row.evaluations = Some(GREEDY_LOOKAHEADS_UNITS.len() as u64);
    row.status = Some(format!("look-ahead {lookahead:.0} units"));
    (greedy, row)
}

/// The hill climber's start, and the seconds it took: the same greedy run (capped where a corner needs
/// it) `solve` starts from; on the ground the greedy run itself.
fn hill_climb_start(
    scene: &Scene,
    sim: &Simulation,
    bound: &LowerBound,
    greedy: Trace,
) -> (Trace, f64) {
    let t = Instant::now();
    let start = if scene.effects.is_air_only() {
        let caps: Vec<f64> = CAP_BEND_WIDTHS_UNITS
            .iter()
            .filter_map(|&w| speed_for_radius(&scene.vars, bend_arc_radius(w)).ok())
            .collect();
        best_capped_greedy(sim, &bound.path, &GREEDY_LOOKAHEADS_UNITS, &caps).0
    } else {
        greedy
    };
    (start, t.elapsed().as_secs_f64())
}

/// `solve` at level `q` and its row.
fn solve_row(
    scene: &Scene,
    settings: &BenchSettings,
    q: Quality,
    bt: f64,
) -> Result<(BenchRow, Outcome)> {
    let mut ss = SearchSettings::for_quality(q);
    ss.time_limit = settings.time_limit;
    ss.max_frames = settings.max_frames;
    let t = Instant::now();
    let out = solve(scene, &ss)?;
    let mut row = BenchRow::new(Section::Accuracy, scene, Method::Solve, quality_rank(q), bt)
        .crossing(out.trace.crossing);
    row.quality = Some(q);
    row.wall_seconds = t.elapsed().as_secs_f64();
    row.feasible = Some(out.trace.feasible());
    row.iterations = Some(out.stats.iterations);
    row.evaluations = Some(out.stats.subproblems);
    row.status = Some(format!("{} ({})", out.status, out.source));
    Ok((row, out))
}

/// The hill climber's row beside level `q`: from `climb`'s start (found in its seconds) for its budget.
fn hill_climb_row(
    scene: &Scene,
    sim: &Simulation,
    settings: &BenchSettings,
    q: Quality,
    bt: f64,
    climb: (&Trace, f64, Duration),
) -> BenchRow {
    let (start, start_seconds, budget) = climb;
    let hc = HillClimbSettings::default()
        .with_seed(settings.seed)
        .with_time_budget(budget);
    let h = hill_climb(sim, start, &hc);
    let mut row = BenchRow::new(
        Section::Accuracy,
        scene,
        Method::HillClimb,
        quality_rank(q),
        bt,
    )
    .crossing(h.trace.crossing);
    row.quality = Some(q);
    row.wall_seconds = start_seconds + h.seconds;
    row.feasible = Some(h.trace.feasible());
    row.iterations = Some(h.iterations);
    row.evaluations = Some(h.evaluations);
    let engine_exact = if h.engine_exact.feasible() {
        "valid"
    } else {
        "INVALID"
    };
    row.status = Some(format!(
        "{} accepted; engine-exact {engine_exact}",
        h.accepted
    ));
    row
}

/// The engine-exact replay of level `q`'s plan `controls`, and its row.
fn engine_exact_row(
    scene: &Scene,
    sim: &Simulation,
    q: Quality,
    controls: &[Control],
    bt: f64,
) -> BenchRow {
    let t = Instant::now();
    let run = sim.run_engine_exact(controls);
    let mut row =
        BenchRow::new(Section::Accuracy, scene, Method::EngineExact, 5, bt).crossing(run.crossing);
    row.wall_seconds = t.elapsed().as_secs_f64();
    row.quality = Some(q);
    row.feasible = Some(run.feasible());
    row.status = Some(format!("replay of the {} plan", quality_name(q)));
    row
}

/// `scene` at another frame rate: the same walls, start and finish; the frame cap scaled with the rate.
pub fn scene_at_fps(scene: &Scene, fps: f64) -> Result<Scene> {
    if !(fps.is_finite() && fps > 0.0) {
        return Err(Error::invalid(
            "--scaling-fps",
            fps,
            "a finite number above 0",
        ));
    }
    let mut s = scene.clone();
    s.vars.fps = fps;
    s.vars.validate()?;
    let frames = (scene.max_frames as f64 * fps / scene.vars.fps).ceil();
    s.max_frames = if frames.is_finite() && frames >= 1.0 {
        frames as u64
    } else {
        1
    };
    s.name = format!("{}@{}fps", scene.name, fps);
    Ok(s)
}

/// `scene` solved at `quality` at its own frame rate and at `fps`: two [`Section::Scaling`] rows, the
/// second with the ratios of wall time and frames to the first.
pub fn measure_scaling(
    scene: &Scene,
    fps: f64,
    quality: Quality,
    settings: &BenchSettings,
) -> Result<Vec<BenchRow>> {
    let other = scene_at_fps(scene, fps)?;
    let mut rows: Vec<BenchRow> = Vec::with_capacity(2);
    for s in [scene, &other] {
        let mut ss = SearchSettings::for_quality(quality);
        ss.time_limit = settings.time_limit;
        ss.max_frames = settings.max_frames;
        let t = Instant::now();
        let out = solve(s, &ss)?;
        let wall = t.elapsed().as_secs_f64();
        let mut row = BenchRow::new(
            Section::Scaling,
            s,
            Method::Solve,
            quality_rank(quality),
            out.bound.crossing.time,
        )
        .crossing(out.trace.crossing);
        row.quality = Some(quality);
        row.wall_seconds = wall;
        row.feasible = Some(out.trace.feasible());
        row.iterations = Some(out.stats.iterations);
        row.evaluations = Some(out.stats.subproblems);
        row.status = Some(format!("{} ({})", out.status, out.source));
        if let Some(first) = rows.first() {
            row.wall_ratio = Some(wall / first.wall_seconds.max(f64::MIN_POSITIVE));
            row.frames_ratio = row
                .frames
                .zip(first.frames)
                .map(|(a, b)| a as f64 / (b as f64).max(1.0));
        }
        rows.push(row);
    }
    Ok(rows)
}

/// Draws gap to the lower bound (percent) against wall time (seconds, log scale) for the accuracy rows
/// with a time: one colour per scene, a line through the greedy and solve rows, circles for solve, crosses
/// for hill climbing, a triangle for the engine-exact replay. One `<svg>` element, over any writer.
pub fn write_accuracy_svg(rows: &[BenchRow], w: &mut impl std::io::Write) -> std::io::Result<()> {
    use plotters::prelude::*;
    const COLOURS: [RGBColor; 6] = [
        RGBColor(31, 119, 180),
        RGBColor(214, 39, 40),
        RGBColor(44, 160, 44),
        RGBColor(148, 103, 189),
        RGBColor(255, 127, 14),
        RGBColor(140, 86, 75),
    ];
    let pts: Vec<&BenchRow> = rows
        .iter()
        .filter(|r| r.section == Section::Accuracy && r.method != Method::LowerBound)
        .filter(|r| r.gap.is_some_and(f64::is_finite) && r.wall_seconds.is_finite())
        .collect();
    let mut scenes: Vec<&str> = Vec::new();
    for r in &pts {
        if !scenes.contains(&r.scene.as_str()) {
            scenes.push(&r.scene);
        }
    }
    let floor_s = 1e-4;
    let wall = |r: &BenchRow| r.wall_seconds.max(floor_s);
    let gap_pct = |r: &BenchRow| 100.0 * r.gap.unwrap_or(0.0);
    let x_hi = pts.iter().map(|r| wall(r)).fold(1.0, f64::max) * 2.0;
    let x_lo = pts.iter().map(|r| wall(r)).fold(x_hi, f64::min) / 2.0;
    let y_hi = pts.iter().map(|r| gap_pct(r)).fold(1.0, f64::max) * 1.1;
    let mut out = String::new();
    let drawn = (|| -> std::result::Result<(), Box<dyn std::error::Error>> {
        let root = SVGBackend::with_string(&mut out, (960, 600)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                "Gap to the lower bound against wall time",
                ("sans-serif", 20),
            )
            .margin(12)
            .x_label_area_size(44)
            .y_label_area_size(64)
            .build_cartesian_2d((x_lo..x_hi).log_scale(), 0.0..y_hi)?;
        chart
            .configure_mesh()
            .x_desc("wall time (s, log scale)")
            .y_desc("gap to lower bound (%)")
            .draw()?;
        for (i, scene) in scenes.iter().enumerate() {
            let colour = COLOURS[i % COLOURS.len()];
            let of = |m: Method| {
                pts.iter()
                    .filter(move |r| r.scene == *scene && r.method == m)
                    .map(|r| (wall(r), gap_pct(r)))
            };
            let mut line: Vec<(f64, f64)> = of(Method::Greedy).chain(of(Method::Solve)).collect();
            line.sort_by(|a, b| a.0.total_cmp(&b.0));
            chart
                .draw_series(LineSeries::new(line, colour.stroke_width(2)))?
                .label(scene.to_string())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour));
            chart.draw_series(
                of(Method::Greedy)
                    .chain(of(Method::Solve))
                    .map(|p| Circle::new(p, 5, colour.filled())),
            )?;
            chart.draw_series(
                of(Method::HillClimb).map(|p| Cross::new(p, 6, colour.stroke_width(2))),
            )?;
            chart.draw_series(
                of(Method::EngineExact).map(|p| TriangleMarker::new(p, 7, colour.filled())),
            )?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()?;
        root.present()?;
        Ok(())
    })();
    drawn.map_err(|e| std::io::Error::other(format!("drawing the accuracy figure: {e}")))?;
    w.write_all(out.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bend90() -> Scene {
        let text = include_str!("../scenarios/hl-bend90-100fps.toml");
        Scene::from_toml_str(text, "hl-bend90-100fps.toml").unwrap_or_else(|e| panic!("{e}"))
    }

    #[test]
    fn scene_at_fps_changes_only_the_rate_and_cap() {
        let s = bend90();
        let t = scene_at_fps(&s, 1000.0).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(t.vars.fps, 1000.0);
        assert!((t.frame_time_s() - 0.001).abs() < 1e-15);
        assert_eq!(t.max_frames, s.max_frames * 10);
        assert_eq!(t.walls, s.walls);
        assert_eq!(t.start, s.start);
        assert!(scene_at_fps(&s, 0.0).is_err());
        assert!(scene_at_fps(&s, f64::NAN).is_err());
    }

    #[test]
    fn corner_speed_of_the_bend_matches_calc_bend() {
        // README: `calc bend --width 160 --fps 100` gives 1144.3756 ups.
        let v = corner_speed_ups(&bend90(), 160.0).unwrap_or(f64::NAN);
        assert!((v - 1144.3756).abs() < 1e-3, "{v}");
        assert_eq!(corner_speed_ups(&bend90(), 20.0), None);
    }

    #[test]
    fn the_svg_has_one_series_per_scene() {
        let s = bend90();
        let mut a = BenchRow::new(Section::Accuracy, &s, Method::Greedy, 1, 4.0)
            .crossing(Some(Crossing::new(406, 0.5, 0.01)));
        a.wall_seconds = 0.2;
        let mut b = a.clone();
        b.method = Method::Solve;
        b.wall_seconds = 3.0;
        let mut v = Vec::new();
        let r = write_accuracy_svg(&[a, b], &mut v);
        assert!(r.is_ok());
        let text = String::from_utf8_lossy(&v);
        assert!(text.starts_with("<svg"), "{}", &text[..text.len().min(80)]);
        assert!(text.contains("hl-bend90-100fps"));
    }
}
