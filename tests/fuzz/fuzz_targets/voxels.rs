//! Fuzz target: the voxels parser (see `../checks.rs` for what is checked).
#![no_main]
#[path = "../checks.rs"]
mod checks;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    checks::check("voxels", data);
});
