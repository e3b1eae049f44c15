//! The registration study of Ban §3 (fig. 3): SVD against Ban's weighted SVD
//! ([`crate::calibrate::registration`], eqs. 12–25) on point sets with gross errors, over a grid of
//! outlier counts × outlier magnitude ranges. A scenario holding a `[registration_study]`
//! table (docs/formats.md) runs it with `calbench run`.
//!
//! Each draw (one per trial, seed `trial_seed(seed, t)`): `points` base points uniform in the
//! box `center_mm ± size_mm / 2`, seen from the tracker at `tracker_pose` (as in a scenario's
//! `[tracker]`); every coordinate of the measured points gets uniform noise in
//! `±noise_mm` (Ban: "0–0.02 mm random error in x, y, z"). The base points and the noise are
//! shared by every cell of the grid (common random numbers: the cells differ only in their
//! gross errors); each cell then displaces `count` points chosen at random by a magnitude
//! uniform in `[0, m]` mm along a random direction ([`crate::sim::add_outliers`]). Both
//! registrations are fitted to the same data, and each one's registration error is the mean
//! distance of the registered noise-free points from the base points (Ban's mean absolute
//! error of the transformed point set). Fig. 3 plots the difference SVD − weighted SVD.
//!
//! Draws run in parallel; sums are taken in trial order, so the output depends on the seed
//! alone, not on the thread count.

use rand::Rng as _;
use rayon::prelude::*;
use serde::Deserialize;

use crate::calibrate::registration::{register_svd, register_wsvd, Registration};
use crate::error::{finite_non_negative, finite_positive, Error, Result};
use crate::numeric::rng;
use crate::numeric::{Frame, Real, Vec3};
use crate::study::claims::{self, Claim};
use crate::study::verdict::{self, Evaluation};
use crate::study::whole::Head;

/// The section of a scenario that makes it a registration study.
pub const REGISTRATION_STUDY: &str = "registration_study";

/// The `[registration_study]` table. Defaults are Ban §3's simulation: 50 points, ±0.02 mm
/// noise, 2, 4, …, 16 gross errors of 0–0.2 … 0–1 mm, in Ban's 800 mm cube.
#[derive(Clone, Debug, PartialEq, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct RegistrationStudy {
    /// Points per set. Default 50.
    pub points: usize,
    /// Half-width of the uniform noise on each coordinate, mm. Default 0.02.
    pub noise_mm: Real,
    /// Numbers of points given a gross error (rows of the grid). Default 2, 4, …, 16.
    pub outlier_counts: Vec<usize>,
    /// Upper ends of the gross errors' magnitude ranges `[0, m]`, mm (columns of the grid).
    /// Default 0.2, 0.4, 0.6, 0.8, 1.0.
    pub magnitude_mm: Vec<Real>,
    /// Centre of the box the points are drawn in, base frame, mm. Default (1000, 0, 900).
    pub center_mm: [Real; 3],
    /// Edge lengths of that box, mm. Default 800 mm each (Ban's cube).
    pub size_mm: [Real; 3],
    /// The tracker frame in the base frame: x, y, z mm; rx, ry, rz deg (fixed X-Y-Z), as
    /// `tracker.pose` of a scenario. Default (2500, 0, 500, 0, 0, 180).
    pub tracker_pose: [Real; 6],
}

impl Default for RegistrationStudy {
    fn default() -> Self {
        RegistrationStudy {
            points: 50,
            noise_mm: 0.02,
            outlier_counts: (1..=8).map(|i| 2 * i).collect(),
            magnitude_mm: vec![0.2, 0.4, 0.6, 0.8, 1.0],
            center_mm: [1000.0, 0.0, 900.0],
            size_mm: [800.0; 3],
            tracker_pose: [2500.0, 0.0, 500.0, 0.0, 0.0, 180.0],
        }
    }
}

/// A scenario file running the registration study: `name`, `description`, `seed`,
/// `trials` (draws per cell, default 100) as in every scenario, the
/// `[registration_study]` table and the paper's `[[claims]]` on it ([`ENTRIES`], [`METRIC`]).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RegistrationScenario {
    /// The keys every study takes ([`Head::take`]).
    #[serde(skip)]
    pub head: Head,
    /// The study's settings.
    pub registration_study: RegistrationStudy,
    /// `[[claims]]` as written.
    #[serde(default, rename = "claims")]
    raw_claims: Vec<toml::Table>,
    /// The claims, checked against the grid's entries.
    #[serde(skip)]
    pub claims: Vec<Claim>,
}

/// What a claim of the registration study names: per cell, the SVD's registration error,
/// the weighted SVD's, and their difference SVD − weighted SVD (Ban fig. 3), each an entry
/// `"svd / 16 × 0–1 mm"` (method / cell, [`RegistrationStudy::cell_names`]).
pub const ENTRIES: [&str; 3] = ["svd", "wsvd", "difference"];

/// The one metric of a registration-study claim: a draw's registration error, mm.
pub const METRIC: claims::Metric = claims::Metric::RegistrationError;

impl RegistrationScenario {
    /// Parses and checks the scenario in `table`, read from `path` (named in errors).
    pub fn from_table(table: toml::Table, path: &std::path::Path) -> Result<Self> {
        let ferr = |place: &str, msg: String| Error::file(path, place, msg);
        let takes = "with [registration_study] takes only name, description, seed, trials, \
                     that table and [[claims]]";
        let trials = (100, 1..=crate::study::scenario::MAX_TRIALS);
        let (head, mut s): (Head, RegistrationScenario) =
            crate::study::whole::parse(table, path, trials, takes)?;
        s.head = head;
        s.registration_study.check().map_err(|e| e.in_file(path))?;
        let methods = ENTRIES.map(String::from);
        let cells = s.registration_study.cell_names();
        let names = claims::Names {
            methods: &methods,
            strategies: &cells,
            pose: false,
            axis: false,
            unmodelled: false,
            searches: false,
        };
        s.claims = claims::parse_with(&s.raw_claims, &names, |m| {
            (m == METRIC.key()).then_some(METRIC).ok_or_else(|| {
                format!("unknown metric \"{m}\"; a registration study's claims take \"{METRIC}\"")
            })
        })
        .map_err(|(k, m)| ferr(&k, m))?;
        Ok(s)
    }

    /// Each claim evaluated on the study's `draws` ([`RegistrationStudy::draws`]): paired by
    /// draw, whichever cells and registrations it names.
    pub fn evaluate_claims(&self, draws: &[Vec<(Real, Real)>]) -> Vec<(&Claim, Evaluation)> {
        let cells = draws.first().map_or(0, Vec::len);
        // values[entry][cell]: one value per draw, in draw order.
        let values: Vec<Vec<Vec<Real>>> = (0..ENTRIES.len())
            .map(|e| {
                (0..cells)
                    .map(|k| {
                        draws
                            .iter()
                            .map(|d| match e {
                                0 => d[k].0,
                                1 => d[k].1,
                                _ => d[k].0 - d[k].1,
                            })
                            .collect()
                    })
                    .collect()
            })
            .collect();
        self.claims
            .iter()
            .map(|c| (c, verdict::evaluate(c, |(e, k)| &values[e][k])))
            .collect()
    }
}

/// One cell of the grid: means over the draws.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Cell {
    /// Points with a gross error.
    pub outlier_count: usize,
    /// Upper end of the magnitude range, mm.
    pub magnitude_mm: Real,
    /// Mean registration error of the SVD, mm.
    pub svd_mm: Real,
    /// Mean registration error of the weighted SVD, mm.
    pub wsvd_mm: Real,
    /// `svd_mm − wsvd_mm` (Ban fig. 3), mm.
    pub difference_mm: Real,
    /// Share of the draws in which the weighted SVD was the better of the two.
    pub wsvd_better_fraction: Real,
}

/// The name of the cell of `count` points with a gross error of up to `magnitude_mm`, as a
/// claim names it: `16 × 0–1 mm`.
fn cell_name(count: usize, magnitude_mm: Real) -> String {
    format!("{count} × 0–{magnitude_mm} mm")
}

impl Cell {
    /// The cell's name, as a claim names it: `16 × 0–1 mm`.
    pub fn name(&self) -> String {
        cell_name(self.outlier_count, self.magnitude_mm)
    }
}

impl RegistrationStudy {
    /// Checks the settings (keys as in the table).
    pub fn check(&self) -> Result<()> {
        let biggest = self.outlier_counts.iter().copied().max().unwrap_or(0);
        if self.points < 3 {
            return Err(Error::setting(
                "registration_study.points",
                format!("must be at least 3, got {}", self.points),
            ));
        }
        if self.outlier_counts.is_empty() || biggest > self.points {
            return Err(Error::setting(
                "registration_study.outlier_counts",
                format!(
                    "must be a non-empty list of counts up to points = {}, got {:?}",
                    self.points, self.outlier_counts
                ),
            ));
        }
        if self.magnitude_mm.is_empty() {
            return Err(Error::setting(
                "registration_study.magnitude_mm",
                "must be a non-empty list of magnitudes (mm)",
            ));
        }
        for m in &self.magnitude_mm {
            finite_non_negative("registration_study.magnitude_mm", *m)?;
        }
        // Each count and each magnitude is a row or column of the grid of cells (Ban fig. 3):
        // one given twice would run a cell twice under one name.
        let twice = [
            (
                "outlier_counts",
                crate::study::given_twice(
                    &self.outlier_counts,
                    PartialEq::eq,
                    ToString::to_string,
                    "cells",
                ),
            ),
            (
                "magnitude_mm",
                crate::study::given_twice(
                    &self.magnitude_mm,
                    PartialEq::eq,
                    ToString::to_string,
                    "cells",
                ),
            ),
        ];
        if let Some((key, Some((j, msg)))) = twice.into_iter().find(|(_, m)| m.is_some()) {
            return Err(Error::setting(
                format!("registration_study.{key}[{j}]"),
                msg,
            ));
        }
        finite_non_negative("registration_study.noise_mm", self.noise_mm)?;
        for s in self.size_mm {
            finite_positive("registration_study.size_mm", s)?;
        }
        // Lengths within a robot file's range: beyond it the points' squares overflow and
        // the registration fails in the run, with no key to blame.
        let most = crate::robot::MAX_LENGTH_MM;
        let (xyz, angles) = self.tracker_pose.split_at(3);
        for (key, v) in [
            ("magnitude_mm", &self.magnitude_mm[..]),
            ("noise_mm", &[self.noise_mm]),
            ("size_mm", &self.size_mm),
            ("center_mm", &self.center_mm),
            ("tracker_pose", xyz),
        ] {
            crate::error::lengths_within(&format!("registration_study.{key}"), v, most)?;
        }
        let key = "registration_study.tracker_pose";
        if let Some(v) = angles.iter().find(|v| !v.is_finite()) {
            let shown = crate::error::shown(*v);
            return Err(Error::setting(
                key,
                format!("must be 6 finite numbers, got {shown}"),
            ));
        }
        match crate::sim::settings::beyond_turn(angles) {
            Some(msg) => Err(Error::setting(key, format!("rx, ry, rz {msg}"))),
            None => Ok(()),
        }
    }

    /// The cells' names in grid order (outlier counts outer, magnitudes inner), as a claim
    /// names them: `16 × 0–1 mm`.
    pub fn cell_names(&self) -> Vec<String> {
        self.outlier_counts
            .iter()
            .flat_map(|&c| self.magnitude_mm.iter().map(move |&m| cell_name(c, m)))
            .collect()
    }

    /// The grid's cells (outlier counts outer, magnitudes inner), each averaged over
    /// `trials` draws from `seed`.
    pub fn run(&self, seed: u64, trials: usize) -> Result<Vec<Cell>> {
        Ok(self.cells(&self.draws(seed, trials)?))
    }

    /// Every draw's (SVD, weighted SVD) registration errors per cell, in grid order: `trials`
    /// draws from `seed`, in draw order whatever the thread count.
    pub fn draws(&self, seed: u64, trials: usize) -> Result<Vec<Vec<(Real, Real)>>> {
        self.check()?;
        (0..trials)
            .into_par_iter()
            .map(|t| self.draw(rng::trial_seed(seed, t as u64)))
            .collect()
    }

    /// The cells' means over `per_trial` ([`RegistrationStudy::draws`]).
    pub fn cells(&self, per_trial: &[Vec<(Real, Real)>]) -> Vec<Cell> {
        let n = per_trial.len() as Real;
        let mut cells = Vec::new();
        for (ci, &count) in self.outlier_counts.iter().enumerate() {
            for (mi, &m) in self.magnitude_mm.iter().enumerate() {
                let k = ci * self.magnitude_mm.len() + mi;
                let (mut svd, mut wsvd, mut better) = (0.0, 0.0, 0.0);
                for d in per_trial {
                    svd += d[k].0;
                    wsvd += d[k].1;
                    if d[k].1 < d[k].0 {
                        better += 1.0;
                    }
                }
                cells.push(Cell {
                    outlier_count: count,
                    magnitude_mm: m,
                    svd_mm: svd / n,
                    wsvd_mm: wsvd / n,
                    difference_mm: (svd - wsvd) / n,
                    wsvd_better_fraction: better / n,
                });
            }
        }
        cells
    }

    /// A registration of a draw that its points do not determine (`e`), refused as the
    /// setting that drew them, `size_mm`: a box with no extent in two directions draws
    /// collinear points.
    fn blamed(&self, e: Error) -> Error {
        match e {
            Error::Singular(msg) => Error::setting(
                "registration_study.size_mm",
                format!(
                    "the points drawn in a box of {:?} mm do not determine the registration \
                     ({msg}): give the box an extent in at least two directions",
                    self.size_mm
                ),
            ),
            e => e,
        }
    }

    /// One draw: the (SVD, weighted SVD) registration errors of every cell, in grid order.
    pub fn draw(&self, seed: u64) -> Result<Vec<(Real, Real)>> {
        let p = &self.tracker_pose;
        let tracker =
            Frame::from_xyz_rpy([p[0], p[1], p[2]], [p[3], p[4], p[5]].map(Real::to_radians));
        let mut g = rng::stream(seed, "registration/points");
        let base: Vec<Vec3> = (0..self.points)
            .map(|_| {
                Vec3::from_fn(|i, _| {
                    self.center_mm[i] + self.size_mm[i] * (g.random::<Real>() - 0.5)
                })
            })
            .collect();
        // Tracker coordinates of the base points, and the same with noise.
        let clean: Vec<Vec3> = base.iter().map(|b| tracker.apply_inverse(b)).collect();
        let noisy: Vec<Vec3> = clean
            .iter()
            .map(|a| a + Vec3::from_fn(|_, _| self.noise_mm * (2.0 * g.random::<Real>() - 1.0)))
            .collect();
        let error = |r: &Registration| {
            clean
                .iter()
                .zip(&base)
                .map(|(a, b)| (r.frame.apply(a) - b).norm())
                .sum::<Real>()
                / base.len() as Real
        };
        let mut out = Vec::with_capacity(self.outlier_counts.len() * self.magnitude_mm.len());
        let mut measured = noisy.clone();
        for &count in &self.outlier_counts {
            for &m in &self.magnitude_mm {
                measured.copy_from_slice(&noisy);
                let mut go = rng::stream(seed, &format!("registration/outliers/{count}/{m}"));
                crate::sim::add_outliers(&mut measured, count, [0.0, m], &mut go);
                out.push((
                    error(&register_svd(&base, &measured, None).map_err(|e| self.blamed(e))?),
                    error(&register_wsvd(&base, &measured).map_err(|e| self.blamed(e))?),
                ));
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Without gross errors or noise both registrations recover the tracker exactly, in
    /// every cell (magnitude 0 leaves the points where they are).
    #[test]
    fn exact_data_register_exactly() {
        let s = RegistrationStudy {
            noise_mm: 0.0,
            outlier_counts: vec![0, 3],
            magnitude_mm: vec![0.0],
            ..RegistrationStudy::default()
        };
        for c in s.run(7, 3).unwrap() {
            assert!(c.svd_mm < 1e-9 && c.wsvd_mm < 1e-9, "{c:?}");
        }
    }

    /// Ban's fig. 3: the gap between the SVD's and the weighted SVD's mean error is
    /// positive and grows with the number of gross errors (2–16 of 50) and with their size
    /// (0–0.2 … 0–1 mm).
    #[test]
    fn wsvd_advantage_grows_with_outlier_count_and_size() {
        let s = RegistrationStudy {
            outlier_counts: vec![2, 4, 8, 16],
            magnitude_mm: vec![0.2, 0.6, 1.0],
            ..RegistrationStudy::default()
        };
        let cells = s.run(1, 40).unwrap();
        let gap = |i: usize, k: usize| cells[i * 3 + k].difference_mm;
        for i in 0..4 {
            for k in 0..3 {
                assert!(gap(i, k) > 0.0, "{cells:?}");
                if i > 0 {
                    assert!(gap(i, k) > gap(i - 1, k), "count: {cells:?}");
                }
                if k > 0 {
                    assert!(gap(i, k) > gap(i, k - 1), "size: {cells:?}");
                }
            }
        }
    }

    fn scenario(claims: &str) -> Result<RegistrationScenario> {
        let text = format!(
            "name = \"r\"\nseed = 5\ntrials = 30\n[registration_study]\n\
             outlier_counts = [2, 8]\nmagnitude_mm = [0.2, 1.0]\n{claims}"
        );
        RegistrationScenario::from_table(toml::from_str(&text).unwrap(), "r.toml".as_ref())
    }

    /// A claim's estimate is the paired mean over the draws, so it equals what the cells'
    /// means give: wsvd − svd in a cell, and a difference of two cells' differences.
    #[test]
    fn claims_are_paired_over_the_draws_and_agree_with_the_cells() {
        let claim = |id: &str, rel: &str| {
            format!(
                "[[claims]]\nid = \"{id}\"\nstatement = \"s\"\npaper = \"p\"\nvalue = 1\n\
                 metric = \"{METRIC}\"\nrelation = '{rel}'\n"
            )
        };
        let sc = scenario(
            &(claim("below", r#""wsvd / 8 × 0–1 mm" < "svd / 8 × 0–1 mm""#)
                + &claim(
                    "grows",
                    r#""difference / 8 × 0–1 mm" > "difference / 2 × 0–0.2 mm""#,
                )),
        )
        .unwrap();
        let draws = sc.registration_study.draws(5, 30).unwrap();
        let cells = sc.registration_study.cells(&draws);
        let names = sc.registration_study.cell_names();
        assert_eq!(
            names,
            ["2 × 0–0.2 mm", "2 × 0–1 mm", "8 × 0–0.2 mm", "8 × 0–1 mm"]
        );
        let evaluated = sc.evaluate_claims(&draws);
        let (below, grows) = (&evaluated[0].1, &evaluated[1].1);
        assert_eq!((below.n, grows.n), (30, 30));
        approx::assert_relative_eq!(
            below.estimate,
            -cells[3].difference_mm,
            max_relative = 1e-12
        );
        approx::assert_relative_eq!(
            grows.estimate,
            cells[3].difference_mm - cells[0].difference_mm,
            max_relative = 1e-12
        );
        assert_eq!(below.verdict, verdict::Verdict::Reproduces, "{below:?}");
    }

    /// A claim on an entry the grid lacks, or with another metric, is refused by its key.
    #[test]
    fn bad_claims_are_refused_by_key() {
        let key = METRIC.key();
        let bad = [
            (
                "relation = '\"svd / 3 × 0–1 mm\" < 1'",
                "claims[0].relation",
                "no entry",
            ),
            (
                "relation = '\"svd / 8 × 0–1 mm\" < 1'\nmetric = \"eta_mean_pct\"",
                "claims[0].metric",
                key.as_str(),
            ),
        ];
        for (rel, key, says) in bad {
            let metric = if rel.contains("metric") {
                ""
            } else {
                "metric = \"registration_error_mm\"\n"
            };
            let text = format!(
                "[[claims]]\nid = \"c\"\nstatement = \"s\"\npaper = \"p\"\nvalue = 1\n{metric}{rel}\n"
            );
            let e = scenario(&text).unwrap_err().to_string();
            assert!(e.contains(key) && e.contains(says), "{e}");
        }
    }

    #[test]
    fn bad_settings_are_refused_by_key() {
        let bad = [
            RegistrationStudy {
                points: 2,
                ..RegistrationStudy::default()
            },
            RegistrationStudy {
                outlier_counts: vec![60],
                ..RegistrationStudy::default()
            },
            RegistrationStudy {
                magnitude_mm: vec![],
                ..RegistrationStudy::default()
            },
            RegistrationStudy {
                noise_mm: -1.0,
                ..RegistrationStudy::default()
            },
            RegistrationStudy {
                tracker_pose: [2500.0, 0.0, 500.0, 0.0, 0.0, 1e300],
                ..RegistrationStudy::default()
            },
        ];
        for s in bad {
            assert!(s
                .check()
                .unwrap_err()
                .key()
                .unwrap()
                .starts_with("registration_study"));
        }
    }
}
