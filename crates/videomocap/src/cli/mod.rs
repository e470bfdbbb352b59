//! The headless command line: each command calls one library step and reports progress on
//! stderr (indicatif) and, with `--json`, a summary on stdout.

pub mod args;
mod batch;
mod carve;
mod cpus;
pub mod export;
mod info;
pub mod lift;
mod run;
pub mod track;
mod volume;

use args::{Command, GlobalArgs};
use indicatif::{ProgressBar, ProgressStyle};

/// Exit code for processing that failed.
pub const EXIT_FAILED: u8 = 1;
/// Exit code for bad usage or bad input (clap uses it too).
pub const EXIT_BAD_INPUT: u8 = 2;

/// An error with the process exit code it maps to.
#[derive(Debug)]
pub struct ExitError {
    /// 1 processing failed, 2 bad usage or bad input.
    pub code: u8,
    /// What went wrong (names the file).
    pub error: anyhow::Error,
}

impl ExitError {
    /// Bad usage or bad input: exit code 2.
    pub fn bad_input(error: impl Into<anyhow::Error>) -> Self {
        ExitError {
            code: EXIT_BAD_INPUT,
            error: error.into(),
        }
    }

    /// Processing failed: exit code 1.
    pub fn failed(error: impl Into<anyhow::Error>) -> Self {
        ExitError {
            code: EXIT_FAILED,
            error: error.into(),
        }
    }
}

/// Runs one command (never the GUI).
pub fn run(command: Command, global: &GlobalArgs) -> Result<(), ExitError> {
    match command {
        Command::Info { video } => info::run(&video, global),
        Command::Track(a) => track::run(&a, global),
        Command::Lift(a) => lift::run(&a, global),
        Command::Export(a) => export::run(&a, global),
        Command::Run(a) => run::run(&a, global),
        Command::Batch(a) => batch::run(&a, global),
        Command::Volume(a) => volume::run(&a, global),
        Command::Carve(a) => carve::run(&a, global),
        Command::Gui { .. } => Err(ExitError::bad_input(anyhow::anyhow!(
            "the desktop app is opened by main, not by the CLI"
        ))),
    }
}

/// A progress bar on stderr, hidden with `--quiet` or when stderr is not a terminal.
pub fn progress_bar(global: &GlobalArgs, total: u64, what: &str) -> ProgressBar {
    if global.quiet {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(total);
    let style = ProgressStyle::with_template(
        "{msg:>10} [{bar:40}] {pos}/{len} frames, {per_sec}, eta {eta}",
    )
    .map(|s| s.progress_chars("=> "))
    .unwrap_or_else(|_| ProgressStyle::default_bar());
    bar.set_style(style);
    bar.set_message(what.to_owned());
    bar
}

/// Prints a message on stderr unless `--quiet`.
pub fn say(global: &GlobalArgs, message: &str) {
    if !global.quiet {
        eprintln!("{message}");
    }
}

/// The error and its causes, each cause added only if the message does not already say it
/// (library errors quote their cause in their own message).
pub fn message_with_causes(error: &anyhow::Error) -> String {
    let mut message = error.to_string();
    for cause in error.chain().skip(1) {
        let text = cause.to_string();
        if !message.contains(&text) {
            message.push_str(": ");
            message.push_str(&text);
        }
    }
    message
}
