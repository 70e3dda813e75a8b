"""One clip from many: every animation of a file in turn (a pose library's one-key poses held), labelled
with its name, so a set of authored poses is one evaluation clip (`s2h evaluate --animation all`); and a
motion through some of those poses in an order of one's own (the thumb to each fingertip and back)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from s2h_viewer.hand.motion import Motion
from s2h_viewer.hand.rotations import slerp
from s2h_viewer.semantics.signature import held_poses

#: frames a one-key pose is held for (windowed methods see it as a held pose, not a one-frame flash)
HOLD_FRAMES = 12
#: frames of slerp from one animation's last frame to the next one's first
BLEND_FRAMES = 8


def concatenate_clips(clips: list[Motion], name: str, hold: int = HOLD_FRAMES, blend: int = BLEND_FRAMES
                      ) -> Motion:
    """``clips`` (on one hand) one after another, each labelled with its name on its frames ("" on the
    blends between them); a pose (`is_pose`) is held ``hold`` frames."""
    if not clips:
        raise ValueError("no clips to concatenate")
    parts, labels = [], []
    for k, clip in enumerate(clips):
        q = np.repeat(clip.q_tbs[:1], hold, axis=0) if is_pose(clip) else clip.q_tbs
        if k:
            parts.append(_blend(parts[-1][-1], q[0], blend))
            labels.append(np.full(blend, "", dtype=object))
        parts.append(q)
        labels.append(np.full(len(q), clip.name, dtype=object))
    first = clips[0]
    return Motion(np.concatenate(parts), fps=first.fps, name=name, hand_name=first.hand_name,
                  labels=np.concatenate(labels), meta={**first.meta, "clips": [c.name for c in clips]})


def pose_sequence(clip: Motion, names: Sequence[str], name: str, hold: int = HOLD_FRAMES,
                  blend: int = BLEND_FRAMES) -> Motion:
    """A motion through the poses ``clip`` holds (`semantics.signature.held_poses`), in the order of ``names`` (a
    pose may come back), each held ``hold`` frames and slerped into the next over ``blend``: authored poses made a
    motion that moves what one wants to follow (a clip of poses moves its thumb little between most of them)."""
    frames = dict(held_poses(clip.labels))
    missing = [n for n in names if n not in frames]
    if missing:
        raise ValueError(f"{clip.name}: holds no pose named {', '.join(map(repr, missing))}")
    poses = [Motion(clip.q_tbs[frames[n]:frames[n] + 1], fps=clip.fps, name=n, hand_name=clip.hand_name,
                    meta=clip.meta) for n in names]
    return concatenate_clips(poses, name, hold, blend)


def is_pose(clip: Motion) -> bool:
    """A clip that holds one pose: a single key (a glTF key at 0 s and 1/30 s reads as 2 equal frames)."""
    return bool(np.abs(clip.q_tbs - clip.q_tbs[:1]).max() < 1e-6)


def _blend(start: np.ndarray, end: np.ndarray, n: int) -> np.ndarray:
    """(n, 15, 4) rotations strictly between ``start`` and ``end`` (15, 4), by slerp per joint."""
    t = np.arange(1, n + 1) / (n + 1)
    return slerp(np.broadcast_to(start, (n, *start.shape)), np.broadcast_to(end, (n, *end.shape)), t)
