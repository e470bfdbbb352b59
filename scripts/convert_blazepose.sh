#!/usr/bin/env bash
# Reproduces assets/blazepose/pose_landmark_full.onnx from the mediapipe wheel (a one-off step,
# not part of the build: it needs TensorFlow, about 600 MB). See assets/blazepose/SOURCE.md.
#   bash scripts/convert_blazepose.sh [OUT.onnx]
set -euo pipefail
out="${1:-assets/blazepose/pose_landmark_full.onnx}"
venv="$(mktemp -d)/venv"
python3 -m venv "$venv"
"$venv/bin/pip" install -q mediapipe==0.10.21 tensorflow-cpu==2.21.0 tf2onnx==1.17.0
tflite="$("$venv/bin/python" -c 'import mediapipe, os; print(os.path.join(os.path.dirname(mediapipe.__file__), "modules/pose_landmark/pose_landmark_full.tflite"))')"
echo "tflite: $tflite ($(sha256sum "$tflite" | cut -d' ' -f1); expected e9a5c5cb17f736fafd4c2ec1da3b3d331d6edbe8a0d32395855aeb2cdfd64b9f)"
"$venv/bin/python" -m tf2onnx.convert --tflite "$tflite" --output "$out" --opset 13
echo "wrote $out ($(sha256sum "$out" | cut -d' ' -f1); the bundled file is 10657ff783740583f9a640a7d676b5592202adbecf10a0f0d82accb11716a4a2)"
