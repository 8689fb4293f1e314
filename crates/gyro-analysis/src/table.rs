//! The one routine every table for people goes through (the CLI's listings and the analysis
//! reports): columns padded to their widest cell, two spaces apart, left or right aligned,
//! optionally a header with a rule under it; or the same cells as a Markdown table.

/// How a column's cells line up.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Align {
    Left,
    Right,
}

/// Rows of text cells. Build with [`Table::new`] (or [`Table::headless`]), set alignments, add
/// rows, then [`Table::render`] or [`Table::render_markdown`].
#[derive(Clone, Debug, Default)]
pub struct Table {
    header: Option<Vec<String>>,
    align: Vec<Align>,
    rows: Vec<Vec<String>>,
    indent: String,
    rule: bool,
}

impl Table {
    /// A table with these column titles, every column left-aligned.
    pub fn new<S: AsRef<str>>(header: &[S]) -> Table {
        Table {
            header: Some(header.iter().map(|s| s.as_ref().to_owned()).collect()),
            align: vec![Align::Left; header.len()],
            ..Table::default()
        }
    }

    /// A table of `columns` columns without titles.
    pub fn headless(columns: usize) -> Table {
        Table {
            align: vec![Align::Left; columns],
            ..Table::default()
        }
    }

    /// Aligns column `column`.
    pub fn align(mut self, column: usize, align: Align) -> Table {
        if let Some(a) = self.align.get_mut(column) {
            *a = align;
        }
        self
    }

    /// Aligns every column after the first to the right (a label, then numbers).
    pub fn numbers_right(mut self) -> Table {
        for a in self.align.iter_mut().skip(1) {
            *a = Align::Right;
        }
        self
    }

    /// Starts every rendered line with `indent`.
    pub fn indent(mut self, indent: &str) -> Table {
        self.indent = indent.to_owned();
        self
    }

    /// Draws a rule of dashes under the header.
    pub fn rule(mut self) -> Table {
        self.rule = true;
        self
    }

    /// Adds a row (missing cells are empty, extra cells are dropped).
    pub fn row<S: Into<String>>(&mut self, cells: impl IntoIterator<Item = S>) {
        let mut r: Vec<String> = cells.into_iter().map(Into::into).collect();
        r.resize(self.align.len(), String::new());
        self.rows.push(r);
    }

    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    fn lines(&self) -> impl Iterator<Item = &Vec<String>> {
        self.header.iter().chain(&self.rows)
    }

    /// Aligned columns for a terminal, one line per row, each ending in a newline (trailing
    /// spaces trimmed).
    pub fn render(&self) -> String {
        let widths: Vec<usize> = (0..self.align.len())
            .map(|c| {
                self.lines()
                    .map(|l| l[c].chars().count())
                    .max()
                    .unwrap_or(0)
            })
            .collect();
        let line = |r: &Vec<String>| {
            let cells: Vec<String> = r
                .iter()
                .zip(&widths)
                .zip(&self.align)
                .map(|((s, w), a)| {
                    let pad = " ".repeat(w.saturating_sub(s.chars().count()));
                    match a {
                        Align::Left => format!("{s}{pad}"),
                        Align::Right => format!("{pad}{s}"),
                    }
                })
                .collect();
            format!("{}{}\n", self.indent, cells.join("  ").trim_end())
        };
        let mut out = String::new();
        if let Some(h) = &self.header {
            out.push_str(&line(h));
            if self.rule {
                let total = widths.iter().sum::<usize>() + 2 * widths.len().saturating_sub(1);
                out.push_str(&format!("{}{}\n", self.indent, "-".repeat(total)));
            }
        }
        for r in &self.rows {
            out.push_str(&line(r));
        }
        out
    }

    /// The same cells as a Markdown table (`|` in cells escaped; right-aligned columns marked
    /// `---:`, left-aligned `:---`).
    pub fn render_markdown(&self) -> String {
        let esc = |s: &String| s.replace('|', "\\|");
        let row = |r: &Vec<String>| {
            format!(
                "| {} |\n",
                r.iter().map(esc).collect::<Vec<_>>().join(" | ")
            )
        };
        let empty = vec![String::new(); self.align.len()];
        let mut out = row(self.header.as_ref().unwrap_or(&empty));
        let marks: Vec<&str> = self
            .align
            .iter()
            .map(|a| match a {
                Align::Left => ":---",
                Align::Right => "---:",
            })
            .collect();
        out.push_str(&format!("|{}|\n", marks.join("|")));
        for r in &self.rows {
            out.push_str(&row(r));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pads_aligns_and_trims() {
        let mut t = Table::new(&["metric", "a", "bb"]).numbers_right().rule();
        t.row(["period", "1.5", "12.25"]);
        t.row(["x", "", "3"]);
        assert_eq!(
            t.render(),
            "metric    a     bb\n------------------\nperiod  1.5  12.25\nx                3\n"
        );
        assert_eq!(
            t.render_markdown(),
            "| metric | a | bb |\n|:---|---:|---:|\n| period | 1.5 | 12.25 |\n| x |  | 3 |\n"
        );
        let mut h = Table::headless(2).indent("  ");
        h.row(["k", "v|w"]);
        assert_eq!(h.render(), "  k  v|w\n");
        assert!(h.render_markdown().contains("v\\|w"));
    }
}
