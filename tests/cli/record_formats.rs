//! The formats of what `merge` and `run --resume` read back (docs/formats.md § 7.3, § 7.3.1): a
//! shard or a checkpoint written by an earlier calbench, whose records this one would read with
//! a field missing, is refused naming the file, the key `format`, what it has and what is
//! expected; and each format fixes the keys its files hold, so that a record changed without a
//! new format fails here.

use std::collections::BTreeSet;
use std::path::Path;

use crate::cells::INSTRUMENTS;
use crate::common::{
    calbench, calbench_ok, kill_once_checkpointed, one_line_naming, path_arg, read, root, tmp_dir,
    write_scenario,
};
use crate::search_ecdf::small_qiao;

/// Per `format` of `shard.json`, the keys of its shards ([`shard_keys`]): `shard.json`'s, then
/// those of a record of `records.txt` (`records.txt:` …), over a Monte-Carlo study with tracker
/// noise and sag (`ci-guard`), one with searches on full-pose data (`small_qiao`) and an
/// instruments study (`tests/cli/cells.rs`). A row is never edited: a record or `shard.json`
/// that holds other keys is a new format, refused by `merge` as an earlier one.
const SHARD_KEYS: &[(&str, &str)] = &[
    (
        "calbench-shard-8",
        "blocks blocks[].info blocks[].info.error_params blocks[].info.external \
         blocks[].info.fixed blocks[].info.full_pose blocks[].info.index blocks[].info.methods \
         blocks[].info.params blocks[].info.point blocks[].info.robot blocks[].info.searches \
         blocks[].info.separation blocks[].info.strategies blocks[].info.true_compliance \
         blocks[].trial0 blocks[].trial0.per_point blocks[].trial0.per_point_attitude_deg \
         blocks[].trial0.traces format machine machine.cores machine.cpu machine.host machine.os \
         records records.txt:point records.txt:result records.txt:result.after \
         records.txt:result.before records.txt:result.crb records.txt:result.crb_trace \
         records.txt:result.errors records.txt:result.not_determinable \
         records.txt:result.outcomes records.txt:result.outcomes[].after_mm \
         records.txt:result.outcomes[].after_mm.max records.txt:result.outcomes[].after_mm.mean \
         records.txt:result.outcomes[].after_mm.rms records.txt:result.outcomes[].after_mm.std \
         records.txt:result.outcomes[].before_mm records.txt:result.outcomes[].before_mm.max \
         records.txt:result.outcomes[].before_mm.mean records.txt:result.outcomes[].before_mm.rms \
         records.txt:result.outcomes[].before_mm.std \
         records.txt:result.outcomes[].calibration_after_mm \
         records.txt:result.outcomes[].calibration_after_mm.max \
         records.txt:result.outcomes[].calibration_after_mm.mean \
         records.txt:result.outcomes[].calibration_after_mm.rms \
         records.txt:result.outcomes[].calibration_after_mm.std \
         records.txt:result.outcomes[].calibration_before_mm \
         records.txt:result.outcomes[].calibration_before_mm.max \
         records.txt:result.outcomes[].calibration_before_mm.mean \
         records.txt:result.outcomes[].calibration_before_mm.rms \
         records.txt:result.outcomes[].calibration_before_mm.std \
         records.txt:result.outcomes[].evaluations records.txt:result.outcomes[].identified \
         records.txt:result.outcomes[].iterations records.txt:result.outcomes[].method \
         records.txt:result.outcomes[].optional \
         records.txt:result.outcomes[].optional.calibration_after_attitude_deg \
         records.txt:result.outcomes[].optional.calibration_after_attitude_deg.max \
         records.txt:result.outcomes[].optional.calibration_after_attitude_deg.mean \
         records.txt:result.outcomes[].optional.calibration_after_attitude_deg.rms \
         records.txt:result.outcomes[].optional.calibration_after_attitude_deg.std \
         records.txt:result.outcomes[].optional.calibration_before_attitude_deg \
         records.txt:result.outcomes[].optional.calibration_before_attitude_deg.max \
         records.txt:result.outcomes[].optional.calibration_before_attitude_deg.mean \
         records.txt:result.outcomes[].optional.calibration_before_attitude_deg.rms \
         records.txt:result.outcomes[].optional.calibration_before_attitude_deg.std \
         records.txt:result.outcomes[].optional.validation_after_attitude_deg \
         records.txt:result.outcomes[].optional.validation_after_attitude_deg.max \
         records.txt:result.outcomes[].optional.validation_after_attitude_deg.mean \
         records.txt:result.outcomes[].optional.validation_after_attitude_deg.rms \
         records.txt:result.outcomes[].optional.validation_after_attitude_deg.std \
         records.txt:result.outcomes[].optional.validation_after_axis_abs_mm \
         records.txt:result.outcomes[].optional.validation_after_axis_mm \
         records.txt:result.outcomes[].optional.validation_after_deg \
         records.txt:result.outcomes[].optional.validation_after_deg.max \
         records.txt:result.outcomes[].optional.validation_after_deg.mean \
         records.txt:result.outcomes[].optional.validation_after_deg.rms \
         records.txt:result.outcomes[].optional.validation_after_deg.std \
         records.txt:result.outcomes[].optional.validation_before_attitude_deg \
         records.txt:result.outcomes[].optional.validation_before_attitude_deg.max \
         records.txt:result.outcomes[].optional.validation_before_attitude_deg.mean \
         records.txt:result.outcomes[].optional.validation_before_attitude_deg.rms \
         records.txt:result.outcomes[].optional.validation_before_attitude_deg.std \
         records.txt:result.outcomes[].optional.validation_before_axis_abs_mm \
         records.txt:result.outcomes[].optional.validation_before_axis_mm \
         records.txt:result.outcomes[].optional.validation_before_deg \
         records.txt:result.outcomes[].optional.validation_before_deg.max \
         records.txt:result.outcomes[].optional.validation_before_deg.mean \
         records.txt:result.outcomes[].optional.validation_before_deg.rms \
         records.txt:result.outcomes[].optional.validation_before_deg.std \
         records.txt:result.outcomes[].optional.validation_before_fitted_mm \
         records.txt:result.outcomes[].rank_deficient_expected \
         records.txt:result.outcomes[].search records.txt:result.outcomes[].search.at_budget \
         records.txt:result.outcomes[].search.budget \
         records.txt:result.outcomes[].search.final_fitness \
         records.txt:result.outcomes[].search.hits records.txt:result.outcomes[].seconds \
         records.txt:result.outcomes[].strategy records.txt:result.outcomes[].termination \
         records.txt:result.truth records.txt:result.x records.txt:trial scenario scenario_file \
         seconds seed settings shard shard.count shard.index trials units",
    ),
    (
        "calbench-shard-9",
        "blocks blocks[].info blocks[].info.error_params blocks[].info.external \
         blocks[].info.fixed blocks[].info.full_pose blocks[].info.index blocks[].info.methods \
         blocks[].info.params blocks[].info.point blocks[].info.robot blocks[].info.searches \
         blocks[].info.separation blocks[].info.strategies blocks[].info.true_compliance \
         blocks[].sum blocks[].trial0 blocks[].trial0.per_point \
         blocks[].trial0.per_point_attitude_deg blocks[].trial0.traces format machine \
         machine.cores machine.cpu machine.host machine.os records records.txt:point \
         records.txt:result records.txt:result.after records.txt:result.before \
         records.txt:result.crb records.txt:result.crb_trace records.txt:result.errors \
         records.txt:result.not_determinable records.txt:result.outcomes \
         records.txt:result.outcomes[].after_mm records.txt:result.outcomes[].after_mm.max \
         records.txt:result.outcomes[].after_mm.mean records.txt:result.outcomes[].after_mm.rms \
         records.txt:result.outcomes[].after_mm.std records.txt:result.outcomes[].before_mm \
         records.txt:result.outcomes[].before_mm.max records.txt:result.outcomes[].before_mm.mean \
         records.txt:result.outcomes[].before_mm.rms records.txt:result.outcomes[].before_mm.std \
         records.txt:result.outcomes[].calibration_after_mm \
         records.txt:result.outcomes[].calibration_after_mm.max \
         records.txt:result.outcomes[].calibration_after_mm.mean \
         records.txt:result.outcomes[].calibration_after_mm.rms \
         records.txt:result.outcomes[].calibration_after_mm.std \
         records.txt:result.outcomes[].calibration_before_mm \
         records.txt:result.outcomes[].calibration_before_mm.max \
         records.txt:result.outcomes[].calibration_before_mm.mean \
         records.txt:result.outcomes[].calibration_before_mm.rms \
         records.txt:result.outcomes[].calibration_before_mm.std \
         records.txt:result.outcomes[].evaluations records.txt:result.outcomes[].identified \
         records.txt:result.outcomes[].iterations records.txt:result.outcomes[].method \
         records.txt:result.outcomes[].optional \
         records.txt:result.outcomes[].optional.calibration_after_attitude_deg \
         records.txt:result.outcomes[].optional.calibration_after_attitude_deg.max \
         records.txt:result.outcomes[].optional.calibration_after_attitude_deg.mean \
         records.txt:result.outcomes[].optional.calibration_after_attitude_deg.rms \
         records.txt:result.outcomes[].optional.calibration_after_attitude_deg.std \
         records.txt:result.outcomes[].optional.calibration_before_attitude_deg \
         records.txt:result.outcomes[].optional.calibration_before_attitude_deg.max \
         records.txt:result.outcomes[].optional.calibration_before_attitude_deg.mean \
         records.txt:result.outcomes[].optional.calibration_before_attitude_deg.rms \
         records.txt:result.outcomes[].optional.calibration_before_attitude_deg.std \
         records.txt:result.outcomes[].optional.validation_after_attitude_deg \
         records.txt:result.outcomes[].optional.validation_after_attitude_deg.max \
         records.txt:result.outcomes[].optional.validation_after_attitude_deg.mean \
         records.txt:result.outcomes[].optional.validation_after_attitude_deg.rms \
         records.txt:result.outcomes[].optional.validation_after_attitude_deg.std \
         records.txt:result.outcomes[].optional.validation_after_axis_abs_mm \
         records.txt:result.outcomes[].optional.validation_after_axis_mm \
         records.txt:result.outcomes[].optional.validation_after_deg \
         records.txt:result.outcomes[].optional.validation_after_deg.max \
         records.txt:result.outcomes[].optional.validation_after_deg.mean \
         records.txt:result.outcomes[].optional.validation_after_deg.rms \
         records.txt:result.outcomes[].optional.validation_after_deg.std \
         records.txt:result.outcomes[].optional.validation_before_attitude_deg \
         records.txt:result.outcomes[].optional.validation_before_attitude_deg.max \
         records.txt:result.outcomes[].optional.validation_before_attitude_deg.mean \
         records.txt:result.outcomes[].optional.validation_before_attitude_deg.rms \
         records.txt:result.outcomes[].optional.validation_before_attitude_deg.std \
         records.txt:result.outcomes[].optional.validation_before_axis_abs_mm \
         records.txt:result.outcomes[].optional.validation_before_axis_mm \
         records.txt:result.outcomes[].optional.validation_before_deg \
         records.txt:result.outcomes[].optional.validation_before_deg.max \
         records.txt:result.outcomes[].optional.validation_before_deg.mean \
         records.txt:result.outcomes[].optional.validation_before_deg.rms \
         records.txt:result.outcomes[].optional.validation_before_deg.std \
         records.txt:result.outcomes[].optional.validation_before_fitted_mm \
         records.txt:result.outcomes[].rank_deficient_expected \
         records.txt:result.outcomes[].search records.txt:result.outcomes[].search.at_budget \
         records.txt:result.outcomes[].search.budget \
         records.txt:result.outcomes[].search.final_fitness \
         records.txt:result.outcomes[].search.hits records.txt:result.outcomes[].seconds \
         records.txt:result.outcomes[].strategy records.txt:result.outcomes[].termination \
         records.txt:result.truth records.txt:result.x records.txt:trial scenario scenario_file \
         seconds seed settings shard shard.count shard.index trials units",
    ),
    (
        "calbench-shard-10",
        "blocks blocks[].info blocks[].info.error_params blocks[].info.external \
         blocks[].info.fixed blocks[].info.full_pose blocks[].info.index blocks[].info.methods \
         blocks[].info.params blocks[].info.point blocks[].info.robot blocks[].info.searches \
         blocks[].info.separation blocks[].info.strategies blocks[].info.true_compliance \
         blocks[].sum blocks[].trial0 blocks[].trial0.per_point \
         blocks[].trial0.per_point_attitude_deg blocks[].trial0.traces format inputs machine \
         machine.cores machine.cpu machine.host machine.os records records.txt:point \
         records.txt:result records.txt:result.after records.txt:result.before \
         records.txt:result.crb records.txt:result.crb_trace records.txt:result.errors \
         records.txt:result.not_determinable records.txt:result.outcomes \
         records.txt:result.outcomes[].after_mm records.txt:result.outcomes[].after_mm.max \
         records.txt:result.outcomes[].after_mm.mean records.txt:result.outcomes[].after_mm.rms \
         records.txt:result.outcomes[].after_mm.std records.txt:result.outcomes[].before_mm \
         records.txt:result.outcomes[].before_mm.max records.txt:result.outcomes[].before_mm.mean \
         records.txt:result.outcomes[].before_mm.rms records.txt:result.outcomes[].before_mm.std \
         records.txt:result.outcomes[].calibration_after_mm \
         records.txt:result.outcomes[].calibration_after_mm.max \
         records.txt:result.outcomes[].calibration_after_mm.mean \
         records.txt:result.outcomes[].calibration_after_mm.rms \
         records.txt:result.outcomes[].calibration_after_mm.std \
         records.txt:result.outcomes[].calibration_before_mm \
         records.txt:result.outcomes[].calibration_before_mm.max \
         records.txt:result.outcomes[].calibration_before_mm.mean \
         records.txt:result.outcomes[].calibration_before_mm.rms \
         records.txt:result.outcomes[].calibration_before_mm.std \
         records.txt:result.outcomes[].evaluations records.txt:result.outcomes[].identified \
         records.txt:result.outcomes[].iterations records.txt:result.outcomes[].method \
         records.txt:result.outcomes[].optional \
         records.txt:result.outcomes[].optional.calibration_after_attitude_deg \
         records.txt:result.outcomes[].optional.calibration_after_attitude_deg.max \
         records.txt:result.outcomes[].optional.calibration_after_attitude_deg.mean \
         records.txt:result.outcomes[].optional.calibration_after_attitude_deg.rms \
         records.txt:result.outcomes[].optional.calibration_after_attitude_deg.std \
         records.txt:result.outcomes[].optional.calibration_before_attitude_deg \
         records.txt:result.outcomes[].optional.calibration_before_attitude_deg.max \
         records.txt:result.outcomes[].optional.calibration_before_attitude_deg.mean \
         records.txt:result.outcomes[].optional.calibration_before_attitude_deg.rms \
         records.txt:result.outcomes[].optional.calibration_before_attitude_deg.std \
         records.txt:result.outcomes[].optional.validation_after_attitude_deg \
         records.txt:result.outcomes[].optional.validation_after_attitude_deg.max \
         records.txt:result.outcomes[].optional.validation_after_attitude_deg.mean \
         records.txt:result.outcomes[].optional.validation_after_attitude_deg.rms \
         records.txt:result.outcomes[].optional.validation_after_attitude_deg.std \
         records.txt:result.outcomes[].optional.validation_after_axis_abs_mm \
         records.txt:result.outcomes[].optional.validation_after_axis_mm \
         records.txt:result.outcomes[].optional.validation_after_deg \
         records.txt:result.outcomes[].optional.validation_after_deg.max \
         records.txt:result.outcomes[].optional.validation_after_deg.mean \
         records.txt:result.outcomes[].optional.validation_after_deg.rms \
         records.txt:result.outcomes[].optional.validation_after_deg.std \
         records.txt:result.outcomes[].optional.validation_before_attitude_deg \
         records.txt:result.outcomes[].optional.validation_before_attitude_deg.max \
         records.txt:result.outcomes[].optional.validation_before_attitude_deg.mean \
         records.txt:result.outcomes[].optional.validation_before_attitude_deg.rms \
         records.txt:result.outcomes[].optional.validation_before_attitude_deg.std \
         records.txt:result.outcomes[].optional.validation_before_axis_abs_mm \
         records.txt:result.outcomes[].optional.validation_before_axis_mm \
         records.txt:result.outcomes[].optional.validation_before_deg \
         records.txt:result.outcomes[].optional.validation_before_deg.max \
         records.txt:result.outcomes[].optional.validation_before_deg.mean \
         records.txt:result.outcomes[].optional.validation_before_deg.rms \
         records.txt:result.outcomes[].optional.validation_before_deg.std \
         records.txt:result.outcomes[].optional.validation_before_fitted_mm \
         records.txt:result.outcomes[].rank_deficient_expected \
         records.txt:result.outcomes[].search records.txt:result.outcomes[].search.at_budget \
         records.txt:result.outcomes[].search.budget \
         records.txt:result.outcomes[].search.final_fitness \
         records.txt:result.outcomes[].search.hits records.txt:result.outcomes[].seconds \
         records.txt:result.outcomes[].strategy records.txt:result.outcomes[].termination \
         records.txt:result.truth records.txt:result.x records.txt:trial scenario scenario_file \
         seconds seed settings shard shard.count shard.index trials units",
    ),
];

/// Per `format` of `checkpoint.json`, the keys of a checkpoint of `ci-guard`
/// ([`checkpoint_keys`]), the same way.
const CHECKPOINT_KEYS: &[(&str, &str)] = &[
    (
        "calbench-checkpoint-6",
        "bytes done format host pid records.txt:point records.txt:result \
     records.txt:result.crb_trace records.txt:result.outcomes \
     records.txt:result.outcomes[].after_mm records.txt:result.outcomes[].after_mm.max \
     records.txt:result.outcomes[].after_mm.mean records.txt:result.outcomes[].after_mm.rms \
     records.txt:result.outcomes[].after_mm.std records.txt:result.outcomes[].before_mm \
     records.txt:result.outcomes[].before_mm.max records.txt:result.outcomes[].before_mm.mean \
     records.txt:result.outcomes[].before_mm.rms records.txt:result.outcomes[].before_mm.std \
     records.txt:result.outcomes[].calibration_after_mm \
     records.txt:result.outcomes[].calibration_after_mm.max \
     records.txt:result.outcomes[].calibration_after_mm.mean \
     records.txt:result.outcomes[].calibration_after_mm.rms \
     records.txt:result.outcomes[].calibration_after_mm.std \
     records.txt:result.outcomes[].calibration_before_mm \
     records.txt:result.outcomes[].calibration_before_mm.max \
     records.txt:result.outcomes[].calibration_before_mm.mean \
     records.txt:result.outcomes[].calibration_before_mm.rms \
     records.txt:result.outcomes[].calibration_before_mm.std \
     records.txt:result.outcomes[].evaluations records.txt:result.outcomes[].identified \
     records.txt:result.outcomes[].iterations records.txt:result.outcomes[].method \
     records.txt:result.outcomes[].optional \
     records.txt:result.outcomes[].optional.calibration_after_attitude_deg \
     records.txt:result.outcomes[].optional.calibration_before_attitude_deg \
     records.txt:result.outcomes[].optional.validation_after_attitude_deg \
     records.txt:result.outcomes[].optional.validation_after_axis_abs_mm \
     records.txt:result.outcomes[].optional.validation_after_axis_mm \
     records.txt:result.outcomes[].optional.validation_after_deg \
     records.txt:result.outcomes[].optional.validation_before_attitude_deg \
     records.txt:result.outcomes[].optional.validation_before_axis_abs_mm \
     records.txt:result.outcomes[].optional.validation_before_axis_mm \
     records.txt:result.outcomes[].optional.validation_before_deg \
     records.txt:result.outcomes[].optional.validation_before_fitted_mm \
     records.txt:result.outcomes[].rank_deficient_expected records.txt:result.outcomes[].search \
     records.txt:result.outcomes[].seconds records.txt:result.outcomes[].strategy \
     records.txt:result.outcomes[].termination records.txt:result.truth records.txt:trial \
     scenario scenario_file seed settings shard trials version",
    ),
    (
        "calbench-checkpoint-7",
        "bytes done format host inputs pid records.txt:point records.txt:result \
     records.txt:result.crb_trace records.txt:result.outcomes \
     records.txt:result.outcomes[].after_mm records.txt:result.outcomes[].after_mm.max \
     records.txt:result.outcomes[].after_mm.mean records.txt:result.outcomes[].after_mm.rms \
     records.txt:result.outcomes[].after_mm.std records.txt:result.outcomes[].before_mm \
     records.txt:result.outcomes[].before_mm.max records.txt:result.outcomes[].before_mm.mean \
     records.txt:result.outcomes[].before_mm.rms records.txt:result.outcomes[].before_mm.std \
     records.txt:result.outcomes[].calibration_after_mm \
     records.txt:result.outcomes[].calibration_after_mm.max \
     records.txt:result.outcomes[].calibration_after_mm.mean \
     records.txt:result.outcomes[].calibration_after_mm.rms \
     records.txt:result.outcomes[].calibration_after_mm.std \
     records.txt:result.outcomes[].calibration_before_mm \
     records.txt:result.outcomes[].calibration_before_mm.max \
     records.txt:result.outcomes[].calibration_before_mm.mean \
     records.txt:result.outcomes[].calibration_before_mm.rms \
     records.txt:result.outcomes[].calibration_before_mm.std \
     records.txt:result.outcomes[].evaluations records.txt:result.outcomes[].identified \
     records.txt:result.outcomes[].iterations records.txt:result.outcomes[].method \
     records.txt:result.outcomes[].optional \
     records.txt:result.outcomes[].optional.calibration_after_attitude_deg \
     records.txt:result.outcomes[].optional.calibration_before_attitude_deg \
     records.txt:result.outcomes[].optional.validation_after_attitude_deg \
     records.txt:result.outcomes[].optional.validation_after_axis_abs_mm \
     records.txt:result.outcomes[].optional.validation_after_axis_mm \
     records.txt:result.outcomes[].optional.validation_after_deg \
     records.txt:result.outcomes[].optional.validation_before_attitude_deg \
     records.txt:result.outcomes[].optional.validation_before_axis_abs_mm \
     records.txt:result.outcomes[].optional.validation_before_axis_mm \
     records.txt:result.outcomes[].optional.validation_before_deg \
     records.txt:result.outcomes[].optional.validation_before_fitted_mm \
     records.txt:result.outcomes[].rank_deficient_expected records.txt:result.outcomes[].search \
     records.txt:result.outcomes[].seconds records.txt:result.outcomes[].strategy \
     records.txt:result.outcomes[].termination records.txt:result.truth records.txt:trial \
     scenario scenario_file seed settings shard trials version",
    ),
];

/// The format before `format` (`calbench-shard-8` → `calbench-shard-7`), as an earlier
/// calbench wrote it.
fn previous(format: &str) -> String {
    let (name, n) = format.rsplit_once('-').unwrap();
    let n: u32 = n.parse().unwrap();
    format!("{name}-{}", n - 1)
}

/// The `"format"` of the JSON document `text`.
fn format_of(text: &str) -> String {
    let v: serde_json::Value = serde_json::from_str(text).unwrap();
    v["format"].as_str().expect("a format").to_string()
}

/// `text` with its `"format": "F"` replaced by `"format": "to"`.
fn with_format(text: &str, to: &str) -> String {
    let from = format!("\"format\": \"{}\"", format_of(text));
    assert!(text.contains(&from), "{text}");
    text.replacen(&from, &format!("\"format\": \"{to}\""), 1)
}

/// The path of key `k` under `at` (`records.txt:` for a record's top level).
fn join(at: &str, k: &str) -> String {
    if at.is_empty() || at.ends_with(':') {
        format!("{at}{k}")
    } else {
        format!("{at}.{k}")
    }
}

/// The key paths of a JSON document: `a.b`, `a[].b` for a list's items. The values of the
/// keys in `opaque` are free-form documents (a report's JSON, names to numbers), not
/// fields: their keys are data and are not walked.
fn json_keys(v: &serde_json::Value, at: &str, opaque: &[&str], out: &mut BTreeSet<String>) {
    match v {
        serde_json::Value::Object(m) => {
            for (k, v) in m {
                let p = join(at, k);
                out.insert(p.clone());
                if !opaque.contains(&p.as_str()) {
                    json_keys(v, &p, opaque, out);
                }
            }
        }
        serde_json::Value::Array(items) => {
            for i in items {
                json_keys(i, &format!("{at}[]"), opaque, out);
            }
        }
        _ => {}
    }
}

/// The key paths of a RON value (a record of `records.txt`): a struct's fields, walked
/// through lists and `Some`.
fn ron_keys(v: &ron::Value, at: &str, out: &mut BTreeSet<String>) {
    match v {
        ron::Value::Map(m) => {
            for (k, v) in m.iter() {
                let k = match k {
                    ron::Value::String(s) => s.clone(),
                    other => panic!("{at}: a key that is not a name: {other:?}"),
                };
                let p = join(at, &k);
                out.insert(p.clone());
                ron_keys(v, &p, out);
            }
        }
        ron::Value::Seq(items) => {
            for i in items {
                ron_keys(i, &format!("{at}[]"), out);
            }
        }
        ron::Value::Option(Some(v)) => ron_keys(v, at, out),
        _ => {}
    }
}

/// The key paths of every record of the `records.txt` at `path` (each line's text before its
/// checksum), under `records.txt`.
fn records_keys(path: &Path, out: &mut BTreeSet<String>) {
    let text = read(path);
    assert!(!text.is_empty(), "{}: no record", path.display());
    for line in text.lines() {
        let body = line.rsplit_once(" #").expect("a checksum").0;
        let v: ron::Value = ron::from_str(body).unwrap_or_else(|e| panic!("{body}: {e}"));
        ron_keys(&v, "records.txt:", out);
    }
}

/// Fails, saying what to do, unless `keys` (of files of `format`) are the row of `format` in
/// `table`.
fn assert_fixed(table: &[(&str, &str)], format: &str, keys: &BTreeSet<String>) {
    let now = keys.iter().cloned().collect::<Vec<_>>().join(" ");
    let bump = "bump FORMAT in src/runner/shard.rs and src/runner/checkpoint.rs (an earlier \
                calbench's shards and checkpoints must then be refused, not read with a field \
                missing), give the new formats their rows in tests/cli/record_formats.rs, and \
                name the bump in CHANGELOG.md (Unreleased) and docs/formats.md § 7.3";
    let Some((_, fixed)) = table.iter().find(|(f, _)| *f == format) else {
        panic!("format {format} has no row of keys; its keys are:\n{now}\n(a new format: {bump})");
    };
    let fixed: BTreeSet<String> = fixed.split_whitespace().map(String::from).collect();
    let added: Vec<&String> = keys.difference(&fixed).collect();
    let removed: Vec<&String> = fixed.difference(keys).collect();
    assert!(
        added.is_empty() && removed.is_empty(),
        "the files of format {format} now hold other keys (added {added:?}, removed \
         {removed:?}): a record changed without a new format; {bump}.\nIts keys now:\n{now}"
    );
}

/// Runs `calbench run SCENARIO --trials N --threads 1 --shard 0/1` into `out`.
fn shard(sc: &Path, trials: &str, out: &Path) {
    calbench_ok(&[
        "run",
        path_arg(sc),
        "--trials",
        trials,
        "--threads",
        "1",
        "--shard",
        "0/1",
        "--out",
        path_arg(out),
    ]);
}

/// The format and the keys of the shard folder `dir`: `shard.json`'s and its records'.
fn shard_keys(dir: &Path, out: &mut BTreeSet<String>) -> String {
    let text = read(&dir.join("shard.json"));
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let opaque = [
        "blocks[].info.separation",
        "blocks[].info.true_compliance",
        "blocks[].info.fixed[].scores",
    ];
    json_keys(&v, "", &opaque, out);
    records_keys(&dir.join("records.txt"), out);
    format_of(&text)
}

/// The format and the keys of the checkpoint whose `checkpoint.json` is `meta`.
fn checkpoint_keys(meta: &Path, out: &mut BTreeSet<String>) -> String {
    let text = read(meta);
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    json_keys(&v, "", &[], out);
    records_keys(&meta.with_file_name("records.txt"), out);
    format_of(&text)
}

/// Starts `ci-guard` at 600 trials into `out` and kills it once its checkpoint holds a trial:
/// the checkpoint's `checkpoint.json`.
fn killed_ci_guard(out: &Path) -> std::path::PathBuf {
    let sc = root().join("scenarios/ci-guard.toml");
    let args = ["run", path_arg(&sc), "--trials", "600", "--threads", "1"];
    let meta = kill_once_checkpointed(&[&args[..], &["--out", path_arg(out)]].concat(), out, 300);
    assert!(
        !out.join("summary.json").exists(),
        "the run ended before it was killed"
    );
    meta
}

#[test]
fn merge_refuses_a_shard_of_the_previous_format_naming_it() {
    let dir = tmp_dir("formats-shard");
    let sc = root().join("scenarios/ci-guard.toml");
    let (s0, s1) = (dir.join("s0"), dir.join("s1"));
    for (i, s) in [&s0, &s1].into_iter().enumerate() {
        calbench_ok(&[
            "run",
            path_arg(&sc),
            "--trials",
            "4",
            "--threads",
            "1",
            "--shard",
            &format!("{i}/2"),
            "--out",
            path_arg(s),
        ]);
    }
    let meta = s1.join("shard.json");
    let own = read(&meta);
    let (now, old) = (format_of(&own), previous(&format_of(&own)));
    std::fs::write(&meta, with_format(&own, &old)).unwrap();
    let out = dir.join("merged");
    let args = [
        "merge",
        path_arg(&s0),
        path_arg(&s1),
        "--out",
        path_arg(&out),
    ];
    let o = calbench(&args);
    assert!(!o.status.success(), "merged a shard of format {old}");
    let err = String::from_utf8_lossy(&o.stderr);
    one_line_naming(&err, &meta, &["format", &old, &now, "run the shard again"]);
    let written = std::fs::read_dir(&out).map_or(0, |d| d.count());
    assert_eq!(written, 0, "a refused merge wrote into {}", out.display());
    // The same shard with its own format merges.
    std::fs::write(&meta, &own).unwrap();
    calbench_ok(&args);
}

#[test]
fn resume_refuses_a_checkpoint_of_the_previous_format_naming_it() {
    let dir = tmp_dir("formats-checkpoint");
    let killed = dir.join("killed");
    let meta = killed_ci_guard(&killed);
    let own = read(&meta);
    let records = read(&meta.with_file_name("records.txt"));
    let (now, old) = (format_of(&own), previous(&format_of(&own)));
    let altered = with_format(&own, &old);
    std::fs::write(&meta, &altered).unwrap();
    let o = calbench(&["run", "--resume", path_arg(&killed)]);
    assert!(!o.status.success(), "resumed a checkpoint of format {old}");
    let err = String::from_utf8_lossy(&o.stderr);
    one_line_naming(&err, &meta, &["format", &old, &now, "without --resume"]);
    // Refused before anything changed.
    assert_eq!(read(&meta), altered);
    assert_eq!(read(&meta.with_file_name("records.txt")), records);
    assert!(!killed.join("summary.json").exists());
    // With its own format it resumes.
    std::fs::write(&meta, &own).unwrap();
    calbench_ok(&["run", "--resume", path_arg(&killed)]);
    assert!(killed.join("summary.json").exists());
}

#[test]
fn each_shard_format_fixes_the_keys_of_its_files() {
    let dir = tmp_dir("formats-shard-keys");
    let mut keys = BTreeSet::new();
    let mut formats = BTreeSet::new();
    let qiao = small_qiao(&dir);
    let instruments = write_scenario(&dir, "instruments", INSTRUMENTS);
    for (name, sc, trials) in [
        ("ci-guard", root().join("scenarios/ci-guard.toml"), "2"),
        ("qiao", qiao, "2"),
        ("instruments", instruments, "2"),
    ] {
        let out = dir.join(name);
        shard(&sc, trials, &out);
        formats.insert(shard_keys(&out, &mut keys));
    }
    assert_eq!(formats.len(), 1, "{formats:?}");
    let format = formats.pop_first().unwrap();
    assert_fixed(SHARD_KEYS, &format, &keys);
}

#[test]
fn each_checkpoint_format_fixes_the_keys_of_its_files() {
    let dir = tmp_dir("formats-checkpoint-keys");
    let meta = killed_ci_guard(&dir.join("killed"));
    let mut keys = BTreeSet::new();
    let format = checkpoint_keys(&meta, &mut keys);
    assert_fixed(CHECKPOINT_KEYS, &format, &keys);
}
