//! What a scenario's table sets once every default is filled in: two runs ran one scenario
//! when their tables set the same, however each wrote it (docs/formats.md § 7.1).

use super::{MethodSpec, RawScenario};

/// The settings of the scenario `table` other than `seed` and `trials` (which only choose the
/// draws), every default filled in, as text that is equal for two tables that differ only in
/// how they write a setting: an integer for a float (`2500` for `2500.0`), a default written
/// out (`mpe_a_um = 15.0`), a method's `label` equal to its name. A key whose absence is not
/// a value (`outliers.count`, none by default) differs from every value written. `None` for a table that is
/// not a calibration scenario's (another study kind's, or one refused as written): such a
/// table is compared as written.
pub fn effect(table: &toml::Table) -> Option<String> {
    let mut table = table.clone();
    table.remove("seed");
    table.remove("trials");
    let mut raw: RawScenario = toml::Value::Table(table).try_into().ok()?;
    let methods = std::mem::take(&mut raw.methods)
        .iter()
        .map(MethodSpec::from_table)
        .collect::<std::result::Result<Vec<_>, _>>()
        .ok()?;
    Some(format!("{raw:?}\n{methods:?}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn of(text: &str) -> Option<String> {
        effect(&toml::from_str(text).unwrap())
    }

    const BASE: &str = "name = \"g\"\nseed = 1\ntrials = 3\n[robot]\nbuiltin = \"irb2600\"\n\
                        [tracker]\npose = [2500.0, 0.0, 500.0, 0.0, 0.0, 180.0]\n\
                        [[methods]]\nname = \"lm\"\n";

    #[test]
    fn the_same_settings_written_another_way_have_one_effect() {
        let base = of(BASE).unwrap();
        for same in [
            BASE.replace(
                "[2500.0, 0.0, 500.0, 0.0, 0.0, 180.0]",
                "[2500, 0, 500, 0, 0, 180]",
            ),
            BASE.replace("[tracker]\n", "[tracker]\nmpe_a_um = 15.0\n"),
            BASE.replace("name = \"lm\"\n", "name = \"lm\"\nlabel = \"lm\"\nmu = 1\n"),
            BASE.replace("seed = 1\ntrials = 3\n", "seed = 7\n"),
            format!("{BASE}[outliers]\nmagnitude_mm = [0.5, 1]\n"),
        ] {
            assert_eq!(of(&same).as_deref(), Some(base.as_str()), "{same}");
        }
        for other in [
            BASE.replace("[tracker]\n", "[tracker]\nmpe_a_um = 15.5\n"),
            BASE.replace("name = \"lm\"\n", "name = \"lm\"\nmu = 2\n"),
            BASE.replace("name = \"g\"", "name = \"h\""),
            format!("{BASE}[outliers]\ncount = 2\n"),
        ] {
            assert_ne!(of(&other).as_deref(), Some(base.as_str()), "{other}");
        }
        assert_eq!(of("name = \"g\"\n[registration_study]\n"), None);
    }
}
