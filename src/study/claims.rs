//! A paper's claims as statements a study tests (docs/formats.md "claims"): a scenario's
//! `[[claims]]` name a per-trial metric and a relation between its entries, for example
//! `"bas-pso-differential" < "pso-differential"` or `"lm / detmax-ide" / "lm / random" <= 0.5`;
//! `run` evaluates each on the trials, paired trial by trial, with a 95 % interval, and gives
//! the verdict `reproduces`, `contradicts` or `unresolved`.
//!
//! The relation's grammar:
//!
//! ```text
//! relation := term op bound
//! term     := entry | entry "/" entry
//! bound    := entry | number          (an entry only after a single-entry term)
//! entry    := '"' name '"'            (as in `comparisons`: "method / poses"; a method
//!                                      alone when the study has one strategy, a strategy
//!                                      alone when it has one method)
//! op       := "<" | "<=" | ">" | ">="
//! ```
//!
//! What is estimated, and its interval:
//!
//! - `"a" op "b"`: the mean over trials of the paired difference a − b, against 0: its t
//!   interval (the paired interval of the difference, as `comparisons`' `diff_ci95`);
//! - `"a" / "b" op x`: the ratio of the means of a and b, against x: the paired interval of
//!   the ratio by the delta method (the ratio R = ā / b̄ ± t₀.₉₇₅,ₙ₋₁ · s(aᵢ − R bᵢ) / (√n b̄),
//!   Cochran, *Sampling Techniques*, § 6.4);
//! - `"a" op x`: the mean of a over trials, against x: its t interval.

use crate::numeric::dist;
use crate::numeric::Real;
pub use crate::study::metric::{Metric, Needs};

/// A relation's comparison.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Op {
    /// `<`
    Lt,
    /// `<=`
    Le,
    /// `>`
    Gt,
    /// `>=`
    Ge,
}

/// The left side of a relation: entries as `(method index, strategy index)`.
#[derive(Clone, Debug, PartialEq)]
pub enum Term {
    /// One entry's mean.
    One((usize, usize)),
    /// The ratio of two entries' means.
    Ratio((usize, usize), (usize, usize)),
}

/// The right side.
#[derive(Clone, Debug, PartialEq)]
pub enum Bound {
    /// Another entry (the paired difference is compared with 0).
    Entry((usize, usize)),
    /// A number.
    Number(Real),
}

/// A checked claim of a scenario.
#[derive(Clone, Debug)]
pub struct Claim {
    /// Its id, unique in the scenario.
    pub id: String,
    /// The paper's claim in words.
    pub statement: String,
    /// Where the paper makes it (section, table, figure).
    pub paper: String,
    /// The paper's figure(s), as written.
    pub value: toml::Value,
    /// The metric it compares.
    pub metric: Metric,
    /// The relation as written.
    pub relation: String,
    /// Its left side.
    pub term: Term,
    /// Its comparison.
    pub op: Op,
    /// Its right side.
    pub bound: Bound,
}

/// `[[claims]]` as written.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct RawClaim {
    id: String,
    statement: String,
    paper: String,
    value: toml::Value,
    metric: String,
    relation: String,
}

/// The study's entries a relation may name.
pub struct Names<'a> {
    /// The methods' labels.
    pub methods: &'a [String],
    /// The strategies' names.
    pub strategies: &'a [String],
    /// Whether the tracker measures full poses.
    pub pose: bool,
    /// Whether `validation.axis_errors` is on.
    pub axis: bool,
}

impl Names<'_> {
    fn entry(&self, name: &str) -> Result<(usize, usize), String> {
        let m = |s: &str| self.methods.iter().position(|x| x == s);
        let st = |s: &str| self.strategies.iter().position(|x| x == s);
        if let Some((a, b)) = name.split_once(" / ") {
            if let (Some(mi), Some(si)) = (m(a.trim()), st(b.trim())) {
                return Ok((mi, si));
            }
        } else if let (Some(mi), 1) = (m(name), self.strategies.len()) {
            return Ok((mi, 0));
        } else if let (Some(si), 1) = (st(name), self.methods.len()) {
            return Ok((0, si));
        }
        let all: Vec<String> = self
            .methods
            .iter()
            .flat_map(|m| {
                self.strategies
                    .iter()
                    .map(move |s| format!("\"{m} / {s}\""))
            })
            .collect();
        Err(format!(
            "no entry \"{name}\"; entries are {} (a method alone with one strategy, a \
             strategy alone with one method)",
            all.join(", ")
        ))
    }
}

/// Splits a relation into its tokens: quoted names, numbers, `/` and comparisons.
fn tokens(s: &str) -> Result<Vec<Tok>, String> {
    let mut out = Vec::new();
    let mut rest = s.trim_start();
    while !rest.is_empty() {
        if let Some(r) = rest.strip_prefix('"') {
            let end = r.find('"').ok_or("an entry's name is not closed by '\"'")?;
            out.push(Tok::Name(r[..end].to_string()));
            rest = &r[end + 1..];
        } else if let Some((tok, r)) = SYMBOLS
            .iter()
            .find_map(|(text, tok)| rest.strip_prefix(text).map(|r| (tok.clone(), r)))
        {
            out.push(tok);
            rest = r;
        } else {
            let end = rest.find(char::is_whitespace).unwrap_or(rest.len());
            let word = &rest[..end];
            let x: Real = word
                .parse()
                .ok()
                .filter(|x: &Real| x.is_finite())
                .ok_or_else(|| {
                    format!("\"{word}\" is neither a quoted entry, a number, '/' nor <, <=, >, >=")
                })?;
            out.push(Tok::Number(x));
            rest = &rest[end..];
        }
        rest = rest.trim_start();
    }
    Ok(out)
}

/// The relation's symbols, the two-character ones first.
const SYMBOLS: [(&str, Tok); 5] = [
    ("<=", Tok::Op(Op::Le)),
    (">=", Tok::Op(Op::Ge)),
    ("<", Tok::Op(Op::Lt)),
    (">", Tok::Op(Op::Gt)),
    ("/", Tok::Slash),
];

#[derive(Clone, Debug)]
enum Tok {
    Name(String),
    Number(Real),
    Slash,
    Op(Op),
}

/// Parses `relation` against the study's entries.
fn relation(s: &str, names: &Names) -> Result<(Term, Op, Bound), String> {
    const FORMS: &str = "write \"a\" < \"b\", \"a\" / \"b\" <= 0.5 or \"a\" >= 90 (entries \
                         quoted; <, <=, >, >=)";
    let t = tokens(s)?;
    let parsed = match t.as_slice() {
        [Tok::Name(a), Tok::Op(op), Tok::Name(b)] => (
            Term::One(names.entry(a)?),
            *op,
            Bound::Entry(names.entry(b)?),
        ),
        [Tok::Name(a), Tok::Op(op), Tok::Number(x)] => {
            (Term::One(names.entry(a)?), *op, Bound::Number(*x))
        }
        [Tok::Name(a), Tok::Slash, Tok::Name(b), Tok::Op(op), Tok::Number(x)] => (
            Term::Ratio(names.entry(a)?, names.entry(b)?),
            *op,
            Bound::Number(*x),
        ),
        _ => return Err(format!("cannot read the relation \"{s}\": {FORMS}")),
    };
    let same = match &parsed {
        (Term::One(a), _, Bound::Entry(b)) | (Term::Ratio(a, b), _, _) => a == b,
        _ => false,
    };
    if same {
        return Err(format!(
            "the relation \"{s}\" compares an entry with itself"
        ));
    }
    Ok(parsed)
}

/// Checks a scenario's `[[claims]]` against its entries. A refusal is the key (`claims[i]`,
/// `claims[i].metric`, …) and a message naming the claim's id.
pub fn parse(raw: &[toml::Table], names: &Names) -> Result<Vec<Claim>, (String, String)> {
    parse_with(raw, names, |name| {
        let metric = Metric::PER_TRIAL
            .into_iter()
            .find(|m| m.key() == name)
            .ok_or_else(|| {
                let all: Vec<String> = Metric::PER_TRIAL.iter().map(|m| m.key()).collect();
                format!(
                    "unknown metric \"{name}\"; per-trial metrics are {}",
                    all.join(", ")
                )
            })?;
        match metric.spec().needs {
            Needs::Pose if !names.pose => Some("tracker.measure = \"pose\""),
            Needs::Axis if !names.axis => Some("validation.axis_errors = true"),
            _ => None,
        }
        .map_or(Ok(metric), |need| Err(format!("\"{name}\" needs {need}")))
    })
}

/// [`parse`] for a study with metrics of its own (the registration study's): `metric` gives
/// the metric of a name, or why the name is refused.
pub fn parse_with(
    raw: &[toml::Table],
    names: &Names,
    metric: impl Fn(&str) -> Result<Metric, String>,
) -> Result<Vec<Claim>, (String, String)> {
    let mut out: Vec<Claim> = Vec::new();
    for (i, t) in raw.iter().enumerate() {
        let id = t
            .get("id")
            .and_then(toml::Value::as_str)
            .unwrap_or("")
            .to_string();
        let named = |m: String| {
            if id.is_empty() {
                m
            } else {
                format!("claim \"{id}\": {m}")
            }
        };
        let c: RawClaim = toml::Value::Table(t.clone())
            .try_into()
            .map_err(|e: toml::de::Error| (format!("claims[{i}]"), named(e.message().into())))?;
        if c.id.trim().is_empty() || c.id.contains(char::is_whitespace) {
            return Err((
                format!("claims[{i}].id"),
                "give each claim an id without spaces".into(),
            ));
        }
        if out.iter().any(|x| x.id == c.id) {
            return Err((
                format!("claims[{i}].id"),
                format!("\"{}\" is used twice: give each claim a distinct id", c.id),
            ));
        }
        let metric = metric(&c.metric).map_err(|m| (format!("claims[{i}].metric"), named(m)))?;
        let (term, op, bound) = relation(&c.relation, names)
            .map_err(|m| (format!("claims[{i}].relation"), named(m)))?;
        out.push(Claim {
            id: c.id,
            statement: c.statement,
            paper: c.paper,
            value: c.value,
            metric,
            relation: c.relation,
            term,
            op,
            bound,
        });
    }
    Ok(out)
}

/// A claim's verdict.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Verdict {
    /// The interval lies wholly on the claimed side.
    Reproduces,
    /// The interval lies wholly on the other side.
    Contradicts,
    /// The interval straddles the bound (or there is none).
    Unresolved,
}

impl Verdict {
    /// Its name in `summary.json` and the reports.
    pub fn as_str(self) -> &'static str {
        match self {
            Verdict::Reproduces => "reproduces",
            Verdict::Contradicts => "contradicts",
            Verdict::Unresolved => "unresolved",
        }
    }
}

/// A claim evaluated on a block's trials.
#[derive(Clone, Debug)]
pub struct Evaluation {
    /// What was estimated: `difference`, `ratio` or `mean`.
    pub interval: &'static str,
    /// The bound the estimate is compared with (0 for a difference).
    pub bound: Real,
    /// Trials usable in every entry the claim names.
    pub n: usize,
    /// The estimate.
    pub estimate: Real,
    /// Its 95 % interval (`None` under 2 trials).
    pub ci95: Option<[Real; 2]>,
    /// The verdict.
    pub verdict: Verdict,
    /// For an unresolved claim, the trials at which an interval as wide per trial would just
    /// exclude the bound: n · (half-width / |estimate − bound|)², rounded up.
    pub trials_to_resolve: Option<u64>,
}

/// Evaluates `claim` on per-trial values: `values(method, strategy)` is the claim's metric of
/// that entry, one value per trial in trial order (NaN where the trial failed).
pub fn evaluate<'a>(claim: &Claim, values: impl Fn((usize, usize)) -> &'a [Real]) -> Evaluation {
    let (a, b) = match (&claim.term, &claim.bound) {
        (Term::One(a), Bound::Entry(b)) | (Term::Ratio(a, b), _) => (values(*a), Some(values(*b))),
        (Term::One(a), Bound::Number(_)) => (values(*a), None),
    };
    let rows: Vec<(Real, Real)> = match b {
        Some(b) => a
            .iter()
            .zip(b)
            .filter(|(x, y)| x.is_finite() && y.is_finite())
            .map(|(&x, &y)| (x, y))
            .collect(),
        None => a
            .iter()
            .filter(|x| x.is_finite())
            .map(|&x| (x, 0.0))
            .collect(),
    };
    let n = rows.len();
    let nf = n as Real;
    let mean = |f: &dyn Fn(&(Real, Real)) -> Real| rows.iter().map(f).sum::<Real>() / nf;
    let sd = |f: &dyn Fn(&(Real, Real)) -> Real, m: Real| {
        (rows.iter().map(|r| (f(r) - m).powi(2)).sum::<Real>() / (nf - 1.0)).sqrt()
    };
    let (interval, bound, estimate, ci95) = match (&claim.term, &claim.bound) {
        (Term::One(_), Bound::Entry(_)) => {
            let d = |r: &(Real, Real)| r.0 - r.1;
            let m = mean(&d);
            ("difference", 0.0, m, dist::t_interval(m, sd(&d, m), n))
        }
        (Term::One(_), Bound::Number(x)) => {
            let v = |r: &(Real, Real)| r.0;
            let m = mean(&v);
            ("mean", *x, m, dist::t_interval(m, sd(&v, m), n))
        }
        (Term::Ratio(..), _) => {
            let x = match &claim.bound {
                Bound::Number(x) => *x,
                Bound::Entry(_) => Real::NAN,
            };
            let (ma, mb) = (mean(&|r| r.0), mean(&|r| r.1));
            let ratio = ma / mb;
            let e = |r: &(Real, Real)| r.0 - ratio * r.1;
            // The residuals' mean is 0 by construction of the ratio.
            let ci = dist::t_interval(ratio, sd(&e, 0.0) / mb.abs(), n);
            ("ratio", x, ratio, ci)
        }
    };
    let verdict = match ci95 {
        Some([lo, hi]) if lo.is_finite() && hi.is_finite() => {
            let (claimed, other) = match claim.op {
                Op::Lt => (hi < bound, lo >= bound),
                Op::Le => (hi <= bound, lo > bound),
                Op::Gt => (lo > bound, hi <= bound),
                Op::Ge => (lo >= bound, hi < bound),
            };
            if claimed {
                Verdict::Reproduces
            } else if other {
                Verdict::Contradicts
            } else {
                Verdict::Unresolved
            }
        }
        _ => Verdict::Unresolved,
    };
    let trials_to_resolve = match (verdict, ci95) {
        (Verdict::Unresolved, Some([lo, hi])) => {
            let gap = (estimate - bound).abs();
            let half = (hi - lo) / 2.0;
            (gap > 0.0 && half.is_finite())
                .then(|| (nf * (half / gap).powi(2)).ceil())
                .filter(|t| t.is_finite() && *t < 1e15)
                .map(|t| (t as u64).max(n as u64 + 1))
        }
        _ => None,
    };
    Evaluation {
        interval,
        bound,
        n,
        estimate: if n == 0 { Real::NAN } else { estimate },
        ci95,
        verdict,
        trials_to_resolve,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names() -> (Vec<String>, Vec<String>) {
        (
            vec!["ls".into(), "lm".into()],
            vec!["random".into(), "detmax-ide".into()],
        )
    }

    fn claim(rel: &str) -> Result<Claim, (String, String)> {
        let (m, s) = names();
        let n = Names {
            methods: &m,
            strategies: &s,
            pose: false,
            axis: false,
        };
        let t: toml::Table = toml::from_str(&format!(
            "id = \"c\"\nstatement = \"s\"\npaper = \"§1\"\nvalue = 1\n\
             metric = \"validation_after_mm.rms\"\nrelation = '{rel}'"
        ))
        .expect("toml");
        parse(&[t], &n).map(|mut v| v.remove(0))
    }

    #[test]
    fn the_grammar() {
        let c = claim(r#""lm / detmax-ide" / "lm / random" <= 0.5"#).expect("ratio");
        assert_eq!(c.term, Term::Ratio((1, 1), (1, 0)));
        assert_eq!((c.op, c.bound), (Op::Le, Bound::Number(0.5)));
        let c = claim(r#""ls / random">"lm / random""#).expect("difference");
        assert_eq!((c.term, c.op), (Term::One((0, 0)), Op::Gt));
        for bad in [
            r#""lm / random" < "lm / random""#,
            r#""lm" < "ls""#,
            r#""lm / random" =< 1"#,
            r#""lm / random" < "#,
            r#""lm / nowhere" < 1"#,
            r#"1 < "lm / random""#,
        ] {
            let (key, msg) = claim(bad).expect_err(bad);
            assert_eq!(key, "claims[0].relation", "{bad}");
            assert!(msg.starts_with("claim \"c\": "), "{msg}");
        }
    }

    #[test]
    fn verdicts_by_hand() {
        let c = claim(r#""lm / random" < "ls / random""#).expect("c");
        let a = [1.0, 2.0, 3.0, Real::NAN];
        let better = [2.0, 3.1, 3.9, 1.0];
        let e = evaluate(&c, |k| if k == (1, 0) { &a } else { &better });
        // Differences −1, −1.1, −0.9: mean −1, s 0.1, t₀.₉₇₅,₂ = 4.302652729749464.
        assert_eq!(e.n, 3);
        assert!((e.estimate + 1.0).abs() < 1e-12);
        let h = 4.302652729749464 * 0.1 / 3f64.sqrt();
        let [lo, hi] = e.ci95.expect("ci");
        assert!((lo + 1.0 + h).abs() < 1e-9 && (hi + 1.0 - h).abs() < 1e-9);
        assert_eq!(
            (e.verdict, e.trials_to_resolve),
            (Verdict::Reproduces, None)
        );
        let e = evaluate(&c, |k| if k == (1, 0) { &better } else { &a });
        assert_eq!(e.verdict, Verdict::Contradicts);
        let noisy = [0.0, 4.0, 2.5, 1.0];
        let e = evaluate(&c, |k| if k == (1, 0) { &a } else { &noisy });
        assert_eq!(e.verdict, Verdict::Unresolved);
        // Differences 1, −2, 0.5: mean −1/6, s √2.5833…; (half / gap)² · 3.
        let s = ((49.0 / 36.0 + 121.0 / 36.0 + 4.0 / 9.0) / 2.0 as Real).sqrt();
        let half = 4.302652729749464 * s / 3f64.sqrt();
        let want = (3.0 * (half * 6.0).powi(2)).ceil() as u64;
        assert_eq!(e.trials_to_resolve, Some(want));
        // Ratio of means 2 / 3 against 0.5: the delta method's interval.
        let c = claim(r#""lm / random" / "ls / random" <= 0.5"#).expect("c");
        let e = evaluate(&c, |k| if k == (1, 0) { &a } else { &better });
        assert!((e.estimate - 2.0 / 3.0).abs() < 1e-12);
        assert_eq!((e.interval, e.bound), ("ratio", 0.5));
        // Residuals a − R b: −1/3, −1/15, 2/5; half-width t · s / (√3 · 3) ≈ 0.307.
        let s = ((1.0 / 9.0 + 1.0 / 225.0 + 4.0 / 25.0) / 2.0 as Real).sqrt();
        let h = 4.302652729749464 * s / (3f64.sqrt() * 3.0);
        let [lo, hi] = e.ci95.expect("ci");
        assert!((lo - (2.0 / 3.0 - h)).abs() < 1e-9 && (hi - (2.0 / 3.0 + h)).abs() < 1e-9);
        assert_eq!(e.verdict, Verdict::Unresolved);
    }
}
