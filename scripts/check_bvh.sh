#!/usr/bin/env bash
# Checks the BVHs that `videomocap run` and `export --rig mixamo` write for the bundled sample
# with two independent readers: Blender (Debian's package; imports each rig, counts frames and
# bones, compares every joint on every frame with joints3d.csv) and the Python `bvh` package
# (its own forward kinematics, same comparison). Installs what is missing. Not part of CI
# (Blender is large).
#
#   bash scripts/check_bvh.sh            # runs the sample into out/check_bvh/ first
#   bash scripts/check_bvh.sh DIR        # checks DIR/motion.bvh (and DIR/motion.mixamo.bvh if
#                                        # there) against DIR/joints3d.csv
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$HOME/.cargo/bin:$PATH"
sudo_if_needed() { if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi; }

dir="${1:-}"
if [ -z "$dir" ]; then
    bash scripts/setup.sh
    dir=out/check_bvh
    sample=sample_videos/pose2sim_balancing_cam01
    cargo build --release --quiet
    ./target/release/videomocap --quiet run "$sample/video.mp4" --marks "$sample/marks.json" --out-dir "$dir"
    ./target/release/videomocap --quiet export "$dir/skeleton3d.json" --bvh "$dir/motion.mixamo.bvh" --rig mixamo
fi
for f in motion.bvh joints3d.csv; do
    [ -f "$dir/$f" ] || { echo "$dir/$f: missing (run \`videomocap run\` into $dir first)" >&2; exit 2; }
done

if ! python3 -c "import bvh" 2>/dev/null; then
    python3 -m pip install --quiet --user bvh
fi
if ! command -v blender >/dev/null; then
    sudo_if_needed apt-get update -qq
    sudo_if_needed env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends blender
fi

status=0
check() { # file rig
    python3 scripts/check_bvh_reader.py "$1" "$dir/joints3d.csv" "$2" || status=1
    out=$(blender -b --factory-startup --python scripts/check_bvh_blender.py -- "$1" "$dir/joints3d.csv" "$2" 2>&1)
    echo "$out" | grep -E "^blender " || { echo "$out" | tail -20; status=1; }
    echo "$out" | grep -q BLENDER_CHECK_OK || status=1
}
check "$dir/motion.bvh" cmu
if [ -f "$dir/motion.mixamo.bvh" ]; then check "$dir/motion.mixamo.bvh" mixamo; fi
if [ "$status" -eq 0 ]; then echo "BVH check passed: $dir"; else echo "BVH check FAILED: $dir" >&2; fi
exit "$status"
