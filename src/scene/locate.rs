//! Where a key sits in a scene file: every key of the parsed document with its line, so that errors found
//! after parsing (a zero-length wall segment, a start inside a wall) name the right `file:line`.
//!
//! Keys are written as in messages: `engine.fps`, `walls[2].points`, `walls[2].points[3]`.

use crate::error::Error;
use std::ops::Range;
use toml::de::{DeTable, DeValue};
use toml::Spanned;

/// One key or array element of the document.
#[derive(Clone, Debug)]
struct Entry {
    path: String,
    /// The key's own text (absent for array elements).
    key_span: Option<Range<usize>>,
    /// The value (for a `[table]` or `[[array]]` element, its header).
    value_span: Range<usize>,
}

/// The keys of one document and the text they came from.
#[derive(Clone, Debug)]
pub(crate) struct KeyIndex<'t> {
    origin: String,
    text: &'t str,
    entries: Vec<Entry>,
}

impl<'t> KeyIndex<'t> {
    /// The index of a parsed document.
    pub fn new(origin: &str, text: &'t str, doc: &Spanned<DeTable<'_>>) -> Self {
        let mut entries = Vec::new();
        walk_table(doc.get_ref(), "", &mut entries);
        KeyIndex {
            origin: one_line(origin),
            text,
            entries,
        }
    }

    /// An index that knows no keys (errors then carry the file name alone).
    pub fn empty(origin: &str, text: &'t str) -> Self {
        KeyIndex {
            origin: one_line(origin),
            text,
            entries: Vec::new(),
        }
    }

    /// The 1-based line of byte `offset`.
    pub fn line_of_offset(&self, offset: usize) -> usize {
        let end = offset.min(self.text.len());
        self.text.as_bytes()[..end]
            .iter()
            .filter(|&&b| b == b'\n')
            .count()
            + 1
    }

    /// The line of `path`, or of its nearest ancestor present in the file (a key filled in by a default
    /// points at its table); `None` when not even the top-level key is there.
    pub fn line_of(&self, path: &str) -> Option<usize> {
        let mut p = path;
        loop {
            if let Some(e) = self.entries.iter().find(|e| e.path == p) {
                let span = e.key_span.as_ref().unwrap_or(&e.value_span);
                return Some(self.line_of_offset(span.start));
            }
            p = parent(p)?;
        }
    }

    /// The innermost key whose text or value holds byte `offset`.
    pub fn path_at(&self, offset: usize) -> Option<&str> {
        let holds = |r: &Range<usize>| r.start <= offset && (offset < r.end || r.is_empty());
        self.entries
            .iter()
            .filter_map(|e| {
                [e.key_span.as_ref(), Some(&e.value_span)]
                    .into_iter()
                    .flatten()
                    .filter(|r| holds(r))
                    .map(|r| r.len())
                    .min()
                    .map(|len| (len, e.path.as_str()))
            })
            .min_by_key(|&(len, _)| len)
            .map(|(_, path)| path)
    }

    /// `origin:line` for `path` (just `origin` when the line is unknown).
    pub fn location(&self, path: &str) -> String {
        match self.line_of(path) {
            Some(line) => format!("{}:{line}", self.origin),
            None => self.origin.clone(),
        }
    }

    /// A scene error at `path`, located by the key `locate_at` (often `path` itself, or a point inside it).
    pub fn error_at(&self, path: &str, locate_at: &str, message: impl Into<String>) -> Error {
        Error::Scene {
            location: self.location(locate_at),
            key: one_line(path),
            message: one_line(&message.into()),
        }
    }

    /// A scene error at `path`, on the line of `path`.
    pub fn error(&self, path: &str, message: impl Into<String>) -> Error {
        self.error_at(path, path, message)
    }

    /// A scene error from the TOML reader: its span gives the line and, when the document parsed, the key.
    pub fn toml_error(&self, e: &toml::de::Error) -> Error {
        let (location, key) = match e.span() {
            Some(span) => (
                format!("{}:{}", self.origin, self.line_of_offset(span.start)),
                self.path_at(span.start).unwrap_or("-").to_string(),
            ),
            None => (self.origin.clone(), "-".to_string()),
        };
        Error::Scene {
            location,
            key,
            message: one_line(&friendly(e.message())),
        }
    }
}

/// `walls[2].points` -> `walls[2]` -> `walls`; `None` at the top.
fn parent(path: &str) -> Option<&str> {
    let cut = path.rfind(['.', '['])?;
    Some(&path[..cut])
}

fn walk_table(table: &DeTable<'_>, prefix: &str, out: &mut Vec<Entry>) {
    for (k, v) in table.iter() {
        // A quoted key may hold any character; written as an escape, a line break cannot split a message.
        let name = one_line(k.get_ref());
        let path = if prefix.is_empty() {
            name
        } else {
            format!("{prefix}.{name}")
        };
        out.push(Entry {
            path: path.clone(),
            key_span: Some(k.span()),
            value_span: v.span(),
        });
        walk_value(v.get_ref(), &path, out);
    }
}

fn walk_value(value: &DeValue<'_>, path: &str, out: &mut Vec<Entry>) {
    match value {
        DeValue::Table(t) => walk_table(t, path, out),
        DeValue::Array(items) => {
            for (i, item) in items.iter().enumerate() {
                let item_path = format!("{path}[{i}]");
                out.push(Entry {
                    path: item_path.clone(),
                    key_span: None,
                    value_span: item.span(),
                });
                walk_value(item.get_ref(), &item_path, out);
            }
        }
        _ => {}
    }
}

/// `text` with every character that would break an error's one line (control characters such as `\n`,
/// `\r` or NUL, and the Unicode line and paragraph separators) written as its escape (`\n`, `\u{2028}`).
/// File names, quoted keys and string values can hold any of them.
pub(crate) fn one_line(text: &str) -> String {
    let breaks = |c: char| c.is_control() || matches!(c, '\u{2028}' | '\u{2029}');
    if !text.contains(breaks) {
        return text.to_string();
    }
    text.chars()
        .map(|c| {
            if breaks(c) {
                c.escape_default().to_string()
            } else {
                c.to_string()
            }
        })
        .collect()
}

/// The TOML reader's message in the words of a scene file (`f64` -> `a number`).
fn friendly(message: &str) -> String {
    message
        .replace("expected f64", "expected a number")
        .replace("expected u64", "expected a whole number of at least 0")
        .replace("expected a boolean", "expected true or false")
        .replace('\n', " ")
}
