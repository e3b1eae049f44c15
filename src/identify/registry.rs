//! The identification methods by name, and a scenario's `[[methods]]` entry read into a
//! [`MethodSpec`] (docs/formats.md `[[methods]]`).
//!
//! Every method's options are one struct: `#[derive(Deserialize)]` with
//! `deny_unknown_fields` and `Default`, checked by its [`Method::check`]. An entry's common
//! keys (`name`, `label`, `k`) are read here; every other key goes to the options struct. A
//! bad entry is refused with the key and what is wrong.

use std::sync::Arc;

use serde::de::DeserializeOwned;

use super::qiao::method::Metaheuristic;
use super::{LmOptions, LsOptions, Method, PoseErrorLs, RidgeOptions, RobustOptions};
use crate::error::{Error, Result};
use crate::identify::qiao::{check_k, BasOptions, BasPsoOptions, PsoOptions, DEFAULT_K};
use crate::numeric::Real;
use crate::robot::{Param, Robot};

/// A refused `[[methods]]` entry: the key (empty when the entry as a whole is wrong) and
/// what is wrong.
pub type EntryError = (String, String);

/// Reads a method's options from the entry's table (common keys removed) and checks them.
pub type Build = fn(&toml::Table) -> std::result::Result<Arc<dyn Method>, EntryError>;

/// A registered method: its name in scenarios, a one-line summary and its reader.
pub struct MethodEntry {
    /// `name = "…"` in `[[methods]]`.
    pub name: &'static str,
    /// What it is, for `--help` texts and error messages.
    pub summary: &'static str,
    /// Reads and checks the options.
    pub build: Build,
}

/// Every identification method. Adding a method: one file with its options struct
/// implementing [`Method`], and one line here.
pub const METHODS: &[MethodEntry] = &[
    MethodEntry {
        name: "ls",
        summary: "Gauss–Newton least squares (Li 2018 eq. 13); with error_model, on a pose-error model (Qiao 2021)",
        build: ls,
    },
    MethodEntry {
        name: "ridge",
        summary: "ridge estimation (Li 2018 eq. 14)",
        build: options::<RidgeOptions>,
    },
    MethodEntry {
        name: "igg3",
        summary: "IGG3 robust ridge (Li 2018 §2.2)",
        build: options::<RobustOptions>,
    },
    MethodEntry {
        name: "lm",
        summary: "Levenberg–Marquardt (Guo 2024 eq. 8; Ban)",
        build: lm,
    },
    MethodEntry {
        name: "bas",
        summary: "beetle antennae search (Qiao 2021 eq. 13)",
        build: options::<Metaheuristic<BasOptions>>,
    },
    MethodEntry {
        name: "pso",
        summary: "particle swarm (Qiao 2021 eq. 12)",
        build: options::<Metaheuristic<PsoOptions>>,
    },
    MethodEntry {
        name: "bas-pso",
        summary: "BAS-PSO hybrid (Qiao 2021 eqs. 12–13)",
        build: options::<Metaheuristic<BasPsoOptions>>,
    },
];

/// The names of [`METHODS`], comma-separated.
pub fn method_names() -> String {
    METHODS
        .iter()
        .map(|m| m.name)
        .collect::<Vec<_>>()
        .join(", ")
}

/// `ls` is plain Gauss–Newton, or with the key `error_model` least squares on a pose-error
/// model.
fn ls(t: &toml::Table) -> std::result::Result<Arc<dyn Method>, EntryError> {
    use crate::identify::qiao::error_models::ERROR_MODEL;
    if t.contains_key(ERROR_MODEL) {
        options::<PoseErrorLs>(t)
    } else {
        // An unknown key's refusal names `error_model` too, which the entry may also take.
        options::<LsOptions>(t)
            .map_err(|(k, msg)| (k, super::options::with_taken(msg, &[&[ERROR_MODEL]])))
    }
}

/// `lm`, refusing a damping key its form does not read ([`super::lm::refuse_unread`]).
fn lm(t: &toml::Table) -> std::result::Result<Arc<dyn Method>, EntryError> {
    super::lm::refuse_unread(t)?;
    options::<LmOptions>(t)
}

/// The reader of a method whose options struct is `M`.
pub fn options<M: Method + DeserializeOwned + 'static>(
    t: &toml::Table,
) -> std::result::Result<Arc<dyn Method>, EntryError> {
    let m: M = super::options::read(t)?;
    m.check().map_err(split)?;
    Ok(Arc::new(m))
}

/// A setting error as (key, message).
fn split(e: Error) -> EntryError {
    match e {
        Error::Setting { key, msg } => (key, msg.to_string()),
        other => (String::new(), other.to_string()),
    }
}

/// One identification method of a study, with its label and orientation weight.
#[derive(Clone, Debug)]
pub struct MethodSpec {
    /// The method's name (`name = "…"`).
    pub name: &'static str,
    /// The name in reports, `summary.json` and `trials.csv` (`label`, default the name).
    pub label: String,
    /// Weight of orientation against position residuals on full-pose data, mm per rad (key
    /// `k`, default [`DEFAULT_K`]).
    pub k: Real,
    /// The method with its options.
    pub method: Arc<dyn Method>,
    /// Priors on parameter errors (key `priors = { a2 = 0.05, … }`): each parameter's error
    /// has σ (mm, rad; rad/(N·m) for a compliance) about 0, the nominal value. Empty: none.
    pub priors: Vec<(Param, Real)>,
    /// Where the Jacobian methods record the RMS point residual of each evaluation
    /// (`identify`'s convergence trace); `None`: not recorded.
    pub trace: Option<super::TraceRecorder>,
    /// Where the Jacobian methods start ([`super::CalibrationProblem::start`]); empty: at the
    /// nominal robot.
    pub start: Vec<Real>,
}

impl MethodSpec {
    /// The method `name` with `options`, the keys of a `[[methods]]` entry that a front end
    /// gives beside its choice of method (the command line's `--set`, Python's `options`).
    /// Options that name a method themselves are refused (key `name`): the command line had
    /// run that method instead of the one chosen, and Python had ignored it.
    pub fn with_options(
        name: &str,
        mut options: toml::Table,
    ) -> std::result::Result<MethodSpec, EntryError> {
        if let Some(v) = options.get("name") {
            let msg = format!(
                "{v} among the options: the method is chosen apart from its options (here \
                 \"{name}\"); leave `name` out"
            );
            return Err(("name".to_string(), msg));
        }
        options.insert("name".into(), toml::Value::String(name.into()));
        MethodSpec::from_table(&options)
    }

    /// Reads one `[[methods]]` entry: `name`, optional `label` and `k`, and the method's
    /// options.
    pub fn from_table(t: &toml::Table) -> std::result::Result<MethodSpec, EntryError> {
        let string = |k: &str| match t.get(k) {
            None => Ok(None),
            Some(toml::Value::String(s)) => Ok(Some(s.clone())),
            Some(v) => Err((k.to_string(), format!("must be a string, got {v}"))),
        };
        let name = string("name")?.ok_or_else(|| {
            (
                "name".to_string(),
                format!("missing; allowed: {}", method_names()),
            )
        })?;
        let entry = METHODS.iter().find(|m| m.name == name).ok_or_else(|| {
            (
                "name".to_string(),
                format!("unknown method \"{name}\"; allowed: {}", method_names()),
            )
        })?;
        let label = string("label")?.unwrap_or_else(|| name.clone());
        if label.trim().is_empty() {
            let msg = "must name the method in the reports; leave it out for the method's name";
            return Err(("label".to_string(), msg.to_string()));
        }
        if let Some(msg) = hidden_label(&label) {
            return Err(("label".to_string(), msg.to_string()));
        }
        let k = match t.get("k") {
            None => DEFAULT_K,
            Some(v) => {
                let k = v
                    .as_float()
                    .or_else(|| v.as_integer().map(|i| i as Real))
                    .ok_or_else(|| ("k".to_string(), format!("must be a number, got {v}")))?;
                check_k(k).map_err(split)?;
                k
            }
        };
        let priors = match t.get("priors") {
            None => Vec::new(),
            Some(toml::Value::Table(p)) => p
                .iter()
                .map(|(name, v)| prior_value(name, v).map_err(|m| (format!("priors.{name}"), m)))
                .collect::<std::result::Result<_, _>>()?,
            Some(v) => {
                let msg = format!("must be a table of parameter = σ, got {v}");
                return Err(("priors".to_string(), msg));
            }
        };
        let mut rest = t.clone();
        for common in ["name", "label", "k", "priors"] {
            rest.remove(common);
        }
        let method = (entry.build)(&rest)?;
        Ok(MethodSpec {
            name: entry.name,
            label,
            k,
            method,
            priors,
            trace: None,
            start: Vec::new(),
        })
    }

    /// The Tikhonov precisions `1/σ²` of `params` from [`MethodSpec::priors`] (0 for a
    /// parameter without a prior; empty without priors), for [`super::CalibrationProblem`].
    /// Fails when a prior names a parameter that is not identified.
    pub fn precisions(&self, params: &[Param]) -> Result<Vec<Real>> {
        if self.priors.is_empty() {
            return Ok(Vec::new());
        }
        let mut l = vec![0.0; params.len()];
        for &(p, sigma) in &self.priors {
            let k = params.iter().position(|q| *q == p).ok_or_else(|| {
                Error::setting(
                    format!("priors.{p}"),
                    "is not among the identified parameters (fixed, or not in the model)",
                )
            })?;
            l[k] = 1.0 / (sigma * sigma);
        }
        Ok(l)
    }

    /// The method's name.
    pub fn name(&self) -> &'static str {
        self.name
    }

    /// A method supplied from outside ([`super::external`]) under `label`, with the default
    /// orientation weight.
    pub fn external(label: &str, method: super::external::External) -> MethodSpec {
        MethodSpec {
            name: super::external::EXTERNAL,
            label: label.to_string(),
            k: DEFAULT_K,
            method: Arc::new(method),
            priors: Vec::new(),
            trace: None,
            start: Vec::new(),
        }
    }

    /// The method as a message names it: its name, or the label of a method supplied from
    /// outside (a Python function's name), which has no name of calbench's.
    pub fn shown_name(&self) -> &str {
        if self.is_external() {
            &self.label
        } else {
            self.name
        }
    }

    /// Whether the method was supplied from outside rather than read from a scenario.
    pub fn is_external(&self) -> bool {
        self.name == super::external::EXTERNAL
    }
}

/// One prior `NAME = σ` as TOML reads it ([`parse_prior`]), where TOML reads an unquoted
/// dotted name `base.x = σ` as the key `x` of a table `base`: refused saying so.
pub fn prior_value(name: &str, v: &toml::Value) -> std::result::Result<(Param, Real), String> {
    if let Some((key, _)) = v.as_table().and_then(|t| t.iter().next()) {
        return Err(format!(
            "`{name}.{key}` is read by TOML as the key `{key}` of a table `{name}`: quote a \
             parameter name that holds a dot, \"{name}.{key}\" = σ"
        ));
    }
    parse_prior(
        name,
        v.as_float().or_else(|| v.as_integer().map(|i| i as Real)),
    )
}

/// The priors of the file `path` for `robot`, `NAME = σ` lines (TOML), by name (`--prior
/// FILE`, Python's `prior=PATH`): a file that is not TOML, holds no prior, or names a
/// parameter or σ that is not one, or a parameter `robot` does not have (`theta9` of a
/// six-joint arm; a joint's compliance `cN` is the compliance model's), is refused naming
/// the file, the line and the key.
pub fn prior_file(path: &std::path::Path, robot: &Robot) -> Result<Vec<(Param, Real)>> {
    let text = crate::error::read_text(path)?;
    let t: toml::Table = crate::error::toml_keys(path, &text)?;
    if t.is_empty() {
        return Err(Error::file(path, "priors", "holds no `NAME = σ` line"));
    }
    let known = robot.params();
    t.iter()
        .map(|(name, v)| {
            prior_value(name, v)
                .and_then(|(p, sigma)| match known.contains(&p) || p.is_compliance() {
                    true => Ok((p, sigma)),
                    false => Err(format!(
                        "`{p}` is not a parameter of robot `{}`",
                        robot.name
                    )),
                })
                .map_err(|m| Error::toml_file(path, &text, name, format!("key `{name}`"), m))
        })
        .collect()
}

/// One prior `NAME = σ`: a parameter name ([`Param::parse`]) and a finite σ > 0; the message
/// says what is wrong.
pub fn parse_prior(name: &str, sigma: Option<Real>) -> std::result::Result<(Param, Real), String> {
    let p = Param::parse(name.trim())
        .ok_or_else(|| format!("`{name}` is not a parameter name (a2, theta3, base.x, …)"))?;
    match sigma {
        // A σ whose precision 1/σ² overflows would pin the parameter at an infinite weight.
        Some(s) if s.is_finite() && s > 0.0 && (1.0 / (s * s)).is_finite() => Ok((p, s)),
        Some(s) if s.is_finite() && s > 0.0 => Err(format!(
            "σ = {} is too small: its precision 1/σ² overflows (to hold a parameter at its \
             nominal value, fix it)",
            crate::error::shown(s)
        )),
        Some(s) => Err(format!(
            "σ must be finite and above 0, got {}",
            crate::error::shown(s)
        )),
        None => Err("σ must be a number".to_string()),
    }
}

/// A method by name with its default options (`calbench identify --method`).
pub fn method_by_name(name: &str) -> Result<MethodSpec> {
    let mut t = toml::Table::new();
    t.insert("name".into(), toml::Value::String(name.into()));
    MethodSpec::from_table(&t).map_err(|(_, msg)| Error::option(crate::error::Opt::Method, msg))
}

/// Why `label` cannot name a method, when it holds a control character (bidirectional
/// overrides included): a label names the method in the reports and on the terminal. A
/// scenario's `[[methods]]` entry and a method supplied from outside
/// ([`crate::study::scenario::Scenario::with_method`]) and a task's Python method
/// (`calbench.task(..., name=)`) are refused alike.
pub fn hidden_label(label: &str) -> Option<&'static str> {
    label.chars().any(crate::error::is_hidden).then_some(
        "must be a name without control characters (bidirectional overrides included), as \
         `name` is: it names the method in the reports and on the terminal",
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entry(text: &str) -> std::result::Result<MethodSpec, EntryError> {
        MethodSpec::from_table(&toml::from_str(text).unwrap())
    }

    #[test]
    fn a_method_from_outside_is_shown_by_its_label_not_as_external() {
        let f = super::super::external::External {
            name: "mine".into(),
            run: Arc::new(|_| Err("unused".into())),
        };
        let spec = MethodSpec::external("mine", f);
        assert_eq!((spec.name(), spec.shown_name()), ("external", "mine"));
        assert_eq!(method_by_name("lm").unwrap().shown_name(), "lm");
    }

    #[test]
    fn every_registered_method_builds_with_its_defaults() {
        for m in METHODS {
            let spec = method_by_name(m.name).unwrap();
            assert_eq!(spec.name(), m.name);
            assert_eq!(spec.label, m.name);
        }
    }

    #[test]
    fn options_are_read_and_bad_keys_named() {
        let s = entry("name = \"igg3\"\nlabel = \"robust\"\nk0 = 2\nweight = \"huber\"").unwrap();
        assert_eq!(s.label, "robust");
        assert!(format!("{:?}", s.method).contains("Huber"));
        let (k, msg) = entry("name = \"ls\"\nepsilon = 1").unwrap_err();
        assert_eq!(k, "epsilon");
        assert!(msg.contains("eps"), "{msg}");
        let (k, _) = entry("name = \"lm\"\neps = \"small\"").unwrap_err();
        assert_eq!(k, "eps");
        let (k, msg) = entry("name = \"igg3\"\nk0 = 3\nk1 = 2").unwrap_err();
        assert_eq!(k, "k1");
        assert!(msg.contains("exceed"), "{msg}");
        let (k, _) = entry("name = \"bas\"\nbound_mm = -1").unwrap_err();
        assert_eq!(k, "bound_mm");
        let (k, _) = entry("name = \"pso\"\nvelocity = 2").unwrap_err();
        assert_eq!(k, "velocity");
        let (k, _) = entry("name = \"ridge\"\nxi = \"wide\"").unwrap_err();
        assert_eq!(k, "xi");
        let (k, _) = entry("name = \"nope\"").unwrap_err();
        assert_eq!(k, "name");
        let (k, _) = entry("name = \"ls\"\nk = 0").unwrap_err();
        assert_eq!(k, "k");
        assert!(entry("name = \"ls\"\nerror_model = \"direct_fk\"\niterations = 3").is_ok());
        let (k, _) = entry("name = \"ls\"\nerror_model = \"dh\"").unwrap_err();
        assert_eq!(k, "error_model");
    }

    /// An unknown key of an entry whose table feeds two or more structs is refused listing
    /// every key the entry takes: igg3's had listed the ridge's alone, not `weight`, `k0`,
    /// `k1` or `per`.
    #[test]
    fn an_unknown_key_lists_every_key_of_the_entry() {
        for (name, also) in [
            ("igg3", &["xi", "weight", "k0", "k1", "sigma0", "per"][..]),
            ("ls", &["eps", "error_model"]),
            ("bas", &["antenna", "bound_mm", "decay", "error_model"]),
            ("bas-pso", &["population", "c3", "bound_rad", "step_floor"]),
        ] {
            let (k, msg) = entry(&format!("name = \"{name}\"\nbogus = 1")).unwrap_err();
            assert_eq!(k, "bogus", "{name}");
            assert!(msg.starts_with("unknown field `bogus`, expected "), "{msg}");
            for key in also {
                assert!(
                    msg.contains(&format!("`{key}`")),
                    "{name}: {key} missing from {msg}"
                );
            }
            // Every key listed is one the entry takes.
            for key in msg.split('`').skip(3).step_by(2) {
                let t = format!("name = \"{name}\"\n{key} = \"?\"");
                let (k, m) = entry(&t).unwrap_err();
                assert!(
                    !m.starts_with("unknown field"),
                    "{name}: {key} is not taken: {m}"
                );
                assert_eq!(k, key, "{name}");
            }
        }
    }
}
