#!/usr/bin/env bash
# The README's second command (and what CI runs): set up, then every check and every test.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
export PATH="$HOME/.cargo/bin:$PATH"
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
