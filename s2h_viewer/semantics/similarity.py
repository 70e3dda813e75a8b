"""Masked cosine similarity between two ASMs, the weight scheme, and the semantic loss L_sem.

Zero-norm entries (the diagonal ``m == k``, masked by position, and any coincident points) are
masked out of every cosine and mean, never divided by. L_sem is the paper's weighted sum divided by the weight total
(a constant 580 for a full mask: 20 x 28 finger cells + 20 x 9 anchors, each finger row's
softmax adding 1), so it lies in [-1, 1] and loss weights do not depend on the matrix size.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch

from s2h_viewer.hand import topology as topo
from s2h_viewer.semantics.asm import SELF_CELLS

_EPS = 1e-9


def valid_mask(d: torch.Tensor) -> torch.Tensor:
    """(..., 20, 29) True off the diagonal where the ASM vector has non-zero length."""
    return (d.norm(dim=-1) > _EPS) & ~SELF_CELLS.to(d.device)


def masked_cosine(d_a: torch.Tensor, d_b: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Cosine of corresponding ASM vectors, and the mask of cells where both are non-zero.

    Masked cells get cosine 0 and no gradient through a zero norm.
    """
    valid = valid_mask(d_a) & valid_mask(d_b)
    na = d_a.norm(dim=-1).clamp_min(_EPS)
    nb = d_b.norm(dim=-1).clamp_min(_EPS)
    cos = (d_a * d_b).sum(-1) / (na * nb)
    return torch.where(valid, cos, torch.zeros_like(cos)), valid


def semantic_weights(d_source: torch.Tensor) -> torch.Tensor:
    """``w[k, m] = 1 + softmax_m(-|D[k, m]|)`` over the 20 finger columns, 1 for anchors (``D`` in palm
    lengths, as `semantic_matrix` gives it).

    Near joints count more (a touching pair dominates its row). Masked cells get weight 0 and are
    left out of the softmax.
    """
    valid = valid_mask(d_source)
    finger = slice(0, topo.N_FINGER_JOINTS)
    logits = -d_source[..., finger, :].norm(dim=-1)
    logits = logits.masked_fill(~valid[..., finger], float("-inf"))
    weights = torch.ones_like(valid, dtype=d_source.dtype)
    weights[..., finger] += torch.softmax(logits, dim=-1)
    return weights * valid


@dataclass(frozen=True)
class SourceSemantics:
    """What L_sem needs of the source ASM, computed once: its unit directions and weights (ASM-Opt
    compares one source with many targets). Directions are kept components first, as
    `semantic_matrix_by_axis` lays out a target, so every reduction runs over long rows."""

    directions: torch.Tensor  # (..., 3, 20, 29) unit vectors, components first, zero where masked
    weights: torch.Tensor  # (..., 20, 29) `semantic_weights`, zero where masked

    @classmethod
    def of(cls, d_source: torch.Tensor) -> SourceSemantics:
        """From a source ASM (..., 20, 29, 3) as `semantic_matrix` gives it."""
        norm = d_source.norm(dim=-1, keepdim=True).clamp_min(_EPS)
        directions = d_source / norm * valid_mask(d_source)[..., None]
        return cls(directions=directions.movedim(-1, -3).contiguous(), weights=semantic_weights(d_source))

    def similarity(self, d_target: torch.Tensor) -> torch.Tensor:
        """L_sem against ``d_target`` (..., 20, 29, 3): weighted mean cosine over the cells valid on both
        sides, averaged over frames (scalar)."""
        return self.similarity_by_axis(d_target.movedim(-1, -3))

    def similarity_by_axis(self, d_target: torch.Tensor) -> torch.Tensor:
        """`similarity` against a target ASM laid out components first (..., 3, 20, 29); the gradient
        goes to ``d_target`` only."""
        return _SimilarityByAxis.apply(d_target, self.directions, self.weights)


class _SimilarityByAxis(torch.autograd.Function):
    """L_sem against a components-first target with its gradient written out,
    ``dL/dD = c (u - cos D / |D|)`` with ``c = w / (|D| W T)`` per cell: autograd through
    ``(D * D).sum`` and ``(u * D).sum`` makes five full-size passes and buffers, this makes one
    (ASM-Opt runs it at every step). Zero cells (``|D| <= eps``) are left out and get no gradient."""

    @staticmethod
    def forward(ctx, d_target: torch.Tensor, directions: torch.Tensor, weights: torch.Tensor) -> torch.Tensor:
        components, directions_by = d_target.unbind(-3), directions.unbind(-3)
        squared, dot = components[0] * components[0], directions_by[0] * components[0]
        for d, u in zip(components[1:], directions_by[1:]):
            squared.addcmul_(d, d)
            dot.addcmul_(u, d)
        weights = weights * (squared > _EPS ** 2)
        total = weights.sum((-1, -2), keepdim=True).clamp_min(_EPS)
        inverse_norm = squared.clamp_min_(_EPS ** 2).rsqrt_()
        cos = dot.mul_(inverse_norm)
        per_frame = (weights * cos).sum((-1, -2), keepdim=True) / total
        coefficient = weights.div_(total).mul_(inverse_norm).div_(per_frame.numel())
        ctx.save_for_backward(d_target, directions, coefficient, cos.mul_(inverse_norm))
        return per_frame.mean()

    @staticmethod
    def backward(ctx, grad: torch.Tensor) -> tuple[torch.Tensor, None, None]:
        d_target, directions, coefficient, cos_over_norm = ctx.saved_tensors
        coefficient = coefficient * grad
        out = d_target * (-cos_over_norm * coefficient).unsqueeze(-3)
        return out.addcmul_(directions, coefficient.unsqueeze(-3)), None, None


def semantic_similarity(d_source: torch.Tensor, d_target: torch.Tensor) -> torch.Tensor:
    """L_sem: the weighted mean cosine between source and target ASMs, averaged over frames (scalar)."""
    return SourceSemantics.of(d_source).similarity(d_target)
