#!/usr/bin/env bash
# The README's second command (and what CI runs): set up, then every check and every test.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
export PATH="$HOME/.cargo/bin:$PATH"
# A fresh clone gains nothing from incremental caches, which double the build's disk use
# (a CI run once failed linking on a full disk).
export CARGO_INCREMENTAL=0
cargo fmt --check
# Each stage's files form a line, not a circle (issue 92).
python3 scripts/module_cycles.py
python3 scripts/house_count.py --strict
cargo clippy --locked --workspace --all-targets --quiet -- -D warnings
# The stages build without FFmpeg (image sequences only) and never pull in the GUI.
cargo check --locked -p videomocap-core --no-default-features --quiet
cargo check --locked -p videomocap --no-default-features --quiet
RUSTDOCFLAGS="-D warnings" cargo doc --locked --workspace --no-deps --quiet
cargo test --locked --workspace
