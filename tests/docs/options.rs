//! docs/formats.md's option tables of the methods (§ 4.12) against the options structs.

use super::root;

/// docs/formats.md's option tables of the methods (§ 4.12) agree with the options structs:
/// each documented default, given explicitly, builds the same method as no key at all, and
/// each documented range (`> 0`, `≥ 0`, `≥ 1`, `in [0, 1)`) refuses the value just outside
/// it, naming the key.
#[test]
fn method_option_tables_match_the_declarations() {
    use calbench::identify::registry::METHODS;
    let text = std::fs::read_to_string(root().join("docs/formats.md")).unwrap();
    let mut method = None;
    let (mut defaults, mut ranges) = (0, 0);
    let mut after_blank = true;
    for line in text.lines() {
        if !line.starts_with('|') {
            // A paragraph opening with a method's name starts its table; any other ends it.
            let head = line.trim_start_matches("**");
            if after_blank && !line.trim().is_empty() {
                method = METHODS
                    .iter()
                    .find(|m| head.starts_with(&format!("`{}`", m.name)))
                    .filter(|_| !line.contains("with `error_model`"));
            }
            after_blank = line.trim().is_empty();
            continue;
        }
        after_blank = false;
        let Some(m) = method else { continue };
        let cells: Vec<&str> = line
            .split(" | ")
            .map(|c| c.trim_matches(['|', ' ']))
            .collect();
        let Some(key) = cells[0].strip_prefix('`').and_then(|k| k.strip_suffix('`')) else {
            continue;
        };
        // The keys of `lm`'s adaptive damping are read (and refused unread) only with
        // `adaptive = true`.
        let mut context = toml::Table::new();
        if m.name == "lm" && ["lambda0", "lambda_factor"].contains(&key) {
            context.insert("adaptive".into(), toml::Value::Boolean(true));
        }
        let build = |v: toml::Value| {
            let mut t = context.clone();
            t.insert(key.to_string(), v);
            (m.build)(&t)
        };
        let default: Option<toml::Value> =
            toml::from_str::<toml::Table>(&format!("v = {}", cells[1]))
                .ok()
                .and_then(|mut t| t.remove("v"));
        let Some(default) = default else { continue };
        let given = build(default.clone()).map(|x| format!("{x:?}"));
        let none = (m.build)(&context).map(|x| format!("{x:?}"));
        assert_eq!(
            given, none,
            "{}: `{key}` = {} is not the default",
            m.name, cells[1]
        );
        defaults += 1;
        let integer = default.is_integer();
        let value = |x: f64| {
            if integer {
                toml::Value::Integer(x as i64)
            } else {
                toml::Value::Float(x)
            }
        };
        let outside: &[f64] = if cells[2].contains("in [0, 1)") {
            &[1.0, -0.1]
        } else if cells[2].contains("> 0") {
            &[0.0]
        } else if cells[2].contains("≥ 0") {
            &[-1.0]
        } else if cells[2].contains("≥ 1") {
            &[0.0]
        } else {
            &[]
        };
        for &x in outside {
            match build(value(x)) {
                Err((k, _)) => assert_eq!(k, key, "{}: {key} = {x} refused naming {k}", m.name),
                Ok(_) => panic!(
                    "{}: {key} = {x} is outside `{}` but accepted",
                    m.name, cells[2]
                ),
            }
            ranges += 1;
        }
    }
    assert!(
        defaults >= 20 && ranges >= 20,
        "{defaults} defaults, {ranges} ranges checked"
    );
}
