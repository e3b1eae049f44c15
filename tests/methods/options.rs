//! Each method's options are declared once: the options structs' fields are the keys, and
//! no key is written out again by hand in the identification code.

use calbench::identify::options::fields;
use calbench::identify::qiao::{BasOptions, BeetleTerm, PsoOptions, Schedules};
use calbench::identify::{
    qiao::method::SearchBox, LmOptions, LsOptions, PoseErrorLs, RidgeOptions, Robustness,
};

/// The non-test code of every `.rs` file under `dir` (a file's own tests start at its
/// `#[cfg(test)]` module; `tests.rs` files and `tests/` folders are tests).
fn code_under(dir: &std::path::Path) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                if p.file_name().unwrap() != "tests" {
                    stack.push(p);
                }
            } else if p.extension().is_some_and(|x| x == "rs")
                && p.file_name().unwrap() != "tests.rs"
            {
                let text = std::fs::read_to_string(&p).unwrap();
                let code = text.split("#[cfg(test)]\nmod tests").next().unwrap();
                out.push((p.display().to_string(), code.to_string()));
            }
        }
    }
    out
}

#[test]
fn method_option_keys_are_declared_once() {
    let structs: &[(&str, &[&str])] = &[
        ("LsOptions", fields::<LsOptions>()),
        ("RidgeOptions", fields::<RidgeOptions>()),
        ("Robustness", fields::<Robustness>()),
        ("LmOptions", fields::<LmOptions>()),
        ("PoseErrorLs", fields::<PoseErrorLs>()),
        ("SearchBox", fields::<SearchBox>()),
        ("Schedules", fields::<Schedules>()),
        ("BasOptions", fields::<BasOptions>()),
        ("PsoOptions", fields::<PsoOptions>()),
        ("BeetleTerm", fields::<BeetleTerm>()),
    ];
    let mut keys = Vec::new();
    for (name, f) in structs {
        assert!(!f.is_empty(), "{name} declares no keys");
        keys.extend(f.iter().copied());
    }
    // The introspection sees what the scenarios use.
    for k in [
        "eps",
        "xi",
        "k1",
        "sigma0",
        "lambda_factor",
        "bound_mm",
        "antenna_floor",
        "c3",
    ] {
        assert!(keys.contains(&k), "{k} missing from {keys:?}");
    }
    let root = crate::common::root();
    let identify = code_under(&root.join("src/identify"));
    for key in &keys {
        let quoted = format!("\"{key}\"");
        let hits: Vec<&str> = identify
            .iter()
            .flat_map(|(p, code)| code.matches(quoted.as_str()).map(move |_| p.as_str()))
            .collect();
        assert!(
            hits.len() <= 1,
            "{quoted} written {} times: {hits:?}",
            hits.len()
        );
    }
    // Qiao's schedule floors: one declaration in the whole library and the Python module.
    let mut all = code_under(&root.join("src"));
    all.extend(code_under(&root.join("python/src")));
    let floors: Vec<&str> = all
        .iter()
        .flat_map(|(p, code)| code.matches("antenna_floor").map(move |_| p.as_str()))
        .collect();
    assert_eq!(floors.len(), 1, "{floors:?}");
}
