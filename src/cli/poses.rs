//! `calbench poses SCENARIO --strategy S [--count M] [--curve A,B,…] --out DIR`: choose a
//! calibration pose set on the scenario's nominal robot (Guo 2024 §3).

use std::path::PathBuf;

use anyhow::Result;
use calbench::error::Error;
use calbench::poses::SelectOptions;
use calbench::report::{self, output::PoseList, Output};
use calbench::sim::poses::sample_region;
use calbench::study::plan;
use calbench::study::scenario::{Scenario, StrategyName};
use clap::builder::{PossibleValuesParser, TypedValueParser};

/// The files always written (`curve.*` only with `--curve`).
const OUTPUTS: [&str; 3] = report::poses::FILES;

/// Arguments of `calbench poses`.
#[derive(clap::Args)]
pub struct PosesArgs {
    /// The scenario file.
    pub scenario: PathBuf,
    /// How the poses are chosen from the candidates; a `-full` strategy optimises over the
    /// full model (every joint parameter, no separation), as in a scenario.
    #[arg(long, value_parser = strategies())]
    pub strategy: StrategyName,
    /// Number of poses (default: calibration.count).
    #[arg(long)]
    pub count: Option<usize>,
    /// Print the objective against these pose counts (e.g. 20,40,60,80).
    #[arg(long, value_delimiter = ',', value_parser = pose_count, action = clap::ArgAction::Set)]
    pub curve: Option<Vec<usize>>,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
}

/// `--strategy`: the names of the scenario strategies that choose among candidates.
fn strategies() -> impl TypedValueParser<Value = StrategyName> {
    use strum::IntoEnumIterator as _;
    let names = StrategyName::iter()
        .filter(|s| s.selection().is_some())
        .map(<&'static str>::from);
    PossibleValuesParser::new(names).map(|name| {
        name.parse::<StrategyName>()
            .unwrap_or_else(|_| unreachable!("\"{name}\" is a strategy's own name"))
    })
}

/// One element of `--curve`, blanks around it ignored.
fn pose_count(text: &str) -> std::result::Result<usize, String> {
    text.trim()
        .parse::<usize>()
        .map_err(|_| "not a pose count (a whole number)".to_string())
}

/// Chooses the poses, writes the output folder and prints the scores (and the curve).
pub fn run(args: &PosesArgs) -> Result<()> {
    let out = &args.out;
    super::guard_out(out, &OUTPUTS, [&args.scenario])?;
    let sc = Scenario::load(&args.scenario)?;
    // As `run` warns of them (`Scenario::warnings`): a robot too small for its length unit or
    // with limits in radians, settings not read.
    for w in sc.warnings() {
        eprintln!("warning: {w}");
    }
    let (optimiser, full) = args
        .strategy
        .selection()
        .unwrap_or_else(|| unreachable!("--strategy takes the optimising strategies only"));
    let strategy_name: &'static str = args.strategy.into();
    let nominal = sc.robot()?;
    let measure = sc.tracker.measure.measure();
    let c = &sc.calibration;
    let count = args.count.unwrap_or(c.count);
    if count == 0 || count > c.candidates {
        return Err(Error::setting(
            "--count",
            format!(
                "must be between 1 and calibration.candidates ({})",
                c.candidates
            ),
        )
        .into());
    }
    // Every argument is checked before any work: the pool is `candidates` poses.
    if let Some(bad) = args
        .curve
        .iter()
        .flatten()
        .find(|&&n| n == 0 || n > c.candidates)
    {
        return Err(Error::setting(
            "--curve",
            format!("\"{bad}\" is not a pose count in 1..={}", c.candidates),
        )
        .into());
    }
    let twice = args.curve.as_deref().and_then(|counts| {
        calbench::study::given_twice(counts, PartialEq::eq, ToString::to_string, "curve points")
    });
    if let Some((_, msg)) = twice {
        return Err(Error::setting("--curve", msg).into());
    }
    let mut g = calbench::numeric::rng::stream(sc.seed, "poses-command");
    let pool = sample_region(&nominal, &c.region, c.candidates, &mut g)?;
    let scored = match (full, c.separate) {
        (true, _) => plan::ScoredModel::Full,
        (false, true) => plan::ScoredModel::Separated(c.separate_threshold),
        (false, false) => plan::ScoredModel::Plain,
    };
    // The kinematic parameters the scenario identifies, as its study's optimisers see them.
    let (identified, _) = plan::study_params(&sc, &nominal)?;
    let (model, params, separation) =
        plan::optimiser_model(&nominal, measure, &pool, scored, &identified);
    let mut opts = SelectOptions::new(count);
    opts.objective = c.objective;
    // A pose count refused by the selection names `--count` when that gave it.
    let sel =
        calbench::poses::select(&model, &pool, optimiser, &opts, &mut g).map_err(|e| match e {
            Error::Setting { key, msg } if key == "calibration.count" && args.count.is_some() => {
                Error::Setting {
                    key: "--count".into(),
                    msg,
                }
            }
            e => e,
        })?;
    // Everything is computed before anything is written, and written as a whole.
    let curve = args
        .curve
        .as_deref()
        .map(|counts| calbench::poses::objective_curve(&model, &pool, counts, &opts, &mut g))
        .transpose()?;
    let scores = report::poses::Scores {
        strategy: strategy_name,
        selection: &sel,
        params: &params,
        separation: separation.as_ref(),
    };
    let pose_list = PoseList {
        name: OUTPUTS[0],
        robot: &nominal,
        rows: &sel.poses[..],
    };
    let trace = report::poses::trace(&sel);
    let mut outputs: Vec<&dyn Output> = vec![&pose_list, &scores, &trace];
    let curve_files = curve.as_deref().map(|pts| {
        let objective = c.objective.as_str();
        (
            report::poses::curve(pts),
            report::poses::curve_figure(objective, pts),
        )
    });
    if let Some((csv, figure)) = &curve_files {
        outputs.extend([csv as &dyn Output, figure]);
    }
    report::output::folder(out, &outputs)?;
    out!(
        "{} of {} candidates by {}: composite {:.4}, O1 {:.4e}, GCN {:.4e}, condition number {:.4e}",
        sel.poses.len(),
        pool.len(),
        strategy_name,
        sel.scores.composite,
        sel.scores.o1,
        sel.scores.gcn,
        sel.scores.condition_number
    );
    if let Some(pts) = &curve {
        out!("objective against pose count (Guo 2024 fig. 7):");
        for (n, f) in pts {
            out!("  {n:>5} {f:.6}");
        }
    }
    Ok(())
}
