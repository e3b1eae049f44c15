//! Tests of the searches: Halton points, the minima of test functions, reproducibility and
//! the refusal of bad options.

use super::search::primes;
use super::*;
use crate::error::{Error, Result};
use crate::numeric::rng::stream;
use crate::numeric::Real;
use approx::assert_relative_eq;

fn sphere(x: &[Real]) -> Real {
    let c = [1.0, -2.0, 0.5, 3.0, -1.0];
    x.iter().zip(c).map(|(a, b)| (a - b) * (a - b)).sum()
}

fn rosenbrock(x: &[Real]) -> Real {
    (1.0 - x[0]).powi(2) + 100.0 * (x[1] - x[0] * x[0]).powi(2)
}

fn dist(x: &[Real], c: &[Real]) -> Real {
    x.iter()
        .zip(c)
        .map(|(a, b)| (a - b) * (a - b))
        .sum::<Real>()
        .sqrt()
}

#[test]
fn halton_matches_radical_inverse_by_hand() {
    assert_relative_eq!(halton(0, 2), 0.0);
    assert_relative_eq!(halton(1, 2), 0.5);
    assert_relative_eq!(halton(2, 2), 0.25);
    assert_relative_eq!(halton(3, 2), 0.75);
    assert_relative_eq!(halton(6, 2), 0.375, epsilon = 1e-15); // 110b → .011b
    assert_relative_eq!(halton(1, 3), 1.0 / 3.0, epsilon = 1e-15);
    assert_relative_eq!(halton(5, 3), 7.0 / 9.0, epsilon = 1e-15); // 12₃ → .21₃
    assert_eq!(primes(6), vec![2, 3, 5, 7, 11, 13]);
    let b = Bounds {
        lower: vec![-1.0, 10.0, 0.0],
        upper: vec![1.0, 20.0, 5.0],
    };
    let pop = halton_population(4, &b);
    assert_eq!(pop.len(), 4);
    // Point 0 is (h(1,2), h(1,3), h(1,5)) = (1/2, 1/3, 1/5) scaled.
    assert_relative_eq!(pop[0][0], 0.0, epsilon = 1e-15);
    assert_relative_eq!(pop[0][1], 10.0 + 10.0 / 3.0, epsilon = 1e-12);
    assert_relative_eq!(pop[0][2], 1.0, epsilon = 1e-12);
    assert_relative_eq!(pop[1][0], -0.5, epsilon = 1e-15);
    for p in &pop {
        for (i, v) in p.iter().enumerate() {
            assert!(*v >= b.lower[i] && *v <= b.upper[i]);
        }
    }
}

#[test]
fn swarms_find_the_sphere_minimum() {
    let b = Bounds::symmetric(&[5.0; 5]);
    let c = [1.0, -2.0, 0.5, 3.0, -1.0];
    let o = PsoOptions {
        iterations: 300,
        ..Default::default()
    };
    let r = pso(&sphere, &b, &o, &mut stream(3, "pso")).unwrap();
    assert!(dist(&r.x, &c) < 1e-4, "pso {:?}", r.x);
    let o = hybrid(300);
    let r = bas_pso(&sphere, &b, &o, &mut stream(3, "bas_pso")).unwrap();
    assert!(dist(&r.x, &c) < 1e-4, "bas_pso {:?}", r.x);
    assert_eq!(r.evaluations, 40 + 300 * 3 * 40);
    assert_eq!(r.trace.len(), 300);
    assert!(r.trace.windows(2).all(|w| w[1] <= w[0]));
    let o = BasOptions {
        iterations: 3000,
        ..Default::default()
    };
    let r = bas(&sphere, &b, &o, &mut stream(3, "bas")).unwrap();
    assert!(dist(&r.x, &c) < 1e-2, "bas {:?}", r.x);
    assert_relative_eq!(r.fitness, sphere(&r.x));
}

/// BAS-PSO with `iterations` and the other options at their defaults.
fn hybrid(iterations: usize) -> BasPsoOptions {
    BasPsoOptions {
        swarm: PsoOptions {
            iterations,
            ..Default::default()
        },
        ..Default::default()
    }
}

#[test]
fn swarms_find_the_rosenbrock_minimum() {
    let b = Bounds::symmetric(&[2.0, 2.0]);
    let o = PsoOptions {
        iterations: 400,
        ..Default::default()
    };
    let r = pso(&rosenbrock, &b, &o, &mut stream(4, "pso")).unwrap();
    assert!(dist(&r.x, &[1.0, 1.0]) < 1e-3, "pso {:?}", r.x);
    let o = hybrid(400);
    let r = bas_pso(&rosenbrock, &b, &o, &mut stream(4, "bas_pso")).unwrap();
    assert!(dist(&r.x, &[1.0, 1.0]) < 1e-3, "bas_pso {:?}", r.x);
    let o = BasOptions {
        iterations: 5000,
        ..Default::default()
    };
    let r = bas(&rosenbrock, &b, &o, &mut stream(4, "bas")).unwrap();
    assert!(dist(&r.x, &[1.0, 1.0]) < 0.1, "bas {:?} {}", r.x, r.fitness);
}

#[test]
fn results_depend_on_the_seed_only() {
    let b = Bounds::symmetric(&[5.0; 5]);
    let o = BasPsoOptions {
        swarm: PsoOptions {
            iterations: 50,
            ..Default::default()
        },
        ..Default::default()
    };
    let a = bas_pso(&sphere, &b, &o, &mut stream(9, "x")).unwrap();
    let seq = BasPsoOptions {
        swarm: PsoOptions {
            parallel: false,
            ..o.swarm.clone()
        },
        ..o.clone()
    };
    let s = bas_pso(&sphere, &b, &seq, &mut stream(9, "x")).unwrap();
    assert_eq!(a, s);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(3)
        .build()
        .unwrap();
    let t = pool.install(|| bas_pso(&sphere, &b, &o, &mut stream(9, "x")).unwrap());
    assert_eq!(a, t);
    let other = bas_pso(&sphere, &b, &o, &mut stream(10, "x")).unwrap();
    assert_ne!(a.x, other.x);
    // Same seed, same result: PSO and BAS too.
    let same = |run: &dyn Fn() -> MetaResult| assert_eq!(run(), run());
    let (po, bo) = (hybrid(50).swarm, BasOptions::default());
    same(&|| pso(&sphere, &b, &po, &mut stream(9, "x")).unwrap());
    same(&|| bas(&sphere, &b, &bo, &mut stream(9, "x")).unwrap());
}

fn key(e: Error) -> String {
    e.key()
        .unwrap_or_else(|| panic!("not a setting error: {e}"))
        .into()
}

/// The key named when the default options, edited by `edit`, are run by `run`.
fn refused<O: Default>(
    edit: impl FnOnce(&mut O),
    run: impl FnOnce(&O) -> Result<MetaResult>,
) -> String {
    let mut o = O::default();
    edit(&mut o);
    key(run(&o).unwrap_err())
}

#[test]
fn bad_options_are_refused_by_name() {
    let b = Bounds::symmetric(&[1.0; 3]);
    let mut rng = stream(1, "x");
    let mut r = stream(1, "y");
    assert_eq!(
        refused(
            |o: &mut PsoOptions| o.population = 0,
            |o| pso(&sphere, &b, o, &mut r)
        ),
        "population"
    );
    assert_eq!(
        refused(
            |o: &mut PsoOptions| o.c1 = Real::NAN,
            |o| pso(&sphere, &b, o, &mut r)
        ),
        "c1"
    );
    // The constriction factor needs c1 + c2 > 4.
    let weak = |o: &mut PsoOptions| (o.c1, o.c2) = (1.0, 1.0);
    assert_eq!(refused(weak, |o| pso(&sphere, &b, o, &mut r)), "c1");
    let hybrid = |o: &BasPsoOptions| bas_pso(&sphere, &b, o, &mut stream(2, "y"));
    assert_eq!(
        refused(|o: &mut BasPsoOptions| o.swarm.population = 0, hybrid),
        "population"
    );
    assert_eq!(
        refused(
            |o: &mut BasPsoOptions| o.beetle.schedules.antenna = Real::INFINITY,
            hybrid
        ),
        "antenna"
    );
    let beetle = |o: &BasOptions| bas(&sphere, &b, o, &mut stream(3, "y"));
    assert_eq!(
        refused(|o: &mut BasOptions| o.schedules.decay = 1.0, beetle),
        "decay"
    );
    assert_eq!(
        refused(|o: &mut BasOptions| o.iterations = 0, beetle),
        "iterations"
    );
    let inverted = Bounds {
        lower: vec![0.0, 1.0],
        upper: vec![1.0, 0.0],
    };
    let r = pso(&sphere, &inverted, &PsoOptions::default(), &mut rng);
    assert_eq!(key(r.unwrap_err()), "bounds");
    let nan = Bounds {
        lower: vec![Real::NAN],
        upper: vec![1.0],
    };
    let r = bas(&sphere, &nan, &BasOptions::default(), &mut rng);
    assert_eq!(key(r.unwrap_err()), "bounds");
    let ragged = Bounds {
        lower: vec![0.0],
        upper: vec![1.0, 2.0],
    };
    let r = bas_pso(&sphere, &ragged, &BasPsoOptions::default(), &mut rng);
    assert_eq!(key(r.unwrap_err()), "bounds");
}

#[test]
fn nan_fitness_counts_as_worst() {
    let b = Bounds::symmetric(&[2.0; 2]);
    let f = |x: &[Real]| if x[0] < 0.0 { Real::NAN } else { sphere(x) };
    let o = PsoOptions {
        iterations: 100,
        ..Default::default()
    };
    let r = pso(&f, &b, &o, &mut stream(2, "x")).unwrap();
    assert!(r.fitness.is_finite() && r.x[0] >= 0.0);
}

/// Qiao's cube is the scenarios' box region: the same draws give the same poses.
#[test]
fn poses_in_cube_is_the_box_region() {
    let robot = crate::robot::builtin::tx60();
    let (centre, edge) = ([550.0, 0.0, 550.0], 1000.0);
    let cube = poses_in_cube(&robot, 20, centre, edge, 200_000, &mut stream(7, "p")).unwrap();
    let region = crate::sim::settings::Region::Box {
        center_mm: centre,
        size_mm: [edge; 3],
    };
    let boxed = crate::sim::poses::sample_region(&robot, &region, 20, &mut stream(7, "p")).unwrap();
    assert_eq!(cube, boxed);
    let e = poses_in_cube(
        &robot,
        5,
        [5000.0, 0.0, 0.0],
        10.0,
        1000,
        &mut stream(7, "p"),
    );
    assert!(matches!(e, Err(Error::Compute(_))));
}
