//! The `videomocap` binary: parses arguments and hands over to the CLI or the desktop app.

mod cli;
#[cfg(feature = "gui")]
mod gui;

use clap::Parser;
use cli::args::{Cli, Command};
use std::process::ExitCode;

fn main() -> ExitCode {
    let args = Cli::parse();
    let result = match args.command {
        None => open_gui(None),
        Some(Command::Gui { video }) => open_gui(video),
        Some(command) => cli::run(command, &args.global),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", message_with_causes(&e.error));
            ExitCode::from(e.code)
        }
    }
}

#[cfg(feature = "gui")]
fn open_gui(video: Option<std::path::PathBuf>) -> Result<(), cli::ExitError> {
    gui::run(video).map_err(cli::ExitError::failed)
}

#[cfg(not(feature = "gui"))]
fn open_gui(_video: Option<std::path::PathBuf>) -> Result<(), cli::ExitError> {
    Err(cli::ExitError::bad_input(anyhow::anyhow!(
        "this build has no desktop app (feature \"gui\"); use a command, see --help"
    )))
}

/// The error and its causes, each cause added only if the message does not already say it
/// (library errors quote their cause in their own message).
fn message_with_causes(error: &anyhow::Error) -> String {
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
