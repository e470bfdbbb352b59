#!/usr/bin/env bash
# Fuzzes every parser that reads user files (marks, tracks2d, skeleton3d, project, BVH, PLY,
# XYZ, voxel grids) with cargo fuzz (libFuzzer), SECONDS per target (default 300), and prints a
# table of executions, corpus size and crashes. Crashes are left in tests/fuzz/artifacts/TARGET/;
# copy each into tests/fuzz/regressions/TARGET/ (a cargo test replays them all) and fix it.
#
#   scripts/fuzz.sh [SECONDS] [TARGET...]
#
# Needs a nightly toolchain (libFuzzer's instrumentation) and cargo-fuzz; both are installed
# when missing. The corpus grows in tests/fuzz/corpus/ (not committed), seeded from
# tests/fuzz/seeds/.
set -euo pipefail
cd "$(dirname "$0")/.."
secs="${1:-300}"
shift || true
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  targets=(marks tracks2d skeleton3d project bvh ply xyz voxels)
fi
rustup run nightly rustc --version >/dev/null 2>&1 || rustup toolchain install nightly --profile minimal
command -v cargo-fuzz >/dev/null 2>&1 || cargo install cargo-fuzz --locked
cargo +nightly fuzz build --fuzz-dir tests/fuzz -O >/dev/null

printf '%-11s %8s %14s %10s %8s %8s\n' target seconds executions execs/s corpus crashes
for t in "${targets[@]}"; do
  corpus="tests/fuzz/corpus/$t"
  artifacts="tests/fuzz/artifacts/$t"
  mkdir -p "$corpus" "$artifacts"
  log="tests/fuzz/artifacts/$t.log"
  before=$(find "$artifacts" -type f | wc -l)
  # -fork keeps fuzzing after a crash (each crash is saved, the run goes on).
  cargo +nightly fuzz run --fuzz-dir tests/fuzz -O "$t" "$corpus" "tests/fuzz/seeds/$t" -- \
    -max_total_time="$secs" -max_len=65536 -rss_limit_mb=2048 -timeout=10 \
    -print_final_stats=1 -artifact_prefix="$artifacts/" >"$log" 2>&1 || true
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1)
  rate=$(grep -o 'stat::average_exec_per_sec: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1)
  after=$(find "$artifacts" -type f | wc -l)
  printf '%-11s %8s %14s %10s %8s %8s\n' "$t" "$secs" "${execs:-?}" "${rate:-?}" \
    "$(find "$corpus" -type f | wc -l)" "$((after - before))"
done
