//! The command line and the files it reads: `simulate`, `identify`, `fk`, `check`, `import`
//! and `compensate` end to end, strict refusals of bad inputs, fuzzing of the robot, scenario
//! and measurement parsers, real tracker data (the IPA UR10 rows in `examples/ipa-ur10/`), and
//! typed arguments: allowed values listed, `--out` checked before any work; refusals that name
//! the file, the line and the key; the HTML pages opened in headless Chromium.

#[path = "../common/mod.rs"]
mod common;

mod blocked;
mod cells;
mod cli;
mod cluster;
mod committed;
mod compensate;
mod determinable;
mod determinism;
mod duplicate_keys;
mod edited;
mod endless;
mod final_fitness;
mod fixed_models;
mod foreign_db;
mod fuzz;
mod guard;
mod guard_edits;
mod guo;
mod harmonics;
mod html;
mod impossible;
mod inputs;
mod instruments;
mod interchange;
mod kernel;
mod kind_counts;
mod kinds;
mod layers;
mod live_run;
mod malformed;
mod malformed_lines;
mod mapping_sets;
mod memory;
mod noise;
mod outputs;
mod per_trial;
mod plausible;
mod practice;
mod precision;
mod profiles;
mod rank_causes;
mod reading_lines;
mod readmit;
mod readmit_cv;
mod realdata;
mod record_figures;
mod record_formats;
mod record_keys;
mod record_layout;
mod record_task;
mod records;
mod refusals;
mod refused_out;
mod regenerate;
mod registration_rows;
mod report_baseline;
mod results;
mod results_team;
mod robot_model;
mod run_options;
mod search_ecdf;
mod shard_edges;
mod shown_numbers;
mod socket_task;
mod spelled;
mod strict_inputs;
mod study_files;
mod task;
mod task_rows;
mod terminal_names;
mod typed;
mod validation_kind;
mod verdicts;
mod worse;
mod written_otherwise;
