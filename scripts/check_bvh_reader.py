"""Reads a BVH written by videomocap with the independent Python `bvh` package, runs its own
forward kinematics, and compares every joint of every frame with the 3D CSV written beside it
(world metres, Y up). Exit 0 when all lie within 1 mm.

Usage: python3 scripts/check_bvh_reader.py motion.bvh joints3d.csv [cmu|mixamo]
"""
import csv
import math
import sys

from bvh import Bvh

from bvh_rig import joints

CM_PER_M = 100.0


def matmul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def apply(m, v):
    return [sum(m[i][k] * v[k] for k in range(3)) for i in range(3)]


def axis_rotation(axis, degrees):
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    if axis == "X":
        return [[1, 0, 0], [0, c, -s], [0, s, c]]
    if axis == "Y":
        return [[c, 0, s], [0, 1, 0], [-s, 0, c]]
    return [[c, -s, 0], [s, c, 0], [0, 0, 1]]


def end_site_offset(mocap, name):
    joint = mocap.get_joint(name)
    for child in joint.children:
        if child.value[:2] == ["End", "Site"]:
            return [float(v) for v in child["OFFSET"]]
    raise LookupError(f"{name} has no End Site")


def forward_kinematics(mocap, frame):
    """World position (cm) and rotation of every joint, and of each joint's End Site."""
    pos, rot, ends = {}, {}, {}
    for joint in mocap.get_joints():
        name = joint.name
        channels = mocap.joint_channels(name)
        values = mocap.frame_joint_channels(frame, name, channels)
        offset = list(mocap.joint_offset(name))
        local = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
        for ch, v in zip(channels, values):
            if ch.endswith("position"):
                offset["XYZ".index(ch[0])] += v
            else:
                local = matmul(local, axis_rotation(ch[0], v))
        parent = mocap.joint_parent(name)
        if parent is None:
            pos[name], rot[name] = offset, local
        else:
            p = parent.name
            d = apply(rot[p], offset)
            pos[name] = [pos[p][i] + d[i] for i in range(3)]
            rot[name] = matmul(rot[p], local)
        try:
            d = apply(rot[name], end_site_offset(mocap, name))
            ends[name] = [pos[name][i] + d[i] for i in range(3)]
        except LookupError:
            pass
    return pos, ends


def main():
    bvh_path, csv_path = sys.argv[1], sys.argv[2]
    table = joints(sys.argv[3] if len(sys.argv) > 3 else "cmu")
    with open(bvh_path) as f:
        mocap = Bvh(f.read())
    truth = {}
    with open(csv_path) as f:
        for row in csv.DictReader(f):
            truth.setdefault(int(row["frame"]), {})[row["joint"]] = [
                float(row["x_m"]), float(row["y_m"]), float(row["z_m"])]
    frames = sorted(truth)
    if mocap.nframes != len(frames):
        print(f"FAIL: the BVH has {mocap.nframes} frames, the CSV {len(frames)}")
        return 1
    worst = (0.0, None, None)
    for k, index in enumerate(frames):
        pos, ends = forward_kinematics(mocap, k)
        for joint, (name, end) in table.items():
            p = ends[name] if end else pos[name]
            err = math.dist([v / CM_PER_M for v in p], truth[index][joint])
            if err > worst[0]:
                worst = (err, joint, index)
    print(f"python bvh package: {mocap.nframes} frames, {len(mocap.get_joints())} joints, "
          f"frame time {mocap.frame_time:.6f} s; largest joint difference to the CSV "
          f"{worst[0] * 1000:.3f} mm ({worst[1]}, frame {worst[2]})")
    # The CSV holds 5 decimals (0.01 mm), the BVH 4 decimals of cm and degrees.
    return 0 if worst[0] <= 1e-3 else 1


if __name__ == "__main__":
    sys.exit(main())
