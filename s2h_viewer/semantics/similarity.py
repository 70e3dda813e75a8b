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
    compares one source with many targets)."""

    directions: torch.Tensor  # (..., 20, 29, 3) unit vectors, zero where masked
    weights: torch.Tensor  # (..., 20, 29) `semantic_weights`, zero where masked

    @classmethod
    def of(cls, d_source: torch.Tensor) -> SourceSemantics:
        norm = d_source.norm(dim=-1, keepdim=True).clamp_min(_EPS)
        return cls(directions=d_source / norm * valid_mask(d_source)[..., None], weights=semantic_weights(d_source))

    def similarity(self, d_target: torch.Tensor) -> torch.Tensor:
        """L_sem against ``d_target``: weighted mean cosine over the cells valid on both sides, averaged
        over frames (scalar)."""
        norm = d_target.norm(dim=-1)
        weights = self.weights * (norm > _EPS)
        cos = (self.directions * d_target).sum(-1) / norm.clamp_min(_EPS)
        return ((weights * cos).sum((-1, -2)) / weights.sum((-1, -2)).clamp_min(_EPS)).mean()


def semantic_similarity(d_source: torch.Tensor, d_target: torch.Tensor) -> torch.Tensor:
    """L_sem: the weighted mean cosine between source and target ASMs, averaged over frames (scalar)."""
    return SourceSemantics.of(d_source).similarity(d_target)
