#!/usr/bin/env bash
# The README's first command: set up, build, and run the main job on the bundled real sample.
# With a display it opens the desktop app on the sample; without one it runs the headless
# pipeline and prints where the results are.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
export PATH="$HOME/.cargo/bin:$PATH"
cargo build --release --quiet
bin=target/release/videomocap
sample=sample_videos/pose2sim_balancing_cam01
out=out/sample

if [ -n "${DISPLAY:-}${WAYLAND_DISPLAY:-}" ] && [ -z "${VIDEOMOCAP_HEADLESS:-}" ]; then
  exec "$bin" gui "$sample/video.mp4"
fi

mkdir -p "$out"
"$bin" info "$sample/video.mp4"
"$bin" info "$sample/video.mp4" --json > "$out/info.json"
"$bin" run "$sample/video.mp4" --marks "$sample/marks.json" --out-dir "$out"
echo
echo "Results in $out/: tracks2d.json/.csv (2D), skeleton3d.json (3D, camera space),"
echo "motion.bvh (load in Blender: File > Import > Motion Capture (.bvh), scale 0.01 for metres),"
echo "joints3d.csv and motion.trc (world metres, Y up), info.json"
