#!/usr/bin/env bash
# Rebuilds the lift's pose prior, assets/pose_prior/pose_prior.json, from the motion-capture
# takes in MOCAP_DIR (default ../shared/data/mocap_prior: 67 CMU takes, gzip BVH, none of the
# benchmark suite's test split; `videomocap-bench prior` refuses those). The file lists the
# takes it read; the lift bundles it at build time, so rebuild afterwards.
# Usage: dev/pose_prior.sh [MOCAP_DIR]   (assets/pose_prior/SOURCE.md says what it read)
set -euo pipefail
cd "$(dirname "$0")/.."
mocap="${1:-../shared/data/mocap_prior}"
cargo build --profile quick -p videomocap-bench
target="${CARGO_TARGET_DIR:-target}"
"$target/quick/videomocap-bench" prior "$mocap" --out assets/pose_prior/pose_prior.json
sha256sum assets/pose_prior/pose_prior.json
