#!/usr/bin/env python3
"""Baselines a user would pick instead of videomocap's tracker, run on the same clips from the
same (clicked) marks: OpenCV pyramidal Lucas-Kanade (all 16 joints as points, frame to frame) and
CSRT (one tracker per joint, a square box of 8% of the marked stature around it).

`videomocap-bench track` runs this when Python's OpenCV is present: it writes a jobs file (one
entry per clip: its video, the marks it tracks from, which methods, where to write) and scores the
positions written here itself, with the same metrics as its own tracker. Each output is
{"lk": [[[x, y] x 16] per frame], "csrt": ...}.

    python3 -m pip install opencv-contrib-python-headless numpy   # once
    python3 scripts/opencv_baselines.py JOBS.json
"""
import json
import math
import os
import sys

try:
    import cv2
    import numpy as np
except ImportError:
    sys.exit("needs OpenCV and numpy: python3 -m pip install opencv-contrib-python-headless numpy")

FRACTIONS = {  # stature fractions of the chains, as assets/proportions.json
    "trunk": (["head_top", "neck", "chest", "pelvis"], 0.155 + 0.125 + 0.19),
    "leg": (["left_hip", "left_knee", "left_ankle"], 0.245 + 0.246),
}


def frames(path):
    cap = cv2.VideoCapture(path)
    while True:
        ok, img = cap.read()
        if not ok:
            return
        yield img


def stature_px(marks):
    best = 0.0
    for chain, frac in FRACTIONS.values():
        px = sum(math.dist(marks[a], marks[b]) for a, b in zip(chain, chain[1:]))
        best = max(best, px / frac)
    return best


def track_lk(video, pts):
    out = [pts.copy()]
    prev = None
    p = pts.reshape(-1, 1, 2).astype(np.float32)
    for img in frames(video):
        grey = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
        if prev is not None:
            q, st, _ = cv2.calcOpticalFlowPyrLK(prev, grey, p, None, winSize=(21, 21), maxLevel=3)
            p = np.where(st.reshape(-1, 1, 1) == 1, q, p)
            out.append(p.reshape(-1, 2).astype(np.float64))
        prev = grey
    return out


def track_csrt(video, pts, side):
    trackers = []
    out = []
    for k, img in enumerate(frames(video)):
        if k == 0:
            for x, y in pts:
                t = cv2.TrackerCSRT_create()
                t.init(img, (int(x - side / 2), int(y - side / 2), int(side), int(side)))
                trackers.append([t, (x, y)])
            out.append(pts.copy())
            continue
        row = []
        for tr in trackers:
            ok, box = tr[0].update(img)
            if ok:
                tr[1] = (box[0] + box[2] / 2, box[1] + box[3] / 2)
            row.append(tr[1])
        out.append(np.array(row))
    return out


def main():
    jobs = json.load(open(sys.argv[1]))
    for job in jobs:
        marks = job["marks"]
        pts = np.array([marks[j] for j in job["joints"]], dtype=np.float64)
        side = max(9, 0.08 * stature_px(marks))
        out = {}
        if "lk" in job["methods"]:
            out["lk"] = [p.tolist() for p in track_lk(job["video"], pts)]
        if "csrt" in job["methods"]:
            out["csrt"] = [p.tolist() for p in track_csrt(job["video"], pts, side)]
        tmp = job["out"] + ".tmp"
        with open(tmp, "w") as f:
            json.dump(out, f)
        os.replace(tmp, job["out"])
        print(f"{job['name']}: {', '.join(out)}", file=sys.stderr, flush=True)


if __name__ == "__main__":
    main()
