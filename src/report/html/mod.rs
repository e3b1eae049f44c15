//! `report.html` and `compare.html` (docs/formats.md, "The HTML pages"): one self-contained
//! file per page. The plots are the report's own SVG files ([`super::plots`]) inlined, the
//! style sheet is inline, and a few lines of optional script sort the tables; nothing refers
//! to another file or host, so a page opens anywhere, offline, as it is.
//!
//! [`Page`] holds the pieces every page shares (headings with a contents list, tables,
//! figures with a title and a text alternative, warnings); [`run`], [`identify`] and
//! [`compare`] fill one each from results that are already computed.

pub mod compare;
pub mod history;
pub mod identify;
pub mod leaderboard;
pub mod run;

use std::fmt::Write as _;
use std::path::Path;

use crate::error::{read_text, Result};

/// The style sheet of every page: readable at 1280 px and at phone width (tables scroll
/// sideways inside their box, plots shrink to the window).
const STYLE: &str = "\
:root{color-scheme:light}\
body{font:15px/1.45 system-ui,-apple-system,'Segoe UI',sans-serif;color:#1d1d1f;margin:0 auto;\
max-width:1240px;padding:0 14px 40px;overflow-wrap:break-word}\
h1{font-size:1.55em;margin:.8em 0 .2em}h2{font-size:1.2em;border-bottom:1px solid #ccc;\
margin-top:1.8em;padding-bottom:.15em}h3{font-size:1.02em;margin:1.2em 0 .3em}\
p{margin:.4em 0 .7em;max-width:70em}\
nav{font-size:.92em;margin:.6em 0 1em}nav a{margin-right:.9em;white-space:nowrap}\
.box{overflow-x:auto;margin:.5em 0 1em}\
table{border-collapse:collapse;font-size:13px;font-variant-numeric:tabular-nums}\
p.cap{font-size:13px;color:#555;margin:.8em 0 .2em}\
th,td{border:1px solid #d8d8d8;padding:3px 7px;text-align:right;vertical-align:top}\
th{background:#f1f3f5;cursor:pointer}td.t,th.t{text-align:left}td:not(.t){white-space:nowrap}\
code{font-size:.92em;background:#f1f3f5;padding:0 3px;border-radius:3px}\
tr.regressed td,tr.failed td{background:#fde0e0}tr.regressed td:first-child{border-left:4px solid #c62828}\
tr.alone td,tr.low td{background:#eef3fb}td.flag{color:#b3261e;font-weight:600}\
.plots{display:grid;grid-template-columns:repeat(auto-fill,minmax(min(100%,520px),1fr));gap:14px}\
figure{margin:0}figure svg{display:block;width:100%;height:auto;border:1px solid #e3e3e3}\
figcaption{font-size:13px;color:#555;margin-top:3px}\
.warn{background:#fff4d6;border-left:4px solid #e0a800;padding:6px 10px;margin:.5em 0}\
.good{background:#e6f4ea;border-left:4px solid #2e7d32;padding:6px 10px;margin:.5em 0}\
pre{overflow-x:auto;background:#f6f6f6;padding:8px 10px;font-size:12px}\
dl{display:grid;grid-template-columns:max-content 1fr;gap:2px 14px;margin:.5em 0}\
dt{color:#555}dd{margin:0}summary{cursor:pointer;color:#0b57d0;margin:.4em 0}\
@media (max-width:640px){body{font-size:14px;padding:0 8px 30px}h1{font-size:1.3em}}";

/// Sorts a table by the column whose header is clicked (numbers as numbers). The page is
/// complete without it.
const SCRIPT: &str = "\
document.querySelectorAll('table.sortable th').forEach(function(th){\
th.addEventListener('click',function(){var t=th.closest('table'),b=t.tBodies[0],\
i=Array.prototype.indexOf.call(th.parentNode.children,th),d=th.dataset.d==='a'?-1:1;\
th.dataset.d=d>0?'a':'z';var rows=Array.prototype.slice.call(b.rows);\
rows.sort(function(r,s){var x=r.cells[i]?r.cells[i].textContent:'',\
y=s.cells[i]?s.cells[i].textContent:'',p=parseFloat(x),q=parseFloat(y);\
return d*(isNaN(p)||isNaN(q)?x.localeCompare(y):p-q);});\
rows.forEach(function(r){b.appendChild(r);});});});";

/// `text` with the five characters that mean something in HTML (`&`, `<`, `>`, `"`, `'`) as
/// entities, for element text and quoted attribute values alike: the one escaping every page
/// writer uses (quick-xml's, whose entities HTML5 reads the same).
pub fn escape(text: &str) -> String {
    quick_xml::escape::escape(text).into_owned()
}

/// Plain text that may hold the two inline marks of the reports' Markdown notes — `` `code` ``
/// and `**strong**` — as HTML: escaped ([`escape`]), each pair of marks as its element, so
/// that no mark shows as a character; an unpaired mark stays as written.
pub fn inline(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 16);
    let mut rest = text;
    loop {
        let code = rest.find('`');
        let strong = rest.find("**");
        let (at, mark, tag) = match (code, strong) {
            (Some(c), Some(s)) if s < c => (s, "**", "strong"),
            (Some(c), _) => (c, "`", "code"),
            (None, Some(s)) => (s, "**", "strong"),
            (None, None) => break,
        };
        let after = &rest[at + mark.len()..];
        let Some(end) = after.find(mark) else {
            break;
        };
        out += &escape(&rest[..at]);
        let _ = write!(out, "<{tag}>{}</{tag}>", escape(&after[..end]));
        rest = &after[end + mark.len()..];
    }
    out += &escape(rest);
    out
}

/// Whether a table cell reads as a number (right-aligned) rather than text.
fn numeric_cell(text: &str) -> bool {
    let t = text.trim().trim_end_matches('%');
    t == crate::report::markdown::MISSING || t.parse::<f64>().is_ok()
}

/// A page being written: a title, a contents list of its sections and the body.
pub struct Page {
    title: String,
    lead: String,
    sections: Vec<(String, String)>,
    body: String,
    figures: usize,
}

impl Page {
    /// A page titled `title` with the introductory line `lead` (plain text).
    pub fn new(title: &str, lead: &str) -> Page {
        Page {
            title: title.to_string(),
            lead: lead.to_string(),
            sections: Vec::new(),
            body: String::new(),
            figures: 0,
        }
    }

    /// Starts a section headed `title`, listed in the contents.
    pub fn section(&mut self, title: &str) {
        let id = format!("s{}", self.sections.len() + 1);
        let _ = writeln!(self.body, "<h2 id=\"{id}\">{}</h2>", escape(title));
        self.sections.push((id, title.to_string()));
    }

    /// A sub-heading within a section.
    pub fn heading(&mut self, title: &str) {
        let _ = writeln!(self.body, "<h3>{}</h3>", escape(title));
    }

    /// A paragraph of plain text ([`inline`] marks rendered).
    pub fn para(&mut self, text: &str) {
        let _ = writeln!(self.body, "<p>{}</p>", inline(text));
    }

    /// A warning in plain words, set off from the text.
    pub fn warning(&mut self, text: &str) {
        let _ = writeln!(
            self.body,
            "<p class=\"warn\"><strong>Warning:</strong> {}</p>",
            inline(text)
        );
    }

    /// A reassuring note (nothing to warn about), set off like a warning.
    pub fn fine(&mut self, text: &str) {
        let _ = writeln!(self.body, "<p class=\"good\">{}</p>", inline(text));
    }

    /// Lines of plain text folded under a line that opens them (a group of warnings).
    pub fn folded(&mut self, summary: &str, lines: &[String]) {
        let _ = write!(
            self.body,
            "<details class=\"warn\"><summary>{}</summary><ul>",
            escape(summary)
        );
        for l in lines {
            let _ = write!(self.body, "<li>{}</li>", inline(l));
        }
        self.body += "</ul></details>\n";
    }

    /// Pairs of term and value as a definition list.
    pub fn facts(&mut self, items: &[(&str, String)]) {
        self.body += "<dl>";
        for (k, v) in items {
            let _ = write!(self.body, "<dt>{}</dt><dd>{}</dd>", escape(k), escape(v));
        }
        self.body += "</dl>\n";
    }

    /// Preformatted text (a scenario's settings) under a line that opens and closes it.
    pub fn pre(&mut self, summary: &str, text: &str) {
        let _ = writeln!(
            self.body,
            "<details><summary>{}</summary><pre>{}</pre></details>",
            escape(summary),
            escape(text)
        );
    }

    /// A sortable table with a caption and a header row; `class(i)` marks row `i`
    /// (`regressed`, `failed`, `alone`, `low`) or leaves it plain.
    pub fn table_with(
        &mut self,
        caption: &str,
        headers: &[impl AsRef<str>],
        rows: &[Vec<String>],
        class: impl Fn(usize) -> Option<&'static str>,
    ) {
        let s = &mut self.body;
        let _ = write!(
            s,
            "<p class=\"cap\">{c}</p><div class=\"box\"><table class=\"sortable\" \
             aria-label=\"{c}\"><thead><tr>",
            c = escape(caption)
        );
        for (i, h) in headers.iter().enumerate() {
            let text = rows
                .iter()
                .all(|r| r.get(i).is_none_or(|c| !numeric_cell(c)));
            let _ = write!(
                s,
                "<th scope=\"col\"{}>{}</th>",
                if text { " class=\"t\"" } else { "" },
                escape(h.as_ref())
            );
        }
        s.push_str("</tr></thead><tbody>\n");
        for (i, row) in rows.iter().enumerate() {
            match class(i) {
                Some(c) => {
                    let _ = write!(s, "<tr class=\"{c}\">");
                }
                None => s.push_str("<tr>"),
            }
            for cell in row {
                let _ = if numeric_cell(cell) {
                    write!(s, "<td>{}</td>", escape(cell))
                } else {
                    write!(s, "<td class=\"t\">{}</td>", inline(cell))
                };
            }
            s.push_str("</tr>\n");
        }
        s.push_str("</tbody></table></div>\n");
    }

    /// A sortable table with a caption and a header row.
    pub fn table(&mut self, caption: &str, headers: &[impl AsRef<str>], rows: &[Vec<String>]) {
        self.table_with(caption, headers, rows, |_| None);
    }

    /// Opens a grid of figures (two side by side on a wide window, one on a phone).
    pub fn plots_begin(&mut self) {
        self.body += "<div class=\"plots\">\n";
    }

    /// Closes the grid of [`Page::plots_begin`].
    pub fn plots_end(&mut self) {
        self.body += "</div>\n";
    }

    /// An SVG drawing inlined as a figure: `title` becomes its `<title>` and caption, `alt`
    /// its text alternative (`<desc>`); the drawing is scaled to the width of its box.
    pub fn figure(&mut self, svg: &str, title: &str, alt: &str) {
        self.figures += 1;
        let id = format!("f{}", self.figures);
        let Some(start) = svg.find("<svg") else {
            return;
        };
        let svg = &svg[start..];
        let Some(open_end) = svg.find('>') else {
            return;
        };
        // Keep the view box (the drawing's own size) and let the style sheet set the size.
        let open = &svg[..open_end];
        let view_box = open
            .split("viewBox=\"")
            .nth(1)
            .and_then(|v| v.split('"').next())
            .unwrap_or("0 0 960 600");
        let _ = writeln!(
            self.body,
            "<figure><svg viewBox=\"{view_box}\" role=\"img\" aria-labelledby=\"{id}t {id}d\">\
             <title id=\"{id}t\">{t}</title><desc id=\"{id}d\">{a}</desc>{rest}\
             <figcaption>{t}</figcaption></figure>",
            t = escape(title),
            a = escape(alt),
            rest = svg[open_end + 1..].trim_start(),
        );
    }

    /// The plot `<stem>.svg` in `dir` (written by [`super::plots`]) inlined as a figure.
    pub fn figure_file(&mut self, dir: &Path, stem: &str, title: &str, alt: &str) -> Result<()> {
        let path = dir.join(format!("{stem}.svg"));
        let svg = read_text(&path)?;
        self.figure(&svg, title, alt);
        Ok(())
    }

    /// The whole page.
    pub fn finish(self) -> String {
        let mut s = String::with_capacity(self.body.len() + 4096);
        let _ = write!(
            s,
            "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
             <meta name=\"viewport\" content=\"width=device-width,initial-scale=1\">\
             <meta name=\"generator\" content=\"calbench {}\">\
             <title>{}</title><style>{STYLE}</style></head>\n<body>\n<h1>{}</h1>\n<p>{}</p>\n",
            env!("CARGO_PKG_VERSION"),
            escape(&self.title),
            escape(&self.title),
            escape(&self.lead)
        );
        if self.sections.len() > 1 {
            s += "<nav aria-label=\"contents\">";
            for (id, title) in &self.sections {
                let _ = write!(s, "<a href=\"#{id}\">{}</a>", escape(title));
            }
            s += "</nav>\n";
        }
        s += &self.body;
        let _ = write!(s, "<script>{SCRIPT}</script>\n</body></html>\n");
        s
    }

    /// The page as the output file `name`.
    pub fn output(self, name: &str) -> crate::report::output::Text<'_> {
        crate::report::output::Text {
            name,
            text: self.finish(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_is_escaped_and_figures_get_a_title_and_description() {
        assert_eq!(escape("a<b & \"c\"'"), "a&lt;b &amp; &quot;c&quot;&apos;");
        let mut p = Page::new("T <1>", "lead");
        p.section("One");
        p.figure(
            "<svg width=\"960\" height=\"600\" viewBox=\"0 0 960 600\" xmlns=\"http://www.w3.org/2000/svg\">\n<rect/></svg>",
            "A & B",
            "two bars",
        );
        p.table("c", &["name", "value"], &[vec!["x".into(), "1.5".into()]]);
        let html = p.finish();
        assert!(html.contains("<title>T &lt;1&gt;</title>"));
        assert!(html.contains(
            "<svg viewBox=\"0 0 960 600\" role=\"img\" aria-labelledby=\"f1t f1d\"><title id=\"f1t\">A &amp; B</title><desc id=\"f1d\">two bars</desc><rect/></svg>"
        ));
        assert!(!html.contains("http://"), "{html}");
        assert!(
            html.contains("<th scope=\"col\" class=\"t\">name</th><th scope=\"col\">value</th>")
        );
        assert!(html.contains("<td class=\"t\">x</td><td>1.5</td>"));
    }

    #[test]
    fn inline_marks_become_elements_and_nothing_of_markdown_is_left() {
        assert_eq!(
            inline("a `\"x\" < 1` and **b** `c`"),
            "a <code>&quot;x&quot; &lt; 1</code> and <strong>b</strong> <code>c</code>"
        );
        assert_eq!(inline("no marks <here>"), "no marks &lt;here&gt;");
        assert_eq!(inline("one ` alone"), "one ` alone");
        let mut p = Page::new("t", "l");
        p.para(crate::report::run::claims::NOTE);
        p.para(crate::report::run::comparisons::NOTE);
        p.para(crate::report::run::searches::NOTE);
        p.para(crate::report::run::INTERVAL_NOTE);
        let html = p.finish();
        let text: String = html
            .split("<p>")
            .skip(2)
            .map(|s| s.split("</p>").next().unwrap_or(""))
            .collect();
        assert!(!text.contains('`') && !text.contains("**"), "{text}");
        assert!(text.contains("<code>calibrated</code>"), "{text}");
    }
}
