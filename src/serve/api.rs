//! The routes: the page, the scene to start from, solving an edit, progress, and the downloads of the last
//! valid result. Every answer to the page is JSON with a `status`; no input panics a handler.

use super::http::{Request, Response};
use super::worker::{quality_name, Answer, SolveJob, Solved, Solver};
use crate::error::Error;
use crate::optimise::{Quality, SearchSettings};
use crate::report;
use crate::scene::SceneEdit;
use crate::sim::Trace;
use serde::Deserialize;
use serde_json::{json, Value};
use std::sync::Arc;
use std::time::Duration;

/// The name an edited scene has in error messages: the file "Save scene" writes.
pub const EDIT_ORIGIN: &str = "scene.toml";

/// What the handlers share.
pub struct App {
    /// The scene the page starts from.
    pub initial: SceneEdit,
    /// The quality the page starts with.
    pub quality: Quality,
    /// Each solve's time limit.
    pub time_limit: Duration,
    /// The solve worker.
    pub solver: Arc<Solver>,
    /// `Host` values accepted (empty: any); guards a loopback server against DNS rebinding.
    pub allowed_hosts: Vec<String>,
}

/// `POST /api/solve`: the scene as edited and the quality.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolveRequest {
    /// The edited scene.
    pub scene: SceneEdit,
    /// `fast`, `balanced` or `exact`.
    pub quality: String,
}

/// An edit the page sent, checked and ready to solve.
#[derive(Debug)]
pub struct CheckedEdit {
    /// The job for the worker.
    pub job: SolveJob,
}

/// Reads and validates the body of `POST /api/solve` without solving: a malformed body is a 400, a scene
/// the validator refuses a 422 with its one-line error and key.
pub fn check_edit(body: &[u8], time_limit: Duration) -> Result<CheckedEdit, Response> {
    let request: SolveRequest = serde_json::from_slice(body)
        .map_err(|e| Response::error(400, "bad-request", &format!("request body: {e}")))?;
    let quality = match request.quality.as_str() {
        "fast" => Quality::Fast,
        "balanced" => Quality::Balanced,
        "exact" => Quality::Exact,
        other => {
            return Err(invalid(&Error::InvalidValue {
                name: "quality".to_string(),
                value: format!("{other:?}"),
                allowed: "fast, balanced or exact".to_string(),
            }))
        }
    };
    let scene = request
        .scene
        .validate(EDIT_ORIGIN)
        .map_err(|e| invalid(&e))?;
    let settings = SearchSettings {
        time_limit: Some(time_limit),
        ..SearchSettings::for_quality(quality)
    };
    Ok(CheckedEdit {
        job: SolveJob {
            scene,
            toml: request.scene.to_toml(),
            settings,
        },
    })
}

/// A 422 for a refused scene: the one-line error, the key at fault and the `file:line`.
fn invalid(e: &Error) -> Response {
    let (key, location) = match e {
        Error::Scene { key, location, .. } => (key.clone(), location.clone()),
        Error::InvalidValue { name, .. } => (name.clone(), String::new()),
        _ => (String::new(), String::new()),
    };
    Response::json(
        422,
        &json!({ "status": "invalid", "error": e.to_string(), "key": key, "location": location }),
    )
}

/// Answers one request.
pub fn handle(app: &App, req: &Request, page: &'static str) -> Response {
    if !app.allowed_hosts.is_empty()
        && !req
            .host
            .as_ref()
            .is_some_and(|h| app.allowed_hosts.iter().any(|a| a.eq_ignore_ascii_case(h)))
    {
        return Response::error(403, "forbidden", "unexpected Host header");
    }
    match (req.method.as_str(), req.path.as_str()) {
        ("GET", "/" | "/index.html") => Response {
            status: 200,
            content_type: "text/html; charset=utf-8",
            body: page.as_bytes().to_vec(),
            headers: Vec::new(),
        },
        ("GET", "/api/scene") => Response::json(
            200,
            &json!({
                "scene": app.initial,
                "quality": quality_name(app.quality),
                "time_limit_s": app.time_limit.as_secs_f64(),
            }),
        ),
        ("GET", "/api/progress") => match serde_json::to_value(app.solver.progress()) {
            Ok(v) => Response::json(200, &v),
            Err(e) => Response::error(500, "error", &e.to_string()),
        },
        ("POST", "/api/solve") => solve(app, req),
        ("GET", path) if path.starts_with("/download/") => {
            download(app, &path["/download/".len()..])
        }
        (_, "/" | "/index.html" | "/api/scene" | "/api/progress" | "/api/solve") => {
            Response::error(405, "bad-request", "method not allowed")
        }
        _ => Response::error(404, "not-found", "no such page"),
    }
}

fn solve(app: &App, req: &Request) -> Response {
    let is_json = req.content_type.as_deref().is_some_and(|t| {
        t.split(';')
            .next()
            .is_some_and(|m| m.trim().eq_ignore_ascii_case("application/json"))
    });
    if !is_json {
        return Response::error(415, "bad-request", "send the edit as application/json");
    }
    let checked = match check_edit(&req.body, app.time_limit) {
        Ok(c) => c,
        Err(response) => return response,
    };
    let id = app.solver.submit(checked.job);
    // The running solve ends within its time limit (its last stage may overrun it a little); a solve
    // cancelled for this edit runs before it.
    let patience = 2 * app.time_limit + Duration::from_secs(30);
    match app.solver.wait(id, patience) {
        Some(Answer::Solved(solved)) => Response::json(200, &solved_json(&solved)),
        Some(Answer::Superseded { by }) => Response::json(
            200,
            &json!({ "status": "superseded", "id": id, "superseded_by": by }),
        ),
        Some(Answer::Failed(e @ Error::NoValidPath(_))) => Response::json(
            200,
            &json!({ "status": "no-path", "id": id, "error": e.to_string() }),
        ),
        Some(Answer::Failed(e)) => Response::json(
            200,
            &json!({ "status": "error", "id": id, "error": e.to_string() }),
        ),
        None => Response::error(503, "error", "the solve did not answer in time"),
    }
}

/// The summary `solve --json` prints, without what only the command line uses (`plans`, `scene_path`).
fn summary(solved: &Solved) -> Value {
    let mut summary = crate::cli::solve::summary_json(
        &solved.job.scene,
        solved.job.settings.quality,
        &solved.outcome,
    );
    if let Some(map) = summary.as_object_mut() {
        map.remove("plans");
        map.insert(
            "scene_path".to_string(),
            json!(file_name(&solved.job.scene.name, "toml")),
        );
    }
    summary
}

/// One run for drawing: per frame (0 is the start) `x`, `y` (units) and `speed` (ups).
fn run_json(label: &str, trace: &Trace) -> Value {
    let records = || std::iter::once(&trace.start).chain(trace.frames.iter());
    json!({
        "label": label,
        "valid": trace.feasible(),
        "x": records().map(|r| r.pos.x).collect::<Vec<_>>(),
        "y": records().map(|r| r.pos.y).collect::<Vec<_>>(),
        "speed": records().map(|r| r.speed).collect::<Vec<_>>(),
    })
}

fn solved_json(solved: &Solved) -> Value {
    json!({
        "status": "solved",
        "id": solved.id,
        "summary": summary(solved),
        "frame_time_s": solved.job.scene.frame_time_s(),
        "runs": [
            run_json("greedy", &solved.outcome.greedy),
            run_json("optimised", &solved.outcome.trace),
        ],
        "scene_toml": solved.job.toml,
    })
}

/// A file name from a scene name: letters, digits, `-`, `_` and `.` kept, anything else `_`.
fn file_name(name: &str, extension: &str) -> String {
    let stem: String = name
        .chars()
        .take(80)
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.') {
                c
            } else {
                '_'
            }
        })
        .collect();
    let stem = if stem.trim_matches('.').is_empty() {
        "scene".to_string()
    } else {
        stem
    };
    format!("{stem}.{extension}")
}

/// `GET /download/{scene.toml, plan.hltas, trajectory.csv, report.html}` of the last valid result.
fn download(app: &App, what: &str) -> Response {
    let Some(solved) = app.solver.last_solved() else {
        return Response::error(404, "not-found", "nothing solved yet");
    };
    let scene = &solved.job.scene;
    let outcome = &solved.outcome;
    let written = |write: &dyn Fn(&mut Vec<u8>) -> std::io::Result<()>| {
        let mut bytes = Vec::new();
        write(&mut bytes).map(|()| bytes)
    };
    let result = match what {
        "scene.toml" => Ok(Response::download(
            "application/toml",
            &file_name(&scene.name, "toml"),
            solved.job.toml.clone().into_bytes(),
        )),
        "trajectory.csv" => written(&|w| report::write_trajectory_csv(&outcome.trace, w))
            .map(|b| Response::download("text/csv", &file_name(&scene.name, "csv"), b))
            .map_err(|e| e.to_string()),
        "report.html" => {
            let summary = summary(&solved);
            let input = report::ReportInput::new(scene, &outcome.bound, &summary)
                .with_run("greedy", &outcome.greedy)
                .with_run("optimised", &outcome.trace);
            written(&|w| report::write_html(&input, w))
                .map(|b| {
                    Response::download(
                        "text/html; charset=utf-8",
                        &file_name(&scene.name, "html"),
                        b,
                    )
                })
                .map_err(|e| e.to_string())
        }
        "plan.hltas" => report::hltas_script(&outcome.trace, &scene.vars, &scene.name)
            .map_err(|e| e.to_string())
            .and_then(|script| {
                written(&|w| {
                    script
                        .to_writer(w)
                        .map_err(|e| std::io::Error::other(format!("{e:?}")))
                })
                .map_err(|e| e.to_string())
            })
            .map(|b| {
                Response::download(
                    "text/plain; charset=utf-8",
                    &file_name(&scene.name, "hltas"),
                    b,
                )
            }),
        _ => {
            return Response::error(
                404,
                "not-found",
                "downloads: scene.toml, plan.hltas, trajectory.csv, report.html",
            )
        }
    };
    result.unwrap_or_else(|e| Response::error(422, "error", &e))
}
