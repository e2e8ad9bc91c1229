//! The planner page in a real browser: `strafeopt serve` on a free port, headless Chromium on the page,
//! driven through the DevTools protocol (a websocket; the page has no test hooks). The test drags a wall
//! vertex with the mouse as a person would, waits for the new plan to be drawn, and checks the time in the
//! table against `strafeopt solve` on the scene the page saves.
//!
//! Skipped (with a line saying so) when `/usr/bin/chromium` is absent, unless `CI=true`: CI installs it.

use serde_json::{json, Value};
use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};
use tungstenite::protocol::Role;
use tungstenite::{Message, WebSocket};

const CHROMIUM: &str = "/usr/bin/chromium";
const PATIENCE: Duration = Duration::from_secs(45);

/// A child process killed when dropped (the server, the browser).
struct Killed(Child);

impl Drop for Killed {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("strafeopt-test-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
    dir
}

/// Starts the server on a free port; returns it and its address.
fn serve() -> (Killed, SocketAddr) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_strafeopt"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args([
            "serve",
            "scenarios/hl-bend90-100fps.toml",
            "--port",
            "0",
            "--quality",
            "fast",
        ])
        .args(["--time-limit", "60"])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap_or_else(|e| panic!("start the server: {e}"));
    let stdout = child.stdout.take().unwrap_or_else(|| panic!("no stdout"));
    let server = Killed(child);
    let mut line = String::new();
    BufReader::new(stdout)
        .read_line(&mut line)
        .unwrap_or_else(|e| panic!("{e}"));
    let addr = line
        .split("http://")
        .nth(1)
        .and_then(|r| r.split('/').next())
        .and_then(|a| a.parse().ok())
        .unwrap_or_else(|| panic!("no address in {line:?}"));
    (server, addr)
}

/// A plain GET; returns the body (read up to its Content-Length: Chromium keeps the connection open).
fn http_get(addr: SocketAddr, path: &str) -> String {
    let s = TcpStream::connect(addr).unwrap_or_else(|e| panic!("connect {addr}: {e}"));
    let _ = s.set_read_timeout(Some(Duration::from_secs(30)));
    let _ = write!(
        &s,
        "GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n"
    );
    let mut reader = BufReader::new(s);
    let mut length = 0usize;
    let mut line = String::new();
    while reader.read_line(&mut line).is_ok_and(|n| n > 0) && line != "\r\n" {
        if let Some((name, value)) = line.split_once(':') {
            if name.eq_ignore_ascii_case("content-length") {
                length = value.trim().parse().unwrap_or(0);
            }
        }
        line.clear();
    }
    let mut body = vec![0u8; length];
    let _ = reader.read_exact(&mut body);
    String::from_utf8_lossy(&body).into_owned()
}

/// Headless Chromium on `url` with the DevTools protocol on a free port.
fn chromium(profile: &Path, url: &str) -> (Killed, u16) {
    let child = Command::new(CHROMIUM)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--no-first-run",
            "--remote-debugging-port=0",
            "--window-size=1400,900",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg(url)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap_or_else(|e| panic!("start {CHROMIUM}: {e}"));
    let browser = Killed(child);
    // Chromium writes the port it chose into the profile.
    let started = Instant::now();
    let port_file = profile.join("DevToolsActivePort");
    loop {
        let text = std::fs::read_to_string(&port_file).unwrap_or_default();
        if let Some(port) = text.lines().next().and_then(|l| l.trim().parse().ok()) {
            return (browser, port);
        }
        assert!(
            started.elapsed() < PATIENCE,
            "chromium wrote no DevToolsActivePort"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// A DevTools session on one page.
struct DevTools {
    ws: WebSocket<TcpStream>,
    next_id: u64,
}

impl DevTools {
    /// Connects to the page target showing `url`.
    fn connect(port: u16, url: &str) -> DevTools {
        let addr = SocketAddr::from(([127, 0, 0, 1], port));
        let started = Instant::now();
        let ws_path = loop {
            let list: Value =
                serde_json::from_str(&http_get(addr, "/json/list")).unwrap_or_default();
            let found = list.as_array().and_then(|targets| {
                targets
                    .iter()
                    .find(|t| {
                        t["type"] == "page" && t["url"].as_str().is_some_and(|u| u.starts_with(url))
                    })
                    .and_then(|t| t["webSocketDebuggerUrl"].as_str())
                    .and_then(|u| {
                        u.split_once(&format!("{port}"))
                            .map(|(_, path)| path.to_string())
                    })
            });
            if let Some(path) = found {
                break path;
            }
            assert!(started.elapsed() < PATIENCE, "no page target: {list}");
            std::thread::sleep(Duration::from_millis(100));
        };
        let mut stream = TcpStream::connect(addr).unwrap_or_else(|e| panic!("{e}"));
        let _ = stream.set_read_timeout(Some(PATIENCE));
        let _ = write!(
            stream,
            "GET {ws_path} HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n\
             Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n"
        );
        // Read the handshake answer byte by byte, so no frame is consumed with it.
        let mut head = Vec::new();
        let mut byte = [0u8; 1];
        while !head.ends_with(b"\r\n\r\n") {
            stream
                .read_exact(&mut byte)
                .unwrap_or_else(|e| panic!("handshake: {e}"));
            head.push(byte[0]);
        }
        let head = String::from_utf8_lossy(&head);
        assert!(head.starts_with("HTTP/1.1 101"), "{head}");
        DevTools {
            ws: WebSocket::from_raw_socket(stream, Role::Client, None),
            next_id: 1,
        }
    }

    /// Sends a command and returns its result.
    fn call(&mut self, method: &str, params: Value) -> Value {
        let id = self.next_id;
        self.next_id += 1;
        let message = json!({ "id": id, "method": method, "params": params }).to_string();
        self.ws
            .send(Message::Text(message.into()))
            .unwrap_or_else(|e| panic!("{method}: {e}"));
        loop {
            let reply = self.ws.read().unwrap_or_else(|e| panic!("{method}: {e}"));
            if let Message::Text(text) = reply {
                let v: Value = serde_json::from_str(text.as_str()).unwrap_or_default();
                if v["id"] == id {
                    assert!(v.get("error").is_none(), "{method}: {v}");
                    return v["result"].clone();
                }
            }
        }
    }

    /// Evaluates `expression` in the page and returns its value.
    fn eval(&mut self, expression: &str) -> Value {
        let r = self.call(
            "Runtime.evaluate",
            json!({ "expression": expression, "returnByValue": true }),
        );
        assert!(r.get("exceptionDetails").is_none(), "{expression}: {r}");
        r["result"]["value"].clone()
    }

    /// Polls `expression` until `done` accepts its value.
    fn wait_for(&mut self, expression: &str, what: &str, done: impl Fn(&Value) -> bool) -> Value {
        let started = Instant::now();
        loop {
            let v = self.eval(expression);
            if done(&v) {
                return v;
            }
            assert!(started.elapsed() < PATIENCE, "{what}: still {v}");
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    fn mouse(&mut self, kind: &str, x: f64, y: f64, buttons: u8) {
        self.call(
            "Input.dispatchMouseEvent",
            json!({ "type": kind, "x": x, "y": y, "button": "left", "buttons": buttons, "clickCount": 1 }),
        );
    }
}

const RESULT_ID: &str =
    "(function () { var p = document.getElementById('paths'); return p && p.getAttribute('data-result-id'); })()";
const TABLE_TIME: &str = "document.getElementById('time-optimised').textContent";
const PLAN_DRAWN: &str =
    "Array.from(document.querySelectorAll('#paths [data-run=optimised] polyline'))\
     .map(function (p) { return p.getAttribute('points'); }).join(' ')";

#[test]
fn dragging_a_wall_vertex_redraws_the_plan_with_the_time_solve_gives() {
    if !Path::new(CHROMIUM).exists() {
        assert_ne!(
            std::env::var("CI").as_deref(),
            Ok("true"),
            "{CHROMIUM} is missing on CI"
        );
        println!("serve_browser: {CHROMIUM} not found; the browser test is skipped");
        return;
    }
    let dir = temp_dir("serve-browser");
    let (_server, addr) = serve();
    let url = format!("http://{addr}/");
    let (_browser, port) = chromium(&dir.join("profile"), &url);
    let mut page = DevTools::connect(port, &url);

    // The first plan is drawn when the page has loaded.
    let first_id = page.wait_for(RESULT_ID, "the first plan", |v| v.is_string());
    let first_time = page.eval(TABLE_TIME);
    let first_plan = page.eval(PLAN_DRAWN);
    assert!(
        first_plan.as_str().is_some_and(|p| p.len() > 1000),
        "{first_plan}"
    );

    // Drag the inner corner of the bend (walls[0], point 1) up and to the left with the mouse.
    let handle = page.eval(
        "(function () { var r = document.querySelector('circle[data-wall=\"0\"][data-point=\"1\"]')\
         .getBoundingClientRect(); return [r.left + r.width / 2, r.top + r.height / 2]; })()",
    );
    let (x, y) = (
        handle[0].as_f64().unwrap_or(f64::NAN),
        handle[1].as_f64().unwrap_or(f64::NAN),
    );
    assert!(x.is_finite() && y.is_finite(), "{handle}");
    page.mouse("mouseMoved", x, y, 0);
    page.mouse("mousePressed", x, y, 1);
    for step in 1..=10 {
        let f = f64::from(step) / 10.0;
        page.mouse("mouseMoved", x - 20.0 * f, y - 20.0 * f, 1);
    }
    page.mouse("mouseReleased", x - 20.0, y - 20.0, 0);

    let new_id = page.wait_for(RESULT_ID, "a new plan", |v| v.is_string() && *v != first_id);
    let new_time = page.eval(TABLE_TIME);
    let new_plan = page.eval(PLAN_DRAWN);
    assert_ne!(new_plan, first_plan, "the drawn plan did not change");
    assert_ne!(new_time, first_time, "the time in the table did not change");
    let moved = page.eval(
        "document.querySelector('circle[data-wall=\"0\"][data-point=\"1\"] title').textContent",
    );
    assert!(
        moved.as_str().is_some_and(|t| !t.contains("(1040, 160)")),
        "{moved}"
    );
    let error_shown = page.eval("!document.getElementById('edit-error').hidden");
    assert_eq!(error_shown, json!(false));

    // The table's time is what `solve` gives for the scene the page saves.
    let saved = dir.join("saved.toml");
    std::fs::write(&saved, http_get(addr, "/download/scene.toml"))
        .unwrap_or_else(|e| panic!("{e}"));
    let out = Command::new(env!("CARGO_BIN_EXE_strafeopt"))
        .args(["solve", "--quality", "fast", "--json"])
        .arg(&saved)
        .output()
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let solved: Value = serde_json::from_slice(&out.stdout).unwrap_or_default();
    let time = solved["time"].as_f64().unwrap_or(f64::NAN);
    assert_eq!(
        new_time,
        json!(format!("{time:.6}")),
        "page {new_id}, solve {solved}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
