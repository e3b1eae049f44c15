//! Hot loops allocate nothing (docs/architecture.md, "Invariants"): the identification
//! problem's evaluation (chain walk, Jacobian rows, residuals) and the solvers' iterations work
//! in buffers made once per problem.
//!
//! The test crate's allocator counts the allocations of the calling thread (the test harness
//! runs other tests on other threads at the same time), and each test compares a run of k
//! iterations with one of more: every allocation made per iteration shows as a difference.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use calbench::identify::robot::RobotProblem;
use calbench::identify::solver::{solve, LeastSquares};
use calbench::identify::MethodSpec;
use calbench::measurement::Measure;
use calbench::numeric::{rng, Real, Vec3};
use calbench::robot::builtin;
use calbench::robot::identifiability::analyse;
use calbench::robot::sampling::uniform_joint_poses;
use calbench::robot::{Chain, Robot};
use nalgebra::{DMatrix, DVector};

use super::common::alternating_errors;

struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
}

fn count() {
    // `try_with`: the allocator also runs while a thread's locals are torn down.
    let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
}

// SAFETY: every call is forwarded unchanged to the system allocator; the count is a
// thread-local `Cell` with a constant initialiser, which itself never allocates.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        count();
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// The allocations `f` makes on this thread.
fn allocations<T>(f: impl FnOnce() -> T) -> (u64, T) {
    let before = ALLOCATIONS.with(Cell::get);
    let out = f();
    (ALLOCATIONS.with(Cell::get) - before, out)
}

/// The IRB2600's identifiable parameters, 40 poses and their tool points measured on the
/// robot with the paper-sized errors, plus a fixed sub-millimetre scatter.
struct Case {
    nominal: Robot,
    params: Vec<calbench::robot::Param>,
    qs: Vec<Vec<Real>>,
    points: Vec<Vec3>,
}

fn case() -> Case {
    let nominal = builtin::irb2600();
    let mut r = rng::from_seed(7);
    let qs = uniform_joint_poses(&nominal, 40, &mut r);
    let params = analyse(&nominal, &nominal.params(), &qs, Measure::Position).identifiable;
    let truth = nominal.with_errors(&alternating_errors(&params, 0.5, 0.002));
    let chain = Chain::new(&truth);
    let points = qs
        .iter()
        .enumerate()
        .map(|(i, q)| {
            let s = 0.01 * [1.0, -0.7, 0.4, -0.2, 0.9][i % 5];
            chain.fk(q).pos + Vec3::new(s, -s, 0.5 * s)
        })
        .collect();
    Case {
        nominal,
        params,
        qs,
        points,
    }
}

fn problem(c: &Case) -> RobotProblem<'_> {
    RobotProblem::new(
        &c.nominal,
        &c.params,
        &c.qs,
        &c.points,
        None,
        Measure::Position,
    )
    .unwrap()
}

#[test]
fn the_chain_walk_allocates_nothing() {
    let c = case();
    let chain = Chain::new(&c.nominal);
    let (n, sum) = allocations(|| {
        let mut sum = 0.0;
        for _ in 0..50 {
            for q in &c.qs {
                sum += chain.fk(q).pos.x;
            }
        }
        sum
    });
    assert!(sum.is_finite());
    assert_eq!(n, 0, "2000 forward kinematics allocated {n} times");
}

#[test]
fn evaluating_the_identification_problem_allocates_nothing() {
    let c = case();
    let p = problem(&c);
    let size = p.size();
    let x = DVector::from_element(size.params, 1e-4);
    let mut r = DVector::zeros(size.rows());
    let mut j = DMatrix::zeros(size.rows(), size.params);
    p.evaluate(&x, &mut r, &mut j);
    let (n, ()) = allocations(|| {
        for _ in 0..20 {
            p.evaluate(&x, &mut r, &mut j);
        }
    });
    assert!(r.iter().chain(j.iter()).all(|v| v.is_finite()));
    assert_eq!(
        n, 0,
        "20 evaluations (residuals and Jacobian) allocated {n} times"
    );
}

/// The allocations of the method `entry` (a scenario's `[[methods]]` table, without
/// `max_iter`) run for `short` and for `long` iterations on the same problem, its stopping
/// step below any step it takes: equal when an iteration allocates nothing.
fn per_iteration(entry: &str, short: usize, long: usize) {
    let c = case();
    let p = problem(&c);
    let x0 = DVector::zeros(c.params.len());
    let run = |iterations: usize| {
        let text = format!("{entry}\neps = 1e-300\nmax_iter = {iterations}");
        let spec = MethodSpec::from_table(&toml::from_str(&text).unwrap())
            .unwrap_or_else(|e| panic!("{text}: {e:?}"));
        let solver = spec.method.solver().expect("a Jacobian method");
        allocations(|| solve(solver, &p, &x0))
    };
    let (a, short_run) = run(short);
    let (b, long_run) = run(long);
    assert_eq!(
        (short_run.iterations, long_run.iterations),
        (short, long),
        "{entry}: the runs must stop at their iteration limits for the comparison to mean anything"
    );
    assert_eq!(
        a,
        b,
        "{entry}: {short} iterations allocated {a} times, {long} iterations {b}: {} per iteration",
        (b as f64 - a as f64) / (long - short) as f64
    );
}

#[test]
fn gauss_newton_iterations_allocate_nothing() {
    per_iteration("name = \"ls\"", 2, 4);
}

#[test]
fn levenberg_marquardt_iterations_allocate_nothing() {
    per_iteration("name = \"lm\"", 3, 6);
    per_iteration("name = \"lm\"\nadaptive = true", 3, 6);
    per_iteration("name = \"lm\"\nmarquardt = true", 3, 6);
}

#[test]
fn ridge_and_robust_iterations_allocate_nothing() {
    per_iteration("name = \"ridge\"", 2, 4);
    per_iteration("name = \"ridge\"\nxi = 0.01", 2, 4);
    // Past the switch to the robust weights (whose weighted-Jacobian buffer is made at the
    // first weight below 1) and through the refit.
    per_iteration("name = \"igg3\"", 8, 16);
    per_iteration("name = \"igg3\"\nweight = \"huber\"", 8, 16);
    per_iteration("name = \"igg3\"\nweight = \"tukey\"", 8, 16);
}

/// The searches (Qiao 2021 eqs. 12–13): an iteration evaluates the fitness through the chain
/// walk and moves the beetle or the swarm in buffers made once.
#[test]
fn search_iterations_allocate_nothing() {
    use calbench::identify::CalibrationProblem;
    use calbench::measurement::Measurements;
    use calbench::numeric::Frame;
    let c = case();
    let data = Measurements {
        qs: c.qs.clone(),
        points: c.points.clone(),
        ..Default::default()
    };
    let cal = CalibrationProblem::new(&c.nominal, &c.params, &data, Frame::identity(), 1.0);
    // The swarms evaluate their particles on rayon: in a pool of one thread, every
    // evaluation runs on the thread whose allocations are counted.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    for entry in [
        "name = \"bas\"",
        "name = \"pso\"\npopulation = 8",
        "name = \"bas-pso\"\npopulation = 8",
    ] {
        let run = |iterations: usize| {
            let text = format!("{entry}\niterations = {iterations}");
            let spec = MethodSpec::from_table(&toml::from_str(&text).unwrap())
                .unwrap_or_else(|e| panic!("{text}: {e:?}"));
            let mut r = rng::from_seed(3);
            pool.install(|| allocations(|| spec.method.identify(&cal, &mut r).unwrap()))
        };
        let (a, short) = run(20);
        let (b, long) = run(40);
        assert_eq!((short.iterations, long.iterations), (20, 40), "{entry}");
        assert_eq!(
            a, b,
            "{entry}: 20 iterations allocated {a} times, 40 iterations {b}"
        );
    }
}
