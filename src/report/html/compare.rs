//! `calbench compare A B --out DIR`: two runs side by side, entry by entry, as `compare.html`
//! and `compare.md`. Every metric `calbench check` guards is listed with both values, the
//! difference, the relative change, the Holm-adjusted interval of the change and its status
//! ([`crate::analysis::regression::Status`]), trial by trial when both folders hold the same trials;
//! the regressions are the ones `calbench check` reports with the same tolerance (B is
//! compared against A as a summary against its baseline). An entry in only one of the runs
//! is listed as such.

use std::fmt::Write as _;
use std::path::Path;

use super::Page;
pub use crate::analysis::regression::Side;
use crate::analysis::regression::{compare_with, Compared, Status};
use crate::error::Result;
use crate::numeric::Real;
use crate::report::markdown::{fmt_num, inline, table};
use crate::report::output::{Outputs, Text};
use crate::report::plots::{changes_svg, ChangePoint};
use crate::report::scenario_file;
use crate::study::stats::Entry;

impl Side {
    /// The run as the page names it: its file, scenario, trials and seed (`?` for what the
    /// summary does not say).
    fn describe(&self) -> String {
        let s = &self.summary;
        let or_unknown = |v: Option<String>| v.unwrap_or_else(|| "?".into());
        format!(
            "{} (scenario {}, {} trials, seed {})",
            self.path.display(),
            s.scenario,
            or_unknown(s.trials.map(|n| n.to_string())),
            or_unknown(s.seed.map(|n| n.to_string()))
        )
    }
}

/// Run B compared with run A (its baseline) by `check`'s rules: every metric `check` looks
/// at, with both values ([`compare_with`], paired when both folders hold the same trials).
pub struct Comparison {
    /// A, then B.
    pub runs: [Side; 2],
    /// Allowed relative worsening (0.05 = 5 %).
    pub tolerance: Real,
    all: Vec<Compared>,
    /// The settings A and B ran differently ([`scenario_file::settings_apart`]).
    apart: Vec<String>,
}

impl Comparison {
    /// Compares run `b` with run `a` at `tolerance`, reading what each ran
    /// ([`scenario_file::ran`]: a `scenario.toml` with a wrong hash line is refused, as by
    /// `check`).
    pub fn new(a: Side, b: Side, tolerance: Real) -> Result<Comparison> {
        let pairs = a.trials.as_ref().zip(b.trials.as_ref());
        let all = compare_with(&b.summary, &a.summary, tolerance, pairs);
        let apart = scenario_file::settings_apart(&a, &b)?;
        Ok(Comparison {
            runs: [a, b],
            tolerance,
            all,
            apart,
        })
    }

    /// The entries of run `i` (0: A, 1: B) that the other run lacks. `check` counts each
    /// metric of an entry only in A as a regression.
    pub fn only_in(&self, i: usize) -> Vec<String> {
        let theirs = &self.runs[1 - i].summary.results;
        self.runs[i]
            .summary
            .results
            .iter()
            .filter(|e| !theirs.iter().any(|t| t.same_entry(e)))
            .map(Entry::key)
            .collect()
    }

    /// The compared metrics of the entries in both runs, in A's order.
    pub fn rows(&self) -> Vec<&Compared> {
        let only_a = self.only_in(0);
        self.all
            .iter()
            .filter(|c| !only_a.contains(&c.metric.entry))
            .collect()
    }

    /// Every metric `check` looks at, in A's order, an entry only in A's metrics included
    /// (each a regression: missing in B).
    pub fn all(&self) -> &[Compared] {
        &self.all
    }

    /// The number of regressions `check` would report (an entry only in A's metrics too).
    pub fn regressions(&self) -> usize {
        self.all.iter().filter(|c| c.regressed).count()
    }

    /// How many of the [`Comparison::regressions`] B lacks: the metrics of the entries only
    /// in A, and those of an entry in both that B has no value of.
    pub fn missing_in_b(&self) -> usize {
        let missing = |c: &&Compared| c.regressed && c.metric.value.is_nan();
        self.all.iter().filter(missing).count()
    }

    /// The verdict of one compared metric, in words.
    pub fn status(c: &Compared) -> String {
        let m = &c.metric;
        match c.status {
            Status::Regression if m.value.is_nan() => "regression: missing in B".into(),
            Status::Unresolved => match c.trials_needed {
                Some(n) => format!("unresolved (≈ {n} trials would resolve it)"),
                None => "unresolved".into(),
            },
            s => s.as_str().into(),
        }
    }

    /// How many metrics have status `s`.
    pub fn count(&self, s: Status) -> usize {
        self.all.iter().filter(|c| c.status == s).count()
    }

    /// The table of the entries in both runs: headers and rows.
    pub fn table(&self) -> (Vec<&'static str>, Vec<Vec<String>>) {
        let headers = vec![
            "entry",
            "metric",
            "A",
            "B",
            "B − A",
            "change %",
            "status",
            "interval of B − A (Holm)",
            "p (Holm)",
            "compared",
        ];
        let rows = self
            .rows()
            .into_iter()
            .map(|c| {
                let m = &c.metric;
                let diff = m.value - m.baseline;
                let rel = if m.baseline != 0.0 {
                    100.0 * diff / m.baseline.abs()
                } else {
                    Real::NAN
                };
                vec![
                    m.entry.clone(),
                    m.metric.clone(),
                    fmt_num(m.baseline, 6),
                    fmt_num(m.value, 6),
                    fmt_num(diff, 4),
                    fmt_num(rel, 3),
                    Self::status(c),
                    c.diff_ci.map_or(String::new(), |[lo, hi]| {
                        format!("[{}, {}]", fmt_num(lo, 3), fmt_num(hi, 3))
                    }),
                    fmt_num(c.p_holm, 3),
                    if c.paired { "paired" } else { "unpaired" }.into(),
                ]
            })
            .collect();
        (headers, rows)
    }

    /// The verdict the pages lead with: no regression or how many, then the count of each
    /// status.
    pub fn verdict(&self) -> String {
        let pct = fmt_num(100.0 * self.tolerance, 4);
        let paired = self.all.iter().filter(|c| c.paired).count();
        let tally = format!(
            "{} unresolved (worse by {pct} % or more, within the Monte-Carlo noise), {} changed \
             within tolerance, {} improved, {} no change; {paired} of {} metrics compared \
             trial by trial.",
            self.count(Status::Unresolved),
            self.count(Status::Changed),
            self.count(Status::Improved),
            self.count(Status::NoChange),
            self.all.len()
        );
        if self.regressions() == 0 {
            format!("No regression (the rules of calbench check): {tally}")
        } else {
            format!(
                "{} metrics of B regressed: worse than A by {pct} % or more with an interval \
                 of the change that excludes zero, or missing (calbench check would fail). \
                 {tally}",
                self.regressions()
            )
        }
    }

    /// The warning the pages give when A and B ran different scenarios (by name, or by
    /// their settings where both say what they ran), which `check` refuses to compare.
    pub fn scenario_note(&self) -> Option<String> {
        let (sa, sb) = (
            &self.runs[0].summary.scenario,
            &self.runs[1].summary.scenario,
        );
        let which = if sa != sb {
            format!("A is a run of scenario \"{sa}\" and B of scenario \"{sb}\"")
        } else if !self.apart.is_empty() {
            format!(
                "A and B ran scenario \"{sa}\" with other settings ({})",
                self.apart.join("; ")
            )
        } else {
            return None;
        };
        Some(format!(
            "{which}: calbench check refuses such a pair; the entries are compared by name all \
             the same."
        ))
    }

    /// The entries in only one run: name and `A only` or `B only`.
    fn only_rows(&self) -> Vec<Vec<String>> {
        (0..2)
            .flat_map(|i| {
                let side = ["A only", "B only"][i];
                self.only_in(i)
                    .into_iter()
                    .map(move |e| vec![e, side.to_string()])
            })
            .collect()
    }

    /// `compare.md`.
    pub fn markdown(&self) -> String {
        let mut s = String::from("# Comparison of two runs\n\n");
        let _ = writeln!(s, "- A: {}", inline(&self.runs[0].describe()));
        let _ = writeln!(s, "- B: {}\n", inline(&self.runs[1].describe()));
        let _ = writeln!(s, "{}\n", self.verdict());
        if let Some(n) = self.scenario_note() {
            let _ = writeln!(s, "{}\n", inline(&n));
        }
        s += "## Entries in both runs\n\n";
        let (h, rows) = self.table();
        s += &table(&h, &rows);
        let only = self.only_rows();
        if !only.is_empty() {
            s += "\n## Entries in only one run\n\n";
            s += &table(&["entry", "in"], &only);
        }
        let _ = write!(s, "\n## How to read this page\n\n{}\n", self.how_to_read());
        s
    }

    /// The plot of the changes of the metrics of the entries in both runs (toward worse,
    /// % of A, with their intervals), as SVG; `None` when none has a finite change (or
    /// the plot cannot be drawn: the table below says it all).
    fn changes_plot(&self) -> Option<String> {
        let order = [
            Status::Regression,
            Status::Unresolved,
            Status::Changed,
            Status::Improved,
            Status::NoChange,
        ];
        let points: Vec<ChangePoint> = self
            .rows()
            .into_iter()
            .filter_map(|c| {
                let m = &c.metric;
                let scale = 100.0 / m.baseline.abs();
                let sign = if c.higher_is_better { -1.0 } else { 1.0 };
                let worse = sign * (m.value - m.baseline) * scale;
                if !worse.is_finite() {
                    return None;
                }
                let interval = c.diff_ci.map(|[lo, hi]| {
                    let (a, b) = (sign * lo * scale, sign * hi * scale);
                    [a.min(b), a.max(b)]
                });
                Some(ChangePoint {
                    label: format!("{}: {}", m.entry, m.metric),
                    worse_pct: worse,
                    interval,
                    status: order.iter().position(|s| *s == c.status).unwrap_or(4),
                })
            })
            .collect();
        if points.is_empty() {
            return None;
        }
        let names: Vec<&str> = order.iter().map(|s| s.as_str()).collect();
        changes_svg(
            "B against A: change toward worse, % of A",
            &points,
            &names,
            100.0 * self.tolerance,
        )
        .ok()
    }

    /// The page's "How to read" text, `compare.html`'s and `compare.md`'s.
    fn how_to_read(&self) -> String {
        format!(
            "η is better higher, errors, parameter RMSE and failures lower. A metric regresses \
             when B is worse than A by at least {} % of A's magnitude (and by more than 1e-9) \
             and the interval of the change, Holm-adjusted over the metrics compared, excludes \
             zero, or when B lacks it; worse by the tolerance within the noise is unresolved \
             (more trials would tell); a significant change within the tolerance is changed, \
             within tolerance. The change is paired, trial by trial, when both runs share \
             scenario, seed and trials and both folders hold trials.csv; otherwise it comes \
             from the summaries' 95 % intervals (Welch). This is the rule calbench check \
             applies to B against the baseline A with a tolerance of {} (strict, it also \
             fails on unresolved). Timing is not compared.",
            fmt_num(100.0 * self.tolerance, 4),
            fmt_num(self.tolerance, 6)
        )
    }

    /// `compare.html`.
    pub fn page(&self) -> Page {
        let mut page = Page::new(
            "Comparison of two runs",
            &format!(
                "A: {} — B: {}",
                self.runs[0].describe(),
                self.runs[1].describe()
            ),
        );
        page.section("Verdict");
        if self.regressions() == 0 {
            page.fine(&self.verdict());
        } else {
            page.warning(&self.verdict());
        }
        if let Some(n) = self.scenario_note() {
            page.warning(&n);
        }
        if let Some(svg) = self.changes_plot() {
            page.figure(
                &svg,
                "The changes from A to B toward worse, with their Holm-adjusted intervals",
                &format!(
                    "One point per compared metric of the entries in both runs: B's change \
                     toward worse in % of A, with the interval of the change as a bar, \
                     coloured by status; the dashed line is the tolerance ({} %). {}",
                    fmt_num(100.0 * self.tolerance, 4),
                    self.verdict()
                ),
            );
        }
        page.section("Entries in both runs");
        let (h, rows) = self.table();
        let compared = self.rows();
        page.table_with(
            "Every guarded metric: A, B, their difference, B's relative change, its status \
             and the Holm-adjusted interval of the change; marked rows are regressions",
            &h,
            &rows,
            |i| compared[i].regressed.then_some("regressed"),
        );
        let only = self.only_rows();
        if !only.is_empty() {
            page.section("Entries in only one run");
            page.para(
                "Entries are matched by method, poses and swept value. An entry of A missing \
                 from B counts as a regression of each of its metrics.",
            );
            page.table_with("Entries in only one run", &["entry", "in"], &only, |i| {
                Some(if only[i][1] == "A only" {
                    "regressed"
                } else {
                    "alone"
                })
            });
        }
        page.section("How to read this page");
        page.para(&self.how_to_read());
        page
    }
}

/// The files [`write()`] writes.
pub const OUTPUTS: [&str; 2] = ["compare.html", "compare.md"];

/// The files of `c`: `compare.html` and `compare.md`.
pub fn outputs(c: &Comparison) -> Outputs<'static> {
    let page = c.page().output(OUTPUTS[0]);
    let md = Text {
        name: OUTPUTS[1],
        text: c.markdown(),
    };
    vec![Box::new(page), Box::new(md)]
}

/// Writes `compare.html` and `compare.md` of `c` into the folder `out` as a whole.
pub fn write(c: &Comparison, out: &Path) -> Result<()> {
    crate::report::output::folder_of(out, &outputs(c))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::{json, Value};
    use std::path::PathBuf;

    fn side(eta: Real, methods: &[&str]) -> Side {
        let results: Vec<Value> = methods
            .iter()
            .map(|m| {
                json!({"method": m, "poses": "random", "eta_mean_pct": eta,
                       "validation_after_mm": {"mean": 0.1, "rms": 0.1, "max": 0.1, "std": 0.0},
                       "failures": 0})
            })
            .collect();
        let path = PathBuf::from(format!("{eta}.json"));
        let doc = json!({"scenario": "s", "trials": 4, "seed": 1, "results": results});
        Side {
            summary: crate::analysis::regression::check_summary(doc, &path).unwrap(),
            path,
            trials: None,
            scenario: None,
        }
    }

    #[test]
    fn regressions_are_those_of_check_and_lone_entries_are_listed() {
        let (a, b) = (side(90.0, &["ls", "lm"]), side(80.0, &["ls", "igg3"]));
        let expected = crate::analysis::regression::compare(&b.summary, &a.summary, 0.05).len();
        let c = Comparison::new(a, b, 0.05).unwrap();
        assert_eq!(c.regressions(), expected);
        assert_eq!(c.only_in(0), ["lm / random"]);
        assert_eq!(c.only_in(1), ["igg3 / random"]);
        let (_, rows) = c.table();
        let eta = rows.iter().find(|r| r[1] == "eta_mean_pct").unwrap();
        assert_eq!(eta[2..7], ["90", "80", "-10", "-11.1", "regression"]);
        let rms = rows
            .iter()
            .find(|r| r[1] == "validation_after_mm.rms")
            .unwrap();
        assert_eq!(rms[6], "no change");
        let md = c.markdown();
        let line = |entry: &str| md.lines().find(|l| l.contains(entry)).unwrap_or_default();
        assert!(line("lm / random").contains("A only"), "{md}");
        assert!(line("igg3 / random").contains("B only"), "{md}");
        let same = Comparison::new(side(90.0, &["ls"]), side(90.0, &["ls"]), 0.05).unwrap();
        assert_eq!(same.regressions(), 0);
        assert!(!same.page().finish().contains("class=\"regressed\""));
        assert!(c.page().finish().contains("<tr class=\"regressed\">"));
    }
}
