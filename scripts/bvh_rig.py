"""Where each of videomocap's 16 joints sits in the BVH it writes (see crates/videomocap-core/src/export/rig.rs):
joint name -> (BVH joint, whether the position is that joint's End Site rather than the joint
itself). Shared by check_bvh_reader.py and check_bvh_blender.py (in Blender, an End Site is the
tail of its joint's bone)."""

JOINTS = {
    "pelvis": ("Hips", False), "chest": ("Chest", False), "neck": ("Neck", False),
    "head_top": ("Head", True),
    "left_shoulder": ("LeftArm", False), "left_elbow": ("LeftForeArm", False),
    "left_wrist": ("LeftForeArm", True),
    "right_shoulder": ("RightArm", False), "right_elbow": ("RightForeArm", False),
    "right_wrist": ("RightForeArm", True),
    "left_hip": ("LeftUpLeg", False), "left_knee": ("LeftLeg", False),
    "left_ankle": ("LeftLeg", True),
    "right_hip": ("RightUpLeg", False), "right_knee": ("RightLeg", False),
    "right_ankle": ("RightLeg", True),
}
