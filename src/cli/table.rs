//! Aligned text tables for the bench commands: two spaces between columns, text left-aligned and numbers
//! right-aligned, a last left-aligned column (notes, status) not padded.

/// Column widths, characters, that fit the header and every row.
pub fn column_widths<R: AsRef<[String]>>(header: &[&str], rows: &[R]) -> Vec<usize> {
    let mut widths: Vec<usize> = header.iter().map(|h| h.chars().count()).collect();
    for r in rows {
        for (w, c) in widths.iter_mut().zip(r.as_ref()) {
            *w = (*w).max(c.chars().count());
        }
    }
    widths
}

/// One line of the table: each cell padded to its width, on the left where `right_aligned` says so.
pub fn aligned_line(cells: &[String], widths: &[usize], right_aligned: &[bool]) -> String {
    let mut s = String::new();
    for (i, ((c, &w), &right)) in cells.iter().zip(widths).zip(right_aligned).enumerate() {
        if i > 0 {
            s.push_str("  ");
        }
        if right {
            s.push_str(&format!("{c:>w$}"));
        } else if i + 1 == cells.len() {
            s.push_str(c);
        } else {
            s.push_str(&format!("{c:<w$}"));
        }
    }
    s.trim_end().to_string() + "\n"
}

/// The header and rows as a table.
pub fn aligned_table<R: AsRef<[String]>>(
    header: &[&str],
    rows: &[R],
    right_aligned: &[bool],
) -> String {
    let widths = column_widths(header, rows);
    let header: Vec<String> = header.iter().map(|h| h.to_string()).collect();
    let mut out = aligned_line(&header, &widths, right_aligned);
    for r in rows {
        out.push_str(&aligned_line(r.as_ref(), &widths, right_aligned));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_line_up_on_the_right_and_the_last_text_column_is_not_padded() {
        let rows = vec![
            vec!["a".to_string(), "1".to_string(), "ok".to_string()],
            vec!["bbb".to_string(), "100".to_string(), "slow".to_string()],
        ];
        let t = aligned_table(&["name", "n", "note"], &rows, &[false, true, false]);
        assert_eq!(t, "name    n  note\na       1  ok\nbbb   100  slow\n");
    }
}
