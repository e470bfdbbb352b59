//! The `videomocap` binary: parses arguments and hands over to the command line or the desktop
//! app (`videomocap-app`).

use clap::Parser;
use std::process::ExitCode;
use videomocap::cli;
use videomocap::cli::args::{Cli, Command};

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
            eprintln!("error: {}", cli::message_with_causes(&e.error));
            ExitCode::from(e.code)
        }
    }
}

#[cfg(feature = "gui")]
fn open_gui(video: Option<std::path::PathBuf>) -> Result<(), cli::ExitError> {
    videomocap_app::run(video).map_err(cli::ExitError::failed)
}

#[cfg(not(feature = "gui"))]
fn open_gui(_video: Option<std::path::PathBuf>) -> Result<(), cli::ExitError> {
    Err(cli::ExitError::bad_input(anyhow::anyhow!(
        "this build has no desktop app (feature \"gui\"); use a command, see --help"
    )))
}
