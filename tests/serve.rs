//! `strafeopt serve` through real HTTP: the real binary on a free port, raw requests over TCP. Bad input
//! (malformed JSON, oversized or odd requests, NaN and infinite coordinates, scenes with no valid path)
//! gets a one-line answer and the server goes on; two quick edits get the first superseded and the second
//! solved with its own scene's result. The JSON edit handler is fuzzed with proptest.

use proptest::prelude::*;
use serde_json::{json, Value};
use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};
use strafeopt::optimise::{solve, Quality, SearchSettings};
use strafeopt::scene::{Scene, SceneEdit};
use strafeopt::serve::api::check_edit;

const BEND: &str = include_str!("../scenarios/hl-bend90-100fps.toml");

/// A server process, stopped when dropped.
struct Served {
    child: Child,
    addr: SocketAddr,
}

impl Drop for Served {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Starts `strafeopt serve --port 0` (any free port) and reads the address it prints.
fn serve(extra: &[&str]) -> Served {
    let mut child = Command::new(env!("CARGO_BIN_EXE_strafeopt"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args([
            "serve",
            "--port",
            "0",
            "--quality",
            "fast",
            "--time-limit",
            "60",
        ])
        .args(extra)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap_or_else(|e| panic!("start the server: {e}"));
    let mut line = String::new();
    let stdout = child.stdout.take().unwrap_or_else(|| panic!("no stdout"));
    BufReader::new(stdout)
        .read_line(&mut line)
        .unwrap_or_else(|e| panic!("read the address: {e}"));
    let addr = line
        .split("http://")
        .nth(1)
        .and_then(|rest| rest.split('/').next())
        .and_then(|a| a.parse().ok())
        .unwrap_or_else(|| panic!("no address in {line:?}"));
    Served { child, addr }
}

/// Sends `request` as it is and returns the status and the body.
fn raw(addr: SocketAddr, request: &[u8]) -> (u16, String) {
    let mut stream = TcpStream::connect(addr).unwrap_or_else(|e| panic!("connect: {e}"));
    stream
        .set_read_timeout(Some(Duration::from_secs(150)))
        .unwrap_or_else(|e| panic!("{e}"));
    // The server may answer (and stop reading) before a refused body is all sent.
    let _ = stream.write_all(request);
    let mut answer = Vec::new();
    let _ = stream.read_to_end(&mut answer);
    let text = String::from_utf8_lossy(&answer).into_owned();
    let status = text
        .split(' ')
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no status in {text:?}"));
    let body = text
        .split_once("\r\n\r\n")
        .map(|(_, b)| b.to_string())
        .unwrap_or_default();
    (status, body)
}

fn request(
    addr: SocketAddr,
    method: &str,
    path: &str,
    content_type: &str,
    body: &[u8],
) -> (u16, String) {
    let mut bytes = format!(
        "{method} {path} HTTP/1.1\r\nHost: {addr}\r\nContent-Type: {content_type}\r\nContent-Length: {}\r\n\r\n",
        body.len()
    )
    .into_bytes();
    bytes.extend_from_slice(body);
    raw(addr, &bytes)
}

fn get(addr: SocketAddr, path: &str) -> (u16, String) {
    raw(
        addr,
        format!("GET {path} HTTP/1.1\r\nHost: {addr}\r\n\r\n").as_bytes(),
    )
}

fn post_solve(addr: SocketAddr, body: &str) -> (u16, Value) {
    let (status, text) = request(
        addr,
        "POST",
        "/api/solve",
        "application/json",
        body.as_bytes(),
    );
    let value = serde_json::from_str(&text).unwrap_or_else(|e| panic!("{e}: {text}"));
    (status, value)
}

fn bend_edit() -> SceneEdit {
    SceneEdit::from_toml_str(BEND, "bend.toml").unwrap_or_else(|e| panic!("{e}"))
}

fn solve_body(edit: &SceneEdit) -> String {
    json!({ "scene": edit, "quality": "fast" }).to_string()
}

/// An answer that refuses the input: the status, a `status` word and a one-line error.
fn assert_refused(answer: (u16, Value), status: u16, word: &str, contains: &str) {
    let (code, body) = answer;
    assert_eq!(code, status, "{body}");
    assert_eq!(body["status"], word, "{body}");
    let error = body["error"].as_str().unwrap_or_default();
    assert!(!error.contains('\n'), "{error:?} is more than a line");
    assert!(
        error.contains(contains),
        "{error:?} should say {contains:?}"
    );
}

fn assert_alive(addr: SocketAddr) {
    let (status, body) = get(addr, "/api/scene");
    assert_eq!(status, 200, "{body}");
}

#[test]
fn malformed_and_odd_requests_get_one_line_answers() {
    let s = serve(&[]);
    for (body, says) in [
        ("{", "EOF while parsing"),
        ("not json", "expected ident"),
        ("[]", "invalid length 0"),
        (
            r#"{"scene": 5, "quality": "fast"}"#,
            "invalid type: integer",
        ),
        (r#"{"quality": "fast"}"#, "missing field `scene`"),
    ] {
        assert_refused(post_solve(s.addr, body), 400, "bad-request", says);
    }
    let mut edit = json!({ "scene": bend_edit(), "quality": "fast" });
    edit["scene"]["walls"][0]["colour"] = json!("red");
    assert_refused(
        post_solve(s.addr, &edit.to_string()),
        400,
        "bad-request",
        "unknown field `colour`",
    );
    let edit = json!({ "scene": bend_edit(), "quality": "slow" });
    assert_refused(
        post_solve(s.addr, &edit.to_string()),
        422,
        "invalid",
        "fast, balanced or exact",
    );
    // Not JSON by its type (a form post from another site), a missing route, a wrong method, a foreign Host.
    let (status, _) = request(
        s.addr,
        "POST",
        "/api/solve",
        "text/plain",
        solve_body(&bend_edit()).as_bytes(),
    );
    assert_eq!(status, 415);
    assert_eq!(get(s.addr, "/nowhere").0, 404);
    assert_eq!(
        request(s.addr, "DELETE", "/api/solve", "application/json", b"").0,
        405
    );
    let foreign = raw(
        s.addr,
        b"GET /api/scene HTTP/1.1\r\nHost: attacker.example:80\r\n\r\n",
    );
    assert_eq!(foreign.0, 403);
    assert_eq!(raw(s.addr, b"BREW /pot HTCPCP/1.0 \x00\r\n\r\n").0, 400);
    assert_alive(s.addr);
}

#[test]
fn oversized_requests_are_refused_before_they_are_read() {
    let s = serve(&[]);
    // A body over 1 MiB: refused from its Content-Length.
    let big = vec![b' '; (1 << 20) + 1];
    let (status, body) = request(s.addr, "POST", "/api/solve", "application/json", &big);
    assert_eq!(status, 413, "{body}");
    assert!(body.contains("at most 1048576"), "{body}");
    // A head over 16 KiB, too many headers, a chunked body.
    let long = format!(
        "GET / HTTP/1.1\r\nHost: {}\r\nX-Long: {}\r\n\r\n",
        s.addr,
        "a".repeat(20_000)
    );
    assert_eq!(raw(s.addr, long.as_bytes()).0, 431);
    let many: String = (0..60).map(|i| format!("X-H{i}: {i}\r\n")).collect();
    let many = format!("GET / HTTP/1.1\r\nHost: {}\r\n{many}\r\n", s.addr);
    assert_eq!(raw(s.addr, many.as_bytes()).0, 431);
    let chunked = format!(
        "POST /api/solve HTTP/1.1\r\nHost: {}\r\nContent-Type: application/json\r\nTransfer-Encoding: chunked\r\n\r\n1\r\n{{\r\n0\r\n\r\n",
        s.addr
    );
    assert_eq!(raw(s.addr, chunked.as_bytes()).0, 411);
    // Too many wall points for the validator to be quick: refused before validation.
    let mut edit = bend_edit();
    edit.walls.push(strafeopt::scene::edit::WallEdit {
        kind: strafeopt::scene::BoundaryKind::Rule,
        points: (0..2500)
            .map(|i| [i as f64, -300.0 - (i % 2) as f64])
            .collect(),
        closed: false,
    });
    assert_refused(
        post_solve(s.addr, &solve_body(&edit)),
        422,
        "invalid",
        "at most 2000",
    );
    assert_alive(s.addr);
}

#[test]
fn nan_and_infinite_coordinates_are_refused_with_their_key() {
    let s = serve(&[]);
    let good = serde_json::to_string(&json!({ "scene": bend_edit(), "quality": "fast" }))
        .unwrap_or_default();
    let start = r#""position":[40.0,80.0]"#;
    assert!(good.contains(start), "{good}");
    // JSON has no NaN or infinity: the tokens, an overflowing literal and the `null` a browser sends for
    // them are malformed requests.
    for (bad, says) in [
        (r#""position":[NaN,80.0]"#, "at line 1 column"),
        (r#""position":[Infinity,80.0]"#, "at line 1 column"),
        (
            r#""position":[-inf,80.0]"#,
            "invalid number at line 1 column",
        ),
        (r#""position":[1e999,80.0]"#, "number out of range"),
        (
            r#""position":[null,80.0]"#,
            "invalid type: null, expected f64",
        ),
    ] {
        assert_refused(
            post_solve(s.addr, &good.replacen(start, bad, 1)),
            400,
            "bad-request",
            says,
        );
    }
    // Finite but beyond any map: the validator's error, at the key and the line of the saved scene.
    let mut edit = bend_edit();
    edit.start.position = [1e308, 80.0];
    let (status, body) = post_solve(s.addr, &solve_body(&edit));
    assert_refused(
        (status, body.clone()),
        422,
        "invalid",
        "start.position: got [1e308, 80]",
    );
    assert_eq!(body["key"], "start.position");
    assert!(
        body["error"]
            .as_str()
            .unwrap_or_default()
            .starts_with("scene.toml:"),
        "{body}"
    );
    let mut edit = bend_edit();
    edit.walls[0].points[3] = [-1e300, 0.0];
    let (status, body) = post_solve(s.addr, &solve_body(&edit));
    assert_refused(
        (status, body.clone()),
        422,
        "invalid",
        "point 3 is at (-1e300, 0)",
    );
    assert_eq!(body["key"], "walls[0].points");
    let mut edit = bend_edit();
    edit.start.velocity = [f64::MAX, f64::MAX];
    assert_refused(
        post_solve(s.addr, &solve_body(&edit)),
        422,
        "invalid",
        "start.velocity",
    );
    assert_alive(s.addr);
}

#[test]
fn scenes_with_no_valid_path_say_so() {
    let s = serve(&[]);
    // A wall across the second leg: the validator finds no way for the hull.
    let mut edit = bend_edit();
    edit.walls.push(strafeopt::scene::edit::WallEdit {
        kind: strafeopt::scene::BoundaryKind::Rule,
        points: vec![[1000.0, 600.0], [1250.0, 600.0]],
        closed: false,
    });
    let (status, body) = post_solve(s.addr, &solve_body(&edit));
    assert_refused(
        (status, body.clone()),
        422,
        "invalid",
        "no path for the hull",
    );
    assert_eq!(body["key"], "finish");
    // A way through, but a frame cap too short for any run to reach the line: the solver's answer.
    let mut edit = bend_edit();
    edit.max_frames = Some(100);
    assert_refused(
        post_solve(s.addr, &solve_body(&edit)),
        200,
        "no-path",
        "no valid path",
    );
    // Nothing was solved, so there is nothing to download.
    assert_eq!(get(s.addr, "/download/scene.toml").0, 404);
    assert_alive(s.addr);
}

/// Waits until the server reports a running solve.
fn wait_until_running(addr: SocketAddr) {
    let started = Instant::now();
    while started.elapsed() < Duration::from_secs(60) {
        let (_, body) = get(addr, "/api/progress");
        let progress: Value = serde_json::from_str(&body).unwrap_or_default();
        if progress["running"] == true {
            return;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    panic!("the first solve never started");
}

#[test]
fn a_second_quick_edit_supersedes_the_first_and_gets_its_own_result() {
    let s = serve(&[]);
    let first = bend_edit();
    // The second edit moves the finish line 200 units nearer: a different, shorter plan.
    let mut second = bend_edit();
    second.finish.a[1] = 1000.0;
    second.finish.b[1] = 1000.0;
    let addr = s.addr;
    let first_body = solve_body(&first);
    let first_answer = std::thread::spawn(move || post_solve(addr, &first_body));
    wait_until_running(addr);
    let (status, answer) = post_solve(addr, &solve_body(&second));
    let (first_status, first_answer) = first_answer
        .join()
        .unwrap_or_else(|_| panic!("the first request panicked"));

    assert_eq!(first_status, 200, "{first_answer}");
    assert_eq!(first_answer["status"], "superseded", "{first_answer}");
    assert_eq!(
        first_answer["superseded_by"], answer["id"],
        "{first_answer} {answer}"
    );
    assert_eq!(status, 200, "{answer}");
    assert_eq!(answer["status"], "solved", "{answer}");

    // The answer is the second scene's own solve.
    let scene = second
        .validate("second.toml")
        .unwrap_or_else(|e| panic!("{e}"));
    let expected = solve(&scene, &SearchSettings::for_quality(Quality::Fast))
        .unwrap_or_else(|e| panic!("{e}"));
    let crossing = expected
        .trace
        .crossing
        .unwrap_or_else(|| panic!("no crossing"));
    let summary = &answer["summary"];
    assert_eq!(
        summary["frames"].as_u64(),
        Some(crossing.frames),
        "{summary}"
    );
    let time = summary["time"].as_f64().unwrap_or(f64::NAN);
    assert!(
        (time - crossing.time).abs() < 1e-9,
        "{time} against {}",
        crossing.time
    );
    let first_scene = first
        .validate("first.toml")
        .unwrap_or_else(|e| panic!("{e}"));
    let first_bound = first_scene
        .corridor()
        .and_then(|c| strafeopt::optimise::lower_bound(&first_scene, &c))
        .map(|b| b.crossing.frames)
        .unwrap_or(0);
    assert!(
        crossing.frames < first_bound,
        "the second scene should be quicker than the first's bound ({} frames)",
        first_bound
    );
    // Drawn runs: frame 0 plus one point per frame up to the crossing frame.
    let runs = answer["runs"].as_array().cloned().unwrap_or_default();
    assert_eq!(runs.len(), 2);
    assert_eq!(runs[1]["label"], "optimised");
    assert_eq!(
        runs[1]["x"].as_array().map(Vec::len),
        Some(expected.trace.frames.len() + 1)
    );

    // The downloads are the second scene's: its TOML reads back as the same scene.
    let (status, toml) = get(addr, "/download/scene.toml");
    assert_eq!(status, 200);
    let saved = Scene::from_toml_str(&toml, "second.toml").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(saved, scene);
    let (status, hltas) = get(addr, "/download/plan.hltas");
    assert_eq!(status, 200, "{hltas}");
    assert!(hltas.starts_with("version 1"), "{hltas}");
    let (status, csv) = get(addr, "/download/trajectory.csv");
    assert_eq!(status, 200);
    assert_eq!(csv.lines().count(), expected.trace.frames.len() + 2);
    let (status, report) = get(addr, "/download/report.html");
    assert_eq!(status, 200);
    assert!(report.contains("<svg") && report.contains("optimised"));
}

#[test]
fn the_page_is_self_contained() {
    let s = serve(&[]);
    let (status, page) = get(s.addr, "/");
    assert_eq!(status, 200);
    assert!(page.contains("<svg id=\"plot\"") && page.contains("/api/solve"));
    assert!(!page.contains("/*PAGE_JS*/") && !page.contains("/*PAGE_CSS*/"));
    // Nothing from elsewhere: no absolute URL other than the SVG namespace.
    for (i, _) in page.match_indices("http") {
        let rest = &page[i..];
        assert!(
            rest.starts_with("http://www.w3.org/2000/svg"),
            "{}",
            &rest[..rest.len().min(60)]
        );
    }
    let (_, scene) = get(s.addr, "/api/scene");
    let scene: Value = serde_json::from_str(&scene).unwrap_or_default();
    assert_eq!(scene["quality"], "fast");
    assert_eq!(scene["time_limit_s"], 60.0);
    let edit: SceneEdit =
        serde_json::from_value(scene["scene"].clone()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(edit, bend_edit());
}

#[test]
fn a_bad_command_line_is_refused() {
    for (args, says) in [
        (vec!["--time-limit", "0"], "--time-limit"),
        (vec!["--time-limit", "1e300"], "at most 3600"),
        (vec!["no-such-scene.toml"], "cannot read the file"),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_strafeopt"))
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .args(["serve", "--port", "0"])
            .args(&args)
            .output()
            .unwrap_or_else(|e| panic!("{e}"));
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(says), "{args:?}: {err}");
    }
}

/// A JSON value for the fuzzer: numbers of every size, strings, nulls, arrays and objects.
fn any_json() -> impl Strategy<Value = Value> {
    let leaf = prop_oneof![
        Just(Value::Null),
        any::<bool>().prop_map(Value::from),
        any::<f64>()
            .prop_map(|v| serde_json::Number::from_f64(v).map_or(Value::Null, Value::Number)),
        any::<i64>().prop_map(Value::from),
        "[a-z\\-]{0,12}".prop_map(Value::from),
    ];
    leaf.prop_recursive(3, 16, 4, |inner| {
        prop_oneof![
            prop::collection::vec(inner.clone(), 0..4).prop_map(Value::Array),
            prop::collection::vec(("[a-z\\-]{1,10}", inner), 0..4)
                .prop_map(|kv| Value::Object(kv.into_iter().collect())),
        ]
    })
}

/// Every place in `v` (as JSON pointers).
fn pointers(v: &Value, at: String, out: &mut Vec<String>) {
    out.push(at.clone());
    match v {
        Value::Array(items) => items
            .iter()
            .enumerate()
            .for_each(|(i, x)| pointers(x, format!("{at}/{i}"), out)),
        Value::Object(map) => map
            .iter()
            .for_each(|(k, x)| pointers(x, format!("{at}/{k}"), out)),
        _ => {}
    }
}

fn assert_handled(body: &[u8]) {
    match check_edit(body, Duration::from_secs(1)) {
        Ok(checked) => {
            assert!(checked.job.scene.walls.iter().all(|w| w.points.len() >= 2));
        }
        Err(response) => {
            assert!(matches!(response.status, 400 | 422), "{}", response.status);
            let answer: Value = serde_json::from_slice(&response.body).unwrap_or_default();
            let error = answer["error"].as_str().unwrap_or_default();
            assert!(!error.is_empty() && !error.contains('\n'), "{error:?}");
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, rng_seed: proptest::test_runner::RngSeed::Fixed(7), ..ProptestConfig::default() })]

    #[test]
    fn the_edit_handler_answers_any_bytes(bytes in prop::collection::vec(any::<u8>(), 0..300)) {
        assert_handled(&bytes);
    }

    #[test]
    fn the_edit_handler_answers_any_change_to_a_good_edit(
        pick in any::<prop::sample::Index>(),
        value in any_json(),
        cut in any::<prop::sample::Index>(),
        truncate in any::<bool>(),
    ) {
        let mut edit = json!({ "scene": bend_edit(), "quality": "fast" });
        let mut places = Vec::new();
        pointers(&edit, String::new(), &mut places);
        let place = places[pick.index(places.len())].clone();
        if let Some(slot) = edit.pointer_mut(&place) {
            *slot = value;
        }
        let text = edit.to_string().into_bytes();
        let end = if truncate { cut.index(text.len() + 1) } else { text.len() };
        assert_handled(&text[..end]);
    }

    #[test]
    fn the_edit_handler_answers_any_coordinates(
        wall in 0usize..1, point in 0usize..6, x in any::<f64>(), y in any::<f64>(),
        sx in any::<f64>(), vy in any::<f64>(),
    ) {
        let mut edit = bend_edit();
        edit.walls[wall].points[point] = [x, y];
        edit.start.position[0] = sx;
        edit.start.velocity[1] = vy;
        assert_handled(solve_body(&edit).as_bytes());
    }
}
