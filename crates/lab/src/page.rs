//! The report page as a list of blocks, written twice: as Markdown
//! (`tables.md`) and as an HTML page that opens offline (`index.html`: no
//! script, no network, pictures as relative links, and under a picture the
//! links to the run viewer's pages of the runs it draws; the picture itself
//! opens the first).

use std::fmt::Write as _;

/// A picture on the page.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Figure {
    /// Caption under the picture.
    pub title: String,
    /// Path relative to the report folder (e.g. `pictures/e1-field01.png`).
    pub src: String,
    /// The runs it draws, each linked to its viewer page
    /// ([`crate::suite::ReportContext::viewer_page`]; a scenario's runs are
    /// on one page, [`crate::suite::ReportContext::viewer_runs_page`], each
    /// at its `#run=K`). The picture links the first.
    pub runs: Vec<RunLink>,
}

/// A link to one run's viewer page.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RunLink {
    /// What the link says (`#0`, `leg 3`…).
    pub label: String,
    /// Path relative to the report folder (e.g. `viewer/e1-field01-0.html`).
    pub href: String,
}

/// One block of the page.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Block {
    /// A Markdown table: header row, separator row, rows.
    Table(String),
    /// A section heading.
    Heading(String),
    /// Markdown paragraphs separated by blank lines; a paragraph that starts
    /// with `## ` is a heading.
    Text(String),
    /// Pictures under a heading, with an explanation (HTML page only).
    Figures {
        /// Section heading.
        heading: String,
        /// What the pictures show.
        caption: String,
        /// The pictures.
        figures: Vec<Figure>,
    },
    /// SVG charts drawn into the page itself (inline, scaled to the page's
    /// width, kept whole on a printed page), under a heading (HTML page
    /// only; the Markdown page names them).
    InlineCharts {
        /// Section heading.
        heading: String,
        /// What the charts show.
        caption: String,
        /// (title, SVG markup) of each chart.
        charts: Vec<(String, String)>,
    },
    /// Charts under a heading, shown wide (HTML page only).
    Charts {
        /// Section heading.
        heading: String,
        /// What the charts show.
        caption: String,
        /// The charts.
        figures: Vec<Figure>,
    },
}

/// A report page.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Page {
    /// Title (the suite's name).
    pub title: String,
    /// The first paragraph (runs, seed), Markdown.
    pub intro: String,
    /// Links to the raw data, HTML page only (appended to the intro).
    pub raw_data: String,
    /// The blocks, in order.
    pub blocks: Vec<Block>,
}

/// Escapes text for HTML.
pub fn html_escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// Text for HTML with Markdown's inline `**strong**` and `` `code` ``
/// (escaped first; a text with an unpaired marker keeps its markers).
pub fn inline_html(s: &str) -> String {
    fn pairs(text: &str, marker: &str, tag: &str, inner: impl Fn(&str) -> String) -> String {
        let parts: Vec<&str> = text.split(marker).collect();
        if parts.len() % 2 == 0 {
            return parts.iter().map(|p| inner(p)).collect::<Vec<_>>().join(marker);
        }
        let mut out = String::new();
        for (k, p) in parts.iter().enumerate() {
            if k % 2 == 1 {
                let _ = write!(out, "<{tag}>{}</{tag}>", inner(p));
            } else {
                out.push_str(&inner(p));
            }
        }
        out
    }
    pairs(&html_escape(s), "`", "code", |t| {
        pairs(t, "**", "strong", str::to_string)
    })
}

/// A Markdown table as an HTML table (the separator row is dropped; cells
/// keep their inline `**strong**` and `` `code` ``, as [`inline_html`]).
pub fn table_to_html(md: &str) -> String {
    let mut out = String::from("<table>\n");
    for (i, line) in md.lines().enumerate() {
        if i == 1 {
            continue;
        }
        let cells: Vec<&str> = line.trim().trim_matches('|').split('|').map(str::trim).collect();
        let tag = if i == 0 { "th" } else { "td" };
        out.push_str("<tr>");
        for c in cells {
            let _ = write!(out, "<{tag}>{}</{tag}>", inline_html(c));
        }
        out.push_str("</tr>\n");
    }
    out.push_str("</table>\n");
    out
}

const STYLE: &str = "body{font-family:system-ui,sans-serif;max-width:1200px;margin:2em auto;padding:0 1em;color:#222}\ntable{border-collapse:collapse;margin:1em 0;font-size:14px}\ntd,th{border:1px solid #ccc;padding:3px 8px;text-align:right}\ntd:first-child,th:first-child{text-align:left}\nth{background:#f2f2f2}\n.pics{display:flex;flex-wrap:wrap;gap:12px}\nfigure{margin:0;width:280px}\nfigure img{width:280px;border:1px solid #ccc}\nfigcaption{font-size:13px}\n.runs{color:#555}\n.runs a{margin-left:4px}\nfigure.chart{width:760px}\nfigure.chart img{width:760px;border:none}\nfigure.inline-chart{width:100%;margin:1em 0}\nfigure.inline-chart svg{width:100%;height:auto;display:block}\n@media print{body{max-width:none;margin:0}figure.inline-chart{break-inside:avoid;page-break-inside:avoid}h2{break-after:avoid}}\ncode{background:#f4f4f4;padding:0 2px}\n";

impl Page {
    /// The page as Markdown (tables and text; pictures are on the HTML
    /// page only).
    pub fn markdown(&self) -> String {
        let mut md = format!("# {} — results\n\n{}\n\n", self.title, self.intro);
        for b in &self.blocks {
            match b {
                Block::Table(t) => {
                    md.push_str(t);
                    md.push('\n');
                }
                Block::Heading(h) => {
                    let _ = write!(md, "\n## {h}\n\n");
                }
                Block::Text(t) => md.push_str(t),
                Block::Figures { .. } | Block::Charts { .. } => {}
                Block::InlineCharts { heading, charts, .. } => {
                    let _ = writeln!(md, "## {heading}\n");
                    for (title, _) in charts {
                        let _ = writeln!(md, "- chart: {title} (in index.html)");
                    }
                    md.push('\n');
                }
            }
        }
        md
    }

    /// The page as a self-contained HTML document.
    pub fn html(&self) -> String {
        let mut html = String::new();
        let _ = write!(
            html,
            "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{0} — petrinav report</title>\n<style>\n{STYLE}</style></head><body>\n<h1>{0}</h1>\n<p>{1} {2}</p>\n",
            html_escape(&self.title),
            html_escape(&self.intro),
            self.raw_data,
        );
        for b in &self.blocks {
            match b {
                Block::Table(t) => html.push_str(&table_to_html(t)),
                Block::Heading(h) => {
                    let _ = writeln!(html, "<h2>{}</h2>", html_escape(h));
                }
                Block::Text(t) => {
                    for para in t.split("\n\n").filter(|p| !p.trim().is_empty()) {
                        let p = para.trim();
                        if let Some(h) = p.strip_prefix("## ") {
                            let _ = writeln!(html, "<h2>{}</h2>", html_escape(h));
                        } else {
                            let _ = writeln!(html, "<p>{}</p>", inline_html(&p.replace('\n', " ")));
                        }
                    }
                }
                Block::InlineCharts {
                    heading,
                    caption,
                    charts,
                } => {
                    let _ = writeln!(
                        html,
                        "<h2>{}</h2>\n<p>{}</p>",
                        html_escape(heading),
                        inline_html(caption)
                    );
                    for (title, svg) in charts {
                        let _ = writeln!(
                            html,
                            "<figure class=\"inline-chart\">{svg}<figcaption>{}</figcaption></figure>",
                            html_escape(title)
                        );
                    }
                }
                Block::Figures {
                    heading,
                    caption,
                    figures,
                }
                | Block::Charts {
                    heading,
                    caption,
                    figures,
                } => {
                    let class = if matches!(b, Block::Charts { .. }) {
                        " class=\"chart\""
                    } else {
                        ""
                    };
                    let _ = writeln!(
                        html,
                        "<h2>{}</h2>\n<p>{}</p>\n<div class=\"pics\">",
                        html_escape(heading),
                        inline_html(caption)
                    );
                    for f in figures {
                        let runs = if f.runs.is_empty() {
                            String::new()
                        } else {
                            let links: Vec<String> = f
                                .runs
                                .iter()
                                .map(|r| {
                                    format!(
                                        "<a href=\"{}\">{}</a>",
                                        html_escape(&r.href),
                                        html_escape(&r.label)
                                    )
                                })
                                .collect();
                            format!("<br><span class=\"runs\">viewer:{}</span>", links.join(""))
                        };
                        // The picture opens its first run's viewer page, if it
                        // has one, else the picture itself.
                        let target = f.runs.first().map_or(&f.src, |r| &r.href);
                        let _ = writeln!(
                            html,
                            "<figure{class}><a href=\"{target}\"><img src=\"{src}\" alt=\"{0}\"></a><figcaption>{0}{runs}</figcaption></figure>",
                            html_escape(&f.title),
                            target = html_escape(target),
                            src = html_escape(&f.src),
                        );
                    }
                    html.push_str("</div>\n");
                }
            }
        }
        html.push_str("</body></html>\n");
        html
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_page_renders_to_markdown_and_html() {
        let page = Page {
            title: "demo <1>".into(),
            intro: "3 runs per scenario, base seed 1.".into(),
            raw_data: "Raw data: <a href=\"results.jsonl\">results.jsonl</a>.".into(),
            blocks: vec![
                Block::Table("| a | b |\n|---|---:|\n| x | 1.00 |\n".into()),
                Block::Heading("More".into()),
                Block::Text("\n## Why\n\nBecause a < b\nand so on.\n".into()),
                Block::Figures {
                    heading: "Pictures".into(),
                    caption: "runs".into(),
                    figures: vec![Figure {
                        title: "x".into(),
                        src: "pictures/x.png".into(),
                        runs: vec![RunLink {
                            label: "#0".into(),
                            href: "viewer/x-0.html".into(),
                        }],
                    }],
                },
            ],
        };
        let md = page.markdown();
        assert!(md.starts_with("# demo <1> — results\n\n3 runs"), "{md}");
        assert!(md.contains("| x | 1.00 |\n\n\n## More\n\n\n## Why"), "{md}");
        assert!(!md.contains("pictures/x.png"));
        let html = page.html();
        assert!(html.contains("<h1>demo &lt;1&gt;</h1>"));
        assert!(html.contains("<tr><td>x</td><td>1.00</td></tr>"));
        assert!(html.contains("<p>Because a &lt; b and so on.</p>"));
        assert!(html.contains("<a href=\"viewer/x-0.html\"><img src=\"pictures/x.png\" alt=\"x\"></a>"));
        assert!(html.contains(
            "<figcaption>x<br><span class=\"runs\">viewer:<a href=\"viewer/x-0.html\">#0</a></span>"
        ));
        assert!(html.ends_with("</body></html>\n"));
    }

    #[test]
    fn inline_markdown_becomes_html() {
        assert_eq!(
            inline_html("**a** and `b<c`"),
            "<strong>a</strong> and <code>b&lt;c</code>"
        );
        assert_eq!(inline_html("2 ** 3"), "2 ** 3");
        // Table cells too: a verdict in bold is bold on the page.
        assert!(
            table_to_html("| a | b |\n|---|---|\n| **no** | x<y |\n")
                .contains("<tr><td><strong>no</strong></td><td>x&lt;y</td></tr>")
        );
        assert_eq!(inline_html("one ` tick"), "one ` tick");
    }
}
