//! Tests of pose selection: the objectives, DETMAX, IDE and the selection driver.

use super::*;

#[test]
fn names_parse_and_round_trip() {
    for s in [
        Strategy::Random,
        Strategy::Detmax,
        Strategy::Ide,
        Strategy::DetmaxIde,
    ] {
        assert_eq!(
            crate::robot::names::parse::<Strategy>("s", s.as_str()).ok(),
            Some(s)
        );
    }
    for o in [Objective::Composite, Objective::O1, Objective::O6] {
        assert_eq!(
            crate::robot::names::parse::<Objective>("o", o.as_str()).ok(),
            Some(o)
        );
    }
    assert_eq!(Strategy::DetmaxIde.as_str(), "detmax-ide");
    assert!(crate::robot::names::parse::<Strategy>("s", "DETMAX").is_err());
    assert!(crate::robot::names::parse::<Objective>("o", "o2").is_err());
}

/// The IRB2600 with a tool, its position-identifiable parameters (with an unidentifiable
/// one every index is zero, and tests comparing indices would compare zeros), and the
/// random stream after choosing them.
fn identifiable_model(seed: u64) -> (Robot, RobotPoseModel, Rng) {
    let mut robot = crate::robot::builtin::irb2600();
    robot.set(Param::Tool(0), 80.0);
    let mut rng = crate::numeric::rng::from_seed(seed);
    let rich = crate::robot::sampling::uniform_joint_poses(&robot, 60, &mut rng);
    let params =
        crate::robot::identifiability::analyse(&robot, &robot.params(), &rich, Measure::Position)
            .identifiable;
    let model = RobotPoseModel::new(&robot, &params, Measure::Position);
    (robot, model, rng)
}

#[test]
fn gram_eigen_path_agrees_with_svd_scores() {
    let (robot, model, mut rng) = identifiable_model(3);
    let qs = crate::robot::sampling::uniform_joint_poses(&robot, 12, &mut rng);
    let s = score(&model, &qs);
    let flat: Vec<Real> = qs.iter().flatten().copied().collect();
    let mut ev = Evaluator::new(&model);
    for (o, want) in [
        (Objective::Composite, s.composite),
        (Objective::O1, s.o1),
        (Objective::O6, s.o6),
    ] {
        let got = ev.value(&model, &flat, o);
        assert!(
            want > 0.0,
            "{o:?}: a rank-deficient set would compare zeros"
        );
        assert!(
            (got - want).abs() <= 1e-7 * want.abs(),
            "{o:?}: {got} vs {want}"
        );
    }
}

#[test]
fn sets_evaluated_together_are_the_sets_one_by_one_to_the_bit() {
    // Eight trial sets of 20 poses sharing some poses with a base set (as IDE's crossover
    // makes them), and a ninth call with three sets: the objectives of the lanes, with and
    // without the base set's blocks, are those of `value` one set at a time.
    let (robot, model, mut rng) = identifiable_model(5);
    let (m, dof) = (20, model.dof());
    let flat = |qs: Vec<Vec<Real>>| qs.into_iter().flatten().collect::<Vec<Real>>();
    let base = flat(crate::robot::sampling::uniform_joint_poses(
        &robot, m, &mut rng,
    ));
    let mut sets = Vec::new();
    for t in 0..Spectra::LANES {
        let mut set = flat(crate::robot::sampling::uniform_joint_poses(
            &robot, m, &mut rng,
        ));
        for p in (0..m).filter(|p| (p + t) % 3 != 0) {
            set[p * dof..(p + 1) * dof].copy_from_slice(&base[p * dof..(p + 1) * dof]);
        }
        sets.extend(set);
    }
    let len = m * dof;
    let known = KnownBlocks::new(&model, &base);
    let nothing_known = KnownBlocks::new(&model, &[]);
    let mut ev = Evaluator::new(&model);
    for objective in [Objective::Composite, Objective::O1, Objective::O6] {
        let one_by_one: Vec<Real> = sets
            .chunks_exact(len)
            .map(|set| ev.value(&model, set, objective))
            .collect();
        assert!(one_by_one.iter().all(|&v| v.is_finite() && v > 0.0));
        for k in [&known, &nothing_known] {
            let all = ev.values(&model, &sets, len, objective, k);
            assert_eq!(
                all.map(Real::to_bits).to_vec(),
                one_by_one.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
            );
            let three = ev.values(&model, &sets[..3 * len], len, objective, k);
            assert_eq!(
                three[..3].iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                one_by_one[..3]
                    .iter()
                    .map(|v| v.to_bits())
                    .collect::<Vec<_>>()
            );
            assert!(three[3..].iter().all(|&v| v == Real::NEG_INFINITY));
        }
    }
}

#[test]
fn bad_inputs_are_errors() {
    let robot = crate::robot::builtin::irb2600();
    let params = vec![Param::A(0), Param::A(1), Param::D(0), Param::Theta(1)];
    let model = RobotPoseModel::new(&robot, &params, Measure::Position);
    let mut rng = crate::numeric::rng::from_seed(1);
    let cands = crate::robot::sampling::uniform_joint_poses(&robot, 10, &mut rng);
    let mut bad = cands.clone();
    bad[3][2] = 1e9;
    let mut short = cands.clone();
    short[3] = vec![0.0; 2];
    // Too few poses for 4 parameters (need 2), too many for the pool; a pose outside the
    // limits; a pose of the wrong length.
    for (pool, strategy, count) in [
        (&cands, Strategy::Detmax, 1),
        (&cands, Strategy::Detmax, 11),
        (&bad, Strategy::Random, 3),
        (&short, Strategy::Random, 3),
    ] {
        let o = SelectOptions::new(count);
        assert!(
            select(&model, pool, strategy, &o, &mut rng).is_err(),
            "{strategy:?}, {count} poses"
        );
    }
    let mut o = SelectOptions::new(3);
    o.ide.population = 3;
    assert!(select(&model, &cands, Strategy::Ide, &o, &mut rng).is_err());
    assert!(objective_curve(&model, &cands, &[0], &o, &mut rng).is_err());
}
