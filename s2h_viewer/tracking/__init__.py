"""Tracked hands as a motion source: keypoint recordings (WebXR/OpenXR joint poses, MediaPipe landmarks)
fitted with a hand in the project's topology and a TBS motion by inverse kinematics (DESIGN.md section 9).

Core only (no Qt); the readers are in `s2h_viewer.io` (one module per format)."""
