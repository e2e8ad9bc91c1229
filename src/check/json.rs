//! The `check --json` document: one object with every scene's verdict and the summary.
//!
//! ```json
//! {"scenes": [{"path": "scenarios/hl-bend90-100fps.toml", "verdict": "pass", "run": "solve fast",
//!              "seconds": 0.8, "measured": {"frames": 401, "time": 4.0015, "gap_percent": 0.562,
//!              "valid": true, "engine_exact_valid": true, "status": "converged"},
//!              "refusal": null, "failures": [], "message": null, "changes": []}],
//!  "summary": {"scenes": 1, "passed": 1, "failed": 0, "errors": 0, "skipped": 0, "updated": 0},
//!  "seconds": 0.8, "result": "passed"}
//! ```
//!
//! `verdict` is `pass`, `fail`, `error` or `skipped`; each failure is `{"figure", "limit", "actual",
//! "excess", "message"}`; `changes` (with `--update`) `{"key", "old", "new"}`; `result` is `passed`,
//! `regression` or `bad-input`.

use super::{CheckReport, Overall, SceneCheck, Verdict};
use serde_json::{json, Value};
use std::io::Write;

/// The document of a report.
pub fn to_json(report: &CheckReport) -> Value {
    json!({
        "scenes": report.scenes.iter().map(scene_json).collect::<Vec<_>>(),
        "summary": report.summary(),
        "seconds": report.seconds,
        "result": match report.overall() {
            Overall::Passed => "passed",
            Overall::Regression => "regression",
            Overall::BadInput => "bad-input",
        },
    })
}

/// Writes the document (one line).
pub fn write_json(report: &CheckReport, w: &mut impl Write) -> std::io::Result<()> {
    serde_json::to_writer(&mut *w, &to_json(report))?;
    writeln!(w)
}

fn scene_json(c: &SceneCheck) -> Value {
    let (verdict, failures, message) = match &c.verdict {
        Verdict::Pass => ("pass", &[][..], None),
        Verdict::Fail(f) => ("fail", &f[..], None),
        Verdict::Error(m) => ("error", &[][..], Some(m.as_str())),
        Verdict::Skipped(m) => ("skipped", &[][..], Some(m.as_str())),
    };
    json!({
        "path": c.path.display().to_string(),
        "verdict": verdict,
        "run": c.run,
        "seconds": c.seconds,
        "measured": c.measured.as_ref().map(|m| json!({
            "frames": m.frames,
            "time": m.time_s,
            "gap_percent": m.gap_percent,
            "valid": m.valid,
            "engine_exact_valid": m.engine_exact_valid,
            "status": m.status,
        })),
        "refusal": c.refusal,
        "failures": failures.iter().map(|f| json!({
            "figure": f.figure,
            "limit": f.limit,
            "actual": f.actual,
            "excess": f.excess,
            "message": f.message,
        })).collect::<Vec<_>>(),
        "message": message,
        "changes": c.update.as_ref().map_or(Vec::new(), |u| u.changes.iter().map(|ch| json!({
            "key": ch.key,
            "old": ch.old,
            "new": ch.new,
        })).collect()),
    })
}
