"""Hand topology, `HandModel`, forward kinematics, rotations, skinning, mirroring, procedural hands.

Import the modules themselves (``from s2h_viewer.hand.model import HandModel``): the package imports
nothing, so that `topology` and the rig names load without torch (a command's start-up)."""
