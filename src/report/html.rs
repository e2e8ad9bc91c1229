//! The self-contained HTML report: one file, no scripts, no external resources. Five SVG figures drawn
//! by plotters ([`super::figures`]), a table of the runs, the section-9 radius relations at a few speeds,
//! and a table of the summary (the `--json` object).
//!
//! ```no_run
//! # fn demo(scene: &strafeopt::scene::Scene, bound: &strafeopt::optimise::LowerBound,
//! #         greedy: &strafeopt::sim::Trace, optimised: &strafeopt::sim::Trace,
//! #         summary: &serde_json::Value) -> std::io::Result<()> {
//! use strafeopt::report::{write_html, ReportInput};
//! let input = ReportInput::new(scene, bound, summary)
//!     .with_run("greedy", greedy)
//!     .with_run("optimised", optimised);
//! let mut html = Vec::new();
//! write_html(&input, &mut html)?;
//! # Ok(()) }
//! ```

use super::figures::{self, records};
use crate::optimise::LowerBound;
use crate::physics::curvature::max_accel_radii;
use crate::scene::Scene;
use crate::sim::Trace;
use serde_json::Value;
use std::io::{self, Write};

/// Speeds (ups) of the report's section-9 table (those up to the scene's `sv_maxvelocity`).
pub const RADIUS_TABLE_SPEEDS_UPS: [f64; 5] = [320.0, 500.0, 750.0, 1000.0, 2000.0];

/// One run shown in a report: a label (`greedy`, `optimised`) and its trace.
#[derive(Clone, Copy, Debug)]
pub struct ReportRun<'a> {
    /// The label in legends and tables.
    pub label: &'a str,
    /// The run.
    pub trace: &'a Trace,
}

/// Everything a report shows. The runs are drawn in order, each in its own colour (blue, red, green,
/// purple); the first is usually the greedy baseline and the second the optimised plan.
#[derive(Clone, Debug)]
pub struct ReportInput<'a> {
    /// The scene: name, description, walls, finish line, movement variables, effects, start.
    pub scene: &'a Scene,
    /// The runs, in drawing order.
    pub runs: Vec<ReportRun<'a>>,
    /// The lower bound: its shortest path is drawn in the corridor and its speed profile (iterated from
    /// the start speed) beside the runs' speeds.
    pub bound: &'a LowerBound,
    /// The summary (`simulate --json` / `solve --json`), shown as a table of its keys.
    pub summary: &'a Value,
}

impl<'a> ReportInput<'a> {
    /// A report of `scene` with its lower bound and summary, and no runs yet.
    pub fn new(scene: &'a Scene, bound: &'a LowerBound, summary: &'a Value) -> Self {
        ReportInput {
            scene,
            runs: Vec::new(),
            bound,
            summary,
        }
    }

    /// Adds a run labelled `label`.
    pub fn with_run(mut self, label: &'a str, trace: &'a Trace) -> Self {
        self.runs.push(ReportRun { label, trace });
        self
    }
}

/// Element ids of the five figures, in order: corridor, speed, heading and turn rate, clearance, radius.
pub const FIGURE_IDS: [&str; 5] = [
    "figure-corridor",
    "figure-speed",
    "figure-heading",
    "figure-clearance",
    "figure-radius",
];

/// Id of the summary table.
pub const SUMMARY_TABLE_ID: &str = "summary";

/// Writes the report as one HTML document to `w`: the runs table, figures 1-5 (each an inline `<svg>` in
/// a `<figure>` with the ids of [`FIGURE_IDS`]), the section-9 table and the summary table
/// (`<table id="summary">`). Deterministic: the same input gives the same bytes.
///
/// Errors only when `w` fails or plotters cannot draw (an I/O error either way).
pub fn write_html(input: &ReportInput, w: &mut impl Write) -> io::Result<()> {
    let scene = input.scene;
    let title = format!("strafeopt report: {}", scene.name);
    writeln!(w, "<!DOCTYPE html>")?;
    writeln!(w, "<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">")?;
    writeln!(w, "<title>{}</title>", escape(&title))?;
    writeln!(w, "<style>{STYLE}</style>\n</head>\n<body>")?;
    writeln!(w, "<h1>{}</h1>", escape(&title))?;
    if !scene.description.is_empty() {
        writeln!(
            w,
            "<p class=\"description\">{}</p>",
            escape(&scene.description)
        )?;
    }
    writeln!(
        w,
        "<p>{} at {} fps (frame time {} s), effects: {}.</p>",
        scene.preset.name(),
        fmt_num(scene.vars.fps),
        fmt_num(scene.frame_time_s()),
        escape(&scene.effects.to_string()),
    )?;

    write_runs_table(input, w)?;

    for (id, svg, caption) in captioned_figures(input) {
        let svg = svg?;
        writeln!(
            w,
            "<figure id=\"{id}\">\n{svg}\n<figcaption>{}</figcaption>\n</figure>",
            escape(&caption)
        )?;
    }

    write_radius_table(input, w)?;

    writeln!(w, "<h2>Summary</h2>")?;
    writeln!(
        w,
        "<table id=\"{SUMMARY_TABLE_ID}\">\n<tr><th>key</th><th>value</th></tr>"
    )?;
    for (key, value) in flatten_json(input.summary) {
        writeln!(
            w,
            "<tr><td>{}</td><td>{}</td></tr>",
            escape(&key),
            escape(&value)
        )?;
    }
    writeln!(w, "</table>\n</body>\n</html>")
}

/// The five figures in order, each with its element id (from [`FIGURE_IDS`]) and its caption.
fn captioned_figures(input: &ReportInput) -> [(&'static str, io::Result<String>, String); 5] {
    [
        (
            FIGURE_IDS[0],
            figures::corridor_svg(input),
            "Figure 1. The corridor (to scale unless the title says the y axis is stretched): solid walls in black, rule lines dashed orange, the finish \
             line green, the lower bound's shortest path dashed grey; each run's path with the 32 x 32 hull \
             at a few frames, and its first rule violation or wall contact marked in red."
                .to_string(),
        ),
        (
            FIGURE_IDS[1],
            figures::speed_svg(input),
            format!(
                "Figure 2. Speed against time. The grey dashed curve is the lower bound's speed profile: \
                 the largest speed any control sequence can have after each frame (docs/physics.md section 6); \
                 the vertical lines mark the crossings (lower bound at {:.4} s).",
                input.bound.crossing.time
            ),
        ),
        (
            FIGURE_IDS[2],
            figures::heading_svg(input),
            format!(
                "Figure 3. Where each run is heading: the direction of the velocity (top, degrees \
                 anticlockwise from +x, continuous through half turns) and how fast it turns (bottom, \
                 degrees per second, positive to the left), averaged over {} frames so that a run which \
                 changes sides every frame reads as its mean turn.",
                figures::TURN_RATE_WINDOW_FRAMES
            ),
        ),
        (
            FIGURE_IDS[3],
            figures::clearance_svg(input),
            "Figure 4. Clearance of the 32 x 32 hull to the nearest wall or rule line along each run, \
             units (negative: overlapping), with each run's smallest clearance marked."
                .to_string(),
        ),
        (
            FIGURE_IDS[4],
            figures::radius_svg(input),
            "Figure 5. The radius of the circle through each position and its neighbours, against speed. \
             The curves are maximum-acceleration airstrafing at these settings: the source text's relation \
             (dashed) gives about twice the radius the game draws; the first-order radius (solid) is the \
             one corners are planned with (docs/physics.md section 9)."
                .to_string(),
        ),
    ]
}

const STYLE: &str = "body{font-family:sans-serif;margin:2em;max-width:1000px;color:#222}\
table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;padding:3px 8px;text-align:left}\
th{background:#eee}figure{margin:2em 0}figcaption{font-size:90%;color:#444;max-width:960px}\
code{background:#f3f3f3}";

fn write_runs_table(input: &ReportInput, w: &mut impl Write) -> io::Result<()> {
    writeln!(w, "<h2>Runs</h2>\n<table id=\"runs\">")?;
    writeln!(
        w,
        "<tr><th>run</th><th>controller</th><th>frames</th><th>time (s)</th><th>valid</th>\
         <th>first rule violation</th><th>first wall contact</th><th>final speed (ups)</th>\
         <th>min clearance (units)</th><th>gap to bound</th></tr>"
    )?;
    let lb = input.bound.crossing.time;
    for run in &input.runs {
        let t = run.trace;
        let frames = t.crossing.map_or(t.frames.len() as u64, |c| c.frames);
        let time = t
            .crossing
            .map_or("not reached".to_string(), |c| format!("{:.6}", c.time));
        let gap = t.crossing.map_or("-".to_string(), |c| {
            format!("{:+.3}%", 100.0 * (c.time - lb) / lb.max(f64::MIN_POSITIVE))
        });
        let frame_or_dash = |f: Option<u64>| f.map_or("-".to_string(), |f| f.to_string());
        let clearance = t.min_clearance();
        writeln!(
            w,
            "<tr><td>{}</td><td>{}</td><td>{frames}</td><td>{time}</td><td>{}</td><td>{}</td><td>{}</td>\
             <td>{:.4}</td><td>{}</td><td>{gap}</td></tr>",
            escape(run.label),
            escape(&t.controller),
            if t.feasible() { "yes" } else { "no" },
            frame_or_dash(t.first_rule_violation()),
            frame_or_dash(t.first_contact()),
            t.final_speed(),
            if clearance.is_finite() {
                format!("{clearance:.6}")
            } else {
                "no walls".to_string()
            },
        )?;
    }
    writeln!(
        w,
        "<tr><td>lower bound</td><td>greedy speed profile over the shortest path</td><td>{}</td>\
         <td>{:.6}</td><td>-</td><td>-</td><td>-</td><td>-</td><td>-</td><td>-</td></tr>\n</table>",
        input.bound.crossing.frames, lb
    )?;
    writeln!(
        w,
        "<p>Shortest path of the hull centre: {:.4} units. Frames per run (start included): {}.</p>",
        input.bound.path_length,
        input
            .runs
            .iter()
            .map(|r| format!("{} {}", escape(r.label), records(r.trace).count()))
            .collect::<Vec<_>>()
            .join(", ")
    )
}

fn write_radius_table(input: &ReportInput, w: &mut impl Write) -> io::Result<()> {
    let vars = &input.scene.vars;
    writeln!(
        w,
        "<h2>The radius-speed relation (docs/physics.md section 9)</h2>\n<p>Maximum-acceleration airstrafing at \
         {} fps: the source text's relation against the radius the game draws.</p>\n<table id=\"radii\">\n\
         <tr><th>speed (ups)</th><th>theta (deg)</th><th>source text's relation</th><th>first order</th>\
         <th>circle through 3 simulated positions</th><th>relation / measured</th></tr>",
        fmt_num(vars.fps)
    )?;
    for v in RADIUS_TABLE_SPEEDS_UPS
        .into_iter()
        .filter(|&v| v <= vars.maxvelocity)
    {
        let r = max_accel_radii(vars, v);
        writeln!(
            w,
            "<tr><td>{v:.0}</td><td>{:.3}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            r.theta_rad.to_degrees(),
            fmt_radius(r.source_text),
            fmt_radius(r.first_order),
            fmt_radius(r.measured),
            if r.source_text.is_finite() && r.measured.is_finite() && r.measured > 0.0 {
                format!("{:.3}", r.source_text / r.measured)
            } else {
                "-".to_string()
            }
        )?;
    }
    writeln!(w, "</table>")
}

fn fmt_radius(r: f64) -> String {
    if r.is_finite() {
        format!("{r:.4}")
    } else {
        "straight".to_string()
    }
}

/// A number in its shortest form (`100`, `0.01`).
fn fmt_num(v: f64) -> String {
    format!("{v}")
}

/// The summary's leaves as `(dotted key, text)` rows, in key order (`lower_bound.time`); arrays of numbers
/// or strings are joined with commas, other arrays indexed (`plans.0.label`).
pub fn flatten_json(v: &Value) -> Vec<(String, String)> {
    let mut out = Vec::new();
    flatten_into(v, String::new(), &mut out);
    out
}

fn flatten_into(v: &Value, key: String, out: &mut Vec<(String, String)>) {
    match v {
        Value::Object(map) => {
            for (k, child) in map {
                let k = if key.is_empty() {
                    k.clone()
                } else {
                    format!("{key}.{k}")
                };
                flatten_into(child, k, out);
            }
        }
        Value::Array(items) if items.iter().all(|i| !i.is_object() && !i.is_array()) => {
            let text = items.iter().map(leaf_text).collect::<Vec<_>>().join(", ");
            out.push((key, text));
        }
        Value::Array(items) => {
            // Long arrays of objects (embedded plans) would swamp the table: show their length only.
            if items.len() > 20 {
                out.push((key, format!("({} entries)", items.len())));
            } else {
                for (i, child) in items.iter().enumerate() {
                    flatten_into(child, format!("{key}.{i}"), out);
                }
            }
        }
        leaf => out.push((key, leaf_text(leaf))),
    }
}

fn leaf_text(v: &Value) -> String {
    match v {
        Value::Null => "-".to_string(),
        Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// `text` with `& < > " '` escaped for HTML.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn escaping_and_flattening() {
        assert_eq!(escape("<a & 'b'>"), "&lt;a &amp; &#39;b&#39;&gt;");
        let rows = flatten_json(&json!({"a": 1, "b": {"c": null, "d": [1, 2]}, "e": "x"}));
        assert_eq!(
            rows,
            vec![
                ("a".to_string(), "1".to_string()),
                ("b.c".to_string(), "-".to_string()),
                ("b.d".to_string(), "1, 2".to_string()),
                ("e".to_string(), "x".to_string()),
            ]
        );
    }
}
