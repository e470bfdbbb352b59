#!/usr/bin/env bash
# Makes the bad-video corpus in DIR (default out/bad-videos): one file per way a video can be
# broken or unusual, each 1 s of ffmpeg's testsrc2 unless its case says otherwise. Used by
# tests/bad_videos.rs, which opens and tracks every file and prints the table.
#
#   scripts/bad_videos.sh [DIR]
set -euo pipefail
dir="${1:-out/bad-videos}"
mkdir -p "$dir"
cd "$dir"
ff() { ffmpeg -hide_banner -loglevel error -y "$@"; }
src() { echo "testsrc2=size=${1}:rate=${2:-30}"; }

# A good clip to break.
ff -f lavfi -i "$(src 320x240)" -t 1 -c:v libx264 -pix_fmt yuv420p -g 10 good.mp4
size=$(stat -c %s good.mp4)
# Truncated at 10 %, 50 % and 90 % (the index, moov, is at the end unless faststart).
for pct in 10 50 90; do head -c $((size * pct / 100)) good.mp4 >"truncated_${pct}pct.mp4"; done
ff -f lavfi -i "$(src 320x240)" -t 1 -c:v libx264 -pix_fmt yuv420p -g 10 -movflags +faststart faststart.mp4
fsize=$(stat -c %s faststart.mp4)
head -c $((fsize * 60 / 100)) faststart.mp4 >truncated_60pct_faststart.mp4
# 8 KiB of zeros in the middle.
cp faststart.mp4 zeroed_middle.mp4
dd if=/dev/zero of=zeroed_middle.mp4 bs=1 seek=$((fsize / 2)) count=8192 conv=notrunc status=none
# Wrong extensions: an MP4 called .avi, text and a PNG called .mp4, an empty file.
cp good.mp4 wrong_extension.avi
printf 'not a video\n%.0s' {1..50} >text.mp4
ff -f lavfi -i "$(src 64x48)" -frames:v 1 image.png && mv image.png png_named.mp4
: >empty.mp4
# Audio only.
ff -f lavfi -i "sine=frequency=440:duration=1" -c:a aac audio_only.mp4
# 1×1 pixels; odd sizes (4:4:4 so that x264 takes them); tiny.
ff -f lavfi -i "$(src 320x240)" -t 1 -vf scale=1:1 -c:v libx264 -pix_fmt yuv444p one_pixel.mp4
ff -f lavfi -i "$(src 320x240)" -t 1 -vf scale=321:241 -c:v libx264 -pix_fmt yuv444p odd_321x241.mp4
ff -f lavfi -i "$(src 320x240)" -t 1 -vf scale=17:9 -c:v libx264 -pix_fmt yuv444p tiny_17x9.mp4
# 0 frames: a video stream with no packets.
ff -f lavfi -i "$(src 320x240)" -frames:v 0 -c:v libx264 zero_frames.mp4 || : >zero_frames.mp4
# Variable frame rate: every third frame held 40 ms longer.
ff -f lavfi -i "$(src 320x240)" -t 1 -vf "setpts='(N/30+floor(N/3)*0.04)/TB'" \
  -fps_mode vfr -c:v libx264 -pix_fmt yuv420p vfr.mp4
# Rotated 90° by the display matrix (as phones record portrait).
ff -i good.mp4 -c copy -metadata:s:v:0 rotate=90 rotated_90.mp4
# 10-bit H.264 and HEVC; VP9 in WebM; MJPEG in AVI; a single frame.
ff -f lavfi -i "$(src 320x240)" -t 1 -c:v libx264 -pix_fmt yuv420p10le h264_10bit.mp4
ff -f lavfi -i "$(src 320x240)" -t 1 -c:v libx265 -pix_fmt yuv420p10le -x265-params log-level=none \
  hevc_10bit.mp4
ff -f lavfi -i "$(src 320x240)" -t 1 -c:v libvpx-vp9 -b:v 200k vp9.webm
ff -f lavfi -i "$(src 320x240)" -t 1 -c:v mjpeg -q:v 5 mjpeg.avi
ff -f lavfi -i "$(src 320x240)" -frames:v 1 -c:v libx264 one_frame.mp4
ls
