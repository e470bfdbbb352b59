#!/usr/bin/env python3
"""MediaPipe Pose (BlazePose GHUM "full", the model bundled in the `mediapipe` 0.10.21 wheel, run
offline) as the learned baseline of `videomocap-bench track`: the network alone, on every frame,
with its own person detector and its own tracking between frames (video mode). It never sees the
user's marks: it follows whoever it finds.

`videomocap-bench track` runs this when `mediapipe` imports: it writes a jobs file (one entry per
clip: its video and where to write) and scores the positions written here itself, with the same
metrics as its own tracker. Each output is {"mediapipe": [[[x, y] x 16] per frame]}, null where
no person was found.

Our 16 joints from MediaPipe's 33 landmarks: shoulders, elbows, wrists, hips, knees and ankles are
its landmarks 11-16 and 23-28; neck = the shoulders' midpoint; pelvis = the hips' midpoint; chest
on the line neck -> pelvis at 0.40 of the way (the stature fractions of assets/proportions.json:
neck->chest 0.125, chest->pelvis 0.19); head top = neck + 1.7 x (ears' midpoint - neck) (the
ears sit at about 0.09 of stature above the neck, the head top at 0.155). Its hips are not where
an annotator marks hip joints (they sit higher and wider): the benchmark scores them as they are.

    python3 -m pip install mediapipe==0.10.21   # once
    python3 scripts/mediapipe_baseline.py JOBS.json
"""
import json
import os
import sys

try:
    import cv2
    import mediapipe as mp
except ImportError:
    sys.exit("needs MediaPipe: python3 -m pip install mediapipe==0.10.21")

JOINTS = ["head_top", "neck", "chest", "pelvis",
          "left_shoulder", "left_elbow", "left_wrist",
          "right_shoulder", "right_elbow", "right_wrist",
          "left_hip", "left_knee", "left_ankle",
          "right_hip", "right_knee", "right_ankle"]
LANDMARK = {"left_shoulder": 11, "right_shoulder": 12, "left_elbow": 13, "right_elbow": 14,
            "left_wrist": 15, "right_wrist": 16, "left_hip": 23, "right_hip": 24,
            "left_knee": 25, "right_knee": 26, "left_ankle": 27, "right_ankle": 28}
CHEST_ALONG = 0.125 / (0.125 + 0.19)
HEAD_TOP_OVER_EARS = 1.7


def joints16(landmarks, width, height):
    """Our 16 joints, in pixels, from MediaPipe's normalised landmarks."""
    px = {i: (lm.x * width - 0.5, lm.y * height - 0.5) for i, lm in enumerate(landmarks)}
    mid = lambda a, b: ((a[0] + b[0]) / 2, (a[1] + b[1]) / 2)
    out = {name: px[i] for name, i in LANDMARK.items()}
    neck = mid(px[11], px[12])
    pelvis = mid(px[23], px[24])
    ears = mid(px[7], px[8])
    out["neck"] = neck
    out["pelvis"] = pelvis
    out["chest"] = (neck[0] + (pelvis[0] - neck[0]) * CHEST_ALONG,
                    neck[1] + (pelvis[1] - neck[1]) * CHEST_ALONG)
    out["head_top"] = (neck[0] + (ears[0] - neck[0]) * HEAD_TOP_OVER_EARS,
                       neck[1] + (ears[1] - neck[1]) * HEAD_TOP_OVER_EARS)
    return [list(out[j]) for j in JOINTS]


def run_clip(video):
    frames = []
    cap = cv2.VideoCapture(video)
    with mp.solutions.pose.Pose(static_image_mode=False, model_complexity=1,
                                enable_segmentation=False) as pose:
        while True:
            ok, img = cap.read()
            if not ok:
                break
            h, w = img.shape[:2]
            result = pose.process(cv2.cvtColor(img, cv2.COLOR_BGR2RGB))
            if result.pose_landmarks is None:
                frames.append(None)
            else:
                frames.append(joints16(result.pose_landmarks.landmark, w, h))
    return frames


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    with open(sys.argv[1]) as f:
        jobs = json.load(f)
    for k, job in enumerate(jobs):
        print(f"  MediaPipe {k + 1}/{len(jobs)}: {job['name']}", file=sys.stderr, flush=True)
        out = {"mediapipe": run_clip(job["video"])}
        tmp = job["out"] + ".tmp"
        with open(tmp, "w") as f:
            json.dump(out, f)
        os.replace(tmp, job["out"])


if __name__ == "__main__":
    main()
