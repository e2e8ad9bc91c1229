//! `solve` on generated scenes ([`crate::scene::generate`]): one [`SceneRecord`] per scene, and the
//! distribution (min, median, 90th percentile, max) of each named [`Column`] over the records. A column is
//! a name and a function of a record; adding one to [`columns`] is one line.
//!
//! Wall times are measured around each solve with [`Instant`]: measurements, not targets.

use crate::geometry::BoundaryKind;
use crate::optimise::{solve, SearchSettings, StageSeconds};
use crate::scene::generate::{GeneratedScene, SceneKind};
use serde::Serialize;
use std::time::Instant;

/// One generated scene solved.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SceneRecord {
    /// Scene name, `gen-SEED-INDEX`.
    pub scene: String,
    /// Turns of the corridor.
    pub corners: usize,
    /// Corridor width, units.
    pub width_units: u32,
    /// Frame rate, fps.
    pub fps: u32,
    /// `sv_airaccelerate`.
    pub airaccelerate: u32,
    /// Start speed, ups.
    pub start_speed_ups: u32,
    /// Wall kind.
    pub walls: BoundaryKind,
    /// Scene kind (airborne, groundstrafing, bunnyhopping, Half-Life 2).
    pub kind: SceneKind,
    /// The plan's crossing frame.
    pub frames: Option<u64>,
    /// The plan's crossing time, game seconds.
    pub time_s: Option<f64>,
    /// The plan reaches the line without breaking a rule.
    pub valid: bool,
    /// The plan is also valid in the engine-exact mode.
    pub engine_exact_valid: bool,
    /// The greedy baseline's crossing frame (valid or not).
    pub greedy_frames: Option<u64>,
    /// The greedy baseline reached the line without breaking a rule.
    pub greedy_valid: bool,
    /// The lower bound's crossing frame.
    pub bound_frames: Option<u64>,
    /// The lower bound's time, game seconds.
    pub bound_time_s: Option<f64>,
    /// Greedy frames less the plan's, when both are valid.
    pub frames_gained: Option<i64>,
    /// `(time - bound) / bound`, percent, for a valid plan.
    pub gap_pct: Option<f64>,
    /// Wall-clock time of the solve, seconds.
    pub solve_seconds: f64,
    /// Solve wall time per frame of the plan, milliseconds.
    pub solve_ms_per_frame: Option<f64>,
    /// Where the solve's time went, seconds per stage (`solve`'s `stage_seconds`).
    pub stage_seconds: Option<StageSeconds>,
    /// The relaxed certificate's crossing frame and time, seconds.
    pub relaxed_frames: Option<u64>,
    /// The relaxed certificate's crossing time, game seconds.
    pub relaxed_time_s: Option<f64>,
    /// The spread of the certificate's optimum over its starts that ended at their local optimum, seconds.
    pub relaxed_spread_s: Option<f64>,
    /// The certificate's starts that reached the line but stopped short of their local optimum.
    pub relaxed_short_starts: Option<usize>,
    /// The plan's time less the relaxed optimum's, frames, for a valid plan.
    pub rounding_loss_frames: Option<f64>,
    /// The certificate's estimate of the zigzag of alternating sides, frames.
    pub zigzag_frames: Option<f64>,
    /// The certificate's estimate of the guard under the law's kink, frames.
    pub guard_frames: Option<f64>,
    /// How much of its crossing frame the relaxed optimum leaves, frames: a plan that loses more crosses
    /// a frame later.
    pub relaxed_frame_left: Option<f64>,
    /// Exact-side plans replayed as the game plays them, and how many of those were valid (`solve`'s
    /// `stats.replays`, `stats.valid_replays`).
    pub replays: u64,
    /// See [`SceneRecord::replays`].
    pub valid_replays: u64,
    /// The share of the solve's sub-problems the frame-by-frame solver gave no solution for, handed to
    /// Clarabel, percent (`solve`'s `stats.handed_to_clarabel` over `stats.subproblems`); `None` where
    /// there were none.
    pub handed_to_clarabel_pct: Option<f64>,
    /// The greedy guide that gave the baseline.
    pub greedy_guide: String,
    /// `solve`'s status and the plan's source, or the error.
    pub status: String,
}

impl SceneRecord {
    fn new(g: &GeneratedScene) -> Self {
        let d = &g.drawn;
        SceneRecord {
            scene: g.name.clone(),
            corners: d.turns.len(),
            width_units: d.width_units,
            fps: d.fps,
            airaccelerate: d.airaccelerate,
            start_speed_ups: d.start_speed_ups,
            walls: d.walls,
            kind: d.kind,
            frames: None,
            time_s: None,
            valid: false,
            engine_exact_valid: false,
            greedy_frames: None,
            greedy_valid: false,
            bound_frames: None,
            bound_time_s: None,
            frames_gained: None,
            gap_pct: None,
            solve_seconds: 0.0,
            solve_ms_per_frame: None,
            stage_seconds: None,
            relaxed_frames: None,
            relaxed_time_s: None,
            relaxed_spread_s: None,
            relaxed_short_starts: None,
            rounding_loss_frames: None,
            zigzag_frames: None,
            guard_frames: None,
            relaxed_frame_left: None,
            replays: 0,
            valid_replays: 0,
            handed_to_clarabel_pct: None,
            greedy_guide: String::new(),
            status: String::new(),
        }
    }
}

impl SceneRecord {
    /// The share of the solve's time that `stage` took, percent, on an airborne scene (a scene with
    /// jumps or ground frames runs other stages).
    fn stage_share(&self, stage: fn(&StageSeconds) -> f64) -> Option<f64> {
        let seconds = self.stage_seconds.filter(|_| self.kind == SceneKind::Air)?;
        (self.solve_seconds > 0.0).then(|| 100.0 * stage(&seconds) / self.solve_seconds)
    }
}

/// Solves `g` with `settings` and records the outcome; a solve that fails is
/// a record with its error as the status, not an error.
pub fn measure_generated_scene(g: &GeneratedScene, settings: &SearchSettings) -> SceneRecord {
    let mut r = SceneRecord::new(g);
    let started = Instant::now();
    let outcome = solve(&g.scene, settings);
    r.solve_seconds = started.elapsed().as_secs_f64();
    let out = match outcome {
        Ok(out) => out,
        Err(e) => {
            r.status = format!("error: {e}");
            return r;
        }
    };
    r.frames = out.trace.crossing.map(|c| c.frames);
    r.time_s = out.trace.crossing.map(|c| c.time);
    r.valid = out.trace.feasible();
    r.engine_exact_valid = out.engine_exact.feasible();
    r.greedy_frames = out.greedy.crossing.map(|c| c.frames);
    r.greedy_valid = out.greedy.feasible();
    r.bound_frames = Some(out.bound.crossing.frames);
    r.bound_time_s = Some(out.bound.crossing.time);
    if r.valid {
        let bound = out.bound.crossing.time;
        r.gap_pct = r
            .time_s
            .map(|t| 100.0 * (t - bound) / bound.max(f64::MIN_POSITIVE));
        if r.greedy_valid {
            r.frames_gained = r
                .greedy_frames
                .zip(r.frames)
                .map(|(g, p)| g as i64 - p as i64);
        }
    }
    r.solve_ms_per_frame = r
        .frames
        .filter(|&f| f > 0)
        .map(|f| 1000.0 * r.solve_seconds / f as f64);
    r.stage_seconds = Some(out.stage_seconds);
    r.replays = out.stats.replays;
    r.valid_replays = out.stats.valid_replays;
    r.handed_to_clarabel_pct = (out.stats.subproblems > 0)
        .then(|| 100.0 * out.stats.handed_to_clarabel as f64 / out.stats.subproblems as f64);
    r.greedy_guide = out.greedy_guide.to_string();
    if let Some(c) = out.relaxed {
        r.relaxed_frames = Some(c.frames);
        r.relaxed_time_s = Some(c.time);
        r.relaxed_spread_s = Some(c.spread);
        r.relaxed_short_starts = Some(c.short);
        r.zigzag_frames = c.zigzag_frames;
        r.guard_frames = c.guard_frames;
        let tau = g.scene.frame_time_s();
        r.relaxed_frame_left = Some(c.frame_left(tau));
        if r.valid {
            r.rounding_loss_frames = r.time_s.map(|t| c.loss_frames(t, tau));
        }
    }
    r.status = format!("{} ({})", out.status, out.source);
    r
}

/// [`measure_generated_scene`] on each scene in turn, calling `progress` with each record.
pub fn measure_generated(
    scenes: &[GeneratedScene],
    settings: &SearchSettings,
    progress: &mut dyn FnMut(usize, &SceneRecord),
) -> Vec<SceneRecord> {
    scenes
        .iter()
        .enumerate()
        .map(|(i, g)| {
            let r = measure_generated_scene(g, settings);
            progress(i, &r);
            r
        })
        .collect()
}

/// A named figure of a record; `None` where the record has none (an invalid plan has no gap).
#[derive(Clone, Copy, Debug)]
pub struct Column {
    /// The name printed, with its unit.
    pub name: &'static str,
    /// The figure.
    pub value: fn(&SceneRecord) -> Option<f64>,
}

/// The columns of the distribution table, in order.
pub fn columns() -> Vec<Column> {
    vec![
        Column {
            name: "frames gained on greedy",
            value: |r| r.frames_gained.map(|f| f as f64),
        },
        Column {
            name: "gap to bound (%)",
            value: |r| r.gap_pct,
        },
        Column {
            name: "rounding loss (frames)",
            value: |r| r.rounding_loss_frames,
        },
        Column {
            name: "rounding loss beyond zigzag and guard",
            value: |r| Some(r.rounding_loss_frames? - r.estimated_loss_frames()?),
        },
        Column {
            name: "plan frame less relaxed frame",
            value: |r| {
                r.frames
                    .zip(r.relaxed_frames)
                    .map(|(p, q)| p as f64 - q as f64)
            },
        },
        Column {
            name: "relaxed spread over starts (ms)",
            value: |r| r.relaxed_spread_s.map(|s| 1000.0 * s),
        },
        Column {
            name: "starts short of their optimum",
            value: |r| r.relaxed_short_starts.map(|k| k as f64),
        },
        Column {
            name: "solve time per frame (ms)",
            value: |r| r.solve_ms_per_frame,
        },
        Column {
            name: "solve time (s)",
            value: |r| Some(r.solve_seconds),
        },
        Column {
            name: "sub-problems handed to Clarabel (%)",
            value: |r| r.handed_to_clarabel_pct,
        },
        Column {
            name: "share in the baseline (%)",
            value: |r| r.stage_share(|s| s.baseline),
        },
        Column {
            name: "share in the relaxed line (%)",
            value: |r| r.stage_share(|s| s.relaxed_line),
        },
        Column {
            name: "share in the first plans (%)",
            value: |r| r.stage_share(|s| s.first_plans),
        },
        Column {
            name: "share waiting for the certificate (%)",
            value: |r| r.stage_share(|s| s.certificate_wait),
        },
        Column {
            name: "share in the certificate's lines (%)",
            value: |r| r.stage_share(|s| s.certificate_lines),
        },
        Column {
            name: "share in the polish on (%)",
            value: |r| r.stage_share(|s| s.polish_on),
        },
        Column {
            name: "share in the final-margin round (%)",
            value: |r| r.stage_share(|s| s.final_margin_round),
        },
        Column {
            name: "share in the fine polish (%)",
            value: |r| r.stage_share(|s| s.fine_polish),
        },
    ]
}

/// The distribution of one column over the records that have it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Distribution {
    /// The column's name.
    pub column: &'static str,
    /// Records with a value.
    pub count: usize,
    /// Smallest value.
    pub min: Option<f64>,
    /// Median ([`quantile`] 0.5).
    pub median: Option<f64>,
    /// 90th percentile ([`quantile`] 0.9).
    pub p90: Option<f64>,
    /// Largest value.
    pub max: Option<f64>,
}

/// The `q` quantile of ascending `sorted` values by linear interpolation between closest ranks
/// (`sorted[(n - 1) q]`, interpolated; numpy's default); `None` when empty.
pub fn quantile(sorted: &[f64], q: f64) -> Option<f64> {
    let last = sorted.len().checked_sub(1)?;
    let at = last as f64 * q.clamp(0.0, 1.0);
    let lo = at.floor() as usize;
    let hi = at.ceil() as usize;
    let (a, b) = (sorted[lo], sorted[hi.min(last)]);
    Some(a + (b - a) * (at - lo as f64))
}

/// The distribution of each column over `records`.
pub fn distributions(records: &[SceneRecord], columns: &[Column]) -> Vec<Distribution> {
    columns
        .iter()
        .map(|c| {
            let mut v: Vec<f64> = records
                .iter()
                .filter_map(c.value)
                .filter(|x| x.is_finite())
                .collect();
            v.sort_by(f64::total_cmp);
            Distribution {
                column: c.name,
                count: v.len(),
                min: v.first().copied(),
                median: quantile(&v, 0.5),
                p90: quantile(&v, 0.9),
                max: v.last().copied(),
            }
        })
        .collect()
}

impl SceneRecord {
    /// The valid plan's crossing frame less its relaxed optimum's (`None`: no valid plan or no
    /// certificate): 0 in its frame, negative for a plan ahead of it (one that touches a wall, or a
    /// local relaxed optimum).
    pub fn frames_behind_relaxed(&self) -> Option<i64> {
        let (plan, relaxed) = (self.frames?, self.relaxed_frames?);
        self.valid.then_some(plan as i64 - relaxed as i64)
    }

    /// Whether the certificate's estimates of the zigzag and the guard alone take more than its frame
    /// leaves ([`SceneRecord::relaxed_frame_left`]): then no plan near those estimates crosses in it.
    pub fn estimates_pass_the_relaxed_frame(&self) -> Option<bool> {
        Some(self.estimated_loss_frames()? > self.relaxed_frame_left?)
    }

    /// The certificate's estimates of the zigzag and the guard together, frames.
    fn estimated_loss_frames(&self) -> Option<f64> {
        Some(self.zigzag_frames? + self.guard_frames?)
    }
}

/// Records for which `pred` holds, and all records.
pub fn share(records: &[SceneRecord], pred: impl Fn(&SceneRecord) -> bool) -> (usize, usize) {
    (records.iter().filter(|r| pred(r)).count(), records.len())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_interpolate_between_ranks() {
        let v = [1.0, 2.0, 3.0, 4.0];
        assert_eq!(quantile(&v, 0.5), Some(2.5));
        assert_eq!(quantile(&v, 0.0), Some(1.0));
        assert_eq!(quantile(&v, 1.0), Some(4.0));
        // (n - 1) 0.9 = 2.7: 3 + 0.7 (4 - 3).
        assert!((quantile(&v, 0.9).unwrap_or(f64::NAN) - 3.7).abs() < 1e-12);
        assert_eq!(quantile(&[5.0], 0.9), Some(5.0));
        assert_eq!(quantile(&[], 0.5), None);
    }

    /// A valid plan of 100 frames at 100 fps, `gained` frames on greedy, solved in `seconds`; no
    /// certificate.
    fn record(gained: Option<i64>, seconds: f64) -> SceneRecord {
        SceneRecord {
            scene: "s".to_string(),
            corners: 1,
            width_units: 64,
            fps: 100,
            airaccelerate: 10,
            start_speed_ups: 0,
            walls: BoundaryKind::Rule,
            kind: SceneKind::Air,
            frames: Some(100),
            time_s: Some(1.0),
            valid: true,
            engine_exact_valid: true,
            greedy_frames: None,
            greedy_valid: gained.is_some(),
            bound_frames: Some(99),
            bound_time_s: Some(0.99),
            frames_gained: gained,
            gap_pct: Some(1.0),
            solve_seconds: seconds,
            solve_ms_per_frame: Some(10.0 * seconds),
            stage_seconds: None,
            relaxed_frames: None,
            relaxed_time_s: None,
            relaxed_spread_s: None,
            relaxed_short_starts: None,
            rounding_loss_frames: None,
            zigzag_frames: None,
            guard_frames: None,
            relaxed_frame_left: None,
            replays: 0,
            valid_replays: 0,
            handed_to_clarabel_pct: None,
            greedy_guide: String::new(),
            status: String::new(),
        }
    }

    #[test]
    fn a_stages_share_is_of_the_solve_and_only_on_airborne_scenes() {
        let seconds = StageSeconds {
            relaxed_line: 1.0,
            first_plans: 0.5,
            ..StageSeconds::default()
        };
        let airborne = SceneRecord {
            stage_seconds: Some(seconds),
            ..record(None, 4.0)
        };
        let shares = |r: &SceneRecord| {
            let stages: [fn(&StageSeconds) -> f64; 2] = [|s| s.relaxed_line, |s| s.first_plans];
            stages.map(|f| r.stage_share(f))
        };
        assert_eq!(shares(&airborne), [Some(25.0), Some(12.5)]);
        // A bunnyhop's stages are others; a record without its stages (a failed solve) has none.
        let jumping = SceneRecord {
            kind: SceneKind::Bhop,
            ..airborne.clone()
        };
        assert_eq!(shares(&jumping), [None, None]);
        assert_eq!(shares(&record(None, 4.0)), [None, None]);
    }

    #[test]
    fn distributions_skip_records_without_the_figure() {
        let records = [
            record(Some(3), 1.0),
            record(None, 2.0),
            record(Some(9), 3.0),
        ];
        let d = distributions(&records, &columns());
        assert_eq!(d[0].column, "frames gained on greedy");
        assert_eq!(d[0].count, 2);
        assert_eq!(
            (d[0].min, d[0].median, d[0].max),
            (Some(3.0), Some(6.0), Some(9.0))
        );
        let time = d.iter().find(|c| c.column == "solve time (s)");
        assert_eq!(time.map(|c| (c.count, c.median)), Some((3, Some(2.0))));
        assert_eq!(share(&records, |r| r.greedy_valid), (2, 3));
    }

    #[test]
    fn a_plan_behind_its_relaxed_frame_says_whether_the_estimates_alone_pass_that_frame() {
        // The 90-degree bend at 100 fps: the relaxed optimum leaves 0.035 of frame 400, the zigzag
        // takes about 0.124, and the plan crosses in frame 401.
        let behind = SceneRecord {
            frames: Some(401),
            relaxed_frames: Some(400),
            relaxed_frame_left: Some(0.035),
            zigzag_frames: Some(0.124),
            guard_frames: Some(0.0),
            ..record(Some(1), 1.0)
        };
        assert_eq!(behind.frames_behind_relaxed(), Some(1));
        assert_eq!(behind.estimates_pass_the_relaxed_frame(), Some(true));
        // The same estimates with half a frame left, the plan in that frame.
        let in_frame = SceneRecord {
            frames: Some(400),
            relaxed_frame_left: Some(0.5),
            ..behind.clone()
        };
        assert_eq!(in_frame.frames_behind_relaxed(), Some(0));
        assert_eq!(in_frame.estimates_pass_the_relaxed_frame(), Some(false));
        // No certificate, or no valid plan: nothing to say.
        assert_eq!(record(None, 1.0).frames_behind_relaxed(), None);
        let invalid = SceneRecord {
            valid: false,
            ..behind
        };
        assert_eq!(invalid.frames_behind_relaxed(), None);
    }
}
