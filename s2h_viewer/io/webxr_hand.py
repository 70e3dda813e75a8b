"""WebXR / OpenXR hand joint poses in JSON (``"format": "webxr-hand"``; also ``"openxr-hand"``).

Each frame is what ``XRFrame.fillPoses()`` writes for one hand: one column-major 4x4 matrix per joint
listed in ``"joints"`` (the 25 WebXR names, or OpenXR's ``XR_HAND_JOINT_*`` names, 26 with the palm),
metres; ``null`` for a frame the tracker lost. A joint pose's -Z runs along its bone toward the tip and +Y
out of the back of the hand (the WebXR and OpenXR specs), so our TBS columns are (-Z, -X, +Y).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from s2h_viewer.errors import InputFileError
from s2h_viewer.hand import topology as topo
from s2h_viewer.io.tracking_json import frame_rate, handedness_field, labels_field
from s2h_viewer.tracking.recording import KeypointRecording, check_scale, handedness_score

WEBXR_JOINTS: tuple[str, ...] = ("wrist", "thumb-metacarpal", "thumb-phalanx-proximal", "thumb-phalanx-distal",
                                 "thumb-tip") + tuple(
    f"{finger}-finger-{part}" for finger in ("index", "middle", "ring", "pinky")
    for part in ("metacarpal", "phalanx-proximal", "phalanx-intermediate", "phalanx-distal", "tip"))
OPENXR_JOINTS: tuple[str, ...] = ("XR_HAND_JOINT_PALM_EXT", "XR_HAND_JOINT_WRIST_EXT") + tuple(
    f"XR_HAND_JOINT_{finger}_{part}_EXT" for finger, parts in (
        ("THUMB", ("METACARPAL", "PROXIMAL", "DISTAL", "TIP")),
        *((f, ("METACARPAL", "PROXIMAL", "INTERMEDIATE", "DISTAL", "TIP")) for f in ("INDEX", "MIDDLE", "RING",
                                                                                   "LITTLE")))
    for part in parts)

#: our joint -> the WebXR joint it is (a finger's metacarpal is a palm bone and has no joint of ours)
_OURS_TO_WEBXR = {"wrist": "wrist", "thumb_cmc": "thumb-metacarpal", "thumb_mcp": "thumb-phalanx-proximal",
                  "thumb_ip": "thumb-phalanx-distal", "thumb_tip": "thumb-tip",
                  **{f"{f}_{ours}": f"{f}-finger-{theirs}" for f in ("index", "middle", "ring", "pinky")
                     for ours, theirs in (("mcp", "phalanx-proximal"), ("pip", "phalanx-intermediate"),
                                          ("dip", "phalanx-distal"), ("tip", "tip"))}}
_OPENXR_TO_WEBXR = dict(zip(OPENXR_JOINTS[1:], WEBXR_JOINTS))


def _webxr_name(name: str) -> str | None:
    """A joint name of either spec, as its WebXR name (OpenXR's with or without the prefix and ``_EXT``)."""
    if name in WEBXR_JOINTS:
        return name
    upper = re.sub(r"[\s-]+", "_", str(name).strip().upper())
    if not upper.startswith("XR_HAND_JOINT_"):
        upper = "XR_HAND_JOINT_" + upper
    if not upper.endswith("_EXT"):
        upper += "_EXT"
    if upper == "XR_HAND_JOINT_PALM_EXT":
        return "palm"
    return _OPENXR_TO_WEBXR.get(upper)


def joint_columns(path: Path, joints: object) -> np.ndarray:
    """(21,) for each of our joints, its column in the file's ``"joints"`` list."""
    if not isinstance(joints, list) or not all(isinstance(j, str) for j in joints):
        raise InputFileError(path, '"joints" must be a list of joint names')
    names = [_webxr_name(j) for j in joints]
    unknown = [j for j, n in zip(joints, names) if n is None]
    if unknown:
        raise InputFileError(path, f"unknown hand joints {', '.join(map(repr, unknown[:4]))}: expected the 25 "
                                   f"WebXR joint names or OpenXR's XR_HAND_JOINT_* names")
    missing = [n for n in _OURS_TO_WEBXR.values() if n not in names]
    if missing:
        raise InputFileError(path, f'"joints" lists {len(joints)} joints and lacks {", ".join(missing[:5])}'
                                   f'{" ..." if len(missing) > 5 else ""}: a hand needs all 25 WebXR joints')
    return np.array([names.index(_OURS_TO_WEBXR[j]) for j in topo.JOINT_NAMES])


def read_webxr_hand(path: Path, document: dict, side: str | None = None) -> KeypointRecording:
    """The recording in a parsed webxr-hand document (`io.recordings` parses and dispatches)."""
    fps = frame_rate(path, document.get("fps"))
    columns = joint_columns(path, document.get("joints"))
    n_joints = len(document["joints"])
    frames = document.get("frames")
    if not isinstance(frames, list) or not frames:
        raise InputFileError(path, '"frames" must be a non-empty list of frames')
    matrices = np.full((len(frames), n_joints, 4, 4), np.nan)
    for t, frame in enumerate(frames):
        if frame is None:
            continue
        values = np.asarray(frame, dtype=object)
        if values.ndim != 1 or len(values) != 16 * n_joints:
            raise InputFileError(path, f"frame {t} holds {values.size if values.ndim else 1} values, not "
                                       f"{16 * n_joints} (a 4x4 matrix for each of {n_joints} joints)")
        try:
            numbers = values.astype(np.float64)
        except (TypeError, ValueError):
            raise InputFileError(path, f"frame {t} holds values that are not numbers") from None
        if not np.isfinite(numbers).all():
            raise InputFileError(path, f"frame {t} holds NaN or infinite values (a lost frame is null)")
        matrices[t] = numbers.reshape(n_joints, 4, 4).transpose(0, 2, 1)  # column-major
    ours = matrices[:, columns]
    valid = np.isfinite(ours).all(axis=(1, 2, 3))
    if not valid.any():
        raise InputFileError(path, f"all {len(frames)} frames are null: the hand was never tracked")
    rotations = ours[:, :, :3, :3]
    det = np.linalg.det(np.where(valid[:, None, None, None], rotations, np.eye(3)))
    ortho = np.abs(np.einsum("tjba,tjbc->tjac", rotations[valid], rotations[valid]) - np.eye(3)).max()
    if ortho > 0.02 or np.abs(det[valid] - 1).max() > 0.02:
        raise InputFileError(path, f"joint matrices are not rigid poses (orthonormality error {ortho:.3g}): "
                                   f"expected what XRFrame.fillPoses writes, column-major")
    x, y, z = rotations[..., 0], rotations[..., 1], rotations[..., 2]
    orientations = np.stack([-z, -x, y], axis=-1)
    orientations[:, topo.TIP_JOINTS] = orientations[:, topo.TIP_JOINTS - 1]  # a tip takes its parent's frame
    recording = KeypointRecording(
        positions=ours[:, :, :3, 3].copy(), fps=fps, side="right", name=path.stem,
        format="openxr-hand" if any(str(j).upper().startswith("XR_") for j in document["joints"]) else "webxr-hand",
        orientations=orientations, radii=_radii(path, document.get("radii"), columns, n_joints),
        labels=labels_field(path, document.get("labels"), len(frames)))
    check_scale(recording, path)
    return _sided(path, recording, handedness_field(path, document.get("handedness")), side)


def _radii(path: Path, radii: object, columns: np.ndarray, n_joints: int) -> np.ndarray | None:
    if radii is None:
        return None
    values = np.asarray(radii, dtype=object)
    if values.ndim == 2 and len(values):  # per frame: the median over frames
        values = values[0] if len(values) == 1 else values
    try:
        numbers = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputFileError(path, '"radii" holds values that are not numbers') from None
    if numbers.shape[-1] != n_joints or not np.isfinite(numbers).all() or (numbers <= 0).any():
        raise InputFileError(path, f'"radii" must be {n_joints} positive numbers (one per joint)')
    return np.median(numbers.reshape(-1, n_joints), axis=0)[columns]


def _sided(path: Path, recording: KeypointRecording, declared: str | None, side: str | None) -> KeypointRecording:
    """The side the joint axes form (a file that declares the other is refused); ``--side`` is noted, not
    applied: every hand's motion is carried in right-hand convention, so a right hand's recording drives a
    left hand as it is."""
    score = handedness_score(recording.positions, recording.orientations)
    seen = "right" if score > 0 else "left"
    if declared and declared != seen and abs(score) > 0.2:
        raise InputFileError(path, f'"handedness" says {declared} but the joint axes form a {seen} hand')
    recording.side = seen
    recording.notes.append(f"side: {seen} (joint axes" + (f', as "handedness" says' if declared else "") + ")")
    if side and side != seen:
        recording.notes.append(f"--side {side}: a {seen} hand's recording, read as it is")
    return recording


def save_webxr_hand(path: str | Path, recording: KeypointRecording) -> Path:
    """Write a recording with orientations as webxr-hand JSON (what ``fillPoses`` gives, column-major), each
    finger's metacarpal placed a third of the way from the wrist to its knuckle with the wrist's axes;
    atomically. For tests and examples (the recording's own keypoints, frames with orientations only)."""
    import json

    from s2h_viewer.io.atomic import atomic_path

    if recording.orientations is None:
        raise ValueError("a webxr-hand file needs joint orientations")
    index = {name: i for i, name in enumerate(topo.JOINT_NAMES)}
    webxr_of = {v: k for k, v in _OURS_TO_WEBXR.items()}
    frames = []
    for p, o in zip(recording.positions, recording.orientations):
        if not np.isfinite(p).all():
            frames.append(None)
            continue
        values = []
        for joint in WEBXR_JOINTS:
            if joint in webxr_of:
                j = index[webxr_of[joint]]
                position, axes = p[j], o[j]
            else:  # a finger's metacarpal: on the palm, with the wrist's axes
                knuckle = index[joint.split("-")[0] + "_mcp"]
                position, axes = p[0] + (p[knuckle] - p[0]) / 3.0, o[0]
            twist, bend, splay = axes.T
            matrix = np.eye(4)
            matrix[:3, 0], matrix[:3, 1], matrix[:3, 2], matrix[:3, 3] = -bend, splay, -twist, position
            values += np.round(matrix.T.ravel(), 7).tolist()  # column-major
        frames.append(values)
    document = {"format": "webxr-hand", "fps": recording.fps, "handedness": recording.side,
                "joints": list(WEBXR_JOINTS), "frames": frames}
    path = Path(path)
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(document, separators=(",", ":")))
    return path
