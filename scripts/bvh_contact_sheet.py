#!/usr/bin/env python3
"""A contact sheet of a BVH file's motion, to look at without Blender: a row of frames seen from
the front and a row seen from the side (the BVH's own forward kinematics: channels in the file's
order, offsets, End Sites), stick figures with the subject's left in orange, right in blue.

    python3 scripts/bvh_contact_sheet.py out/vol/motion.bvh docs/volume_motion.jpg [FRAMES] [TILE]

Needs OpenCV and numpy (python3 -m pip install opencv-contrib-python-headless numpy).
"""
import math
import sys

import cv2
import numpy as np


def parse(path):
    """Joints (name, parent, offset, channels, End Site offset) and the motion's rows."""
    tokens = open(path).read().split()
    joints, pos = [], [0]

    def take():
        pos[0] += 1
        return tokens[pos[0] - 1]

    def node(parent):
        j = {"name": take(), "parent": parent, "offset": None, "channels": [], "end": None}
        joints.append(j)
        me = len(joints) - 1
        assert take() == "{"
        while True:
            t = take()
            if t == "OFFSET":
                j["offset"] = [float(take()) for _ in range(3)]
            elif t == "CHANNELS":
                j["channels"] = [take() for _ in range(int(take()))]
            elif t == "JOINT":
                node(me)
            elif t == "End":
                take()
                assert take() == "{"
                assert take() == "OFFSET"
                j["end"] = [float(take()) for _ in range(3)]
                assert take() == "}"
            elif t == "}":
                return

    while take() != "ROOT":
        pass
    node(None)
    while take() != "Frames:":
        pass
    n_frames = int(take())
    take(), take(), take()  # Frame Time: dt
    values = np.array([float(x) for x in tokens[pos[0]:]]).reshape(n_frames, -1)
    return joints, values


def rot(axis, deg):
    a = math.radians(deg)
    c, s = math.cos(a), math.sin(a)
    if axis == "X":
        return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    if axis == "Y":
        return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def positions(joints, row):
    """Global positions of one frame: (parent point index or None, point) per joint, then per
    End Site."""
    k, world, out, index = 0, [], [], []
    for j in joints:
        local = np.eye(3)
        pos = np.array(j["offset"], dtype=float)
        for ch in j["channels"]:
            v = row[k]
            k += 1
            if ch.endswith("position"):
                pos["XYZ".index(ch[0])] = v
            else:
                local = local @ rot(ch[0], v)
        if j["parent"] is None:
            r, p = local, pos
        else:
            pr, pp = world[j["parent"]]
            r, p = pr @ local, pp + pr @ pos
        world.append((r, p))
        index.append(len(out))
        out.append((None if j["parent"] is None else index[j["parent"]], p, j["name"]))
        if j["end"] is not None:
            out.append((index[-1], p + r @ np.array(j["end"]), j["name"]))
    return out


def draw(points, view, size, scale, centre):
    img = np.full((size, size, 3), 255, np.uint8)
    cv2.line(img, (0, size - 12), (size, size - 12), (200, 200, 200), 1)

    def px(p):
        x = p[0] if view == "front" else p[2]
        return (int(size / 2 + (x - centre[0]) * scale), int(size - 12 - (p[1] - centre[1]) * scale))

    for parent, p, name in points:
        if parent is None:
            continue
        colour = (0, 140, 255) if "Left" in name else (255, 120, 0) if "Right" in name else (60, 60, 60)
        cv2.line(img, px(points[parent][1]), px(p), colour, 2, cv2.LINE_AA)
    return img


def main():
    path, out = sys.argv[1], sys.argv[2]
    count = int(sys.argv[3]) if len(sys.argv) > 3 else 8
    tile = int(sys.argv[4]) if len(sys.argv) > 4 else 220
    joints, values = parse(path)
    frames = np.linspace(0, len(values) - 1, count).astype(int)
    posed = [positions(joints, values[f]) for f in frames]
    allp = np.array([p for pts in posed for _, p, _ in pts])
    floor = allp[:, 1].min()
    scale = (tile - 30) / max(allp[:, 1].max() - floor, 1e-6)
    rows = []
    for view in ("front", "side"):
        tiles = []
        for f, pts in zip(frames, posed):
            root = pts[0][1]
            img = draw(pts, view, tile, scale, (root[0] if view == "front" else root[2], floor))
            cv2.putText(img, f"{view}, frame {f}", (4, 14), cv2.FONT_HERSHEY_SIMPLEX, 0.4,
                        (0, 0, 0), 1, cv2.LINE_AA)
            tiles.append(img)
        rows.append(np.hstack(tiles))
    cv2.imwrite(out, np.vstack(rows), [cv2.IMWRITE_JPEG_QUALITY, 88])


if __name__ == "__main__":
    main()
