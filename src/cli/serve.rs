//! `strafeopt serve [SCENE]`: the planner page on a local port (see [`crate::serve`]).

use super::args::ServeArgs;
use crate::error::{Error, Result};
use crate::optimise::search::time_limit;
use crate::scene::SceneEdit;
use crate::serve::{ServeConfig, Server};
use std::io::Write;
use std::net::{IpAddr, Ipv4Addr};

/// The scene the page starts from without SCENE: a 90-degree bend at 100 fps (a `fast` solve takes
/// about a second).
const DEFAULT_SCENE: &str = include_str!("../../scenarios/hl-bend90-100fps.toml");

/// Longest time limit of one solve, seconds: a page waits for its answer.
pub const MAX_TIME_LIMIT_S: f64 = 3600.0;

/// Serves until the process is stopped; prints the address first.
pub fn run(args: &ServeArgs) -> Result<String> {
    if args.time_limit > MAX_TIME_LIMIT_S {
        return Err(Error::invalid(
            "--time-limit",
            args.time_limit,
            format!("a finite number of seconds above 0 and at most {MAX_TIME_LIMIT_S}"),
        ));
    }
    let limit = time_limit(args.time_limit)?;
    let initial = match &args.scene {
        Some(path) => {
            let origin = path.display().to_string();
            let text = std::fs::read_to_string(path).map_err(|e| Error::Scene {
                location: origin.clone(),
                key: "-".to_string(),
                message: format!("cannot read the file: {e}"),
            })?;
            SceneEdit::from_toml_str(&text, &origin)?
        }
        None => SceneEdit::from_toml_str(DEFAULT_SCENE, "hl-bend90-100fps.toml")?,
    };
    let bind = args.bind.unwrap_or(IpAddr::V4(Ipv4Addr::LOCALHOST));
    let quality = args.quality.quality();
    let name = initial.name.clone();
    let server = Server::bind(ServeConfig {
        bind,
        port: args.port,
        initial,
        quality,
        time_limit: limit,
    })?;
    let addr = server.local_addr()?;
    if !bind.is_loopback() {
        eprintln!(
            "strafeopt: warning: serving on {bind}, not 127.0.0.1: anyone who can reach this address can \
             run solves on this machine and read the scenes solved"
        );
    }
    let mut stdout = std::io::stdout().lock();
    let _ = writeln!(
        stdout,
        "strafeopt serve: http://{addr}/ (scene {name}, {} s per solve; Ctrl-C stops)",
        limit.as_secs_f64()
    );
    let _ = stdout.flush();
    drop(stdout);
    server.run()?;
    Ok(String::new())
}
