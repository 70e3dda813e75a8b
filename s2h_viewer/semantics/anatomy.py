"""The anatomical loss L_ana and the violation rate built on the same limits (DESIGN.md section 5).

Angles are measured from the canonical pose (``matrix_to_tbs_euler``: twist, bend, splay), with the
official code's limits (model/tbs/tbs_net.py ``anatomical_loss``, euler branch):

- twist: 0 on every joint;
- splay: 0 on PIP/DIP and the thumb MCP/IP; within +-30 deg on the four MCPs, +-60 deg on the thumb CMC;
- bend: >= -10 deg on the four MCPs (hyperextension), >= -60 deg on the thumb CMC, >= 0 elsewhere;
  <= 90 deg on all (the official asin clamp disabled this term; ours reaches it).

The violation rates read the angles with the bend free past 90 deg (`quat_to_tbs_euler_past_lock`), and
`violation_rates` also counts what a retarget puts further outside than its source.
"""

from __future__ import annotations

import math

import numpy as np
import torch

from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.chunks import frame_chunks
from s2h_viewer.hand.rotations import quat_to_tbs_euler, quat_to_tbs_euler_past_lock, tbs_euler_to_quat

_THUMB_CMC = topo.ARTICULATED_NAMES.index("thumb_cmc")
_FINGER_MCPS = [topo.ARTICULATED_NAMES.index(f"{f}_mcp") for f in topo.FINGERS[1:]]


def _limits() -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """(15,) splay half-range, (15,) lowest bend, (15,) highest bend, radians."""
    splay = torch.zeros(topo.N_ARTICULATED, dtype=torch.float64)
    splay[_FINGER_MCPS] = math.radians(30)
    splay[_THUMB_CMC] = math.radians(60)
    bend_low = torch.zeros(topo.N_ARTICULATED, dtype=torch.float64)
    bend_low[_FINGER_MCPS] = -math.radians(10)
    bend_low[_THUMB_CMC] = -math.radians(60)
    bend_high = torch.full((topo.N_ARTICULATED,), math.pi / 2, dtype=torch.float64)
    return splay, bend_low, bend_high


SPLAY_LIMIT, BEND_LOW, BEND_HIGH = _limits()


def anatomical_excess(q_tbs: torch.Tensor) -> torch.Tensor:
    """(..., 15, 3) how far (radians, >= 0) each joint's twist, bend and splay lie outside their limits."""
    return angle_excess(quat_to_tbs_euler(q_tbs))


def angle_excess(angles: torch.Tensor) -> torch.Tensor:
    """`anatomical_excess` of (..., 15, 3) Euler angles (twist, bend, splay) given directly: smooth in
    them also past a 90 deg bend, where decomposing a rotation again would flip twist and splay."""
    twist, bend, splay = angles.unbind(-1)
    dtype = twist.dtype
    splay_excess = torch.relu(splay.abs() - SPLAY_LIMIT.to(dtype))
    bend_excess = torch.relu(bend - BEND_HIGH.to(dtype)) + torch.relu(BEND_LOW.to(dtype) - bend)
    return torch.stack([twist.abs(), bend_excess, splay_excess], -1)


def clamp_bends(angles: torch.Tensor, margin: float = math.radians(1.0)) -> torch.Tensor:
    """(..., 15, 3) Euler angles with each bend clamped into its limits, ``margin`` inside the 90 deg one
    (where the XYZ angles lock), twist and splay left alone."""
    dtype = angles.dtype
    bend = angles[..., 1].clamp(BEND_LOW.to(dtype), BEND_HIGH.to(dtype) - margin)
    return torch.stack([angles[..., 0], bend, angles[..., 2]], -1)


def limits_reaching(*reached: torch.Tensor, margin: float = math.radians(1.0)) -> tuple[torch.Tensor, torch.Tensor]:
    """(..., 15, 3) lowest and highest (twist, bend, splay) allowed: the anatomical limits (the bend's ``margin``
    inside 90 deg), each widened as far as any of ``reached`` (..., 15, 3 angles) lies outside it, the twist and
    splay's both ways (their limits are symmetric, and so is their excess). Angles clamped into them
    (`clamp_angles`) lie no further outside the limits than the furthest of ``reached``: they add no violation."""
    dtype = reached[0].dtype
    twist = torch.zeros_like(reached[0][..., 0])
    splay = SPLAY_LIMIT.to(dtype).expand_as(twist)
    bend_low, bend_high = BEND_LOW.to(dtype).expand_as(twist), (BEND_HIGH.to(dtype) - margin).expand_as(twist)
    for angles in reached:
        twist = torch.maximum(twist, angles[..., 0].abs())
        splay = torch.maximum(splay, angles[..., 2].abs())
        bend_low = torch.minimum(bend_low, angles[..., 1])
        bend_high = torch.maximum(bend_high, angles[..., 1])
    return torch.stack([-twist, bend_low, -splay], -1), torch.stack([twist, bend_high, splay], -1)


def clamp_angles(angles: torch.Tensor, low: torch.Tensor, high: torch.Tensor) -> torch.Tensor:
    """(..., 15, 3) ``angles`` clamped into [``low``, ``high``] (`limits_reaching`)."""
    return torch.minimum(torch.maximum(angles, low), high)


def within_source_limits(source_q: np.ndarray, q: np.ndarray) -> np.ndarray:
    """(T, 15, 4) ``q`` with each joint's twist, bend and splay kept within its limits, or no further out than the
    source's same angle (`limits_reaching`): a retarget adds no violation the source does not make. ASRN's network,
    on the Meta hand, bent the thumb MCP back 9 deg past straight where the WebXR recording's stays within it (4% of
    its angles violated); on the authored poses it twisted and splayed knuckles and the pinky PIP (1.0-1.7%). Only
    the joints whose angles move change; the others are ``q``'s rotations, bit for bit. A float32 ``q`` is changed
    in place and a chunk of frames done at a time (a long clip's rotations are not copied, its temporaries stay a
    chunk's), as the contact fit does."""
    out = np.asarray(q, dtype=np.float32)
    for first, end in frame_chunks(len(out)):
        with torch.no_grad():
            angles = quat_to_tbs_euler_past_lock(torch.as_tensor(out[first:end], dtype=torch.float64))
            source = quat_to_tbs_euler_past_lock(torch.as_tensor(np.asarray(source_q[first:end]), dtype=torch.float64))
            clamped = clamp_angles(angles, *limits_reaching(source, margin=0.0))
            moved = (clamped - angles).abs().amax(-1) > 1e-9
            if moved.any():
                out[first:end][moved.numpy()] = tbs_euler_to_quat(clamped[moved]).numpy()
    return out


def anatomical_loss(q_tbs: torch.Tensor) -> torch.Tensor:
    """L_ana: sum over joints of squared excesses, averaged over frames (scalar, radians^2)."""
    return anatomical_excess(q_tbs).square().sum(dim=(-1, -2)).mean()


def angle_loss(angles: torch.Tensor) -> torch.Tensor:
    """`anatomical_loss` of (..., 15, 3) Euler angles given directly (the optimisers' variables)."""
    return angle_excess(angles).square().sum(dim=(-1, -2)).mean()


def _excess_past_lock(q_tbs: torch.Tensor | np.ndarray) -> torch.Tensor:
    """(..., 15, 3) `angle_excess` of the angles read with the bend free to pass 90 deg: a knuckle of a fist bent to
    92 deg is 2 deg past its limit, not twisted 180 (what the plain reading, bend within +-90, makes of it)."""
    q = q_tbs if isinstance(q_tbs, torch.Tensor) else torch.as_tensor(np.asarray(q_tbs))
    return angle_excess(quat_to_tbs_euler_past_lock(q.to(torch.float64)))


def violation_rate(q_tbs: torch.Tensor | np.ndarray, tolerance_deg: float = 5.0) -> float:
    """Fraction of (frame, joint) pairs with any angle more than ``tolerance_deg`` outside its limits."""
    return _share_past(_excess_past_lock(q_tbs), tolerance_deg)


def violation_rates(source_q: torch.Tensor | np.ndarray, q_tbs: torch.Tensor | np.ndarray,
                    tolerance_deg: float = 5.0) -> tuple[float, float, float]:
    """The source's `violation_rate`, ``q_tbs``'s, and the violations ``q_tbs`` adds: the share of (frame, joint)
    pairs where some angle lies more than ``tolerance_deg`` further outside its limits than the source's same angle,
    each clip's angles read once. The authored poses themselves break the limits at 0.62 of their angles (a PIP's
    splay, a knuckle's twist), so a retarget that keeps them does too; the third counts what it breaks that the source
    does not (TBS Copy: 0)."""
    source, target = _excess_past_lock(source_q), _excess_past_lock(q_tbs)
    return (_share_past(source, tolerance_deg), _share_past(target, tolerance_deg),
            _share_past(target - source, tolerance_deg))


def _share_past(excess: torch.Tensor, tolerance_deg: float) -> float:
    """The share of (frame, joint) pairs of ``excess`` (..., 15, 3) with any angle over ``tolerance_deg``."""
    return float((excess > math.radians(tolerance_deg)).any(-1).double().mean())
