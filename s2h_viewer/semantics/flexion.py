"""Sideways flexion (DESIGN.md section 9): how far a finger's PIP or DIP bends out of its curl plane.

For each PIP/DIP joint flexing more than `MIN_FLEXION_DEG` in a frame, the angle between its flexion axis
(parent bone x child bone, from FK positions) and the palm's across axis (index MCP -> pinky MCP): 0 is a
clean curl toward the palm, 90 a finger bending sideways. From positions alone, so it holds for any rig.
The thumb's IP is left out: opposition turns its hinge away from the palm's across axis by design.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.model import palm_axes

MIN_FLEXION_DEG = 10.0
#: a joint's tightest curls: frames where it flexes at least this share of its largest flexion in the clip
TIGHTEST_SHARE = 0.8
#: the PIP and DIP joints of the four fingers, as (name, index into the 21 joints)
HINGE_JOINTS: tuple[tuple[str, int], ...] = tuple(
    (f"{finger}_{level}", topo.JOINT_NAMES.index(f"{finger}_{level}"))
    for finger in topo.FINGERS[1:] for level in ("pip", "dip"))


def _bend(positions: np.ndarray, joints: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(T, J, 3) flexion axes (bone into each joint x bone out of it) and (T, J) their bends in degrees (0 straight)
    of ``joints`` (indices into the 21, each with a child) from (T, 21, 3) float64 positions."""
    into = positions[:, joints] - positions[:, topo.PARENTS[joints]]
    out = positions[:, joints + 1] - positions[:, joints]
    axis = np.cross(into, out)
    return axis, np.degrees(np.arctan2(np.linalg.norm(axis, axis=-1), (into * out).sum(-1)))


def flexion_and_sideways(positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(T, 8) flexion and sideways angles in degrees of `HINGE_JOINTS` from (T, 21, 3) joint positions;
    sideways is NaN where the joint flexes less than `MIN_FLEXION_DEG` (no axis to speak of)."""
    positions = np.asarray(positions, dtype=np.float64)
    axis, flexion = _bend(positions, np.array([j for _, j in HINGE_JOINTS]))
    sin = np.linalg.norm(axis, axis=-1)
    index_mcp, pinky_mcp = topo.JOINT_NAMES.index("index_mcp"), topo.JOINT_NAMES.index("pinky_mcp")
    across = positions[:, pinky_mcp] - positions[:, index_mcp]
    across /= np.maximum(np.linalg.norm(across, axis=-1, keepdims=True), 1e-12)
    along = np.abs((axis * across[:, None]).sum(-1)) / np.maximum(sin, 1e-12)
    sideways = np.degrees(np.arccos(np.clip(along, 0.0, 1.0)))
    return flexion, np.where(flexion > MIN_FLEXION_DEG, sideways, np.nan)


_INDEX_MCP, _PINKY_MCP = topo.JOINT_NAMES.index("index_mcp"), topo.JOINT_NAMES.index("pinky_mcp")


def hinge_flexion_and_alignment(positions: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """(T, 8) flexion in radians of `HINGE_JOINTS` and the |cosine| between each one's flexion axis and the palm's
    across axis (1: a clean curl, 0: bending sideways), from (T, 21, 3) positions: `flexion_and_sideways`
    smooth and differentiable (no arccos), for optimisers that must not bend a finger sideways."""
    chains = positions[:, 5:].reshape(len(positions), topo.N_FINGERS - 1, 4, 3)  # index..pinky, MCP to tip
    bones = chains[:, :, 1:] - chains[:, :, :-1]  # MCP->PIP, PIP->DIP, DIP->tip: slices, not gathers
    into, out = bones[:, :, :2], bones[:, :, 1:]  # (T, 4, 2, 3): the PIP's and the DIP's, HINGE_JOINTS' order
    axis = torch.linalg.cross(into, out).flatten(1, 2)
    sin = axis.norm(dim=-1)
    flexion = torch.atan2(sin, (into * out).sum(-1).flatten(1, 2))
    across = positions[:, _PINKY_MCP] - positions[:, _INDEX_MCP]
    across = across / across.norm(dim=-1, keepdim=True).clamp_min(1e-12)
    return flexion, (axis * across[:, None]).sum(-1).abs() / sin.clamp_min(1e-12)


_THUMB_MCP, _THUMB_TIP = topo.JOINT_NAMES.index("thumb_mcp"), topo.JOINT_NAMES.index("thumb_tip")


def thumb_out(positions: torch.Tensor) -> torch.Tensor:
    """(T,) radians the thumb points out to its side, from (T, 21, 3) FK positions: the angle of its visible part
    (MCP -> tip) out of the plane of the palm's finger axis and normal (`palm_axes`), toward the thumb's side.
    A thumbs-up's thumb reads 40-60 deg, one lying along the fingers or in front of the palm near 0, one across
    the palm below 0. Differentiable in the thumb, for the contact fit (the palm's axes carry no gradient: the
    knuckles sit on the wrist whatever the fingers do); `semantics.signature` reads it in degrees."""
    palm = palm_axes((positions - positions[:, :1]).detach().numpy())
    thumb = positions[:, _THUMB_TIP] - positions[:, _THUMB_MCP]
    x, aside, z = torch.einsum("tij,ti->jt", torch.as_tensor(palm, dtype=positions.dtype), thumb)
    return torch.atan2(aside, (x.square() + z.square() + 1e-12).sqrt())


def thumb_across(positions: torch.Tensor) -> torch.Tensor:
    """(T,) how far the thumb's tip lies across the palm, from (T, 21, 3) FK positions: past the index knuckle toward
    the pinky's along the palm's across axis (`palm_axes`), in palm widths (index to pinky knuckle). The authored
    Sign 4 (four fingers up, the thumb folded across the palm) reads 0.60, a thumbs-up -1.4; TBS Copy and ASRN left
    Sign 4's thumb at the palm's side on the real rigs (-0.37 to 0.32). Differentiable in the thumb, for the contact
    fit (the palm's axes carry no gradient, as in `thumb_out`)."""
    positions = positions - positions[:, :1]
    toward_pinky = -torch.as_tensor(palm_axes(positions.detach().numpy())[:, :, 1], dtype=positions.dtype)
    knuckles = (positions[:, _PINKY_MCP] - positions[:, _INDEX_MCP]).detach()
    width = (knuckles * toward_pinky).sum(-1).abs().clamp_min(1e-12)
    return ((positions[:, _THUMB_TIP] - positions[:, _INDEX_MCP]) * toward_pinky).sum(-1) / width


@dataclass(frozen=True)
class SidewaysPeak:
    """The clip's worst sideways flexion at its tightest curls: degrees, which joint, which frame."""

    degrees: float  # NaN when no PIP/DIP flexes past MIN_FLEXION_DEG
    joint: str = ""
    frame: int = -1

    @property
    def where(self) -> str:
        """``"ring_dip@212"``, empty when no finger curls."""
        return "" if np.isnan(self.degrees) else f"{self.joint}@{self.frame}"

    def describe(self) -> str:
        if np.isnan(self.degrees):
            return "no finger curls"
        return f"{topo.joint_label(self.joint)} bends {self.degrees:.0f} deg sideways at frame {self.frame}"


def sideways_peak(positions: np.ndarray) -> SidewaysPeak:
    """The largest sideways angle over each joint's tightest-curl frames (at least `TIGHTEST_SHARE` of that
    joint's largest flexion, and past `MIN_FLEXION_DEG`): the clip's figure."""
    flexion, sideways = flexion_and_sideways(positions)
    tightest = (flexion >= TIGHTEST_SHARE * flexion.max(axis=0, keepdims=True)) & ~np.isnan(sideways)
    if not tightest.any():
        return SidewaysPeak(float("nan"))
    masked = np.where(tightest, sideways, -1.0)
    frame, joint = np.unravel_index(int(np.argmax(masked)), masked.shape)
    return SidewaysPeak(float(masked[frame, joint]), HINGE_JOINTS[joint][0], int(frame))


def finger_peaks(positions: np.ndarray) -> dict[str, SidewaysPeak]:
    """Per PIP/DIP joint, its worst sideways angle over its own tightest curls (NaN where it never flexes
    past `MIN_FLEXION_DEG`): the per-joint lines of `s2h check`."""
    flexion, sideways = flexion_and_sideways(positions)
    out = {}
    for j, (name, _) in enumerate(HINGE_JOINTS):
        tightest = (flexion[:, j] >= TIGHTEST_SHARE * flexion[:, j].max()) & ~np.isnan(sideways[:, j])
        if not tightest.any():
            out[name] = SidewaysPeak(float("nan"))
            continue
        frame = int(np.argmax(np.where(tightest, sideways[:, j], -1.0)))
        out[name] = SidewaysPeak(float(sideways[frame, j]), name, frame)
    return out


def bend_angles(positions: np.ndarray, joint: int) -> np.ndarray:
    """(T,) degrees joint ``joint`` (of the 21) bends: the angle between the bone into it and the bone out of it
    (0 straight), from (T, 21, 3) positions; a fingertip (no bone out) reads its DIP's or the thumb IP's."""
    if joint in topo.TIP_JOINTS:
        joint -= 1
    return _bend(np.asarray(positions, dtype=np.float64), np.array([joint]))[1][:, 0]


#: the thumb's MCP and IP, as (name, index into the 21 joints): hinges, read by their bends
THUMB_HINGES: tuple[tuple[str, int], ...] = tuple((name, topo.JOINT_NAMES.index(name))
                                                  for name in ("thumb_mcp", "thumb_ip"))
#: what `thumb_angles` reads, in order: the CMC's two degrees of freedom, then the hinges
THUMB_ANGLES: tuple[str, ...] = ("thumb_cmc_across", "thumb_cmc_lift") + tuple(name for name, _ in THUMB_HINGES)
#: a thumb joint moving less than this (standard deviation of its angle, degrees) in the source has no motion to follow
MIN_THUMB_MOTION_DEG = 2.0
#: a thumb following the source's less than this (`thumb_follow`'s worst angle) moves otherwise than the source's:
#: drawn red, as a finger bent sideways is (issue 26's goal; the gestures' claw onto the VRM robot reads 0.55)
THUMB_FOLLOWS_FROM = 0.9
#: the thumb angles `thumb_follow` reads, as words name them
THUMB_ANGLE_NAMES = {"thumb_cmc_across": "its metacarpal's swing across the palm",
                     "thumb_cmc_lift": "its metacarpal's lift out of the palm", "thumb_mcp": "its MCP's bend",
                     "thumb_ip": "its IP's bend"}


def thumb_metacarpal_angles(positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(T,), (T,) degrees: the thumb metacarpal's direction (CMC -> MCP) in the palm frame (`palm_axes`), as its
    angle across the palm (in the palm plane, from the fingers' direction toward the thumb's side) and its lift
    out of the palm plane (toward the back of the hand). The CMC turns two ways: each is a motion of its own,
    and one angle of both (the opening to the index's metacarpal) folds them: TBS Copy, which turns the thumb
    exactly as the source's, read 0.80 on the WebXR hand where each of these reads 1.00."""
    positions = np.asarray(positions, dtype=np.float64)
    positions = positions - positions[:, :1]
    palm = palm_axes(positions)
    names = topo.JOINT_NAMES
    bone = positions[:, names.index("thumb_mcp")] - positions[:, names.index("thumb_cmc")]
    local = np.einsum("tij,ti->tj", palm, bone)
    local /= np.maximum(np.linalg.norm(local, axis=-1, keepdims=True), 1e-12)
    return np.degrees(np.arctan2(local[:, 1], local[:, 0])), np.degrees(np.arcsin(np.clip(local[:, 2], -1.0, 1.0)))


def signed_hinge_bends(positions: np.ndarray, joint: int) -> np.ndarray:
    """(T,) degrees joint ``joint`` (of the 21, with a child) bends about its dominant axis over the (T, 21, 3)
    frames, signed: positive where the bone out of it turns across the palm (away from the thumb's side of the
    bone into it). The unsigned bend between the bones (`bend_angles`) folds where a joint passes straight: the
    WebXR thumb's MCP, near straight at rest, read 0.61 for TBS Copy of the authored poses, which turns it as the
    source's; read about its axis, 0.95. The axis is the clip's (the principal direction of the bend axes in the
    frame of the bone into the joint and the palm normal), so a hand's own hinge is read, whatever its frames."""
    positions = np.asarray(positions, dtype=np.float64)
    positions = positions - positions[:, :1]
    into = positions[:, joint] - positions[:, topo.PARENTS[joint]]
    out = positions[:, joint + 1] - positions[:, joint]
    x = into / np.maximum(np.linalg.norm(into, axis=-1, keepdims=True), 1e-12)
    out = out / np.maximum(np.linalg.norm(out, axis=-1, keepdims=True), 1e-12)
    normal = palm_axes(positions)[:, :, 2]
    z = normal - x * (normal * x).sum(-1, keepdims=True)
    z /= np.maximum(np.linalg.norm(z, axis=-1, keepdims=True), 1e-12)
    frame = np.stack([x, np.cross(z, x), z], axis=-1)  # columns: the bone, across it, out of the back
    axes = np.einsum("tij,ti->tj", frame, np.cross(x, out))
    axis = np.linalg.svd(axes, full_matrices=False)[2][0]
    if axis[2] > 0:  # a turn about it must take the bone toward -y: across the palm
        axis = -axis
    return np.degrees(np.arctan2(axes @ axis, (x * out).sum(-1)))


def thumb_angles(positions: np.ndarray) -> dict[str, np.ndarray]:
    """Per `THUMB_ANGLES`, (T,) degrees: the CMC's two (`thumb_metacarpal_angles`), the MCP's and IP's bends
    about their axes (`signed_hinge_bends`). No angle is measured from the wrist-to-CMC "bone": it is no bone on
    most rigs, and sits anywhere from 2 to 5 cm from the wrist."""
    across, lift = thumb_metacarpal_angles(positions)
    return {"thumb_cmc_across": across, "thumb_cmc_lift": lift,
            **{name: signed_hinge_bends(positions, j) for name, j in THUMB_HINGES}}


def thumb_words(follow: float, angle: str) -> str:
    """How closely the thumb follows the source's, and in which angle worst (`RetargetScores.thumb_follow_at`): the
    scores table's and a batch's words."""
    return (f"the thumb follows the source's at {follow:.2f}, worst in {THUMB_ANGLE_NAMES.get(angle, angle)}"
            + (" (under 0.9: it moves otherwise than the source's)" if follow < THUMB_FOLLOWS_FROM else ""))


def thumb_follow(source_positions: np.ndarray, target_positions: np.ndarray) -> dict[str, float]:
    """Per thumb angle (`THUMB_ANGLES`), the correlation over frames of it on the target (`thumb_angles`, from
    positions) with the source's: 1 where the retarget's thumb does what the source's does, whatever the rigs'
    rest poses (and blind to an offset: a thumb held further across the palm throughout reads 1 too); 0 where it
    stays still while the source's moves; NaN for one that barely moves in the source."""
    source, target = thumb_angles(source_positions), thumb_angles(target_positions)
    out = {}
    for name in THUMB_ANGLES:
        if source[name].std() < MIN_THUMB_MOTION_DEG:
            out[name] = float("nan")
        elif target[name].std() < 1e-6:
            out[name] = 0.0
        else:
            out[name] = float(np.corrcoef(source[name], target[name])[0, 1])
    return out
