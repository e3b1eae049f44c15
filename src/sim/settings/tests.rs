//! Tests of the scenario sections of the virtual measurement.

use super::*;

#[test]
fn defaults_match_formats() {
    let t: TrackerSettings = toml::from_str("").unwrap();
    assert_eq!(t, TrackerSettings::default());
    assert_eq!(t.pose, [2500.0, 0.0, 500.0, 0.0, 0.0, 180.0]);
    assert_eq!((t.mpe_a_um, t.mpe_b_um_per_m, t.coverage), (15.0, 6.0, 2.0));
    let e: ErrorSettings = toml::from_str("").unwrap();
    assert_eq!(e.kind, ErrorKind::Paper);
    assert_eq!(e.params, ParamSelection::Identifiable);
    let o: OutlierSettings = toml::from_str("").unwrap();
    assert_eq!(o.count_for(50).unwrap(), 0);
    t.check().unwrap();
    e.check().unwrap();
}

#[test]
fn formats_examples_parse() {
    let e: ErrorSettings = toml::from_str(
        "kind = \"normal\"\nlength_mm = 0.1\nangle_rad = 0.001\nparams = [\"a1\", \"d2\"]",
    )
    .unwrap();
    assert_eq!(e.kind, ErrorKind::Normal);
    assert_eq!(
        e.params,
        ParamSelection::List(vec!["a1".into(), "d2".into()])
    );
    e.check().unwrap();
    let t: TrackerSettings =
        toml::from_str("pose = [1.0, 2.0, 3.0, 0.0, 0.0, 90.0]\nmeasure = \"pose\"").unwrap();
    assert_eq!(t.measure.measure(), Measure::Pose);
    #[derive(Deserialize)]
    struct R {
        region: Region,
    }
    let r: R = toml::from_str(
        "region = { kind = \"box\", center_mm = [550.0, 0.0, 550.0], size_mm = [1000.0, 1000.0, 1000.0] }",
    )
    .unwrap();
    assert!(matches!(r.region, Region::Box { .. }));
    let r: R = toml::from_str("region = { kind = \"joint\" }").unwrap();
    assert_eq!(r.region, Region::Joint {});
    let r: R = toml::from_str("region = { kind = \"grid\", per_joint = 3 }").unwrap();
    assert_eq!(r.region, Region::Grid { per_joint: 3 });
    let o: OutlierSettings = toml::from_str("fraction = 0.1").unwrap();
    assert_eq!(o.count_for(50).unwrap(), 5);
}

#[test]
fn negative_noise_is_refused_with_its_key() {
    let t = TrackerSettings {
        mpe_a_um: -1.0,
        ..Default::default()
    };
    let e = t.check().unwrap_err();
    assert!(
        e.to_string()
            .contains("must be finite and from 0 to 1000000 µm"),
        "{e}"
    );
    assert_eq!(e.key(), Some("tracker.mpe_a_um"));
    // Read from a scenario's text, the same value is refused on its field, as it is read.
    // (text, why, whether it is the tracker's table or the outliers').
    for (text, why, tracker) in [
        ("mpe_a_um = -1.0", "from 0 to", true),
        (
            "mpe_b_um_per_m = 1e308",
            "1000000 µm (1 m, far beyond any tracker's error)",
            true,
        ),
        // A metre and more had been taken, up to a robot file's range, and `simulate`
        // then blamed the robot's lengths for the points the noise carried out of range.
        ("mpe_a_um = 1e9", "from 0 to 1000000 µm", true),
        ("mpe_a_um = 1000001", "from 0 to 1000000 µm", true),
        (
            "angle_noise_deg = 1e300",
            "from 0 to 360 ° (one turn)",
            true,
        ),
        ("coverage = 0.0", "at least 1", true),
        ("coverage = 1e-300", "at least 1", true),
        ("coverage = 0.999", "below 1, σ would exceed", true),
        (
            "pose = [0.0, 0.0, 0.0, 0.0, 0.0, inf]",
            "6 finite numbers",
            true,
        ),
        ("fraction = 1.5", "in [0, 1]", false),
        ("magnitude_mm = [2.0, 1.0]", "lo ≤ hi", false),
    ] {
        let e = if tracker {
            toml::from_str::<TrackerSettings>(text).err()
        } else {
            toml::from_str::<OutlierSettings>(text).err()
        };
        let e = e.unwrap().to_string();
        assert!(e.contains(why), "{text}: {e}");
    }
    let t = TrackerSettings {
        coverage: 0.0,
        ..Default::default()
    };
    assert_eq!(t.check().unwrap_err().key(), Some("tracker.coverage"));
    let e = ErrorSettings {
        length_mm: Real::NAN,
        ..Default::default()
    };
    assert_eq!(e.check().unwrap_err().key(), Some("errors.length_mm"));
}

#[test]
fn more_outliers_than_poses_are_refused() {
    let o = OutlierSettings {
        count: Some(100),
        ..Default::default()
    };
    o.check().unwrap();
    assert_eq!(o.count_for(40).unwrap_err().key(), Some("outliers.count"));
    assert_eq!(o.count_for(100).unwrap(), 100);
    let o = OutlierSettings {
        magnitude_mm: [1.0, 0.5],
        ..Default::default()
    };
    assert_eq!(o.check().unwrap_err().key(), Some("outliers.magnitude_mm"));
    let o = OutlierSettings {
        count: Some(1),
        fraction: Some(0.1),
        ..Default::default()
    };
    assert_eq!(o.check().unwrap_err().key(), Some("outliers.fraction"));
}

#[test]
fn unknown_keys_and_names_are_refused() {
    let e = toml::from_str::<TrackerSettings>("mpe_a = 3.0").unwrap_err();
    assert!(e.to_string().contains("mpe_a"), "{e}");
    let e = toml::from_str::<OutlierSettings>("cont = 3").unwrap_err();
    assert!(e.to_string().contains("cont"), "{e}");
    let e = toml::from_str::<ErrorSettings>("params = \"some\"").unwrap_err();
    assert!(e.to_string().contains("identifiable"), "{e}");
    #[derive(Deserialize, Debug)]
    #[allow(dead_code)]
    struct R {
        region: Region,
    }
    let e = toml::from_str::<R>("region = { kind = \"box\", center_mm = [0.0, 0.0, 0.0], size_mm = [1.0, 1.0, 1.0], sise = 2 }")
        .unwrap_err();
    assert!(e.to_string().contains("sise"), "{e}");
    let s = ErrorSettings {
        params: ParamSelection::List(vec!["a1".into(), "thetta2".into()]),
        ..Default::default()
    };
    let e = s.check().unwrap_err();
    assert!(e.to_string().contains("thetta2"), "{e}");
    assert_eq!(e.key(), Some("errors.params"));
    let r = Region::Box {
        center_mm: [0.0; 3],
        size_mm: [1.0, 0.0, 1.0],
    };
    assert_eq!(
        r.check("validation.region").unwrap_err().key(),
        Some("validation.region")
    );
}
