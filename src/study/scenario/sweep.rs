//! Sweeps (`[sweep]`, `[[sweep]]`) and overrides: the axes as written, their check, and the
//! scenario of each sweep point, made by editing the parsed TOML and checking it again.

use std::path::PathBuf;

use serde::Deserialize;

use super::{Scenario, Source};
use crate::error::{at_line, without_line, Error, Result};
use crate::identify::MethodSpec;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SweepSection {
    pub(super) key: String,
    pub(super) values: Vec<toml::Value>,
    #[serde(default)]
    pub(super) zip: bool,
}

/// `[sweep]` (one axis) or `[[sweep]]` (a grid of axes), told apart by the value's shape so
/// that a refusal is the section's own (an unknown key named with the allowed ones), where
/// an untagged enum said only that no variant matched. The section is read from the file's
/// own deserialiser, so that a refusal of a value in it names that value's key and line
/// (`sweep.values`), not the section's header.
#[derive(Debug)]
pub(super) enum SweepField {
    One(SweepSection),
    Grid(Vec<SweepSection>),
}

impl<'de> Deserialize<'de> for SweepField {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        use serde::de::value::{MapAccessDeserializer, SeqAccessDeserializer};
        struct Shape;
        impl<'de> serde::de::Visitor<'de> for Shape {
            type Value = SweepField;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a table [sweep] or tables [[sweep]]")
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                seq: A,
            ) -> std::result::Result<SweepField, A::Error> {
                Vec::deserialize(SeqAccessDeserializer::new(seq)).map(SweepField::Grid)
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                map: A,
            ) -> std::result::Result<SweepField, A::Error> {
                SweepSection::deserialize(MapAccessDeserializer::new(map)).map(SweepField::One)
            }
        }
        d.deserialize_any(Shape)
    }
}

/// One axis of a sweep: a dotted key and its values.
#[derive(Clone, Debug)]
pub struct SweepAxis {
    /// The key, e.g. `outliers.count` or `methods.<label>.k0`.
    pub key: String,
    /// The values, as written.
    pub values: Vec<toml::Value>,
}

/// The swept settings (docs/formats.md `[sweep]`, `[[sweep]]`): one axis, or several axes run as
/// their cartesian product (the last axis varying fastest) or, with `zip`, paired value by
/// value.
#[derive(Clone, Debug)]
pub struct Sweep {
    /// The axes, in file order.
    pub axes: Vec<SweepAxis>,
    /// The axes' lists are paired (`zip = true` on the first axis) instead of crossed.
    pub zip: bool,
    /// Written as `[[sweep]]` (axis `i` is `sweep[i]` in the file), not as `[sweep]`.
    grid: bool,
}

impl Sweep {
    /// The swept keys, in axis order.
    pub fn keys(&self) -> Vec<&str> {
        self.axes.iter().map(|a| a.key.as_str()).collect()
    }

    /// Every point of the sweep: one value per axis, in run order.
    pub fn points(&self) -> Vec<Vec<toml::Value>> {
        if self.zip {
            let n = self.axes[0].values.len();
            return (0..n)
                .map(|i| self.axes.iter().map(|a| a.values[i].clone()).collect())
                .collect();
        }
        let mut points: Vec<Vec<toml::Value>> = vec![Vec::new()];
        for a in &self.axes {
            points = points
                .iter()
                .flat_map(|p| {
                    a.values.iter().map(move |v| {
                        let mut q = p.clone();
                        q.push(v.clone());
                        q
                    })
                })
                .collect();
        }
        points
    }

    /// The value a point of the sweep (one value per axis) is named by in `summary.json`
    /// (`sweep_value`, a claim's `paper_point`): the one axis's value, or the array of the
    /// axes' values.
    pub fn point_value(point: &[toml::Value]) -> serde_json::Value {
        let json: Vec<serde_json::Value> = point.iter().map(crate::study::toml_to_json).collect();
        match <[_; 1]>::try_from(json) {
            Ok([one]) => one,
            Err(all) => serde_json::Value::Array(all),
        }
    }

    /// Sets each claim's `paper_point` to the point of `sweep` it names, however each writes
    /// its numbers ([`at_point`]), or refuses, as (key, message), one (claim `i` of `claims`)
    /// that is no point of `sweep`, or given without a sweep: no point would be the paper's
    /// setting.
    fn place_paper_points(
        sweep: Option<&Sweep>,
        claims: &mut [crate::study::claims::Claim],
    ) -> std::result::Result<(), (String, String)> {
        let points = sweep.map(Sweep::points).unwrap_or_default();
        for (i, c) in claims.iter_mut().enumerate() {
            let Some(pp) = &c.paper_point else { continue };
            let key = format!("claims[{i}].paper_point");
            if sweep.is_none() {
                let why =
                    "is the swept value at the paper's setting, and the scenario has no sweep";
                return Err((key, format!("claim \"{}\": {why}", c.id)));
            }
            if let Some(p) = points.iter().find(|p| at_point(pp, p)) {
                c.paper_point = Some(match p.as_slice() {
                    [one] => one.clone(),
                    all => toml::Value::Array(all.to_vec()),
                });
            } else {
                let listed: Vec<String> = points
                    .iter()
                    .map(|p| Sweep::point_value(p).to_string())
                    .collect();
                let why = format!(
                    "claim \"{}\": {pp} is no point of the sweep (its points: {}), so no point \
                     would be the paper's setting",
                    c.id,
                    listed.join(", ")
                );
                return Err((key, why));
            }
        }
        Ok(())
    }

    /// The dotted key of `what` (`key`, `values[1]`) of axis `i` as the file writes it:
    /// `sweep.values[1]`, or `sweep[0].values[1]` in a `[[sweep]]` grid.
    fn key_of(&self, i: usize, what: &str) -> String {
        match self.grid {
            true => format!("sweep[{i}].{what}"),
            false => format!("sweep.{what}"),
        }
    }

    /// The key of the file at whose line a refusal of the sweep point `point` is named,
    /// `refused` being the key the scenario refused once the point's values were set: where
    /// `refused` is (or lies in) an axis's key, that axis's value; where it holds one (a
    /// section that does not take the key, or the scenario refusing a section the sweep
    /// adds), that axis's `key`; else the one axis's value, or the sweep itself for a grid.
    fn refused_at(&self, point: &[toml::Value], refused: &str, table: &toml::Table) -> String {
        let within =
            |a: &str, b: &str| a.strip_prefix(b).is_some_and(|r| r.starts_with(['.', '[']));
        let value = |i: usize| {
            let a = &self.axes[i];
            let zipped = |k: usize| self.axes.iter().zip(point).all(|(a, v)| a.values[k] == *v);
            let at = match self.zip {
                true => (0..a.values.len()).find(|&k| zipped(k)),
                false => a.values.iter().position(|v| *v == point[i]),
            };
            at.map_or_else(
                || self.key_of(i, "values"),
                |k| self.key_of(i, &format!("values[{k}]")),
            )
        };
        let keys = || self.axes.iter().map(|a| a.key.as_str()).enumerate();
        let added = |k: &str| !table.contains_key(k.split('.').next().unwrap_or(k));
        if let Some((i, _)) = keys().find(|(_, k)| refused == *k || within(refused, k)) {
            value(i)
        } else if let Some((i, _)) =
            keys().find(|(_, k)| within(k, refused) || (refused == "scenario" && added(k)))
        {
            self.key_of(i, "key")
        } else if self.axes.len() == 1 {
            value(0)
        } else {
            "sweep".into()
        }
    }

    /// The number of independent dimensions the results span: 1 for one axis or zipped
    /// axes, else the number of axes.
    pub fn dims(&self) -> usize {
        if self.zip {
            1
        } else {
            self.axes.len()
        }
    }
}

/// `e`, a refusal of a scenario whose `key` a run's option `opt` set (`--trials`, `trials=`),
/// as a refusal of the option: the value is not the file's, and neither is a line.
pub(crate) fn given(e: Error, key: &str, opt: crate::error::Opt) -> Error {
    match e {
        Error::File { place, msg, .. } if place == key || place.ends_with(&format!(", {key}")) => {
            Error::option(opt, msg)
        }
        e => e,
    }
}

impl Scenario {
    /// The file a refusal names.
    fn shown(&self) -> PathBuf {
        self.path
            .clone()
            .unwrap_or_else(|| PathBuf::from("<built-in default scenario>"))
    }

    /// A refusal of the setting `key` as one of the scenario's file, at the line that writes
    /// it: for a check that needs what the scenario reads (a pose list's rows), made as the
    /// study is planned, before any trial runs.
    pub(crate) fn refusal(&self, key: &str, msg: String) -> Error {
        let line = self.source.as_ref().and_then(|s| s.line(key));
        Error::file(self.shown(), at_line(line, key), msg)
    }

    /// The scenario as read, once its claims' `paper_point`s are found among the sweep's
    /// points. A file's own check, not a sweep point's: a point's scenario has no sweep.
    /// An axis's integer values are its key's floats where the key takes a float (`5` for
    /// `tracker.mpe_a_um` is the point `5.0`, as a run that writes `5.0` names it), and a
    /// `paper_point` is the point it names, however each writes its numbers.
    pub(super) fn with_paper_points_checked(mut self) -> Result<Scenario> {
        self.type_sweep_values();
        let placed = Sweep::place_paper_points(self.sweep.as_ref(), &mut self.claims);
        let Err((key, msg)) = placed else {
            return Ok(self);
        };
        let line = self.source.as_ref().and_then(|s| s.line(&key));
        Err(Error::file(self.shown(), at_line(line, &key), msg))
    }

    /// Each axis's integer values made floats where its key takes a float: the first point
    /// with the axis's first integer as a float is checked as a study ([`Scenario::plan`]);
    /// a key that takes only integers (`outliers.count`) refuses it and keeps them.
    fn type_sweep_values(&mut self) {
        let Some(sw) = &self.sweep else { return };
        let Some(first) = sw.points().into_iter().next() else {
            return;
        };
        let floats: Vec<usize> = (0..sw.axes.len())
            .filter(|&i| {
                let values = &sw.axes[i].values;
                let Some(&toml::Value::Integer(v)) = values.iter().find(|v| v.is_integer()) else {
                    return false;
                };
                let mut point = first.clone();
                point[i] = toml::Value::Float(v as f64);
                self.plan(&point).is_ok()
            })
            .collect();
        let Some(sw) = &mut self.sweep else { return };
        for i in floats {
            for v in &mut sw.axes[i].values {
                if let toml::Value::Integer(n) = *v {
                    *v = toml::Value::Float(n as f64);
                }
            }
        }
    }

    /// A copy with one dotted key (`outliers.count`, `trials`, `tracker.mpe_a_um`) set to
    /// `value`, checked again.
    pub fn with_override(&self, key: &str, value: toml::Value) -> Result<Scenario> {
        if key.starts_with("methods") {
            return Err(Error::setting(key, "methods cannot be overridden"));
        }
        Scenario::from_table(
            self.edited(self.table.clone(), key, value)?,
            self.path.as_deref(),
            Source::edit(&self.source, [key.to_string()]),
        )
        .map(|s| s.keeping_external(self))
    }

    /// The scenario with a run's overrides (`calbench run --trials N --seed S`): the number of
    /// trials and the master seed.
    pub fn with_run_overrides(&self, trials: Option<usize>, seed: Option<u64>) -> Result<Scenario> {
        let mut sc = self.clone();
        if let Some(n) = trials {
            // 2^63 and more wrapped to a negative count, refused as the file's.
            let n = i64::try_from(n).map_err(|_| {
                let most = super::MAX_TRIALS;
                let msg = format!("must be between 1 and {most}, got {n}");
                Error::option(crate::error::Opt::Trials, msg)
            })?;
            sc = sc
                .with_override("trials", toml::Value::Integer(n))
                .map_err(|e| given(e, "trials", crate::error::Opt::Trials))?;
        }
        if let Some(s) = seed {
            let s = i64::try_from(s)
                .map_err(|_| Error::option(crate::error::Opt::Seed, "must be below 2^63"))?;
            sc = sc
                .with_override("seed", toml::Value::Integer(s))
                .map_err(|e| given(e, "seed", crate::error::Opt::Seed))?;
        }
        Ok(sc)
    }

    /// `self` with the methods supplied from outside of `from` (which no table holds).
    fn keeping_external(mut self, from: &Scenario) -> Scenario {
        self.methods
            .extend(from.methods.iter().filter(|m| m.is_external()).cloned());
        self
    }

    /// A copy with a method supplied from outside ([`crate::identify::external`]), run after
    /// the file's methods on the same trials. Its label must differ from every other.
    pub fn with_method(&self, spec: MethodSpec) -> Result<Scenario> {
        if spec.label.trim().is_empty() || self.methods.iter().any(|m| m.label == spec.label) {
            return Err(Error::setting(
                "methods",
                format!(
                    "the label \"{}\" is empty or taken; the scenario's methods are {}",
                    spec.label,
                    self.methods
                        .iter()
                        .map(|m| format!("\"{}\"", m.label))
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ));
        }
        if let Some(msg) = crate::identify::registry::hidden_label(&spec.label) {
            let msg = format!("the label {:?} {msg}", spec.label);
            return Err(Error::setting("methods", msg));
        }
        let mut s = self.clone();
        s.methods.push(spec);
        Ok(s)
    }

    /// The study of one sweep point (one value per axis): the scenario with each swept key
    /// set and no sweep, checked again. A refusal names the file, the swept key and the line
    /// of the sweep's value refused, or of the axis's `key` where the scenario does not take
    /// the key (docs/formats.md `[sweep]`).
    pub fn plan(&self, point: &[toml::Value]) -> Result<Scenario> {
        let shown = self.shown();
        let Some(sw) = &self.sweep else {
            return Ok(self.clone());
        };
        let mut table = self.table.clone();
        table.remove("sweep");
        let line = |key: String| self.source.as_ref().and_then(|s| s.line(&key));
        let mut keys = Vec::new();
        for (i, (axis, v)) in sw.axes.iter().zip(point).enumerate() {
            table = self.edited(table, &axis.key, v.clone()).map_err(|e| {
                let place = format!("sweep key \"{}\"", axis.key);
                Error::file(
                    &shown,
                    at_line(line(sw.key_of(i, "key")), place),
                    e.to_string(),
                )
            })?;
            keys.push(format!("{} = {v}", axis.key));
        }
        let source = Source::edit(
            &self.source,
            sw.axes
                .iter()
                .map(|a| a.key.clone())
                .chain(["sweep".into()]),
        );
        Scenario::from_table(table, self.path.as_deref(), source)
            .map(|s| s.keeping_external(self))
            .map_err(|e| {
                let (msg, refused) = match e {
                    Error::File { place, msg, .. } => {
                        let key = without_line(&place).to_string();
                        (format!("{place}: {msg}"), key)
                    }
                    other => (other.to_string(), String::new()),
                };
                let at = line(sw.refused_at(point, &refused, &self.table));
                Error::file(
                    &shown,
                    at_line(at, format!("sweep ({})", keys.join(", "))),
                    msg,
                )
            })
    }

    /// `table` with the dotted `key` set to `value`. `methods.<label>.<key>` sets a key of
    /// the method whose `label` (or, without one, name) is `<label>`. The key must be one
    /// the scenario can hold: an unknown one is refused when the table is checked again.
    fn edited(&self, mut table: toml::Table, key: &str, value: toml::Value) -> Result<toml::Table> {
        let mut parts: Vec<&str> = key.split('.').collect();
        if parts.iter().any(|p| p.is_empty()) {
            return Err(Error::setting(key, "is not a dotted key"));
        }
        let last = parts.pop().unwrap_or_default();
        if parts.first() == Some(&"methods") {
            if parts.len() != 2 {
                return Err(Error::setting(
                    key,
                    "a method key is swept as methods.<label>.<key>",
                ));
            }
            let label = parts[1];
            let methods = table
                .get_mut("methods")
                .and_then(toml::Value::as_array_mut)
                .ok_or_else(|| Error::setting(key, "the scenario has no [[methods]]"))?;
            let label_of = |t: &toml::Table| {
                t.get("label")
                    .or_else(|| t.get("name"))
                    .and_then(toml::Value::as_str)
                    .map(str::to_string)
            };
            let labels: Vec<String> = methods
                .iter()
                .filter_map(|m| m.as_table().and_then(label_of))
                .collect();
            let m = methods
                .iter_mut()
                .filter_map(toml::Value::as_table_mut)
                .find(|t| label_of(t).as_deref() == Some(label))
                .ok_or_else(|| {
                    Error::setting(
                        key,
                        format!(
                            "no method labelled \"{label}\"; labels: {}",
                            labels.join(", ")
                        ),
                    )
                })?;
            if last == "name" || last == "label" {
                return Err(Error::setting(
                    key,
                    "a method's name and label cannot be swept",
                ));
            }
            m.insert(last.to_string(), value);
            return Ok(table);
        }
        if matches!(parts.first(), Some(&"sweep")) || (parts.is_empty() && last == "name") {
            return Err(Error::setting(key, "cannot be swept or overridden"));
        }

        let mut t = &mut table;
        for p in parts {
            t = t
                .entry(p.to_string())
                .or_insert_with(|| toml::Value::Table(toml::Table::new()))
                .as_table_mut()
                .ok_or_else(|| Error::setting(key, format!("`{p}` is not a section")))?;
        }
        t.insert(last.to_string(), value);
        Ok(table)
    }

    /// One checked scenario per sweep point, with the point's values (or the scenario itself
    /// when there is no sweep).
    pub fn sweep_plans(&self) -> Result<Vec<(Option<Vec<toml::Value>>, Scenario)>> {
        match &self.sweep {
            None => Ok(vec![(None, self.clone())]),
            Some(sw) => sw
                .points()
                .into_iter()
                .map(|p| {
                    let plan = self.plan(&p)?;
                    Ok((Some(p), plan))
                })
                .collect(),
        }
    }
}

/// Checks the sweep section: every axis a key and a non-empty list, keys distinct, zipped
/// lists of one length. Returns (key, message) on refusal.
pub(super) fn check_sweep(field: SweepField) -> std::result::Result<Sweep, (String, String)> {
    let (sections, grid) = match field {
        SweepField::One(s) => (vec![s], false),
        SweepField::Grid(v) => (v, true),
    };
    if sections.is_empty() {
        return Err(("sweep".into(), "give at least one [[sweep]] axis".into()));
    }
    let zip = sections[0].zip;
    let mut axes: Vec<SweepAxis> = Vec::new();
    for (i, s) in sections.into_iter().enumerate() {
        let place = if grid {
            format!("sweep[{i}]")
        } else {
            "sweep".into()
        };
        if s.zip && (i > 0 || !grid) {
            let why = match grid {
                true => "zip = true belongs on the first axis",
                false => "zip = true pairs the axes of a [[sweep]] grid; one [sweep] has none",
            };
            return Err((format!("{place}.zip"), why.into()));
        }
        if s.values.is_empty() {
            return Err((
                format!("{place}.values"),
                format!("\"{}\": give at least one value", s.key),
            ));
        }
        // Every point runs the run's trials from the run's seeds (`--trials`, `--seed`).
        if let Some(what) = match s.key.as_str() {
            "trials" => Some("trials"),
            "seed" => Some("seeds, so that the points differ only in the swept settings"),
            _ => None,
        } {
            return Err((
                format!("{place}.key"),
                format!(
                    "\"{}\" cannot be swept: every sweep point runs the run's {what}",
                    s.key
                ),
            ));
        }
        if !zip {
            let twice = crate::study::given_twice(
                &s.values,
                same_value,
                ToString::to_string,
                "sweep points",
            );
            if let Some((j, msg)) = twice {
                let msg = format!("\"{}\": {msg}", s.key);
                return Err((format!("{place}.values[{j}]"), msg));
            }
        }
        if axes.iter().any(|a| a.key == s.key) {
            return Err((
                format!("{place}.key"),
                format!("\"{}\" is swept twice", s.key),
            ));
        }
        // A table and a key inside it on two axes: one axis's value would override the other's.
        let within = |a: &str, b: &str| a.strip_prefix(b).is_some_and(|r| r.starts_with('.'));
        if let Some(a) = axes
            .iter()
            .find(|a| within(&s.key, &a.key) || within(&a.key, &s.key))
        {
            return Err((
                format!("{place}.key"),
                format!(
                    "\"{}\" and \"{}\", swept on another axis, are a table and a key inside it: \
                     one axis's value would override the other's; sweep one of them",
                    s.key, a.key
                ),
            ));
        }
        if zip && s.values.len() != axes.first().map_or(s.values.len(), |a| a.values.len()) {
            return Err((
                format!("{place}.values"),
                format!(
                    "zipped axes need lists of one length: \"{}\" has {}, \"{}\" {}",
                    axes[0].key,
                    axes[0].values.len(),
                    s.key,
                    s.values.len()
                ),
            ));
        }
        let points = axes.iter().map(|a| a.values.len()).product::<usize>();
        if !zip && points.saturating_mul(s.values.len()) > super::MAX_SWEEP_POINTS {
            let most = super::MAX_SWEEP_POINTS;
            let msg = format!(
                "\"{}\": {} values make a grid of {} points with the axes before: at most \
                 {most} are run",
                s.key,
                s.values.len(),
                points as u128 * s.values.len() as u128
            );
            return Err((format!("{place}.values"), msg));
        }
        axes.push(SweepAxis {
            key: s.key,
            values: s.values,
        });
    }
    Ok(Sweep { axes, zip, grid })
}

/// Two sweep values alike: equal, or numbers of one value (`5` and `5.0`), element by element
/// in arrays.
fn same_value(a: &toml::Value, b: &toml::Value) -> bool {
    use toml::Value::{Array, Float, Integer};
    match (a, b) {
        (Integer(i), Float(f)) | (Float(f), Integer(i)) => *i as f64 == *f,
        (Array(x), Array(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(a, b)| same_value(a, b))
        }
        _ => a == b,
    }
}

/// Whether a claim's `paper_point` `pp` names the sweep point `point`: its one axis's value,
/// or the array of the axes' values ([`Sweep::point_value`]).
fn at_point(pp: &toml::Value, point: &[toml::Value]) -> bool {
    match point {
        [one] => same_value(pp, one),
        all => same_value(pp, &toml::Value::Array(all.to_vec())),
    }
}
