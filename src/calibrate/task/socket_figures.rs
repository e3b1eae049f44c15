//! A socket task's figures (docs/formats.md § 9.4), as the MUKCa data's authors compute
//! them: per socket the spread of the tool points about their mean, pooled, and the error of
//! the distance between the sockets' mean points; and the authors' own figures, read from
//! their `kpis.yaml`.

use std::collections::BTreeMap;
use std::path::Path;

use super::record::SocketFigures;
use crate::error::{read_text, Error, Result};
use crate::numeric::{Real, Vec3};
use crate::robot::MAX_LENGTH_MM;

/// The figures of the tool points `points`, each in the socket `group[i]`, the sockets at
/// `distances` (mm) from socket 1: per row its distance from its socket's mean point, and
/// the figures (the authors' `evaluate_model`: per socket the square root of the summed
/// per-axis population variances; pooled, the rows' RMS distance; the distance error).
pub fn socket_figures(
    points: &[Vec3],
    group: &[usize],
    distances: &[Real],
) -> (Vec<Real>, SocketFigures) {
    let n = distances.len();
    let (mean, count) = socket_means(points, group, n);
    let rows: Vec<Real> = points
        .iter()
        .zip(group)
        .map(|(p, &g)| (p - mean[g]).norm())
        .collect();
    let mut sq = vec![0.0; n];
    for (e, &g) in rows.iter().zip(group) {
        sq[g] += e * e;
    }
    let spread_per_socket_mm = sq
        .iter()
        .zip(&count)
        .map(|(s, &c)| (s / c.max(1) as Real).sqrt())
        .collect();
    let spread_mm = (sq.iter().sum::<Real>() / rows.len().max(1) as Real).sqrt();
    let d2: Real = (1..n)
        .map(|l| ((mean[l] - mean[0]).norm() - distances[l]).powi(2))
        .sum();
    let figures = SocketFigures {
        spread_per_socket_mm,
        spread_mm,
        distance_error_mm: (d2 / (n - 1).max(1) as Real).sqrt(),
    };
    (rows, figures)
}

/// The mean of the tool points `points` in each of the `n` sockets (`group[i]`: the socket of
/// point i), and the count of each.
pub(super) fn socket_means(points: &[Vec3], group: &[usize], n: usize) -> (Vec<Vec3>, Vec<usize>) {
    let mut mean = vec![Vec3::zeros(); n];
    let mut count = vec![0usize; n];
    for (p, &g) in points.iter().zip(group) {
        mean[g] += p;
        count[g] += 1;
    }
    for (m, &c) in mean.iter_mut().zip(&count) {
        *m /= c.max(1) as Real;
    }
    (mean, count)
}

/// The figures of the authors' `kpis.yaml` (m, m²): `var_1`, `var_2` (per-axis variances
/// of each socket's tool points), `fks_1`, `fks_2` (the points, counted) and `distance`
/// (the distance's error, signed), in mm.
pub fn read_kpis(path: &Path) -> Result<SocketFigures> {
    let text = read_text(path)?;
    let mut key = "";
    let mut var = [Vec::new(), Vec::new()];
    let mut count = [0usize; 2];
    let mut distance = None;
    // The line of each key read.
    let mut lines: BTreeMap<&str, usize> = BTreeMap::new();
    for (i, line) in text.lines().enumerate() {
        // A line `key: …` opens the key it names: its own value is read at that key.
        let opened = line
            .split_once(':')
            .filter(|_| !line.starts_with([' ', '-']));
        if let Some((k, _)) = opened {
            key = match k {
                "distance" | "var_1" | "var_2" | "fks_1" | "fks_2" => k,
                _ => "",
            };
        }
        let at = key;
        let bad = |msg: String| Error::file(path, format!("line {}, {at}", i + 1), msg);
        if let (Some((_, rest)), false) = (opened, key.is_empty()) {
            if let Some(first) = lines.insert(key, i + 1) {
                return Err(bad(format!("given twice (first on line {first})")));
            }
            if key != "distance" && !rest.trim().is_empty() {
                let msg = "a list on the key's line is not read: write one `- value` per \
                           line below the key, as the authors' files do";
                return Err(bad(msg.to_string()));
            }
        }
        let num = |s: &str| -> Result<Real> {
            s.trim()
                .parse::<Real>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| bad(format!("\"{}\" is not a number", s.trim())))
        };
        // A figure in m (a variance in m²) that stands for a length of at most 1 km.
        let within = |v: Real, lo: Real, hi: Real, what: &str| -> Result<Real> {
            if (lo..=hi).contains(&v) {
                Ok(v)
            } else {
                let v = crate::error::shown(v);
                Err(bad(format!("must be {what}, got {v}")))
            }
        };
        let (km, km2) = (MAX_LENGTH_MM / 1000.0, (MAX_LENGTH_MM / 1000.0).powi(2));
        if let Some((_, rest)) = opened {
            if key == "distance" {
                let what = "a distance error within ±1000 m (1 km)";
                distance = Some(within(num(rest)?, -km, km, what)?);
            }
        } else if let Some(v) = line.strip_prefix("- - ") {
            match key {
                "fks_1" => count[0] += 1,
                "fks_2" => count[1] += 1,
                _ => {}
            }
            num(v)?;
        } else if let Some(v) = line.strip_prefix("- ") {
            match key {
                "var_1" | "var_2" => {
                    let what = "a variance in [0, 1e6] m² (a spread of at most 1 km)";
                    var[usize::from(key == "var_2")].push(within(num(v)?, 0.0, km2, what)?);
                }
                _ => {}
            }
        }
    }
    let missing = |k: &str| {
        Error::file(path, k, "missing: the authors' kpis.yaml gives var_1, var_2 (3 each), fks_1, fks_2 and distance")
    };
    let distance = distance.ok_or_else(|| missing("distance"))?;
    // A key given with the wrong number of values, at its line.
    let wrong = |k: &str, msg: String| match lines.get(k) {
        Some(n) => Error::file(path, format!("line {n}, {k}"), msg),
        None => missing(k),
    };
    for l in 0..2 {
        if var[l].len() != 3 {
            let msg = format!("{} values where the x, y, z variances are 3", var[l].len());
            return Err(wrong(["var_1", "var_2"][l], msg));
        }
        if count[l] == 0 {
            return Err(wrong(["fks_1", "fks_2"][l], "no point".to_string()));
        }
    }
    let v: Vec<Real> = var.iter().map(|v| v.iter().sum::<Real>()).collect();
    let n = (count[0] + count[1]) as Real;
    Ok(SocketFigures {
        spread_per_socket_mm: v.iter().map(|s| s.sqrt() * 1000.0).collect(),
        spread_mm: ((v[0] * count[0] as Real + v[1] * count[1] as Real) / n).sqrt() * 1000.0,
        distance_error_mm: distance.abs() * 1000.0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibrate::task::Metric;

    /// Two sockets 50 mm apart, each point 1 mm (socket 1) or 2 mm (socket 2) from its
    /// socket's mean, the means 50.5 mm apart: the figures in closed form.
    #[test]
    fn figures_in_closed_form() {
        let v = |x, y, z| Vec3::new(x, y, z);
        let points = [
            v(1.0, 0.0, 0.0),
            v(-1.0, 0.0, 0.0),
            v(50.5, 2.0, 0.0),
            v(50.5, -2.0, 0.0),
            v(50.5, 0.0, 2.0),
            v(50.5, 0.0, -2.0),
        ];
        let (rows, f) = socket_figures(&points, &[0, 0, 1, 1, 1, 1], &[0.0, 50.0]);
        assert_eq!(rows, vec![1.0, 1.0, 2.0, 2.0, 2.0, 2.0]);
        assert_eq!(f.spread_per_socket_mm, vec![1.0, 2.0]);
        assert!((f.spread_mm - (18.0 / 6.0 as Real).sqrt()).abs() < 1e-12);
        assert!((f.distance_error_mm - 0.5).abs() < 1e-12);
        // The pooled spread is the metric of the per-row distances.
        assert!((Metric::SocketSpreadMm.of(&rows).0 - f.spread_mm).abs() < 1e-12);
    }

    /// A key given in flow style, twice, or with four variances, and a list of no point,
    /// were each refused as "missing" (the last one naming `var_2`), with no line.
    #[test]
    fn a_key_present_but_malformed_is_named_at_its_line() {
        let dir = crate::test_dir("kpis-malformed");
        let p = dir.join("kpis.yaml");
        let var = |k: &str, n: usize| format!("{k}:\n{}", "- 1.0e-9\n".repeat(n));
        let points = |k: &str| format!("{k}:\n- - 0.4\n  - 0.0\n  - 0.0\n");
        let good = [
            var("var_1", 3),
            var("var_2", 3),
            points("fks_1"),
            points("fks_2"),
        ];
        let head = "distance: -2.9e-06\n";
        for (text, want) in [
            (
                format!(
                    "{head}{}var_2: [1e-9, 2e-9, 3e-9]\n{}{}",
                    good[0], good[2], good[3]
                ),
                "line 6, var_2: a list on the key's line is not read",
            ),
            (
                format!("{head}{}{}", good.concat(), good[0]),
                "line 18, var_1: given twice (first on line 2)",
            ),
            (
                format!("{head}{}{}{}{}", good[0], var("var_2", 4), good[2], good[3]),
                "line 6, var_2: 4 values where the x, y, z variances are 3",
            ),
            (
                format!("{head}{}{}{}fks_2:\n", good[0], good[1], good[2]),
                "line 14, fks_2: no point",
            ),
        ] {
            std::fs::write(&p, text).unwrap();
            let e = read_kpis(&p).unwrap_err().to_string();
            assert!(e.contains(want), "{e}");
        }
        std::fs::write(&p, format!("{head}{}", good.concat())).unwrap();
        assert!(read_kpis(&p).is_ok());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A malformed `distance:` is refused at its own line and key, not the key before it.
    #[test]
    fn a_malformed_distance_is_named_at_its_key() {
        let dir = crate::test_dir("kpis");
        let p = dir.join("kpis.yaml");
        std::fs::write(&p, "var_1:\n- 1.0e-9\n- 2.0e-9\n- 3.0e-9\ndistance: oops\n").unwrap();
        let e = read_kpis(&p).unwrap_err().to_string();
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(
            e.contains("line 5, distance") && e.contains("\"oops\""),
            "{e}"
        );
        assert!(!e.contains("var_1"), "{e}");
    }

    /// A negative or huge variance (a NaN or infinite spread) and a distance error beyond
    /// 1 km are refused at their line and key, not printed as `NaN` or `inf` and written as
    /// `null` in task.json.
    #[test]
    fn a_variance_or_distance_out_of_range_is_refused_at_its_key() {
        let dir = crate::test_dir("kpis-range");
        let p = dir.join("kpis.yaml");
        let fks = "fks_1:\n- - 0.4\nfks_2:\n- - 0.4\n";
        for (var_1, distance, expected) in [
            (
                "-1.0e-9",
                "1.0e-6",
                "line 7, var_1: must be a variance in [0, 1e6] m²",
            ),
            (
                "1.0e308",
                "1.0e-6",
                "line 7, var_1: must be a variance in [0, 1e6] m²",
            ),
            (
                "1.0e-9",
                "-1.0e308",
                "line 1, distance: must be a distance error within",
            ),
        ] {
            let text = format!(
                "distance: {distance}\n{fks}var_1:\n- {var_1}\n- 2.0e-9\n- 3.0e-9\n\
                 var_2:\n- 1.0e-9\n- 2.0e-9\n- 3.0e-9\n"
            );
            std::fs::write(&p, &text).unwrap();
            let e = read_kpis(&p).unwrap_err().to_string();
            assert!(e.contains(expected), "{e}");
        }
        std::fs::write(&p, "distance: 1.0e-6\nfks_1:\n- - 0.4\nfks_2:\n- - 0.4\nvar_1:\n- 0.0\n- 2.0e-9\n- 3.0e-9\nvar_2:\n- 1.0e-9\n- 2.0e-9\n- 3.0e-9\n").unwrap();
        let ok = read_kpis(&p);
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(ok.unwrap().spread_mm.is_finite());
    }

    /// Panda 6's kpis.yaml: √(5.5 + 9.5 + 13.1)·10⁻⁹ m² = 0.1676 mm, √(7.8 + 23.1 + 18.8)
    /// = 0.2229 mm, 31 points each, distance −2.9294 µm.
    #[test]
    fn the_authors_kpis_read() {
        let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/mukca/panda_6/kpis.yaml");
        let f = read_kpis(&p).unwrap();
        assert!((f.spread_per_socket_mm[0] - 28.1e-9f64.sqrt() * 1e3).abs() < 1e-9);
        assert!((f.spread_per_socket_mm[1] - 49.7e-9f64.sqrt() * 1e3).abs() < 1e-9);
        assert!((f.spread_mm - (77.8e-9f64 / 2.0).sqrt() * 1e3).abs() < 1e-9);
        assert!((f.distance_error_mm - 2.9294e-3).abs() < 1e-12);
    }
}
