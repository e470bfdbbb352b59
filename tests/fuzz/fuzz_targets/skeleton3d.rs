//! Fuzz target: the skeleton3d parser (see `../checks.rs` for what is checked).
#![no_main]
#[path = "../checks.rs"]
mod checks;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    checks::check("skeleton3d", data);
});
