//! Human-readable output: aligned tables and number formatting, and the
//! `out!`/`outln!` macros that write to standard output and return an
//! `io::Result` (so that `petrinav … | head` ends quietly instead of
//! panicking on a closed pipe).

/// Like `print!`, returning `std::io::Result<()>`.
#[macro_export]
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        write!(std::io::stdout().lock(), $($arg)*)
    }};
}

/// Like `println!`, returning `std::io::Result<()>`.
#[macro_export]
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock(), $($arg)*)
    }};
}

use std::fmt::Write as _;

/// A text table with a header line; numeric-looking columns align right.
#[derive(Debug, Default)]
pub struct Table {
    header: Vec<String>,
    rows: Vec<Vec<String>>,
}

impl Table {
    pub fn new<S: Into<String>>(header: impl IntoIterator<Item = S>) -> Table {
        Table {
            header: header.into_iter().map(Into::into).collect(),
            rows: Vec::new(),
        }
    }

    pub fn row<S: Into<String>>(&mut self, cells: impl IntoIterator<Item = S>) {
        self.rows.push(cells.into_iter().map(Into::into).collect());
    }

    pub fn render(&self) -> String {
        let cols = self.header.len();
        let mut width = vec![0usize; cols];
        let mut numeric = vec![true; cols];
        for row in std::iter::once(&self.header).chain(&self.rows) {
            for (c, cell) in row.iter().enumerate().take(cols) {
                width[c] = width[c].max(cell.chars().count());
            }
        }
        for row in &self.rows {
            for (c, cell) in row.iter().enumerate().take(cols) {
                if cell.parse::<f64>().is_err() && cell != "-" {
                    numeric[c] = false;
                }
            }
        }
        let mut out = String::new();
        let line = |out: &mut String, row: &[String]| {
            for c in 0..cols {
                let cell = row.get(c).map_or("", String::as_str);
                let pad = width[c] - cell.chars().count();
                if c > 0 {
                    out.push_str("  ");
                }
                if numeric[c] {
                    out.push_str(&" ".repeat(pad));
                    out.push_str(cell);
                } else {
                    out.push_str(cell);
                    if c + 1 < cols {
                        out.push_str(&" ".repeat(pad));
                    }
                }
            }
            out.push('\n');
        };
        line(&mut out, &self.header);
        let rule: Vec<String> = width.iter().map(|&w| "-".repeat(w)).collect();
        let _ = write!(out, "{}", rule.join("  "));
        out.push('\n');
        for row in &self.rows {
            line(&mut out, row);
        }
        out
    }
}

pub use lab::tables::num;

/// `key: value` lines, keys aligned.
pub fn fields(pairs: &[(&str, String)]) -> String {
    let w = pairs.iter().map(|(k, _)| k.chars().count()).max().unwrap_or(0);
    let mut out = String::new();
    for (k, v) in pairs {
        let _ = writeln!(out, "{k:<w$}  {v}");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers() {
        assert_eq!(num(0.005348131628), "0.00534813");
        assert_eq!(num(13.0), "13");
        assert_eq!(num(1234567.0), "1234567");
        assert_eq!(num(2.5e-9), "2.50000e-9");
        assert_eq!(num(0.0), "0");
    }

    #[test]
    fn table_aligns() {
        let mut t = Table::new(["place", "mean"]);
        t.row(["P1", "0.5"]);
        t.row(["Pallets", "12.25"]);
        let s = t.render();
        assert!(s.contains("P1         0.5\n"), "{s}");
        assert!(s.contains("Pallets  12.25\n"), "{s}");
    }
}
