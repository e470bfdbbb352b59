#!/usr/bin/env bash
# The README's second command (and what CI runs): set up, then every check and every test.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
export PATH="$HOME/.cargo/bin:$PATH"
cargo fmt --check
cargo clippy --all-targets --quiet -- -D warnings
cargo check --no-default-features --quiet
RUSTDOCFLAGS="-D warnings" cargo doc --no-deps --quiet
cargo test
