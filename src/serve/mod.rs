//! `strafeopt serve`: a local planner page. A small HTTP server (std's `TcpListener`, [`http`]) serves one
//! self-contained page (its script and styles compiled in from `page/`; its content security policy lets
//! it load nothing from elsewhere), the scene to start from, and solves of the page's edits ([`api`]).
//! Edits are validated as scene files ([`SceneEdit`]) and solved one at a time by the [`worker`]; a new
//! edit cancels the solve it replaces.
//!
//! Like the command line this is a front end: scenes, solving and the report writers are the library's.

pub mod api;
pub mod http;
pub mod worker;

use crate::error::{Error, Result};
use crate::optimise::Quality;
use crate::scene::SceneEdit;
use api::App;
use std::net::{IpAddr, SocketAddr, TcpListener, TcpStream};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, OnceLock};
use std::time::Duration;
use worker::Solver;

/// Most connections served at once; more are answered 503 at once.
pub const MAX_CONNECTIONS: usize = 32;

const PAGE_HTML: &str = include_str!("page/index.html");
const PAGE_CSS: &str = include_str!("page/page.css");
const PAGE_JS: &str = include_str!("page/page.js");

/// The page with its styles and script inlined.
pub fn page() -> &'static str {
    static PAGE: OnceLock<String> = OnceLock::new();
    PAGE.get_or_init(|| {
        PAGE_HTML
            .replace("/*PAGE_CSS*/", PAGE_CSS)
            .replace("/*PAGE_JS*/", PAGE_JS)
    })
}

/// What to serve and where.
#[derive(Clone, Debug)]
pub struct ServeConfig {
    /// Address to listen on (`127.0.0.1` unless asked otherwise).
    pub bind: IpAddr,
    /// Port (0: any free port).
    pub port: u16,
    /// The scene the page starts from.
    pub initial: SceneEdit,
    /// The quality the page starts with.
    pub quality: Quality,
    /// Each solve's time limit.
    pub time_limit: Duration,
}

/// A bound server, ready to [`run`](Server::run).
pub struct Server {
    listener: TcpListener,
    app: Arc<App>,
}

impl Server {
    /// Binds the listening socket and starts the solve worker.
    pub fn bind(config: ServeConfig) -> Result<Server> {
        let listener = TcpListener::bind(SocketAddr::new(config.bind, config.port))
            .map_err(|e| Error::Io(format!("listening on {}:{}: {e}", config.bind, config.port)))?;
        let port = listener
            .local_addr()
            .map_err(|e| Error::Io(format!("the listening address: {e}")))?
            .port();
        let allowed_hosts = if config.bind.is_loopback() {
            ["127.0.0.1", "localhost", "[::1]"]
                .iter()
                .map(|h| format!("{h}:{port}"))
                .collect()
        } else {
            Vec::new()
        };
        Ok(Server {
            listener,
            app: Arc::new(App {
                initial: config.initial,
                quality: config.quality,
                time_limit: config.time_limit,
                solver: Solver::start(),
                allowed_hosts,
            }),
        })
    }

    /// The address the server listens on.
    pub fn local_addr(&self) -> Result<SocketAddr> {
        self.listener
            .local_addr()
            .map_err(|e| Error::Io(format!("the listening address: {e}")))
    }

    /// Serves until the process ends: one thread per connection, at most [`MAX_CONNECTIONS`].
    pub fn run(self) -> Result<()> {
        let active = Arc::new(AtomicUsize::new(0));
        for stream in self.listener.incoming() {
            let Ok(mut stream) = stream else { continue };
            if active.fetch_add(1, Ordering::SeqCst) >= MAX_CONNECTIONS {
                active.fetch_sub(1, Ordering::SeqCst);
                let busy = http::Response::error(503, "busy", "too many connections; try again");
                let _ = stream.set_write_timeout(Some(http::IO_TIMEOUT));
                let _ = http::write_response(&mut stream, &busy);
                continue;
            }
            let app = Arc::clone(&self.app);
            let active = Arc::clone(&active);
            let spawned = std::thread::Builder::new().spawn(move || {
                serve_connection(&app, stream);
                active.fetch_sub(1, Ordering::SeqCst);
            });
            if spawned.is_err() {
                self.app.solver.shut_down();
                return Err(Error::Io("cannot start a connection thread".to_string()));
            }
        }
        Ok(())
    }
}

fn serve_connection(app: &App, mut stream: TcpStream) {
    let _ = stream.set_read_timeout(Some(http::IO_TIMEOUT));
    let _ = stream.set_write_timeout(Some(http::IO_TIMEOUT));
    match http::read_request(&mut stream) {
        Ok(request) => {
            let response = catch_unwind(AssertUnwindSafe(|| api::handle(app, &request, page())))
                .unwrap_or_else(|_| {
                    http::Response::error(500, "error", "internal error; the server goes on")
                });
            let _ = http::write_response(&mut stream, &response);
        }
        Err(http::ReadError::Refuse(response)) => {
            let _ = http::write_response(&mut stream, &response);
            let _ = stream.shutdown(std::net::Shutdown::Write);
            http::drain(&mut stream);
        }
        Err(http::ReadError::Gone) => {}
    }
}
