//! The metrics of a study, each declared once (docs/formats.md "summary.json", "claims"): its
//! key in `summary.json`'s entries, its `trials.csv` column, which way it improves, its unit,
//! what the study needs for it, and how one trial's outcome gives it. The claims, the paired
//! comparisons, `check`, `history` and the reports name a [`Metric`], never its key.

use std::fmt;

use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::numeric::Real;
pub use crate::study::margin::Margin;
use crate::study::outcome::Outcome;
use crate::study::spill::Spilled;

/// Which way a metric improves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Better {
    /// Smaller is better (errors, failures).
    Lower,
    /// Larger is better (η, improvements).
    Higher,
}

/// What a metric needs of the study.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Needs {
    /// Every Monte-Carlo study has it.
    Nothing,
    /// `tracker.measure = "pose"`.
    Pose,
    /// `validation.axis_errors = true`.
    Axis,
    /// A `[registration_study]`.
    Registration,
    /// A search among the methods (BAS, PSO, BAS-PSO).
    Search,
}

/// How a metric is declared.
pub struct Spec {
    /// Its entry's key in `summary.json`.
    pub field: &'static str,
    /// The statistic of that key's error statistics (`mean`, `rms`, `max`), if it has them.
    pub stat: Option<&'static str>,
    /// Its column in `trials.csv`, if it has one.
    pub column: Option<&'static str>,
    /// Which way it improves.
    pub better: Better,
    /// Its unit.
    pub unit: &'static str,
    /// What the study needs for it.
    pub needs: Needs,
    /// Its value in one trial, from the outcome and the trial's mean η over the parameters;
    /// `None` for a metric that is only a figure over trials.
    pub of_trial: Option<fn(&Outcome, Real) -> Real>,
}

// The entries' keys, each written once.
use crate::calibrate::validation::keys::{AFTER_ATTITUDE_DEG, BEFORE_MM as VALIDATION_BEFORE};
use crate::calibrate::validation::keys::{AFTER_DEG as DEG_AFTER, AFTER_MM as VALIDATION_AFTER};
const CALIBRATION_AFTER: &str = "calibration_after_mm";
/// Also `trials.csv`'s column of each trial's mean η.
const ETA_MEAN: &str = "eta_mean_pct";
const AXIS_AFTER: &str = "validation_after_axis_mm";
/// Also `trials.csv`'s column of each trial's final fitness.
const FINAL_FITNESS: &str = "final_fitness";

macro_rules! metrics {
    ($($(#[$doc:meta])* $name:ident = $field:expr, $stat:expr, $column:expr, $better:ident,
       $unit:expr, $needs:ident, $of:expr;)*) => {
        /// A metric of a study's entries ([`Spec`] says what each is).
        #[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
        pub enum Metric {
            $($(#[$doc])* $name,)*
        }

        impl Metric {
            /// Every metric, in the order declared.
            pub const ALL: [Metric; [$(Metric::$name),*].len()] = [$(Metric::$name),*];

            /// How it is declared.
            pub const fn spec(self) -> Spec {
                match self {
                    $(Metric::$name => Spec {
                        field: $field,
                        stat: $stat,
                        column: $column,
                        better: Better::$better,
                        unit: $unit,
                        needs: Needs::$needs,
                        of_trial: $of,
                    },)*
                }
            }
        }
    };
}

/// The percentage by which `after` improves on `before`.
fn improvement(before: Real, after: Real) -> Real {
    (before - after) / before * 100.0
}

metrics! {
    /// The validation RMS after compensation: the headline of the paired comparisons.
    ValidationAfterRms = VALIDATION_AFTER, Some("rms"), Some("after_rms_mm"), Lower, "mm",
        Nothing, Some(|o, _| o.after_mm.rms);
    /// The mean over the parameters of η (Guo 2024 eq. 29).
    EtaMean = ETA_MEAN, None, Some(ETA_MEAN), Higher, "%", Nothing,
        Some(|_, eta| eta);
    /// The mean validation error after compensation.
    ValidationAfterMean = VALIDATION_AFTER, Some("mean"), Some("after_mean_mm"), Lower, "mm",
        Nothing, Some(|o, _| o.after_mm.mean);
    /// The largest validation error after compensation.
    ValidationAfterMax = VALIDATION_AFTER, Some("max"), Some("after_max_mm"), Lower, "mm",
        Nothing, Some(|o, _| o.after_mm.max);
    /// The mean validation error of the nominal robot.
    ValidationBeforeMean = VALIDATION_BEFORE, Some("mean"), Some("before_mean_mm"), Lower,
        "mm", Nothing, Some(|o, _| o.before_mm.mean);
    /// The validation RMS of the nominal robot.
    ValidationBeforeRms = VALIDATION_BEFORE, Some("rms"), Some("before_rms_mm"), Lower, "mm",
        Nothing, Some(|o, _| o.before_mm.rms);
    /// The improvement of the mean validation error.
    Improvement = "improvement_pct", None, None, Higher, "%", Nothing,
        Some(|o, _| improvement(o.before_mm.mean, o.after_mm.mean));
    /// The improvement of the mean error at the calibration poses.
    CalibrationImprovement = "calibration_improvement_pct", None, None, Higher, "%", Nothing,
        Some(|o, _| improvement(o.calibration_before_mm.mean, o.calibration_after_mm.mean));
    /// The improvement of the RMS error at the calibration poses.
    CalibrationImprovementRms = "calibration_improvement_rms_pct", None, None, Higher, "%",
        Nothing,
        Some(|o, _| improvement(o.calibration_before_mm.rms, o.calibration_after_mm.rms));
    /// The mean error at the calibration poses after compensation.
    CalibrationAfterMean = CALIBRATION_AFTER, Some("mean"), None, Lower, "mm", Nothing,
        Some(|o, _| o.calibration_after_mm.mean);
    /// The RMS error at the calibration poses after compensation.
    CalibrationAfterRms = CALIBRATION_AFTER, Some("rms"), None, Lower, "mm", Nothing,
        Some(|o, _| o.calibration_after_mm.rms);
    /// The RMS of Guo's signed axis errors after compensation.
    AxisAfterRms = AXIS_AFTER, Some("rms"), None, Lower, "mm", Axis,
        Some(|o, _| o.optional.validation_after_axis_mm.map_or(Real::NAN, |s| s.rms));
    /// The mean of Guo's signed axis errors after compensation.
    AxisAfterMean = AXIS_AFTER, Some("mean"), None, Lower, "mm", Axis,
        Some(|o, _| o.optional.validation_after_axis_mm.map_or(Real::NAN, |s| s.mean));
    /// The mean of Guo's absolute axis errors after compensation.
    AxisAbsAfterMean = "validation_after_axis_abs_mm", Some("mean"), None, Lower, "mm", Axis,
        Some(|o, _| {
            o.optional.validation_after_axis_abs_mm.map_or(Real::NAN, |s| s.mean)
        });
    /// The mean orientation error after compensation (rotation angle).
    DegAfterMean = DEG_AFTER, Some("mean"), Some("after_mean_deg"), Lower, "deg", Pose,
        Some(|o, _| o.optional.validation_after_deg.map_or(Real::NAN, |s| s.mean));
    /// The mean of Qiao's attitude error after compensation.
    AttitudeAfterMean = AFTER_ATTITUDE_DEG, Some("mean"), None, Lower, "deg",
        Pose,
        Some(|o, _| {
            o.optional.validation_after_attitude_deg.map_or(Real::NAN, |s| s.mean)
        });
    /// The model evaluations of an identification.
    Evaluations = "evaluations", None, None, Lower, "", Nothing,
        Some(|o, _| o.evaluations as Real);
    /// The iterations of an identification.
    Iterations = "iterations", None, Some("iterations"), Lower, "", Nothing,
        Some(|o, _| o.iterations as Real);
    /// A search's best fitness at the end of its budget (Qiao 2021 eq. 14, mm with k in
    /// mm/rad; fig. 4's curves at their end): NaN for the other methods.
    FinalFitness = FINAL_FITNESS, Some("mean"), Some(FINAL_FITNESS), Lower, "mm", Search,
        Some(|o, _| o.search.as_ref().map_or(Real::NAN, |s| s.final_fitness));
    /// The mean over the parameters of the median η.
    EtaMedian = "eta_median_pct", None, None, Higher, "%", Nothing, None;
    /// The orientation RMS after compensation (rotation angle).
    DegAfterRms = DEG_AFTER, Some("rms"), Some("after_rms_deg"), Lower, "deg", Pose, None;
    /// Identifications that gave no usable result.
    Failures = "failures", None, None, Lower, "", Nothing, None;
    /// The RMSE over trials of an identified parameter's error, per parameter.
    ParamRmse = "param_rmse", None, None, Lower, "mm, rad", Nothing, None;
    /// The registration error of Ban's registration study.
    RegistrationError = "registration_error_mm", None, None, Lower, "mm", Registration, None;
    /// η of each parameter with an injected error (Guo 2024 eq. 29): the metric of a
    /// claim "for every parameter".
    Eta = "eta", None, None, Higher, "%", Nothing, None;
}

impl Metric {
    /// The metrics a trial's outcome gives, in the order the aggregation keeps them.
    pub const PER_TRIAL: [Metric; 19] = {
        let mut out = [Metric::ValidationAfterRms; 19];
        let mut i = 0;
        while i < 19 {
            out[i] = Metric::ALL[i];
            i += 1;
        }
        out
    };

    /// Its place in [`Metric::PER_TRIAL`], if a trial gives it.
    pub fn per_trial_index(self) -> Option<usize> {
        Metric::PER_TRIAL.iter().position(|m| *m == self)
    }

    /// Whether smaller is better.
    pub fn lower_is_better(self) -> bool {
        self.spec().better == Better::Lower
    }

    /// The metric of a key (`validation_after_mm.rms`), if there is one.
    pub fn from_key(key: &str) -> Option<Metric> {
        Metric::ALL.into_iter().find(|m| m.key() == key)
    }

    /// Its default minimum effect of interest (docs/formats.md "Tests and margins"): a
    /// difference smaller than this is of interest to no one. Position and orientation
    /// errors: 1 % of the reference, and at least the finest digit the four papers report
    /// (Qiao 2021's 0.111 mm and 0.0442°: 1 µm, 1e-4°); percentages (η, reductions): the
    /// papers' 0.01 points (Guo's table 6, Ban's table 4); counts: 1 % and at least 1.
    pub fn default_margin(self) -> Margin {
        let (relative, absolute) = match self.spec().unit {
            "mm" | "mm, rad" => (0.01, 1e-3),
            "deg" => (0.01, 1e-4),
            "%" => (0.0, 0.01),
            _ => (0.01, 1.0),
        };
        Margin {
            relative: (relative > 0.0).then_some(relative),
            absolute: Some(absolute),
        }
    }

    /// Whether it measures the arm's error before or after calibration (positions,
    /// orientations, their reductions): a figure that, on an arm with no error outside the
    /// kinematic model, a real robot's cannot be compared with. A search's fitness is a sum
    /// of the measurements' residuals, not such a figure.
    pub fn is_arm_error(self) -> bool {
        let s = self.spec();
        !matches!(s.needs, Needs::Registration | Needs::Search)
            && (matches!(s.unit, "mm" | "deg")
                || matches!(
                    self,
                    Metric::Improvement
                        | Metric::CalibrationImprovement
                        | Metric::CalibrationImprovementRms
                ))
    }

    /// Its key in `summary.json`'s entries, `field[.stat]`.
    pub fn key(self) -> String {
        self.to_string()
    }

    /// Its column in `trials.csv`, if it has one.
    pub fn column(self) -> Option<&'static str> {
        self.spec().column
    }

    /// The key of parameter `name`'s figure of a per-parameter metric ([`Metric::ParamRmse`]):
    /// `param_rmse.NAME`.
    pub fn of_parameter(self, name: &str) -> String {
        format!("{self}.{name}")
    }

    /// For a key of a per-parameter figure (`param_rmse.a2`), the parameter's name.
    pub fn parameter_of(self, key: &str) -> Option<&str> {
        key.strip_prefix(self.spec().field)?.strip_prefix('.')
    }
}

impl fmt::Display for Metric {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = self.spec();
        match s.stat {
            Some(stat) => write!(f, "{}.{stat}", s.field),
            None => f.write_str(s.field),
        }
    }
}

impl Serialize for Metric {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

impl<'de> Deserialize<'de> for Metric {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Metric, D::Error> {
        let key = String::deserialize(d)?;
        Metric::from_key(&key)
            .ok_or_else(|| serde::de::Error::custom(format!("unknown metric \"{key}\"")))
    }
}

/// Each trial's value of every per-trial metric ([`Metric::PER_TRIAL`]) of one entry, in
/// trial order, NaN where the identification failed: read by metric from the study's
/// scratch file ([`Spilled`]), so that a finished study holds no list that grows with its
/// trials.
#[derive(Clone, Debug, Default)]
pub struct PerTrial(Vec<Spilled>);

impl PerTrial {
    /// The streams, one per metric of [`Metric::PER_TRIAL`] in its order.
    pub fn new(streams: Vec<Spilled>) -> PerTrial {
        PerTrial(streams)
    }

    /// The per-trial values of `m`; none for a metric a trial does not give.
    pub fn values(&self, m: Metric) -> crate::error::Result<Vec<Real>> {
        match m.per_trial_index().and_then(|i| self.0.get(i)) {
            Some(s) => s.values(),
            None => Ok(Vec::new()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_are_unique_and_read_back() {
        for m in Metric::ALL {
            assert_eq!(Metric::from_key(&m.key()), Some(m), "{m}");
        }
        for (i, m) in Metric::PER_TRIAL.iter().enumerate() {
            assert!(m.spec().of_trial.is_some(), "{m}");
            assert_eq!(m.per_trial_index(), Some(i));
        }
        let rest = &Metric::ALL[Metric::PER_TRIAL.len()..];
        assert!(rest.iter().all(|m| m.spec().of_trial.is_none()));
        assert_eq!(Metric::ValidationAfterRms.key(), "validation_after_mm.rms");
        assert_eq!(Metric::ParamRmse.parameter_of("param_rmse.a2"), Some("a2"));
        assert_eq!(Metric::FinalFitness.key(), "final_fitness.mean");
        assert!(!Metric::FinalFitness.is_arm_error());
    }
}
