#!/usr/bin/env python3
"""A contact sheet of the benchmark suite as rendered: one frame of each of the first clips, with
the ground truth's joints (filled: visible, hollow: hidden) and bones drawn on it, to look at.

    python3 scripts/contact_sheet.py out/bench-suite docs/suite_v4.jpg [CLIPS] [TILE_HEIGHT]

Needs OpenCV (python3 -m pip install opencv-contrib-python-headless numpy).
"""
import json
import os
import sys

import cv2
import numpy as np

BONES = [(0, 1), (1, 2), (2, 3), (1, 4), (4, 5), (5, 6), (1, 7), (7, 8), (8, 9),
         (3, 10), (10, 11), (11, 12), (3, 13), (13, 14), (14, 15)]
LEFT = {4, 5, 6, 10, 11, 12}


def tile(clip_dir, height):
    gt = json.load(open(os.path.join(clip_dir, "gt.json")))
    k = len(gt["frames"]) // 2
    cap = cv2.VideoCapture(os.path.join(clip_dir, "video.mp4"))
    cap.set(cv2.CAP_PROP_POS_FRAMES, k)
    ok, img = cap.read()
    if not ok:
        return None
    frame = gt["frames"][k]
    pts = frame["points2d"]
    for a, b in BONES:
        pa, pb = (int(round(v)) for v in pts[a]), (int(round(v)) for v in pts[b])
        cv2.line(img, tuple(pa), tuple(pb), (255, 255, 255), 1, cv2.LINE_AA)
    for j, (x, y) in enumerate(pts):
        colour = (0, 200, 255) if j in LEFT else (255, 120, 0)
        cv2.circle(img, (int(round(x)), int(round(y))), 4, colour,
                   -1 if frame["visible"][j] else 1, cv2.LINE_AA)
    scale = height / img.shape[0]
    img = cv2.resize(img, (int(img.shape[1] * scale), height), interpolation=cv2.INTER_AREA)
    name = os.path.basename(clip_dir)
    cv2.putText(img, name, (6, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (0, 0, 0), 3, cv2.LINE_AA)
    cv2.putText(img, name, (6, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1, cv2.LINE_AA)
    return img


def main():
    suite, out = sys.argv[1], sys.argv[2]
    count = int(sys.argv[3]) if len(sys.argv) > 3 else 12
    height = int(sys.argv[4]) if len(sys.argv) > 4 else 300
    names = open(os.path.join(suite, "clips.txt")).read().split()
    step = max(1, len(names) // count)
    tiles = [t for t in (tile(os.path.join(suite, n), height) for n in names[::step][:count])
             if t is not None]
    rows, per_row = [], 4
    for i in range(0, len(tiles), per_row):
        row = tiles[i:i + per_row]
        width = sum(t.shape[1] for t in row)
        rows.append((row, width))
    full = max(w for _, w in rows)
    sheet = np.vstack([np.hstack(r + [np.zeros((height, full - w, 3), np.uint8)]) for r, w in rows])
    cv2.imwrite(out, sheet, [cv2.IMWRITE_JPEG_QUALITY, 85])


if __name__ == "__main__":
    main()
