"""Where each of videomocap's 16 joints sits in the BVH it writes (see crates/videomocap-core/src/export/rig.rs):
joint name -> (BVH joint, whether the position is that joint's End Site rather than the joint
itself). Shared by check_bvh_reader.py and check_bvh_blender.py (in Blender, an End Site is the
tail of its joint's bone). `joints(rig)` gives the names of the `--rig cmu` (default) or
`--rig mixamo` file."""

JOINTS = {
    "pelvis": ("Hips", False), "chest": ("Chest", False), "neck": ("Neck", False),
    "head_top": ("Head", True),
    "left_shoulder": ("LeftArm", False), "left_elbow": ("LeftForeArm", False),
    "left_wrist": ("LeftHand", False),
    "right_shoulder": ("RightArm", False), "right_elbow": ("RightForeArm", False),
    "right_wrist": ("RightHand", False),
    "left_hip": ("LeftUpLeg", False), "left_knee": ("LeftLeg", False),
    "left_ankle": ("LeftFoot", False),
    "right_hip": ("RightUpLeg", False), "right_knee": ("RightLeg", False),
    "right_ankle": ("RightFoot", False),
}

# The Mixamo set renames these (rig.rs, RigNames::Mixamo) and puts `mixamorig:` before all.
MIXAMO_RENAMED = {"Chest": "Spine2", "LHipJoint": "LeftHipJoint", "RHipJoint": "RightHipJoint"}

# Joints (End Sites not counted) of the written rig.
BONES = 21


def joints(rig="cmu"):
    """The table above with the bone names of `rig` ("cmu" or "mixamo")."""
    if rig == "cmu":
        return dict(JOINTS)
    return {k: ("mixamorig:" + MIXAMO_RENAMED.get(n, n), end) for k, (n, end) in JOINTS.items()}
