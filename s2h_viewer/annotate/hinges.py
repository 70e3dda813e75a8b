"""The hinge each finger joint turns about in an avatar's own animations (issue 26).

Where a rig comes with authored motion (its own clips, or a pose file on the same skeleton), each
joint's dominant rotation axis over that motion is the bend axis its author meant: a better witness
than rays cast at a round finger. `animation_hinges` finds the axes; `overrule_with_hinges` checks a
solver's frames against them and, where a joint clearly turns about one axis, bends it about that axis.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from s2h_viewer.annotate.solver import TbsSolution, back_directions
from s2h_viewer.hand import topology as topo

MIN_SHARE = 0.9  # of a joint's squared rotation about its dominant axis, for that axis to count as its hinge
MIN_RANGE_DEG = 20.0  # a joint that turns less than this in the whole motion says nothing about its hinge
AGREE_DEGREES = 10.0  # a solver's bend axis within this of the hinge is left as it is
LABEL = "animation hinge"
#: the joints the anatomy lets bend about one axis only (no splay: PIP, DIP, thumb MCP and IP); a knuckle's or
#: the thumb CMC's dominant axis mixes bend and splay (one authored pose gives a perfectly "clean" one)
HINGE_JOINTS = np.array([name.split("_")[1] not in ("mcp", "cmc") or name == "thumb_mcp"
                         for name in topo.ARTICULATED_NAMES])


@dataclass(frozen=True)
class AnimationHinges:
    """Per articulated joint: the dominant rotation axis (hand space, unit, sign arbitrary), the share of the
    joint's rotation about it (0-1) and the largest turn seen (degrees), over ``frames`` frames of ``source``."""

    axes: np.ndarray  # (15, 3)
    share: np.ndarray  # (15,)
    range_deg: np.ndarray  # (15,)
    frames: int
    source: str

    def usable(self) -> np.ndarray:
        """(15,) bool: one-axis joints (`HINGE_JOINTS`) that clearly turn about one axis, far enough to tell which."""
        return HINGE_JOINTS & (self.share >= MIN_SHARE) & (self.range_deg >= MIN_RANGE_DEG)


def animation_hinges(q_tbs: np.ndarray, rest_frames: np.ndarray, source: str = "") -> AnimationHinges:
    """Hinges of a motion's (T, 15, 4) TBS rotations on a hand whose rest TBS frames (15, 3, 3: columns twist,
    bend, splay in hand space) they were read with; any frames do, the axes come back in hand space."""
    q = np.asarray(q_tbs, dtype=np.float64)
    rotvec = Rotation.from_quat(q.reshape(-1, 4)[:, [1, 2, 3, 0]]).as_rotvec().reshape(*q.shape[:-1], 3)
    scatter = np.einsum("tji,tjk->jik", rotvec, rotvec)  # (15, 3, 3): sum of a a^T over frames
    values, vectors = np.linalg.eigh(scatter)
    axes_local = vectors[:, :, -1]  # the largest eigenvalue's vector per joint
    total = values.sum(-1)
    share = np.where(total > 0, values[:, -1] / np.maximum(total, 1e-300), 0.0)
    angle = np.degrees(np.linalg.norm(rotvec, axis=-1)).max(axis=0) if len(q) else np.zeros(q.shape[1])
    axes = np.einsum("jab,jb->ja", np.asarray(rest_frames, dtype=np.float64), axes_local)
    return AnimationHinges(axes / np.linalg.norm(axes, axis=1, keepdims=True), share, angle, len(q), source)


def hinge_disagreement(frames: np.ndarray, hinges: AnimationHinges) -> np.ndarray:
    """(15,) degrees between each frame's bend axis and the hinge its joint turns about (0-90)."""
    dots = np.abs(np.einsum("ja,ja->j", frames[:, :, 1], hinges.axes))
    return np.degrees(np.arccos(np.clip(dots, 0.0, 1.0)))


def overrule_with_hinges(solution: TbsSolution, hinges: AnimationHinges, positions: np.ndarray) -> TbsSolution:
    """``solution`` with every usable joint whose bend axis lies more than `AGREE_DEGREES` from its hinge bent
    about the hinge (made normal to the bone), basis `LABEL`, confidence the hinge's share; one line per finger
    says how far the solver was off. ``positions`` are the hand's rest joint positions (the splay axis is
    turned out of the back of the hand, as the solver's)."""
    frames, confidence = solution.frames.copy(), solution.confidence.copy()
    basis, diagnostics = list(solution.basis), list(solution.diagnostics)
    off = hinge_disagreement(frames, hinges)
    back = back_directions(positions)
    usable = hinges.usable()
    for f in range(topo.N_FINGERS):
        changed = []
        previous = back[3 * f]  # out of the back of the hand at the base, then each joint as its parent
        for level in range(3):
            j = 3 * f + level
            twist = frames[j][:, 0]
            bend = hinges.axes[j] - twist * (hinges.axes[j] @ twist)
            # a joint that turns about its own bone twists, it does not hinge
            if usable[j] and off[j] > AGREE_DEGREES and np.linalg.norm(bend) >= 0.5:
                splay = np.cross(twist, bend / np.linalg.norm(bend))
                if splay @ previous < 0:
                    splay = -splay
                frames[j] = np.stack([twist, np.cross(splay, twist), splay], axis=1)
                basis[j], confidence[j] = LABEL, float(hinges.share[j])
                changed.append(f"{topo.joint_label(topo.ARTICULATED_NAMES[j])} {off[j]:.0f}")
            previous = frames[j][:, 2]
        if changed:
            diagnostics.append(f"{topo.FINGERS[f]}: bend axes taken from the hinges its animations turn about "
                               f"({hinges.source}); the frames were off by {', '.join(changed)} deg")
    return dataclasses.replace(solution, frames=frames, confidence=confidence, basis=basis, diagnostics=diagnostics)
