//! Cross-validation of a model whose identification re-admits parameters at the identified
//! robot (docs/formats.md § 2.6.1, "Parameters re-checked at the identified robot", and `cv`):
//! each fold is identified as `identify` identifies the whole file, re-check included, so the
//! CV RMS is the figure of the model finally identified. Checked against the folds identified
//! by hand through the library with the re-admitted parameters freed from the start.

use calbench::calibrate::cv::{folds, subset};
use calbench::calibrate::validation::validate_file;
use calbench::calibrate::{calibrate, Registration};
use calbench::identify::method_by_name;
use calbench::measurement::csv::read_measurements;
use calbench::numeric::rng::stream;
use calbench::numeric::Frame;
use calbench::robot::{builtin, Param};

use crate::common::{load_json, tmp_dir};
use crate::readmit::{identify_irb2600_lm, names, off_axis_errors, write_data};

/// Per fold, `params` of the irb2600 identified by `lm` (seed 0) on the other folds of `cal`
/// (4 folds, fold seed 0) and the RMS of the fold's position errors; and the RMS over every
/// held-out point.
fn folds_by_hand(cal: &std::path::Path, params: &[Param]) -> (Vec<f64>, f64) {
    let robot = builtin::irb2600();
    let data = read_measurements(cal, &robot).unwrap();
    let method = method_by_name("lm").unwrap();
    let fold = folds(data.len(), 4, 0);
    let (mut each, mut sum_sq) = (Vec::new(), 0.0);
    for f in 0..4 {
        let (test, train): (Vec<usize>, Vec<usize>) = (0..data.len()).partition(|&i| fold[i] == f);
        let (tr, te) = (subset(&data, &train), subset(&data, &test));
        let mut rng = stream(0, "identify");
        let reg = Registration::Identify;
        let c = calibrate(
            &robot,
            params,
            &tr,
            reg,
            &Frame::identity(),
            &method,
            &mut rng,
        )
        .unwrap();
        let rms = validate_file(&robot, &c, &te).unwrap().after_mm.rms;
        sum_sq += rms * rms * te.len() as f64;
        each.push(rms);
    }
    (each, (sum_sq / data.len() as f64).sqrt())
}

/// The off-axis data of tests/cli/readmit.rs (joint 6's harmonics re-admitted at the
/// identified robot): `identify --models harmonics --cv 4` gives, fold by fold, the RMS of
/// folds identified with `hs6` and `hc6` freed, and not that of the model chosen at the
/// nominal robot, which is several times the noise.
#[test]
fn each_fold_of_the_cv_is_identified_with_the_parameters_the_re_check_admits() {
    let d = tmp_dir("cli-readmit-cv");
    let (cal, val) = (d.join("cal.csv"), d.join("val.csv"));
    let errors = off_axis_errors(0.01, -0.005);
    write_data(&cal, &errors, 0.01, 200, 3);
    write_data(&val, &errors, 0.01, 40, 4);
    let out = d.join("h");
    identify_irb2600_lm(&cal, &val, &["--models", "harmonics", "--cv", "4"], &out);
    let id = load_json(&out.join("identified.json"));
    let params: Vec<Param> = names(&id)
        .iter()
        .map(|n| Param::parse(n).unwrap())
        .collect();
    let n = params.len();
    assert_eq!(
        params[n - 2..],
        [Param::Harmonic(5, 0), Param::Harmonic(5, 1)],
        "{}",
        id["readmitted"]
    );
    let cv = &id["cv"];
    let fold_rms: Vec<f64> = cv["fold_rms"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let (with, rms_with) = folds_by_hand(&cal, &params);
    let (without, rms_without) = folds_by_hand(&cal, &params[..n - 2]);
    // The CV's second fit of a fold starts at the fold's identified robot, the fit by hand at
    // the nominal one: both stop at lm's convergence test, so they agree to about 1e-6 of the
    // RMS (7e-7 measured), not to rounding; without hs6 and hc6 the folds are 3 times off.
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-5 * b;
    for f in 0..4 {
        assert!(
            close(fold_rms[f], with[f]),
            "fold {f}: CV {} against {} by hand with hs6, hc6 ({} without)",
            fold_rms[f],
            with[f],
            without[f]
        );
    }
    let rms = cv["rms"].as_f64().unwrap();
    assert!(close(rms, rms_with), "{rms} against {rms_with}");
    // The re-admission changes the figure: at the noise with the terms, several times it
    // without them (σ ≈ 0.01 mm per point).
    assert!(
        rms_with < 0.015 && rms_without > 3.0 * rms_with,
        "{rms_with} with, {rms_without} without"
    );
}
