//! Plain-text tables with right-aligned columns, the layout of the paper's tables.

use std::fmt::Write;

/// A table: a title, a header row, data rows and notes printed beneath.
pub struct Table {
    title: String,
    header: Vec<String>,
    rows: Vec<Vec<String>>,
    notes: Vec<String>,
}

impl Table {
    /// An empty table with these column headers.
    pub fn new(title: impl Into<String>, header: &[&str]) -> Table {
        Table {
            title: title.into(),
            header: header.iter().map(|s| s.to_string()).collect(),
            rows: Vec::new(),
            notes: Vec::new(),
        }
    }

    /// Adds a row; it must have one cell per header.
    pub fn row(&mut self, cells: Vec<String>) {
        debug_assert_eq!(cells.len(), self.header.len());
        self.rows.push(cells);
    }

    /// Adds a line printed under the table.
    pub fn note(&mut self, note: impl Into<String>) {
        self.notes.push(note.into());
    }

    /// The table as text.
    pub fn render(&self) -> String {
        let mut widths: Vec<usize> = self.header.iter().map(|h| h.chars().count()).collect();
        for r in &self.rows {
            for (w, c) in widths.iter_mut().zip(r) {
                *w = (*w).max(c.chars().count());
            }
        }
        let line = |cells: &[String]| {
            let mut s = String::new();
            for (i, (c, w)) in cells.iter().zip(&widths).enumerate() {
                if i > 0 {
                    s.push_str("  ");
                }
                let pad = w - c.chars().count();
                s.extend(std::iter::repeat_n(' ', pad));
                s.push_str(c);
            }
            s.push('\n');
            s
        };
        let mut out = String::new();
        let _ = writeln!(out, "{}", self.title);
        out.push_str(&line(&self.header));
        let total: usize = widths.iter().sum::<usize>() + 2 * widths.len().saturating_sub(1);
        out.push_str(&"-".repeat(total));
        out.push('\n');
        for r in &self.rows {
            out.push_str(&line(r));
        }
        for n in &self.notes {
            let _ = writeln!(out, "{n}");
        }
        out.push('\n');
        out
    }
}

/// A percentage with no decimals, as the paper prints them ("303%").
pub fn pct(x: f64) -> String {
    if x.is_finite() {
        // Our figures are often far below the paper's: keep two significant digits.
        if x >= 10.0 || x <= 0.0 {
            format!("{x:.0}%")
        } else {
            let decimals = (1.0 - x.log10().floor()) as usize;
            format!("{x:.decimals$}%")
        }
    } else {
        "-".into()
    }
}

/// A value or a dash when absent.
pub fn opt(x: Option<f64>, f: impl Fn(f64) -> String) -> String {
    x.map(f).unwrap_or_else(|| "-".into())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn columns_are_right_aligned() {
        let mut t = Table::new("T", &["a", "bbb"]);
        t.row(vec!["10".into(), "1".into()]);
        let s = t.render();
        assert_eq!(s, "T\n a  bbb\n-------\n10    1\n\n");
    }

    #[test]
    fn percentages_keep_two_significant_digits() {
        assert_eq!(pct(303.4), "303%");
        assert_eq!(pct(5.96), "6.0%");
        assert_eq!(pct(0.0123), "0.012%");
    }
}
