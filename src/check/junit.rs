//! `check --junit out.xml`: the JUnit XML report CI services read (one `<testsuite>`, one `<testcase>` per
//! scene file; a regression is a `<failure>`, bad input an `<error>`, a file without `[expect]`
//! `<skipped>`).
//!
//! ```xml
//! <?xml version="1.0" encoding="UTF-8"?>
//! <testsuites name="strafeopt check" tests="2" failures="1" errors="0" skipped="0" time="1.612">
//!   <testsuite name="strafeopt check" tests="2" failures="1" errors="0" skipped="0" time="1.612">
//!     <testcase classname="scenarios" name="hl-bend90-100fps.toml" file="scenarios/hl-bend90-100fps.toml" time="0.801">
//!       <system-out>solve fast: frame 401, 4.001483 s, gap 0.562%, valid, engine-exact valid, converged</system-out>
//!     </testcase>
//!     <testcase classname="scenarios" name="hl-sbend-100fps.toml" file="scenarios/hl-sbend-100fps.toml" time="0.811">
//!       <failure type="regression" message="frames 552 &gt; 551 (+1 frame)">...</failure>
//!     </testcase>
//!   </testsuite>
//! </testsuites>
//! ```

use super::{measured_text, CheckReport, SceneCheck, Verdict};
use std::io::Write;

/// Writes the report as JUnit XML.
pub fn write_junit(report: &CheckReport, w: &mut impl Write) -> std::io::Result<()> {
    let s = report.summary();
    let counts = format!(
        "tests=\"{}\" failures=\"{}\" errors=\"{}\" skipped=\"{}\" time=\"{:.3}\"",
        s.scenes, s.failed, s.errors, s.skipped, report.seconds
    );
    writeln!(w, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>")?;
    writeln!(w, "<testsuites name=\"strafeopt check\" {counts}>")?;
    writeln!(w, "  <testsuite name=\"strafeopt check\" {counts}>")?;
    for c in &report.scenes {
        write_case(c, w)?;
    }
    writeln!(w, "  </testsuite>")?;
    writeln!(w, "</testsuites>")
}

fn write_case(c: &SceneCheck, w: &mut impl Write) -> std::io::Result<()> {
    let name = c.path.file_name().map_or_else(
        || c.path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    let class = c
        .path
        .parent()
        .map(|p| p.display().to_string())
        .filter(|p| !p.is_empty())
        .unwrap_or_else(|| ".".to_string());
    writeln!(
        w,
        "    <testcase classname=\"{}\" name=\"{}\" file=\"{}\" time=\"{:.3}\">",
        escape(&class),
        escape(&name),
        escape(&c.path.display().to_string()),
        c.seconds
    )?;
    let run = c.run.as_deref().unwrap_or("-");
    match &c.verdict {
        Verdict::Fail(failures) if c.update.is_none() => {
            let summary: Vec<&str> = failures.iter().map(|f| f.message.as_str()).collect();
            writeln!(
                w,
                "      <failure type=\"regression\" message=\"{}\">{}</failure>",
                escape(&summary.join("; ")),
                escape(&format!("{run}\n{}", summary.join("\n")))
            )?;
        }
        Verdict::Error(message) => writeln!(
            w,
            "      <error type=\"bad-input\" message=\"{}\"/>",
            escape(message)
        )?,
        Verdict::Skipped(why) => writeln!(w, "      <skipped message=\"{}\"/>", escape(why))?,
        Verdict::Pass | Verdict::Fail(_) => {}
    }
    if let Some(m) = &c.measured {
        writeln!(
            w,
            "      <system-out>{}</system-out>",
            escape(&format!("{run}: {}", measured_text(m)))
        )?;
    }
    writeln!(w, "    </testcase>")
}

/// Text for an XML attribute or element: the five special characters escaped, and the characters XML 1.0
/// cannot hold at all (control characters other than tab, line feed and carriage return) replaced by
/// U+FFFD.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for ch in text.chars() {
        match ch {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            '\t' => out.push_str("&#9;"),
            '\n' => out.push_str("&#10;"),
            '\r' => out.push_str("&#13;"),
            c if (c as u32) < 0x20 || matches!(c, '\u{FFFE}' | '\u{FFFF}') => out.push('\u{FFFD}'),
            c => out.push(c),
        }
    }
    out
}
