"""The Anatomy-based Semantic Matrix and the distance matrix of the DM baseline (DESIGN.md section 4).

Palm anchors, the official code's (utils/armatures.py ``palm_anchors``), in its column order: the
points 1/3 of the way from the wrist to the middle, ring, pinky and index knuckles, then 2/3 of the
way to the same four, then halfway to the thumb CMC (9 anchors). Like the official ASM, both
matrices are in units of the wrist -> middle-knuckle distance, so magnitudes compare across hands.
"""

from __future__ import annotations

import torch

from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.kinematics import HandPose

#: (knuckle joint, fraction of the way from the wrist) of each palm anchor, in column order
ANCHORS: tuple[tuple[int, float], ...] = tuple(
    (topo.joint_index(f"{finger}_mcp"), fraction) for fraction in (1 / 3, 2 / 3)
    for finger in ("middle", "ring", "pinky", "index")) + ((topo.joint_index("thumb_cmc"), 0.5),)
_ANCHOR_JOINTS = [j for j, _ in ANCHORS]
_ANCHOR_FRACTIONS = [f for _, f in ANCHORS]
_MIDDLE_MCP = topo.joint_index("middle_mcp")
#: frames per block of `semantic_matrix`: a block's (12 x 87) factors, 4 kB a frame, stay in cache
BLOCK_FRAMES = 512
#: (20, 29) True at the cells m == k (a joint seen from itself): zero by definition, masked everywhere.
SELF_CELLS = torch.cat([torch.eye(topo.N_FINGER_JOINTS, dtype=torch.bool),
                        torch.zeros(topo.N_FINGER_JOINTS, topo.N_ANCHORS, dtype=torch.bool)], 1)


def palm_anchors(positions: torch.Tensor) -> torch.Tensor:
    """(T, 21, 3) joint positions -> (T, 9, 3) palm anchors."""
    wrist = positions[:, :1]
    fractions = positions.new_tensor(_ANCHOR_FRACTIONS)[None, :, None]
    return wrist + fractions * (positions[:, _ANCHOR_JOINTS] - wrist)


def palm_unit(pose: HandPose) -> torch.Tensor:
    """(T, 1) the wrist -> middle-knuckle distance per frame: the ASM's unit of length."""
    return (pose.positions[:, _MIDDLE_MCP] - pose.positions[:, 0]).norm(dim=-1, keepdim=True)


def asm_columns(pose: HandPose) -> torch.Tensor:
    """(T, 29, 3) the ASM's column points: 20 finger joints then 9 palm anchors."""
    return torch.cat([pose.finger_positions, palm_anchors(pose.positions)], 1)


def semantic_matrix(pose: HandPose) -> torch.Tensor:
    """ASM ``D[t, k, m] = M_k^T (x_m - x_k) / |x_middle_mcp - x_wrist|``: (T, 20, 29, 3), each column
    point seen from joint k's frame, in units of the palm length.

    Invariant to moving, rotating or scaling the whole hand; ``D[:, k, k]`` is exactly zero (callers mask it).
    One batched product per frame writes the result in its final layout, once:
    ``D[k, (m, a)] = sum_(b, c) [M_k / u, -x_k^T M_k / u][k, (b, c)] * ([x_m, 1][m, b] I[c, a])``, a
    (20 x 12) @ (12 x 87) product. The unit division, the shift and the layout are folded into the small
    (20 x 12) factor, so the big output is never divided, masked or transposed afterwards. Long clips go
    `BLOCK_FRAMES` frames at a time, so the factors stay in cache and only the output goes to memory.
    """
    positions, frames, n_frames = pose.positions, pose.frames, pose.positions.shape[0]
    if n_frames <= BLOCK_FRAMES:
        return _semantic_block(positions, frames)
    blocks = [slice(s, s + BLOCK_FRAMES) for s in range(0, n_frames, BLOCK_FRAMES)]
    if torch.is_grad_enabled() and (positions.requires_grad or frames.requires_grad):
        return torch.cat([_semantic_block(positions[b], frames[b]) for b in blocks])
    out = positions.new_empty(n_frames, topo.N_FINGER_JOINTS, topo.N_ASM_COLUMNS, 3)
    spread = _spread(positions, BLOCK_FRAMES)  # its zeros and ones written once, for every block
    for b in blocks:
        _semantic_block(positions[b], frames[b], spread, out[b])
    return out


def semantic_matrix_by_axis(pose: HandPose) -> torch.Tensor:
    """`semantic_matrix` with the 3 components first, (T, 3, 20, 29): the same numbers laid out for losses
    that reduce over the components (ASM-Opt's L_sem), which then run over rows of 580 cells, not triples.

    One (20 x 4) @ (4 x 29) product per frame and component: ``D[a, k, m] = [M_k / u, -x_k^T M_k / u][k, b, a]
    [x_m, 1][m, b]``."""
    n_frames = pose.positions.shape[0]
    columns = torch.cat([asm_columns(pose), pose.positions.new_ones(n_frames, topo.N_ASM_COLUMNS, 1)], -1)
    d = _seen_from(pose).permute(0, 3, 1, 2) @ columns.transpose(1, 2)[:, None]
    d.diagonal(dim1=2, dim2=3).zero_()  # rounding leaves ~1e-8 at m == k in float32
    return d


def _seen_from(pose: HandPose) -> torch.Tensor:
    """(T, 20, 4, 3) ``[M_k / u, -x_k^T M_k / u][k, b, a]``: what turns ``[x_m, 1]`` into ``D[k, m, a]``."""
    x = pose.finger_positions
    scaled = pose.finger_frames / palm_unit(pose)[:, :, None, None]
    shift = (x[..., 0, None] * scaled[:, :, 0]).addcmul(x[..., 1, None], scaled[:, :, 1])  # x_k^T M_k / u,
    shift = shift.addcmul(x[..., 2, None], scaled[:, :, 2])  # a term a row: faster than 20 T (1x3)@(3x3)
    return torch.cat([scaled, -shift[:, :, None]], 2)


def _spread(like: torch.Tensor, n_frames: int) -> torch.Tensor:
    """(T, 29, 3, 4, 3) ``[x_m, 1][m, b] I[c, a]`` at ``[m, a, b, c]``, the ones set and ``x_m`` left zero."""
    spread = like.new_zeros(n_frames, topo.N_ASM_COLUMNS, 3, 4, 3)
    spread.diagonal(dim1=2, dim2=4)[:, :, 3] = 1.0
    return spread


def _semantic_block(positions: torch.Tensor, frames: torch.Tensor, spread: torch.Tensor | None = None,
                    out: torch.Tensor | None = None) -> torch.Tensor:
    """`semantic_matrix` of one block of frames; into ``out`` (no autograd) with a `_spread` reused.

    The factor ``[x_m, 1][m, b] I[c, a]`` is stored as ``[(m, a), (b, c)]`` and handed to the product
    transposed: MKL's batched product is faster that way round here."""
    pose, n_frames = HandPose(positions, frames), len(positions)
    rows = _seen_from(pose).view(n_frames, topo.N_FINGER_JOINTS, 12)
    spread = _spread(positions, n_frames) if spread is None else spread[:n_frames]
    points = asm_columns(pose)
    for a in range(3):
        spread[:, :, a, :3, a] = points
    product = spread.view(n_frames, 3 * topo.N_ASM_COLUMNS, 12).transpose(1, 2)
    if out is None:
        d = torch.bmm(rows, product).view(n_frames, topo.N_FINGER_JOINTS, topo.N_ASM_COLUMNS, 3)
    else:
        d = out
        torch.bmm(rows, product, out=out.view(n_frames, topo.N_FINGER_JOINTS, 3 * topo.N_ASM_COLUMNS))
    d.diagonal(dim1=1, dim2=2).zero_()  # rounding leaves ~1e-8 at m == k in float32
    return d


def distance_matrix(pose: HandPose) -> torch.Tensor:
    """The DM baseline's feature (Zhang et al. 2023): (T, 20, 29) distances ``|x_m - x_k|`` in palm lengths."""
    x = pose.finger_positions
    return (asm_columns(pose)[:, None, :, :] - x[:, :, None, :]).norm(dim=-1) / palm_unit(pose)[:, :, None]
