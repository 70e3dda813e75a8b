"""Hand topology, `HandModel`, forward kinematics, rotations, skinning, mirroring, procedural hands."""

from s2h_viewer.hand.kinematics import HandPose, forward_kinematics, rig_local_to_tbs, tbs_to_rig_local
from s2h_viewer.hand.model import HandModel, SkinnedMesh
from s2h_viewer.hand.motion import Motion

__all__ = ["HandModel", "HandPose", "Motion", "SkinnedMesh", "forward_kinematics", "rig_local_to_tbs",
           "tbs_to_rig_local"]
