//! Reports: writers over any `io::Write` (the command line opens the files). Nothing here computes physics.
//!
//! - trajectories as CSV or JSON ([`write_trajectory_csv`], [`write_trajectory_json`]);
//! - [`html`]: the self-contained HTML report ([`ReportInput`], [`write_html`]) with the SVG figures of
//!   [`figures`];
//! - [`hltas`]: the plan as a Bunnymod XT script ([`write_hltas`]).

pub mod figures;
pub mod hltas;
pub mod html;

pub use self::hltas::{hltas_script, write_hltas};
pub use html::{write_html, ReportInput, ReportRun};

use crate::sim::{FrameRecord, Trace};
use std::io::{self, Write};

/// Column names of a trajectory, in order.
pub const TRAJECTORY_COLUMNS: [&str; 12] = [
    "frame",
    "time",
    "x",
    "y",
    "vx",
    "vy",
    "speed",
    "yaw",
    "theta",
    "on_ground",
    "ducked",
    "clearance",
];

fn records(trace: &Trace) -> impl Iterator<Item = &FrameRecord> {
    std::iter::once(&trace.start).chain(trace.frames.iter())
}

/// Writes one CSV row per frame (frame 0 is the start): frame, time (s), x, y (units), vx, vy, speed
/// (ups), yaw, theta (degrees), on ground, ducked (0/1), clearance (units).
pub fn write_trajectory_csv(trace: &Trace, w: &mut impl Write) -> io::Result<()> {
    writeln!(w, "{}", TRAJECTORY_COLUMNS.join(","))?;
    for r in records(trace) {
        writeln!(
            w,
            "{},{:.6},{:.9},{:.9},{:.9},{:.9},{:.9},{:.6},{:.6},{},{},{:.9}",
            r.frame,
            r.time,
            r.pos.x,
            r.pos.y,
            r.vel.x,
            r.vel.y,
            r.speed,
            r.yaw_rad.to_degrees(),
            r.theta_rad.to_degrees(),
            u8::from(r.on_ground),
            u8::from(r.ducked),
            finite_or(r.clearance, -1.0),
        )?;
    }
    Ok(())
}

/// Writes the trajectory as a JSON array of objects with the CSV's columns.
pub fn write_trajectory_json(trace: &Trace, w: &mut impl Write) -> io::Result<()> {
    let rows: Vec<serde_json::Value> = records(trace)
        .map(|r| {
            serde_json::json!({
                "frame": r.frame,
                "time": r.time,
                "x": r.pos.x,
                "y": r.pos.y,
                "vx": r.vel.x,
                "vy": r.vel.y,
                "speed": r.speed,
                "yaw": r.yaw_rad.to_degrees(),
                "theta": r.theta_rad.to_degrees(),
                "on_ground": r.on_ground,
                "ducked": r.ducked,
                "clearance": r.clearance.is_finite().then_some(r.clearance),
            })
        })
        .collect();
    serde_json::to_writer(&mut *w, &rows).map_err(io::Error::other)?;
    writeln!(w)
}

/// Clearance with no walls is infinite; CSV readers get `-1` meaning "no wall".
fn finite_or(v: f64, otherwise: f64) -> f64 {
    if v.is_finite() {
        v
    } else {
        otherwise
    }
}
