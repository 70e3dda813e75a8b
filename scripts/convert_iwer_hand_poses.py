#!/usr/bin/env python3
"""Convert the hand poses shipped in the ``iwer`` npm package into the project's "webxr-hand" JSON.

What
----
``iwer`` (Meta's Immersive Web Emulation Runtime, MIT licence) ships three static hand
poses, ``relaxed`` (IWER's "default" pose), ``pinch`` and ``point``, in
``lib/device/configs/hand/{relaxed,pinch,point}.js``.  Each one is a JS object

    {jointTransforms: {<25 WebXR joint names>: {offsetMatrix: [16 floats], radius: r}},
     gripOffsetMatrix: [16 floats]}

The offset matrices are gl-matrix ``mat4`` values, i.e. column-major 4x4 (translation in
elements 12, 13, 14), in metres, for a LEFT hand, relative to the hand's target-ray space.
IWER (``lib/device/XRHandInput.js``) uses them like this:

* the left hand's joint space offset is the matrix itself; the right hand's is the same
  matrix mirrored by ``mirrorMatrixToRight`` (an element-wise sign mask equal to
  ``S @ M @ S`` with ``S = diag(-1, 1, 1, 1)``: a reflection in the YZ plane that keeps the
  joint frames right-handed);
* poses are blended (pinch value) by lerping translation and slerping rotation;
* the target-ray space sits at IWER's default input transform
  (``lib/device/XRTrackedInput.js``): position (-0.25, 1.5, -0.4) for the left hand and
  (0.25, 1.5, -0.4) for the right, identity rotation, in IWER's global space, which is
  also what its ``local-floor`` reference space is.

So ``XRFrame.fillPoses(hand joints, localFloorSpace)`` in IWER returns
``T(default position) @ offsetMatrix`` (mirrored for the right hand), and that is what
this script writes per joint and per frame.

Why
---
The project needs a real WebXR hand pose source (numbers produced by a hand-tracking
runtime, not by our own generator) to test its "webxr-hand" loading and retargeting on.
The IWER poses are that: float32 values with the runtime's own quirks (tips share the
distal joint's rotation, metacarpals share the wrist's).  They are static poses, so a
short recording is made from them: each pose is held for ``HOLD`` frames and consecutive
poses are blended over ``BLEND`` frames (translation lerp, rotation slerp); held frames keep
the package's matrices unchanged (only IWER's sign-flip mirror for the right hand and the
fixed world translation are applied).

Blending.  IWER blends every joint's matrix independently in hand space (its pinch blend).
Between poses whose fingers curl in opposite directions that collapses bones: from
``pinch`` to ``point`` the middle finger's distal->tip bone (2.50 cm in every pose) shrinks
to 0.2 cm mid-blend.  So by default (``--blend hierarchical``) each joint is blended in its
PARENT joint's frame (wrist in hand space, metacarpals relative to the wrist, each phalanx
relative to the previous joint): the local translation is lerped, the local rotation
slerped, and the result composed down the chain, which keeps bone lengths within a
fraction of a millimetre of the poses' own.  ``--blend world`` reproduces IWER's own blend.

The data is TEST DATA ONLY, never training data.

Usage
-----
    npm pack iwer@2.5.0            # in a scratch folder
    python3 scripts/convert_iwer_hand_poses.py /tmp/iwer/iwer-2.5.0.tgz

The argument may be the ``.tgz`` from ``npm pack`` or the unpacked ``package`` folder.
Writes ``assets/recordings/webxr_hand_poses_{right,left}.json`` and prints sanity figures.
Needs Python 3 and numpy only.
"""
from __future__ import annotations

import argparse
import hashlib
import io
import json
import re
import sys
import tarfile
from pathlib import Path

import numpy as np

JOINTS = [
    "wrist",
    "thumb-metacarpal", "thumb-phalanx-proximal", "thumb-phalanx-distal", "thumb-tip",
]
for _finger in ("index-finger", "middle-finger", "ring-finger", "pinky-finger"):
    JOINTS += [f"{_finger}-metacarpal", f"{_finger}-phalanx-proximal", f"{_finger}-phalanx-intermediate",
               f"{_finger}-phalanx-distal", f"{_finger}-tip"]
assert len(JOINTS) == 25

POSE_DIR = "lib/device/configs/hand"
SEQUENCE = ["relaxed", "pinch", "point", "relaxed"]   # ends where it starts, so it loops
HOLD = 20
BLEND = 15
FPS = 30
# IWER's default target-ray transforms (lib/device/XRTrackedInput.js), local-floor space.
TARGET_RAY_POSITION = {"left": (-0.25, 1.5, -0.4), "right": (0.25, 1.5, -0.4)}
# IWER's mirrorMultiplierMatrix (lib/device/XRHandInput.js), column-major element mask.
MIRROR_MASK = np.array([1, -1, -1, 0, -1, 1, 1, 0, -1, 1, 1, 0, -1, 1, 1, 1], dtype=float)
DECIMALS = 8

OUT_DIR = Path(__file__).resolve().parent.parent / "assets" / "recordings"

_JOINT_RE = re.compile(
    r"(?:'([a-z-]+)'|\b([a-z]+)):\s*\{\s*offsetMatrix:\s*\[([^\]]*)\]\s*,\s*radius:\s*([-+0-9.eE]+)")


# --------------------------------------------------------------------------- reading
class Package:
    """Read files from an npm tarball or an unpacked package folder."""

    def __init__(self, path: Path):
        self.path = path
        self._tar = tarfile.open(path, "r:gz") if path.is_file() else None

    def read(self, rel: str) -> str:
        if self._tar is not None:
            member = self._tar.extractfile(f"package/{rel}")
            if member is None:
                raise FileNotFoundError(rel)
            return io.TextIOWrapper(member, encoding="utf-8").read()
        return (self.path / rel).read_text(encoding="utf-8")


def parse_pose(text: str) -> dict[str, np.ndarray]:
    """Return {joint name: 4x4 matrix (row-major numpy of the column-major JS array)}."""
    joints: dict[str, np.ndarray] = {}
    for m in _JOINT_RE.finditer(text):
        name = m.group(1) or m.group(2)
        vals = [float(v) for v in m.group(3).replace("\n", " ").split(",") if v.strip()]
        if len(vals) != 16:
            raise ValueError(f"{name}: {len(vals)} matrix entries")
        joints[name] = np.array(vals).reshape(4, 4).T  # column-major -> matrix
    missing = set(JOINTS) - set(joints)
    if missing:
        raise ValueError(f"missing joints: {sorted(missing)}")
    return {j: joints[j] for j in JOINTS}


# --------------------------------------------------------------------------- maths
def mat_to_quat(r: np.ndarray) -> np.ndarray:
    """Rotation matrix (3x3) -> unit quaternion (x, y, z, w), Shepperd's method."""
    t = np.trace(r)
    if t > 0:
        s = 2.0 * np.sqrt(t + 1.0)
        q = [(r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s, 0.25 * s]
    elif r[0, 0] > r[1, 1] and r[0, 0] > r[2, 2]:
        s = 2.0 * np.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2])
        q = [0.25 * s, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s, (r[2, 1] - r[1, 2]) / s]
    elif r[1, 1] > r[2, 2]:
        s = 2.0 * np.sqrt(1.0 + r[1, 1] - r[0, 0] - r[2, 2])
        q = [(r[0, 1] + r[1, 0]) / s, 0.25 * s, (r[1, 2] + r[2, 1]) / s, (r[0, 2] - r[2, 0]) / s]
    else:
        s = 2.0 * np.sqrt(1.0 + r[2, 2] - r[0, 0] - r[1, 1])
        q = [(r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, 0.25 * s, (r[1, 0] - r[0, 1]) / s]
    q = np.array(q)
    return q / np.linalg.norm(q)


def quat_to_mat(q: np.ndarray) -> np.ndarray:
    x, y, z, w = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def slerp(q0: np.ndarray, q1: np.ndarray, t: float) -> np.ndarray:
    """Shortest-path quaternion slerp (same behaviour as gl-matrix quat.slerp)."""
    d = float(np.dot(q0, q1))
    if d < 0.0:
        q1, d = -q1, -d
    if d > 1.0 - 1e-6:
        q = (1 - t) * q0 + t * q1
    else:
        theta = np.arccos(d)
        q = (np.sin((1 - t) * theta) * q0 + np.sin(t * theta) * q1) / np.sin(theta)
    return q / np.linalg.norm(q)


def blend(m0: np.ndarray, m1: np.ndarray, t: float) -> np.ndarray:
    """IWER's interpolateMatrix: lerp translation and scale, slerp rotation."""
    s0 = np.linalg.norm(m0[:3, :3], axis=0)
    s1 = np.linalg.norm(m1[:3, :3], axis=0)
    q = slerp(mat_to_quat(m0[:3, :3] / s0), mat_to_quat(m1[:3, :3] / s1), t)
    out = np.eye(4)
    out[:3, :3] = quat_to_mat(q) * ((1 - t) * s0 + t * s1)
    out[:3, 3] = (1 - t) * m0[:3, 3] + t * m1[:3, 3]
    return out


def mirror_to_right(m: np.ndarray) -> np.ndarray:
    """IWER's mirrorMatrixToRight applied to a (row-major numpy) matrix."""
    flat = m.T.reshape(16) * MIRROR_MASK
    return flat.reshape(4, 4).T


# --------------------------------------------------------------------------- building
def parent_of(joint: str) -> str | None:
    """WebXR skeleton parent: wrist for the metacarpals, the previous joint along a finger."""
    i = JOINTS.index(joint)
    if joint == "wrist":
        return None
    if joint.endswith("metacarpal"):
        return "wrist"
    return JOINTS[i - 1]


def blend_pose(p0: dict[str, np.ndarray], p1: dict[str, np.ndarray], t: float, mode: str) -> dict[str, np.ndarray]:
    if mode == "world":
        return {j: blend(p0[j], p1[j], t) for j in JOINTS}
    out: dict[str, np.ndarray] = {}
    for j in JOINTS:                       # JOINTS lists every parent before its children
        par = parent_of(j)
        if par is None:
            out[j] = blend(p0[j], p1[j], t)
            continue
        l0 = np.linalg.inv(p0[par]) @ p0[j]
        l1 = np.linalg.inv(p1[par]) @ p1[j]
        out[j] = out[par] @ blend(l0, l1, t)
    return out


def build_sequence(poses: dict[str, dict[str, np.ndarray]],
                   mode: str = "hierarchical") -> tuple[list[dict[str, np.ndarray]], list[str]]:
    """Hand-local (left, target-ray space) joint matrices per frame, plus a label per frame."""
    frames, labels = [], []
    for i, name in enumerate(SEQUENCE):
        if i > 0:
            prev = poses[SEQUENCE[i - 1]]
            for k in range(BLEND):
                t = (k + 1) / (BLEND + 1)
                frames.append(blend_pose(prev, poses[name], t, mode))
                labels.append("")
        for _ in range(HOLD):
            frames.append({j: poses[name][j].copy() for j in JOINTS})
            labels.append(name)
    return frames, labels


def to_world(frames_local: list[dict[str, np.ndarray]], handedness: str) -> np.ndarray:
    """(T, 25, 4, 4) world (IWER local-floor) matrices, as fillPoses would report them."""
    world = np.eye(4)
    world[:3, 3] = TARGET_RAY_POSITION[handedness]
    out = np.empty((len(frames_local), 25, 4, 4))
    for f, frame in enumerate(frames_local):
        for j, name in enumerate(JOINTS):
            m = frame[name] if handedness == "left" else mirror_to_right(frame[name])
            out[f, j] = world @ m
    return out


def fill_poses_layout(mats: np.ndarray) -> list[list[float]]:
    """(T, 25, 4, 4) -> per frame 400 floats, 25 column-major matrices back to back."""
    flat = np.transpose(mats, (0, 1, 3, 2)).reshape(len(mats), 400)
    return [[round(float(v), DECIMALS) + 0.0 for v in row] for row in flat]


# --------------------------------------------------------------------------- checks
def load_frames(doc: dict) -> np.ndarray:
    a = np.asarray(doc["frames"], dtype=float).reshape(-1, 25, 4, 4)
    return np.transpose(a, (0, 1, 3, 2))  # back to row-major matrices


def sanity(doc: dict) -> dict:
    """Bone lengths, axis agreement with the bones and palm, and the handedness check."""
    m = load_frames(doc)
    idx = {n: i for i, n in enumerate(doc["joints"])}
    p = m[:, :, :3, 3]
    rot = m[:, :, :3, :3]
    res: dict = {"frames": int(len(m)), "det_min": float(np.linalg.det(rot).min()),
                 "det_max": float(np.linalg.det(rot).max())}
    chains = [["wrist", "thumb-metacarpal", "thumb-phalanx-proximal", "thumb-phalanx-distal", "thumb-tip"]]
    for f in ("index-finger", "middle-finger", "ring-finger", "pinky-finger"):
        chains.append(["wrist", f"{f}-metacarpal", f"{f}-phalanx-proximal", f"{f}-phalanx-intermediate",
                       f"{f}-phalanx-distal", f"{f}-tip"])
    bones = [("wrist", "index-finger-phalanx-proximal")]
    for c in chains:
        start = 1 if c[0] == "wrist" else 0
        bones += [(a, b) for a, b in zip(c[start:-1], c[start + 1:])]   # phalanx bones (and metacarpals)
    lengths = {}
    for a, b in bones:
        d = np.linalg.norm(p[:, idx[b]] - p[:, idx[a]], axis=1)
        lengths[f"{a}->{b}"] = (float(d.min()), float(d.max()), float(d.max() - d.min()))
    res["bone_lengths_m"] = lengths
    res["bone_len_overall_min_max"] = (min(v[0] for v in lengths.values()), max(v[1] for v in lengths.values()))
    res["bone_len_max_variation"] = max(v[2] for v in lengths.values())

    # -Z along the bone toward the next joint (tips: the bone arriving at the tip).
    cos_nz = {}
    for c in chains:
        for a, b in zip(c[:-1], c[1:]):
            if a == "wrist":
                continue
            d = p[:, idx[b]] - p[:, idx[a]]
            d /= np.linalg.norm(d, axis=1, keepdims=True)
            cos_nz[a] = np.einsum("fi,fi->f", -rot[:, idx[a], :, 2], d)
        d = p[:, idx[c[-1]]] - p[:, idx[c[-2]]]
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        cos_nz[c[-1]] = np.einsum("fi,fi->f", -rot[:, idx[c[-1]], :, 2], d)
    d = p[:, idx["middle-finger-phalanx-proximal"]] - p[:, idx["wrist"]]
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    cos_nz["wrist"] = np.einsum("fi,fi->f", -rot[:, idx["wrist"], :, 2], d)
    allc = np.concatenate(list(cos_nz.values()))
    res["cos_negZ_along_bone_mean"] = float(allc.mean())
    res["cos_negZ_along_bone_min"] = float(allc.min())
    res["cos_negZ_worst_joint"] = min(((k, float(v.mean())) for k, v in cos_nz.items()), key=lambda kv: kv[1])
    nonthumb = np.concatenate([v for k, v in cos_nz.items() if not k.startswith("thumb")])
    res["cos_negZ_along_bone_mean_fingers_only"] = float(nonthumb.mean())

    # +Y out of the back of the hand.  Positional back-of-hand normal from the palm triangle;
    # for a RIGHT hand cross(pinky - wrist, index - wrist) points out of the back, for a left
    # hand the opposite cross does.
    w = p[:, idx["wrist"]]
    ip = p[:, idx["index-finger-phalanx-proximal"]] - w
    pp = p[:, idx["pinky-finger-phalanx-proximal"]] - w
    n_right = np.cross(pp, ip)
    n_right /= np.linalg.norm(n_right, axis=1, keepdims=True)
    n_decl = n_right if doc["handedness"] == "right" else -n_right
    palm_joints = ["wrist"] + [f"{f}-{s}" for f in ("index-finger", "middle-finger", "ring-finger", "pinky-finger")
                               for s in ("metacarpal", "phalanx-proximal")]
    cy = np.stack([np.einsum("fi,fi->f", rot[:, idx[j], :, 1], n_decl) for j in palm_joints])
    res["cos_Y_vs_back_normal_palm_joints_mean"] = float(cy.mean())
    res["cos_Y_vs_back_normal_palm_joints_min"] = float(cy.min())
    cy_all = np.stack([np.einsum("fi,fi->f", rot[:, i, :, 1], n_decl) for i in range(25)])
    res["cos_Y_vs_back_normal_all_joints_mean"] = float(cy_all.mean())

    # Handedness from the joint axes alone: with n = wrist +Y (back of hand) and
    # d = wrist -> middle proximal, a right hand's thumb lies along cross(n, d), a left's opposite.
    n = rot[:, idx["wrist"], :, 1]
    dm = p[:, idx["middle-finger-phalanx-proximal"]] - w
    side = np.cross(n, dm)
    side /= np.linalg.norm(side, axis=1, keepdims=True)
    thumb = p[:, idx["thumb-phalanx-proximal"]] - p[:, idx["middle-finger-metacarpal"]]
    s = np.einsum("fi,fi->f", side, thumb / np.linalg.norm(thumb, axis=1, keepdims=True))
    res["thumb_side_score_min_max (>0 right, <0 left)"] = (float(s.min()), float(s.max()))
    res["handedness_from_axes"] = "right" if (s > 0).all() else "left" if (s < 0).all() else "mixed"
    res["handedness_ok"] = res["handedness_from_axes"] == doc["handedness"]
    return res


# --------------------------------------------------------------------------- main
def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("package", type=Path, help="iwer .tgz from `npm pack iwer@2.5.0`, or its unpacked package/ folder")
    ap.add_argument("--out-dir", type=Path, default=OUT_DIR)
    ap.add_argument("--blend", choices=("hierarchical", "world"), default="hierarchical",
                    help="blend joints in their parent's frame (default, keeps bone lengths) or, like IWER, "
                         "each joint independently in hand space")
    args = ap.parse_args(argv)

    pkg = Package(args.package)
    meta = json.loads(pkg.read("package.json"))
    version = f"{meta['name']}@{meta['version']}"
    poses, digests = {}, {}
    for name in sorted(set(SEQUENCE)):
        rel = f"{POSE_DIR}/{name}.js"
        text = pkg.read(rel)
        digests[rel] = hashlib.sha256(text.encode("utf-8")).hexdigest()
        poses[name] = parse_pose(text)
    frames_local, labels = build_sequence(poses, args.blend)

    args.out_dir.mkdir(parents=True, exist_ok=True)
    ok = True
    for hand in ("right", "left"):
        mats = to_world(frames_local, hand)
        mirror_note = ("the package's left-hand data mirrored to the right exactly as IWER does "
                       "(mirrorMatrixToRight)" if hand == "right" else "the package's own (left-hand) data")
        doc = {
            "format": "webxr-hand",
            "fps": FPS,
            "handedness": hand,
            "joints": JOINTS,
            "frames": fill_poses_layout(mats),
            "source": (f"npm {version} (MIT, Meta Platforms, Inc.), {POSE_DIR}/{{relaxed,pinch,point}}.js: "
                       f"static WebXR hand joint offset matrices; {mirror_note}; placed at IWER's default "
                       f"{hand} target-ray transform (translation {TARGET_RAY_POSITION[hand]}, identity rotation) "
                       f"in its local-floor space; sequence {' -> '.join(SEQUENCE)}, hold {HOLD} frames, "
                       f"blend {BLEND} frames (translation lerp, rotation slerp, "
                       f"{'each joint in its parent joint frame' if args.blend == 'hierarchical' else 'each joint in hand space, as IWER blends'}). Made by "
                       f"scripts/convert_iwer_hand_poses.py. Test data only, never training data."),
            "labels": labels,
        }
        path = args.out_dir / f"webxr_hand_poses_{hand}.json"
        path.write_text(json.dumps(doc, separators=(",", ":")) + "\n", encoding="utf-8")
        res = sanity(json.loads(path.read_text(encoding="utf-8")))
        print(f"{path} ({path.stat().st_size / 1e6:.2f} MB)")
        for k, v in res.items():
            if k != "bone_lengths_m":
                print(f"  {k}: {v}")
        ok &= res["handedness_ok"]
    print("source sha256:", json.dumps(digests, indent=1))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
