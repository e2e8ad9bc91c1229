//! The HTML report in a real browser: headless Chromium lays the page out and a small script, added to a
//! copy of the report, measures each figure. Without `/usr/bin/chromium` the test is skipped (with a line
//! saying so) on a developer's machine, and fails under CI (`CI=true`), which installs it (`.ci/run`).

use assert_cmd::Command as BinCommand;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const CHROMIUM: &str = "/usr/bin/chromium";
const BROWSER_TIMEOUT: Duration = Duration::from_secs(180);

/// Measures the laid-out page: per `<svg>` its size and how many of its lines, paths, boxes and dots
/// have a non-empty box; the summary table's rows. Written into `<pre id="check">` as JSON.
const CHECK_SCRIPT: &str = r#"<script>
(function () {
  var figs = Array.prototype.map.call(document.querySelectorAll('figure > svg'), function (svg) {
    var r = svg.getBoundingClientRect();
    var drawn = 0;
    svg.querySelectorAll('polyline, path, line, rect, circle, polygon').forEach(function (e) {
      var b = e.getBBox();
      if (b.width > 0 || b.height > 0) { drawn += 1; }
    });
    return { id: svg.parentNode.id, width: r.width, height: r.height, top: r.top, drawn: drawn };
  });
  var table = document.getElementById('summary');
  var pre = document.createElement('pre');
  pre.id = 'check';
  pre.textContent = JSON.stringify({
    svgs: document.querySelectorAll('svg').length,
    figures: figs,
    summary_rows: table ? table.rows.length : 0
  });
  document.body.appendChild(pre);
})();
</script>"#;

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "strafeopt-test-browser-{name}-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
    dir
}

/// Runs headless Chromium with a fresh profile; returns its stdout. Fails the test after the timeout.
fn chromium(dir: &Path, extra: &[String], page: &Path) -> String {
    let profile = dir.join(format!("profile-{}", extra.len()));
    let out_path = dir.join(format!("stdout-{}.txt", extra.len()));
    let out_file = std::fs::File::create(&out_path).unwrap_or_else(|e| panic!("{e}"));
    let mut child = Command::new(CHROMIUM)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--no-first-run",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(extra)
        .arg(format!("file://{}", page.display()))
        .stdin(Stdio::null())
        .stdout(out_file)
        .stderr(Stdio::null())
        .spawn()
        .unwrap_or_else(|e| panic!("start {CHROMIUM}: {e}"));
    let started = Instant::now();
    loop {
        match child.try_wait() {
            Ok(Some(_)) => break,
            Ok(None) if started.elapsed() < BROWSER_TIMEOUT => {
                std::thread::sleep(Duration::from_millis(100))
            }
            Ok(None) => {
                let _ = child.kill();
                let _ = child.wait();
                panic!("chromium took more than {BROWSER_TIMEOUT:?}");
            }
            Err(e) => panic!("waiting for chromium: {e}"),
        }
    }
    std::fs::read_to_string(&out_path).unwrap_or_default()
}

/// True under CI: `CI` set to `true` (any case) or `1`, as CI services set it.
fn under_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| v.eq_ignore_ascii_case("true") || v == "1")
}

#[test]
fn every_figure_is_drawn_in_the_browser() {
    if !Path::new(CHROMIUM).exists() {
        assert!(
            !under_ci(),
            "report_browser: {CHROMIUM} not found, and CI must run the browser test (install chromium)"
        );
        println!("report_browser: {CHROMIUM} not found; the browser test is skipped");
        return;
    }
    let dir = temp_dir("figures");
    let report = dir.join("report.html");
    let out = BinCommand::cargo_bin("strafeopt")
        .map(|mut c| {
            c.current_dir(env!("CARGO_MANIFEST_DIR"))
                .args(["simulate", "scenarios/hl-hairpin-100fps.toml", "--report"])
                .arg(&report)
                .output()
        })
        .unwrap_or_else(|e| panic!("binary: {e}"))
        .unwrap_or_else(|e| panic!("run: {e}"));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let html = std::fs::read_to_string(&report).unwrap_or_else(|e| panic!("{e}"));
    let checked = dir.join("checked.html");
    std::fs::write(
        &checked,
        html.replace("</body>", &format!("{CHECK_SCRIPT}\n</body>")),
    )
    .unwrap_or_else(|e| panic!("{e}"));

    let dom = chromium(&dir, &["--dump-dom".to_string()], &checked);
    let start = dom
        .find("<pre id=\"check\">")
        .map(|i| i + "<pre id=\"check\">".len())
        .unwrap_or_else(|| panic!("the check did not run; DOM of {} bytes", dom.len()));
    let end = dom[start..]
        .find("</pre>")
        .map(|j| start + j)
        .unwrap_or(dom.len());
    let check: Value = serde_json::from_str(&dom[start..end].replace("&amp;", "&"))
        .unwrap_or_else(|e| panic!("{e}: {}", &dom[start..end]));
    let count = strafeopt::report::html::FIGURE_IDS.len() as u64;
    assert_eq!(check["svgs"].as_u64(), Some(count), "{check}");
    let figures = check["figures"].as_array().cloned().unwrap_or_default();
    assert_eq!(figures.len() as u64, count, "{check}");
    let ids: Vec<&str> = figures.iter().filter_map(|f| f["id"].as_str()).collect();
    assert_eq!(ids, strafeopt::report::html::FIGURE_IDS);
    let mut previous_bottom = f64::NEG_INFINITY;
    for f in &figures {
        let (w, h, top) = (
            f["width"].as_f64().unwrap_or(0.0),
            f["height"].as_f64().unwrap_or(0.0),
            f["top"].as_f64().unwrap_or(0.0),
        );
        assert!(w >= 900.0 && h >= 300.0, "figure laid out too small: {f}");
        assert!(top >= previous_bottom, "figures overlap: {f}");
        previous_bottom = top + h;
        assert!(
            f["drawn"].as_u64().unwrap_or(0) >= 20,
            "figure nearly empty: {f}"
        );
    }
    assert!(check["summary_rows"].as_u64().unwrap_or(0) >= 15, "{check}");

    // And a screenshot of the page as printed (no script): a PNG of a page with figures, not a blank one.
    let png = dir.join("report.png");
    chromium(
        &dir,
        &[
            format!("--screenshot={}", png.display()),
            "--window-size=1200,4000".to_string(),
        ],
        &report,
    );
    let bytes = std::fs::read(&png).unwrap_or_default();
    assert!(bytes.starts_with(b"\x89PNG"), "no screenshot written");
    assert!(
        bytes.len() > 50_000,
        "screenshot of {} bytes: a blank page?",
        bytes.len()
    );
    let _ = std::fs::remove_dir_all(&dir);
}
