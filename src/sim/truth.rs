//! The true robot's parameter errors.
//!
//! The paper set of Guo 2024 §4.2 puts +0.5 mm on every length and +0.05 rad on every angle
//! parameter; random sets draw each error from a normal or uniform law whose size depends on
//! the parameter's type (length or angle). Errors go on the joint and tool parameters only:
//! the base pose is the business of the registration (the tracker frame is unknown to the
//! calibration), so base errors would only duplicate the tracker pose.

use rand::Rng as _;
use rand_distr::StandardNormal;

use super::settings::{listed_params, ErrorKind, ErrorSettings, ParamSelection};
use crate::error::{Error, Result};
use crate::measurement::Measure;
use crate::numeric::rng::Rng;
use crate::numeric::Real;
use crate::robot::identifiability::identifiable_generic;
use crate::robot::{Param, Robot};

/// The joint and tool parameters of `robot` (base excluded, held at its nominal value)
/// that are identifiable from `measure` data
/// ([`crate::robot::identifiability::identifiable_generic`]). Deterministic, so callers may cache
/// it per (robot, measure).
pub fn identifiable_params(robot: &Robot, measure: Measure) -> Vec<Param> {
    let params: Vec<Param> = robot
        .params()
        .into_iter()
        .filter(|p| !matches!(p, Param::Base(_)))
        .collect();
    identifiable_generic(robot, &params, measure)
}

/// The parameters selected by `sel` for `robot`: refuses names that are not parameters of
/// the robot's model, naming `key`, the scenario key that listed them (a list), or the name's
/// own key in it (the table `errors.values`, whose keys are the names).
pub fn selected_params(
    robot: &Robot,
    sel: &ParamSelection,
    measure: Measure,
    key: &str,
) -> Result<Vec<Param>> {
    match sel {
        ParamSelection::Identifiable => Ok(identifiable_params(robot, measure)),
        ParamSelection::All => Ok(robot
            .params()
            .into_iter()
            .filter(|p| !matches!(p, Param::Base(_)))
            .collect()),
        ParamSelection::List(names) => {
            let all = robot.params();
            listed_params(names, |n| {
                Param::parse(n).filter(|p| all.contains(p)).ok_or_else(|| {
                    Error::setting(
                        crate::sim::settings::name_key(key, n),
                        format!(
                            "\"{n}\" is not a parameter of robot \"{}\" ({} convention, {} joints)",
                            robot.name,
                            robot.convention.as_str(),
                            robot.dof()
                        ),
                    )
                })
            })
        }
    }
}

/// The injected errors (parameter, mm or rad) of the true robot `nominal + errors`
///: for `paper`, `+length_mm` on lengths and `+angle_rad` on angles (Guo 2024
/// §4.2); for `normal`, N(0, σ²) with σ = `length_mm` / `angle_rad`; for `uniform`,
/// U(−h, h) with the same half-widths; for `none`, no errors (an empty list). The parameters
/// come in flat-vector order for `identifiable`/`all` and in list order otherwise.
pub fn true_errors(
    nominal: &Robot,
    s: &ErrorSettings,
    measure: Measure,
    rng: &mut Rng,
) -> Result<Vec<(Param, Real)>> {
    s.check()?;
    let selection = s.selection();
    if s.kind == ErrorKind::None {
        // Still refuse names that do not exist in this robot.
        if let ParamSelection::List(_) = selection {
            selected_params(nominal, &selection, measure, s.key())?;
        }
        return Ok(Vec::new());
    }
    let params = selected_params(nominal, &selection, measure, s.key())?;
    Ok(draw_errors(&params, s, rng))
}

/// The errors of `params` drawn as `s` says (see [`true_errors`]), in the order of `params`.
pub fn draw_errors(params: &[Param], s: &ErrorSettings, rng: &mut Rng) -> Vec<(Param, Real)> {
    params
        .iter()
        .map(|&p| {
            let size = if p.is_length() {
                s.length_mm
            } else {
                s.angle_rad
            };
            let e = match s.kind {
                ErrorKind::Paper => size,
                ErrorKind::Normal => size * rng.sample::<Real, _>(StandardNormal),
                ErrorKind::Uniform => size * (2.0 * rng.random::<Real>() - 1.0),
                ErrorKind::None => 0.0,
                ErrorKind::Values => s.values.get(&p.to_string()).copied().unwrap_or(0.0),
            };
            (p, e)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::rng::stream;

    #[test]
    fn paper_set_on_named_parameters() {
        let r = crate::robot::builtin::irb2600();
        let s = ErrorSettings {
            params: ParamSelection::List(vec!["a1".into(), "alpha2".into(), "tool.z".into()]),
            ..Default::default()
        };
        let e = true_errors(&r, &s, Measure::Position, &mut stream(1, "errors")).unwrap();
        assert_eq!(
            e,
            vec![
                (Param::A(0), 0.5),
                (Param::Alpha(1), 0.05),
                (Param::Tool(2), 0.5)
            ]
        );
    }

    #[test]
    fn given_values_are_injected_exactly_and_checked() {
        let r = crate::robot::builtin::irb2600();
        let values: std::collections::BTreeMap<String, Real> =
            [("a3", -0.82916), ("alpha5", 2.912955e-3), ("tool.z", 0.1)]
                .into_iter()
                .map(|(k, v)| (k.to_string(), v))
                .collect();
        let s = ErrorSettings {
            kind: ErrorKind::Values,
            values: values.clone(),
            ..Default::default()
        };
        let mut e = true_errors(&r, &s, Measure::Position, &mut stream(1, "e")).unwrap();
        e.sort_by_key(|(p, _)| p.to_string());
        assert_eq!(
            e,
            vec![
                (Param::A(2), -0.82916),
                (Param::Alpha(4), 2.912955e-3),
                (Param::Tool(2), 0.1)
            ]
        );
        // Refused: values with another kind, no values, `params` beside them, a name the
        // robot lacks, a non-finite value.
        let key =
            |s: &ErrorSettings| match true_errors(&r, s, Measure::Position, &mut stream(1, "e")) {
                Err(Error::Setting { key, .. }) => key,
                other => panic!("{other:?}"),
            };
        let normal = ErrorSettings {
            kind: ErrorKind::Normal,
            values: values.clone(),
            ..Default::default()
        };
        assert_eq!(key(&normal), "errors.values");
        let empty = ErrorSettings {
            kind: ErrorKind::Values,
            ..Default::default()
        };
        assert_eq!(key(&empty), "errors.values");
        let both = ErrorSettings {
            params: ParamSelection::All,
            ..s.clone()
        };
        assert_eq!(key(&both), "errors.params");
        let mut foreign = s.clone();
        foreign.values.insert("beta2".into(), 0.01);
        // A name the robot does not have: at its own key, as a bad value is.
        assert_eq!(key(&foreign), "errors.values.beta2");
        let mut nan = s.clone();
        nan.values.insert("d4".into(), Real::NAN);
        assert_eq!(key(&nan), "errors.values.d4");
    }

    #[test]
    fn unknown_or_foreign_names_are_refused_naming_the_key() {
        let r = crate::robot::builtin::irb2600(); // standard DH: no β
        for bad in ["beta2", "theta7", "nonsense"] {
            let s = ErrorSettings {
                params: ParamSelection::List(vec![bad.into()]),
                ..Default::default()
            };
            let e = true_errors(&r, &s, Measure::Position, &mut stream(1, "e")).unwrap_err();
            assert!(
                matches!(&e, Error::Setting { key, .. } if key == "errors.params"),
                "{e}"
            );
            assert!(e.to_string().contains(bad), "{e}");
        }
    }

    #[test]
    fn identifiable_set_excludes_known_dependencies() {
        let r = crate::robot::builtin::irb2600();
        let ids = identifiable_params(&r, Measure::Position);
        // Tool orientation never moves the target point.
        for c in 3..6 {
            assert!(!ids.contains(&Param::Tool(c)));
        }
        assert!(ids.iter().all(|p| !matches!(p, Param::Base(_))));
        // θ6 and the tool point are coupled for position data: not both.
        assert!(
            !(ids.contains(&Param::Theta(5))
                && ids.contains(&Param::Tool(0))
                && ids.contains(&Param::Tool(1)))
        );
        // Its size equals the rank of the analysis and the call is deterministic.
        assert_eq!(ids, identifiable_params(&r, Measure::Position));
        let pose = identifiable_params(&r, Measure::Pose);
        assert!(pose.len() > ids.len());
    }

    #[test]
    fn random_sets_have_the_set_spread() {
        let r = crate::robot::builtin::tx60();
        let mut rng = stream(9, "errors");
        let (mut ls, mut nl, mut amax) = (0.0, 0, 0.0f64);
        for _ in 0..200 {
            let s = ErrorSettings {
                kind: ErrorKind::Normal,
                length_mm: 0.1,
                angle_rad: 0.001,
                params: ParamSelection::All,
                ..Default::default()
            };
            for (p, e) in true_errors(&r, &s, Measure::Pose, &mut rng).unwrap() {
                if p.is_length() {
                    ls += e * e;
                    nl += 1;
                }
            }
            let u = ErrorSettings {
                kind: ErrorKind::Uniform,
                ..s
            };
            for (p, e) in true_errors(&r, &u, Measure::Pose, &mut rng).unwrap() {
                if !p.is_length() {
                    amax = amax.max(e.abs());
                }
            }
        }
        let sd = (ls / nl as Real).sqrt();
        assert!((sd / 0.1 - 1.0).abs() < 0.05, "{sd}");
        assert!(amax <= 0.001 && amax > 0.00099);
        let none = ErrorSettings {
            kind: ErrorKind::None,
            ..Default::default()
        };
        assert!(true_errors(&r, &none, Measure::Position, &mut rng)
            .unwrap()
            .is_empty());
    }
}
