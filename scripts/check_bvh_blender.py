"""Imports a BVH written by videomocap into Blender (run inside Blender: see check_bvh.sh), checks
the frame and bone counts, and compares the armature's joints on every frame with the 3D CSV
beside it. Arguments after `--`: motion.bvh joints3d.csv [cmu|mixamo] (the file's bone names).

Blender 3.4's BVH importer opens files with mode 'rU', which Python 3.11 refuses; the mode is
patched before importing. The importer turns the BVH's Y-up world into Blender's Z-up one
(x, y, z) → (x, −z, y); scale 0.01 turns centimetres into metres.
"""
import builtins
import csv
import math
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bvh_rig import BONES, joints  # noqa: E402

_open = builtins.open
builtins.open = lambda f, m="r", *a, **k: _open(f, m.replace("U", ""), *a, **k)


def main():
    args = sys.argv[sys.argv.index("--") + 1:]
    bvh_path, csv_path = args[0], args[1]
    rig = args[2] if len(args) > 2 else "cmu"
    table = joints(rig)
    with _open(bvh_path) as f:
        declared = next(int(l.split()[1]) for l in f if l.startswith("Frames:"))
    bpy.ops.import_anim.bvh(filepath=bvh_path, global_scale=0.01, frame_start=1)
    armature = bpy.context.selected_objects[0]
    start, end = armature.animation_data.action.frame_range
    frames = int(round(end - start)) + 1
    truth = {}
    with _open(csv_path) as f:
        for row in csv.DictReader(f):
            truth.setdefault(int(row["frame"]), {})[row["joint"]] = (
                float(row["x_m"]), float(row["y_m"]), float(row["z_m"]))
    indices = sorted(truth)
    worst = (0.0, None, None)
    scene = bpy.context.scene
    for k, index in enumerate(indices):
        scene.frame_set(int(start) + k)
        for joint, (bone, tail) in table.items():
            pb = armature.pose.bones[bone]
            p = armature.matrix_world @ (pb.tail if tail else pb.head)
            x, y, z = truth[index][joint]
            err = math.dist((p.x, p.y, p.z), (x, -z, y))
            if err > worst[0]:
                worst = (err, joint, index)
    bones = len(armature.data.bones)
    print(f"blender {bpy.app.version_string}: {rig} rig, imported {bones} bones (expected {BONES}), "
          f"{frames} frames (file declares {declared}); largest joint difference to the CSV "
          f"{worst[0] * 1000:.3f} mm ({worst[1]}, frame {worst[2]})")
    ok = frames == declared and bones == BONES and worst[0] <= 1e-3
    print("BLENDER_CHECK_OK" if ok else "BLENDER_CHECK_FAILED")


main()
