#!/usr/bin/env bash
# Installs what videomocap needs on Debian/Ubuntu and is safe to run again: Debian packages
# (build: pkg-config, clang for bindgen, FFmpeg's -dev libraries; GUI: X11/Wayland/GL; tests:
# ffmpeg, xvfb; screenshots: imagemagick, xdotool) and the Rust toolchain pinned in
# rust-toolchain.toml.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(
  # build
  gcc libc6-dev pkg-config clang libclang-dev
  libavcodec-dev libavformat-dev libavutil-dev libswscale-dev
  # the desktop app, loaded at run time
  libxcursor1 libxi6 libxkbcommon-x11-0 libx11-6 libwayland-client0 libgl1 libegl1 libegl-mesa0 libgl1-mesa-dri
  # tests, screenshots, benchmarks
  ffmpeg xvfb xauth imagemagick xdotool
  # the house checks (scripts/module_cycles.py)
  python3
  # fetching rustup when cargo is missing
  curl ca-certificates
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if ((${#missing[@]})); then
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
  echo "setup: installing ${missing[*]}" >&2
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

if ! command -v cargo >/dev/null 2>&1; then
  if [ -x "$HOME/.cargo/bin/cargo" ]; then
    export PATH="$HOME/.cargo/bin:$PATH"
  else
    echo "setup: installing Rust (rustup)" >&2
    curl --proto '=https' --tlsv1.2 -sSf https://sh.rustup.rs | sh -s -- -y --profile minimal --default-toolchain none
    export PATH="$HOME/.cargo/bin:$PATH"
  fi
fi
# rust-toolchain.toml pins the version; rustup installs it on first use.
cargo --version >/dev/null
echo "setup: ok ($(cargo --version))" >&2
