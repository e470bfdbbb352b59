//! The `videomocap` command line as a library: the user's commands (gui, info, track, lift,
//! export, run, volume, carve), each calling one library step of `videomocap-core` or
//! `videomocap-volume`. `main.rs` parses the arguments and hands over; the developer tool
//! (`dev/bench`) reuses the reporting (`ExitError`, progress) and the settings loaders.

pub mod cli;
