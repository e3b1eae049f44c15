//! The expressions of `docs/reproduction-numbers.toml` (the grammar is in `numbers.rs`'s
//! module doc): committed files read once, and a recursive-descent evaluation.

use super::super::root;
use std::collections::HashMap;

/// The committed files the expressions read, loaded once.
#[derive(Default)]
pub struct Files(HashMap<String, serde_json::Value>);

impl Files {
    fn get(&mut self, file: &str) -> Result<&serde_json::Value, String> {
        if !self.0.contains_key(file) {
            let text = std::fs::read_to_string(root().join(file))
                .map_err(|e| format!("cannot read {file}: {e}"))?;
            let value = if file.ends_with(".json") {
                serde_json::from_str(&text).map_err(|e| format!("{file}: {e}"))?
            } else if file.ends_with(".toml") {
                let v: toml::Value = toml::from_str(&text).map_err(|e| format!("{file}: {e}"))?;
                serde_json::to_value(v).unwrap()
            } else if file.ends_with(".csv") {
                let mut lines = text.lines();
                let head: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
                let rows = lines.map(|l| {
                    let row = head.iter().zip(l.split(',')).map(|(k, v)| {
                        let v = v.parse::<f64>().map_or(v.into(), serde_json::Value::from);
                        (k.to_string(), v)
                    });
                    serde_json::Value::Object(row.collect())
                });
                serde_json::Value::Array(rows.collect())
            } else {
                return Err(format!("{file}: not a .json, .toml or .csv file"));
            };
            self.0.insert(file.to_string(), value);
        }
        Ok(&self.0[file])
    }

    /// `FILE#PATH` (or `PATH` of `default`).
    fn lookup(&mut self, what: &str, default: Option<&str>) -> Result<serde_json::Value, String> {
        let (file, path) = match what.split_once('#') {
            Some((f, p)) if !f.is_empty() => (f, p),
            Some((_, p)) => (default.ok_or("no `file` for {PATH}")?, p),
            None => (default.ok_or("no `file` for {PATH}")?, what),
        };
        let mut v = self.get(file)?;
        let mut rest = path;
        while !rest.is_empty() {
            let (key, label, next) = if let Some(r) = rest.strip_prefix('[') {
                let end = r.find(']').ok_or(format!("unclosed [ in {path}"))?;
                (None, Some(&r[..end]), &r[end + 1..])
            } else {
                let end = rest.find(['/', '[']).unwrap_or(rest.len());
                (Some(&rest[..end]), None, &rest[end..])
            };
            rest = next.strip_prefix('/').unwrap_or(next);
            let found = match (key, label, v) {
                (Some(k), _, serde_json::Value::Array(a)) => {
                    k.parse::<usize>().ok().and_then(|i| a.get(i))
                }
                (Some(k), _, obj) => obj.get(k),
                (None, Some(l), serde_json::Value::Object(o)) => o.get(l),
                (None, Some(l), serde_json::Value::Array(a)) => {
                    a.iter().find(|e| match l.split_once('=') {
                        Some((k, v)) => e[k] == v,
                        None => ["method", "label", "id", "name"].iter().any(|f| e[*f] == l),
                    })
                }
                _ => None,
            };
            v = found.ok_or(format!(
                "{file}: no {path} (at `{}`)",
                key.or(label).unwrap_or("")
            ))?;
        }
        Ok(v.clone())
    }
}

/// The rows of `v` (a `trials.csv`) of `method` (any, without one) whose column `key` is
/// `value` (a number compared as a number).
fn rows_of<'v>(
    v: &'v serde_json::Value,
    method: Option<&'v str>,
    keep: &'v Option<(String, String)>,
) -> Result<impl Iterator<Item = &'v serde_json::Value>, String> {
    let rows = v.as_array().ok_or(format!("not a list of rows: {v}"))?;
    let same = |x: &serde_json::Value, want: &str| match (x.as_f64(), want.parse::<f64>()) {
        (Some(x), Ok(w)) => x == w,
        _ => x.as_str() == Some(want),
    };
    Ok(rows.iter().filter(move |r| {
        method.is_none_or(|m| r["method"] == m)
            && keep
                .as_ref()
                .is_none_or(|(k, want)| same(&r[k.as_str()], want))
    }))
}

/// A recursive-descent evaluation of one source expression.
struct Expr<'a> {
    s: Vec<char>,
    i: usize,
    line: &'a [f64],
    file: Option<&'a str>,
    files: &'a mut Files,
}

impl Expr<'_> {
    fn peek(&mut self) -> Option<char> {
        while self.s.get(self.i).is_some_and(|c| c.is_whitespace()) {
            self.i += 1;
        }
        self.s.get(self.i).copied()
    }

    fn eat(&mut self, c: char) -> bool {
        let hit = self.peek() == Some(c);
        self.i += hit as usize;
        hit
    }

    fn sum(&mut self) -> Result<f64, String> {
        let mut v = self.product()?;
        loop {
            if self.eat('+') {
                v += self.product()?;
            } else if self.eat('-') {
                v -= self.product()?;
            } else {
                return Ok(v);
            }
        }
    }

    fn product(&mut self) -> Result<f64, String> {
        let mut v = self.unary()?;
        loop {
            if self.eat('*') {
                v *= self.unary()?;
            } else if self.eat('/') {
                v /= self.unary()?;
            } else {
                return Ok(v);
            }
        }
    }

    fn unary(&mut self) -> Result<f64, String> {
        if self.eat('-') {
            return Ok(-self.unary()?);
        }
        self.atom()
    }

    fn braces(&mut self) -> Result<serde_json::Value, String> {
        if !self.eat('{') {
            return Err("expected {FILE#PATH}".into());
        }
        let end = (self.i..self.s.len())
            .find(|&j| self.s[j] == '}')
            .ok_or("unclosed {")?;
        let what: String = self.s[self.i..end].iter().collect();
        self.i = end + 1;
        self.files.lookup(what.trim(), self.file)
    }

    fn atom(&mut self) -> Result<f64, String> {
        match self.peek() {
            Some('(') => {
                self.i += 1;
                let v = self.sum()?;
                self.eat(')').then_some(v).ok_or("expected )".into())
            }
            Some('{') => {
                let v = self.braces()?;
                v.as_f64().ok_or(format!("not a number: {v}"))
            }
            Some('$') => {
                self.i += 1;
                let k = self.digits()?;
                let k = k as usize;
                self.line
                    .get(k.wrapping_sub(1))
                    .copied()
                    .ok_or(format!("no number ${k} on the line"))
            }
            Some(c) if c.is_ascii_digit() => self.digits(),
            Some(c) if c.is_ascii_alphabetic() => {
                let start = self.i;
                while self
                    .s
                    .get(self.i)
                    .is_some_and(|c| c.is_ascii_alphanumeric())
                {
                    self.i += 1;
                }
                let name: String = self.s[start..self.i].iter().collect();
                match name.as_str() {
                    "deg" => Ok(180.0 / std::f64::consts::PI),
                    "len" => {
                        self.eat('(');
                        let v = self.braces()?;
                        self.eat(')');
                        match v {
                            serde_json::Value::Array(a) => Ok(a.len() as f64),
                            serde_json::Value::Object(o) => Ok(o.len() as f64),
                            v => Err(format!("len of {v}")),
                        }
                    }
                    "count" => {
                        self.eat('(');
                        let v = self.braces()?;
                        self.eat(',');
                        let a = self.word();
                        let below = self.below("count")?;
                        let b = self.word();
                        self.eat(')').then_some(()).ok_or("count: expected )")?;
                        let rows = v.as_array().ok_or(format!("count of {v}"))?;
                        let mut n = 0;
                        for r in rows {
                            let field = |k: &str| {
                                r[k].as_f64()
                                    .ok_or(format!("count: no number `{k}` in {r}"))
                            };
                            let (x, y) = (field(&a)?, field(&b)?);
                            n += usize::from(if below { x < y } else { x > y });
                        }
                        Ok(n as f64)
                    }
                    "mean" | "median" => {
                        self.eat('(');
                        let rows = self.braces()?;
                        self.eat(',');
                        let column = self.token();
                        let (method, keep) = self.method_and_filter()?;
                        let mut v: Vec<f64> = rows_of(&rows, method.as_deref(), &keep)?
                            .filter_map(|r| r[&column].as_f64())
                            .collect();
                        if v.is_empty() {
                            return Err(format!("{name}: no number `{column}` in the rows"));
                        }
                        v.sort_by(f64::total_cmp);
                        let n = v.len();
                        Ok(match name.as_str() {
                            "mean" => v.iter().sum::<f64>() / n as f64,
                            _ if n % 2 == 1 => v[n / 2],
                            _ => 0.5 * (v[n / 2 - 1] + v[n / 2]),
                        })
                    }
                    "paired" => {
                        self.eat('(');
                        let rows = self.braces()?;
                        self.eat(',');
                        let column = self.token();
                        self.eat(',');
                        let a = self.token();
                        let below = self.below("paired")?;
                        let b = self.token();
                        let keep = if self.eat(',') {
                            Some(self.filter()?)
                        } else {
                            None
                        };
                        self.eat(')').then_some(()).ok_or("paired: expected )")?;
                        let by_trial = |m: &str| -> Result<HashMap<String, f64>, String> {
                            rows_of(&rows, Some(m), &keep)?
                                .map(|r| {
                                    let x = r[&column].as_f64().ok_or(format!(
                                        "paired: no number `{column}` in a row of {m}"
                                    ))?;
                                    Ok((r["trial"].to_string(), x))
                                })
                                .collect()
                        };
                        let (xa, xb) = (by_trial(&a)?, by_trial(&b)?);
                        if xa.is_empty() || xa.len() != xb.len() {
                            return Err(format!("paired: {a} and {b} have different trials"));
                        }
                        let mut n = 0;
                        for (t, x) in &xa {
                            let y = xb.get(t).ok_or(format!("paired: no trial {t} of {b}"))?;
                            n += usize::from(if below { x < y } else { x > y });
                        }
                        Ok(n as f64)
                    }
                    "sqrt" | "abs" => {
                        let v = self.atom()?;
                        Ok(if name == "sqrt" { v.sqrt() } else { v.abs() })
                    }
                    "min" | "max" => {
                        self.eat('(');
                        let a = self.sum()?;
                        self.eat(',');
                        let b = self.sum()?;
                        self.eat(')');
                        Ok(if name == "min" { a.min(b) } else { a.max(b) })
                    }
                    _ => Err(format!("unknown name `{name}`")),
                }
            }
            c => Err(format!("unexpected {c:?}")),
        }
    }

    /// A method's label or a column's name: letters, digits and `_ . -`.
    fn token(&mut self) -> String {
        self.peek();
        let start = self.i;
        while self
            .s
            .get(self.i)
            .is_some_and(|c| c.is_ascii_alphanumeric() || "_.-".contains(*c))
        {
            self.i += 1;
        }
        self.s[start..self.i].iter().collect()
    }

    /// `<` (true) or `>` (false) between the two sides of `what`.
    fn below(&mut self, what: &str) -> Result<bool, String> {
        if self.eat('<') {
            Ok(true)
        } else if self.eat('>') {
            Ok(false)
        } else {
            Err(format!("{what}: expected `a < b` or `a > b`"))
        }
    }

    /// `key=value`.
    fn filter(&mut self) -> Result<(String, String), String> {
        let key = self.token();
        if !self.eat('=') {
            return Err(format!("expected `{key}=value`"));
        }
        Ok((key, self.token()))
    }

    /// The optional `, METHOD` and `, key=value` that close `mean(…)` and `median(…)`.
    #[allow(clippy::type_complexity)]
    fn method_and_filter(&mut self) -> Result<(Option<String>, Option<(String, String)>), String> {
        let (mut method, mut keep) = (None, None);
        while self.eat(',') {
            let t = self.token();
            if self.eat('=') {
                keep = Some((t, self.token()));
            } else {
                method = Some(t);
            }
        }
        self.eat(')').then_some(()).ok_or("expected )")?;
        Ok((method, keep))
    }

    /// A field name (letters, digits, `_`).
    fn word(&mut self) -> String {
        self.peek();
        let start = self.i;
        while self
            .s
            .get(self.i)
            .is_some_and(|c| c.is_ascii_alphanumeric() || *c == '_')
        {
            self.i += 1;
        }
        self.s[start..self.i].iter().collect()
    }

    fn digits(&mut self) -> Result<f64, String> {
        let start = self.i;
        while self
            .s
            .get(self.i)
            .is_some_and(|c| c.is_ascii_digit() || *c == '.' || *c == 'e')
        {
            self.i += 1;
        }
        let t: String = self.s[start..self.i].iter().collect();
        t.parse().map_err(|_| format!("bad number `{t}`"))
    }
}

pub fn eval(src: &str, line: &[f64], file: Option<&str>, files: &mut Files) -> Result<f64, String> {
    let mut e = Expr {
        s: src.chars().collect(),
        i: 0,
        line,
        file,
        files,
    };
    let v = e.sum()?;
    match e.peek() {
        None => Ok(v),
        Some(c) => Err(format!("unexpected {c:?} at {}", e.i)),
    }
}

/// The `$k` an expression uses.
pub fn refs(src: &str) -> Vec<usize> {
    let mut out = Vec::new();
    for (i, _) in src.match_indices('$') {
        let k: String = src[i + 1..]
            .chars()
            .take_while(|c| c.is_ascii_digit())
            .collect();
        out.extend(k.parse::<usize>().ok());
    }
    out
}
