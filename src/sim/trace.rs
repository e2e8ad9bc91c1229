//! The record of a run: per-frame states and the summary figures every report prints.

use crate::physics::{Control, PlayerState, Vec2};
use serde::Serialize;

/// When a run (or the bound) crosses the line: in frame `frames` (1-based), `fraction` of the way through
/// it (the move is linear within a frame), at `time = (frames - 1 + fraction) tau` seconds.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Crossing {
    /// The frame in which the line is crossed (1-based).
    pub frames: u64,
    /// How far through that frame, in `[0, 1]`.
    pub fraction: f64,
    /// Fractional crossing time, seconds.
    pub time: f64,
}

impl Crossing {
    /// The crossing in frame `frames` at `fraction` for frame time `tau_s`.
    pub fn new(frames: u64, fraction: f64, tau_s: f64) -> Self {
        Crossing {
            frames,
            fraction,
            time: ((frames as f64) - 1.0 + fraction) * tau_s,
        }
    }
}

/// The state after one frame, for trajectories and reports.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FrameRecord {
    /// Frame number (1-based; 0 is the start).
    pub frame: u64,
    /// Time at the end of the frame, seconds.
    pub time: f64,
    /// Hull centre, units.
    pub pos: Vec2,
    /// Horizontal velocity, ups.
    pub vel: Vec2,
    /// Horizontal speed, ups.
    pub speed: f64,
    /// View yaw of the frame's control, radians.
    pub yaw_rad: f64,
    /// Strafe angle between the velocity before the frame and the wish direction, radians.
    pub theta_rad: f64,
    /// On the ground after the frame.
    pub on_ground: bool,
    /// Ducked after the frame.
    pub ducked: bool,
    /// Clearance to the nearest wall after the frame, units (negative: overlapping).
    pub clearance: f64,
    /// Wall contacts during the frame.
    pub contacts: u32,
    /// The frame's move crossed into a rule boundary.
    pub broke_rule: bool,
}

/// A whole run.
#[derive(Clone, Debug, PartialEq)]
pub struct Trace {
    /// The controller's name.
    pub controller: String,
    /// The record at frame 0.
    pub start: FrameRecord,
    /// One record per frame.
    pub frames: Vec<FrameRecord>,
    /// The controls played.
    pub controls: Vec<Control>,
    /// The finish crossing, if the line was reached.
    pub crossing: Option<Crossing>,
    /// A state became NaN or infinite (the run stopped there).
    pub numerical_failure: bool,
    /// The budget (time limit or cancellation) ran out before the run ended.
    pub interrupted: bool,
}

impl Trace {
    pub(crate) fn new(controller: String, s: &PlayerState, clearance: f64) -> Self {
        Trace {
            controller,
            start: FrameRecord {
                frame: 0,
                time: 0.0,
                pos: s.pos,
                vel: s.vel,
                speed: s.speed(),
                yaw_rad: s.vel.angle(),
                theta_rad: 0.0,
                on_ground: s.on_ground,
                ducked: s.ducked,
                clearance,
                contacts: 0,
                broke_rule: false,
            },
            frames: Vec::new(),
            controls: Vec::new(),
            crossing: None,
            numerical_failure: false,
            interrupted: false,
        }
    }

    pub(crate) fn push(&mut self, r: FrameRecord, c: Control) {
        self.frames.push(r);
        self.controls.push(c);
    }

    /// Smallest clearance over the start and every frame end, units.
    pub fn min_clearance(&self) -> f64 {
        self.frames
            .iter()
            .map(|f| f.clearance)
            .fold(self.start.clearance, f64::min)
    }

    /// Total wall contacts.
    pub fn collisions(&self) -> u32 {
        self.frames.iter().map(|f| f.contacts).sum()
    }

    /// The first frame with a wall contact.
    pub fn first_contact(&self) -> Option<u64> {
        self.frames.iter().find(|f| f.contacts > 0).map(|f| f.frame)
    }

    /// The first frame whose move crossed into a rule boundary.
    pub fn first_rule_violation(&self) -> Option<u64> {
        self.frames.iter().find(|f| f.broke_rule).map(|f| f.frame)
    }

    /// True when the line was crossed, no rule was broken and every state stayed finite.
    pub fn feasible(&self) -> bool {
        self.crossing.is_some() && self.first_rule_violation().is_none() && !self.numerical_failure
    }

    /// Speed after the last frame, ups.
    pub fn final_speed(&self) -> f64 {
        self.frames.last().map_or(self.start.speed, |f| f.speed)
    }
}
