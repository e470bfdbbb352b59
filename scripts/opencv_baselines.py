#!/usr/bin/env python3
"""Baselines a user would pick instead of videomocap's tracker, run on the same clips from the
same marks: OpenCV pyramidal Lucas-Kanade (all 16 joints as points, frame to frame) and CSRT
(one tracker per joint, a square box of 8% of the marked stature around it).

Clips: the suite's clips listed in out/bench-suite/clips.txt (made by `videomocap bench track`;
without it, every directory there with video.mp4, marks.json and gt.json) and the real sample.
Prints the same metrics as `bench track`: mean error (px), error over torso length, PCK@0.1,
PCK@0.2, lost (> 0.5 torso). Derived joints in gt.json (the real sample's chest) are not scored.

    python3 -m pip install opencv-contrib-python-headless numpy   # once
    python3 scripts/opencv_baselines.py [suite_dir]
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

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
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


class Acc:
    def __init__(self):
        self.n = self.px = self.rel = self.p1 = self.p2 = self.lost = 0

    def add(self, e, torso):
        r = e / max(torso, 1.0)
        self.n += 1
        self.px += e
        self.rel += r
        self.p1 += r <= 0.1
        self.p2 += r <= 0.2
        self.lost += r > 0.5

    def merge(self, o):
        for k in ("n", "px", "rel", "p1", "p2", "lost"):
            setattr(self, k, getattr(self, k) + getattr(o, k))

    def row(self, name):
        n = max(self.n, 1)
        return f"{name:<34} {self.px/n:8.1f} {self.rel/n:9.3f} {self.p1/n:8.3f} {self.p2/n:8.3f} {100*self.lost/n:7.1f}%"


def score(gt, tracks):
    joints = gt["joints"]
    derived = set(gt.get("derived_joints", []))
    acc = Acc()
    for f, pts in zip(gt["frames"], tracks):
        truth = f["points2d"]
        torso = math.dist(truth[joints.index("neck")], truth[joints.index("pelvis")])
        for j, name in enumerate(joints):
            if name not in derived:
                acc.add(math.dist(pts[j], truth[j]), torso)
    return acc


def main():
    suite = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "out", "bench-suite")
    # The current suite's clips are listed in clips.txt (an older render may have left others).
    index = os.path.join(suite, "clips.txt")
    if os.path.isfile(index):
        names = [n.strip() for n in open(index) if n.strip()]
    else:
        names = os.listdir(suite) if os.path.isdir(suite) else []
    clips = sorted(
        os.path.join(suite, d) for d in names if os.path.isfile(os.path.join(suite, d, "gt.json"))
    )
    real = os.path.join(ROOT, "sample_videos", "pose2sim_balancing_cam01")
    print(f"{'clip':<34} {'mean px':>8} {'err/torso':>9} {'PCK@0.1':>8} {'PCK@0.2':>8} {'lost':>8}")
    totals = {"LK": Acc(), "CSRT": Acc()}
    for clip in clips + [real]:
        gt = json.load(open(os.path.join(clip, "gt.json")))
        marks = json.load(open(os.path.join(clip, "marks.json")))["joints"]
        pts = np.array([marks[j] for j in gt["joints"]], dtype=np.float64)
        video = os.path.join(clip, "video.mp4")
        side = max(9, 0.08 * stature_px(marks))
        name = os.path.basename(clip)
        for method, tracks in (("LK", track_lk(video, pts)), ("CSRT", track_csrt(video, pts, side))):
            a = score(gt, tracks)
            print(a.row(f"{name} {method}"), flush=True)
            if clip != real:
                totals[method].merge(a)
    for method, a in totals.items():
        print(a.row(f"SUITE OVERALL {method}"))


if __name__ == "__main__":
    main()
