//! A paper's claims as statements a study tests (docs/formats.md "claims"): a scenario's
//! `[[claims]]` name a per-trial metric and a relation between its entries, for example
//! `"bas-pso-differential" < "pso-differential"` (an ordering, judged beyond the metric's
//! margin of practical relevance) or `"igg3" ~ 0.42` (a point value, judged against the
//! claim's `tolerance` band); `run` evaluates each on the trials, paired trial by trial, with
//! a 95 % interval, and gives a verdict ([`super::verdict::Verdict`]; [`super::verdict`] says how).
//!
//! The relation's grammar:
//!
//! ```text
//! relation := term op bound [ "for every parameter" ]
//! term     := entry | entry "/" entry
//! bound    := entry | number          (an entry only after a single-entry term)
//! entry    := '"' name '"'            (as in `comparisons`: "method / poses"; a method
//!                                      alone when the study has one strategy, a strategy
//!                                      alone when it has one method)
//! op       := "<" | "<=" | ">" | ">=" | "~"   ("~": a point value, bound a number)
//! ```
//!
//! "for every parameter" (metric `eta`, bound an entry) judges the ordering on each
//! parameter with an injected error.

use crate::numeric::Real;
pub use crate::study::metric::{Margin, Metric, Needs};
pub use crate::study::stats::location::About;

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
    /// `~`: a point value within the claim's tolerance band.
    Near,
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
    /// Whether it is about the mean or the median over trials.
    pub about: About,
    /// A point value's band: `tolerance` (relative to the value, absolute, the larger).
    pub tolerance: Option<Margin>,
    /// An ordering's minimum effect of interest, when not the metric's default.
    pub margin: Option<Margin>,
    /// The figure was used to choose a setting of the scenario (an `[unmodelled]` level):
    /// shown, never judged.
    pub calibrated: bool,
    /// Whether the claim can be judged on this arm: `false` for a paper's point value (`~`)
    /// of the arm's error ([`Metric::is_arm_error`]) on an arm with no error outside the
    /// kinematic model.
    pub comparable: bool,
    /// The id of the paper's claim this one tests under another setting (`None`: its own).
    pub family: Option<String>,
    /// The other setting in words (`None`: the paper's setting).
    pub setting: Option<String>,
    /// In a sweep: the swept value at the paper's setting (the other points are other
    /// settings); `None`: every point is the paper's setting.
    pub paper_point: Option<toml::Value>,
    /// "for every parameter": judged on each parameter's η.
    pub every_parameter: bool,
    /// With "for every parameter": the parameters the paper's claim names, each judged (one
    /// with no η in a trial on that trial's absence); `None`: every parameter with an η.
    pub parameters: Option<Vec<String>>,
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
    #[serde(default)]
    about: About,
    tolerance: Option<Margin>,
    margin: Option<Margin>,
    #[serde(default)]
    calibrated: bool,
    family: Option<String>,
    setting: Option<String>,
    paper_point: Option<toml::Value>,
    parameters: Option<Vec<String>>,
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
    /// Whether the simulated arm has error outside the kinematic model (`[unmodelled]`).
    pub unmodelled: bool,
    /// Whether a method is a search (BAS, PSO, BAS-PSO): what `final_fitness` needs.
    pub searches: bool,
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
                    format!(
                        "\"{word}\" is neither a quoted entry, a number, '/' nor <, <=, >, >=, ~"
                    )
                })?;
            out.push(Tok::Number(x));
            rest = &rest[end..];
        }
        rest = rest.trim_start();
    }
    Ok(out)
}

/// The relation's symbols, the two-character ones first.
const SYMBOLS: [(&str, Tok); 6] = [
    ("<=", Tok::Op(Op::Le)),
    (">=", Tok::Op(Op::Ge)),
    ("<", Tok::Op(Op::Lt)),
    (">", Tok::Op(Op::Gt)),
    ("~", Tok::Op(Op::Near)),
    ("/", Tok::Slash),
];

#[derive(Clone, Debug)]
enum Tok {
    Name(String),
    Number(Real),
    Slash,
    Op(Op),
}

/// The suffix of a relation judged on each parameter.
pub const EVERY_PARAMETER: &str = "for every parameter";

/// Parses `relation` against the study's entries (without its "for every parameter").
fn relation(s: &str, names: &Names) -> Result<(Term, Op, Bound), String> {
    const FORMS: &str = "write \"a\" < \"b\", \"a\" / \"b\" <= 0.5, \"a\" ~ 0.42 or \"a\" >= 90 \
                         (entries quoted; <, <=, >, >=, ~), optionally followed by \
                         \"for every parameter\"";
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
    if let (_, Op::Near, Bound::Entry(_)) = &parsed {
        return Err(format!(
            "the relation \"{s}\": `~` takes a number (the paper's value), not an entry"
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
            .chain([Metric::Eta])
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
            Needs::Search if !names.searches => {
                Some("a search among the methods (bas, pso, bas-pso)")
            }
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
        // The key that failed (`claims[0].about`), or the claim's own when one is missing.
        let c: RawClaim = crate::numeric::options::read(t).map_err(|(k, m)| match k.as_str() {
            "" => (format!("claims[{i}]"), named(m)),
            k => (format!("claims[{i}].{k}"), named(m)),
        })?;
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
        let key = |k: &str| format!("claims[{i}].{k}");
        if !matches!(
            c.value,
            toml::Value::String(_)
                | toml::Value::Integer(_)
                | toml::Value::Float(_)
                | toml::Value::Array(_)
        ) {
            let why = format!(
                "is a {}: give a string, a number or an array",
                c.value.type_str()
            );
            return Err((key("value"), named(why)));
        }
        if let Some(f) = c
            .family
            .as_ref()
            .filter(|f| f.trim().is_empty() || f.contains(char::is_whitespace))
        {
            let why = format!("\"{f}\" can be no claim's id: give the id, without spaces, of the paper's claim this one tests");
            return Err((key("family"), named(why)));
        }
        let rel = c.relation.trim();
        let (rel, every_parameter) = match rel.strip_suffix(EVERY_PARAMETER) {
            Some(r) => (r.trim_end(), true),
            None => (rel, false),
        };
        let (term, op, bound) = relation(rel, names).map_err(|m| (key("relation"), named(m)))?;
        if every_parameter != (metric == Metric::Eta) {
            return Err((
                key("relation"),
                named(format!(
                    "metric \"{}\" goes with a relation ending \"{EVERY_PARAMETER}\", and \
                     only it",
                    Metric::Eta
                )),
            ));
        }
        if every_parameter && !matches!((&term, &bound), (Term::One(_), Bound::Entry(_))) {
            return Err((
                key("relation"),
                named(format!(
                    "\"{EVERY_PARAMETER}\" takes an ordering of two entries (\"a\" > \"b\")"
                )),
            ));
        }
        if let Some(p) = &c.parameters {
            let why = if !every_parameter {
                Some(format!(
                    "`parameters` names the parameters of a relation ending \"{EVERY_PARAMETER}\""
                ))
            } else if p.is_empty() {
                Some("give at least one parameter name".into())
            } else {
                p.iter()
                    .enumerate()
                    .find(|(j, x)| p[..*j].contains(x))
                    .map(|(_, x)| format!("\"{x}\" is named twice"))
            };
            if let Some(why) = why {
                return Err((key("parameters"), named(why)));
            }
        }
        for (k, m) in [("tolerance", &c.tolerance), ("margin", &c.margin)] {
            if let Some(m) = m {
                m.check().map_err(|e| (key(k), named(e)))?;
            }
        }
        match (op, &c.tolerance) {
            (Op::Near, None) => {
                return Err((
                    key("tolerance"),
                    named(
                        "a point value (`~`) needs its band: tolerance = { relative = 0.25 } \
                         or { absolute = … } in the metric's unit"
                            .into(),
                    ),
                ))
            }
            (Op::Near, Some(_)) | (_, None) => {}
            (_, Some(_)) => {
                return Err((
                    key("tolerance"),
                    named(
                        "`tolerance` is the band of a point value: write the relation with `~`"
                            .into(),
                    ),
                ))
            }
        }
        if c.margin.is_some() && !matches!(bound, Bound::Entry(_)) {
            return Err((
                key("margin"),
                named(
                    "`margin` is an ordering's minimum effect: the relation compares two entries"
                        .into(),
                ),
            ));
        }
        // A paper's figure (a point value) of the arm's error needs an arm that has error
        // outside the kinematic model to be compared with a real robot's.
        let comparable = names.unmodelled || !metric.is_arm_error() || op != Op::Near;
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
            about: c.about,
            tolerance: c.tolerance,
            margin: c.margin,
            calibrated: c.calibrated,
            comparable,
            family: c.family,
            setting: c.setting,
            paper_point: c.paper_point,
            every_parameter,
            parameters: c.parameters,
        });
    }
    Ok(out)
}

/// Refuses a claim's `parameters` name that is not one of `robot`'s parameters, or that can
/// have no η: not among `injected` (the parameters the scenario gives an error), or a base
/// parameter (η leaves the base out). The key (`claims[i].parameters`) and a message naming
/// the claim's id.
pub fn check_parameters(
    claims: &[Claim],
    robot: &crate::robot::Robot,
    injected: &[crate::robot::Param],
) -> Result<(), (String, String)> {
    use crate::robot::Param;
    let all = robot.params();
    for (i, c) in claims.iter().enumerate() {
        for n in c.parameters.iter().flatten() {
            let why = match Param::parse(n).filter(|p| all.contains(p)) {
                None => format!("is not a parameter of robot \"{}\"", robot.name),
                Some(Param::Base(_)) => "is a base parameter, which η leaves out".to_string(),
                Some(p) if !injected.contains(&p) => {
                    "has no injected error (`errors`), so no trial gives it an η".to_string()
                }
                Some(_) => continue,
            };
            return Err((
                format!("claims[{i}].parameters"),
                format!("claim \"{}\": \"{n}\" {why}", c.id),
            ));
        }
    }
    Ok(())
}

/// The claim a refused key lies in (`claims[0]` of `claims[0].tolerance`), whose
/// `[[claims]]` line places the refusal of a key the claim lacks (a `~` without its band).
pub fn claim_of(key: &str) -> &str {
    key.find("].").map_or(key, |i| &key[..=i])
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    fn names() -> (Vec<String>, Vec<String>) {
        (
            vec!["ls".into(), "lm".into()],
            vec!["random".into(), "detmax-ide".into()],
        )
    }

    fn claim(rel: &str) -> Result<Claim, (String, String)> {
        claim_of("validation_after_mm.rms", rel, false)
    }

    /// The claim of `metric` and `rel`, in a study with a search among its methods or not.
    fn claim_of(metric: &str, rel: &str, searches: bool) -> Result<Claim, (String, String)> {
        parsed(metric, rel, "", false, searches)
    }

    /// The claim of `metric` and `rel` with the extra keys `more`, on a study of ls, lm ×
    /// random, detmax-ide whose arm has error outside the model or not, with a search or not.
    pub(crate) fn parsed(
        metric: &str,
        rel: &str,
        more: &str,
        unmodelled: bool,
        searches: bool,
    ) -> Result<Claim, (String, String)> {
        let (m, s) = names();
        let n = Names {
            methods: &m,
            strategies: &s,
            pose: false,
            axis: false,
            unmodelled,
            searches,
        };
        let t: toml::Table = toml::from_str(&format!(
            "id = \"c\"\nstatement = \"s\"\npaper = \"§1\"\nvalue = 1\n\
             metric = \"{metric}\"\nrelation = '{rel}'\n{more}"
        ))
        .expect("toml");
        parse(&[t], &n).map(|mut v| v.remove(0))
    }

    #[test]
    fn a_final_fitness_claim_needs_a_search() {
        let rel = r#""ls / random" < "lm / random""#;
        let (key, msg) = claim_of("final_fitness.mean", rel, false).expect_err("no search");
        assert_eq!(key, "claims[0].metric", "{msg}");
        assert!(msg.contains("needs a search"), "{msg}");
        let c = claim_of("final_fitness.mean", rel, true).expect("a search");
        assert_eq!(c.metric, Metric::FinalFitness);
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
            r#""lm / random" ~ "ls / random""#,
            r#""lm / random" < "ls / random" for every parameter"#,
        ] {
            let (key, msg) = claim(bad).expect_err(bad);
            assert_eq!(key, "claims[0].relation", "{bad}");
            assert!(msg.starts_with("claim \"c\": "), "{msg}");
        }
        // A point value needs its band, and only a point value takes one.
        let (key, msg) = claim(r#""lm / random" ~ 0.4"#).expect_err("no band");
        assert_eq!(key, "claims[0].tolerance", "{msg}");
        let unknown = r#""lm / random" ~ 0.4'
tolerance = { relative = 0.25 }
x = '"#;
        // An unknown key is named by its own key (it had been the claim's).
        let c = claim(unknown).expect_err("unknown key x");
        assert_eq!(c.0, "claims[0].x");
    }
}
