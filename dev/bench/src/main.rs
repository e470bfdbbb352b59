//! `videomocap-bench`: videomocap's developer tool. The benchmarks (every table of the README
//! and `docs/method.md`), the synthetic renderer as a command, scoring against its ground truth
//! and the crash-safety writer. Built from the repository, never installed.

mod args;
mod bench;
mod bench_baselines;
mod bench_correct;
mod bench_learned;
mod bench_lift;
mod bench_lift_network;
mod bench_motion;
mod bench_retrack;
mod bench_scrub;
mod bench_speed;
mod bench_suite;
mod bench_track;
mod bench_track_speed;
mod bench_views;
mod bench_volume;
mod bench_volume_speed;
mod prior;
mod report;
mod score;
mod stress_write;
mod synth;

use args::{Cli, Command};
use clap::Parser;
use std::process::ExitCode;
use videomocap::cli::{ExitError, message_with_causes, progress_bar, say};

/// Whether the command is a benchmark (its output may be committed for `report`).
fn is_benchmark(command: &Command) -> bool {
    matches!(
        command,
        Command::Track(_)
            | Command::Correct(_)
            | Command::Lift(_)
            | Command::Volume(_)
            | Command::Motion(_)
            | Command::Scrub(_)
            | Command::Learned(_)
            | Command::Speed { .. }
    )
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let global = &cli.global;
    if is_benchmark(&cli.command) && !global.json {
        // The first line of a benchmark's output names it, so an output committed under
        // docs/bench/ says what made it (`report` reads those files).
        let args: Vec<String> = std::env::args().skip(1).collect();
        println!("# videomocap-bench {}\n", args.join(" "));
    }
    let result = match &cli.command {
        Command::Track(a) => bench::run("track", a, global),
        Command::Correct(a) => bench::run("correct", a, global),
        Command::Lift(a) => bench::run("lift", a, global),
        Command::Volume(a) => bench::run("volume", a, global),
        Command::Motion(a) => bench_motion::run(a, global),
        Command::Scrub(a) => bench_scrub::run(a, global),
        Command::Learned(a) => bench_learned::run(a, global),
        Command::Speed { what, args } if what == "track" => bench_speed::run(args, global),
        Command::Speed { what, args } if what == "retrack" => bench_retrack::run(args, global),
        Command::Speed { what, args } if what == "network" => {
            bench_speed::run_network(args, global)
        }
        Command::Speed { what, args } => bench::run(what, args, global),
        Command::Synth(a) => synth::run(a, global),
        Command::Score { tracks, reference } => score::run(tracks, reference, global),
        Command::Prior(a) => prior::run(a, global),
        Command::Report {
            readme,
            figures,
            check,
        } => report::run(
            &report::ReportPaths {
                readme: readme.clone(),
                figures: figures.clone(),
            },
            *check,
        ),
        Command::StressWrite(a) => stress_write::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", message_with_causes(&e.error));
            ExitCode::from(e.code)
        }
    }
}
