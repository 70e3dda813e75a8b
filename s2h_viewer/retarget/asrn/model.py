"""The retargeting network of the paper (section 6 of DESIGN.md), shared by ASRN and DM.

Static encoders (one MLP layer + two ResNet-like 1D conv layers over the joint axis) turn the target's
H and M_rest into a code; four ResNet-like 1D conv layers run over time on the source features, each
layer's input concatenated with the code; a linear head gives, per frame and joint, a rotation vector
applied on top of the source's TBS rotation (zero-initialised: an untrained network is TBS Copy).
"""

from __future__ import annotations

import roma
import torch
from torch import nn

from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.rotations import canonical_quat, quat_multiply

_XYZW_TO_WXYZ = [3, 0, 1, 2]


class ResBlock1d(nn.Module):
    """Two 1D convolutions with a residual connection (1x1 projection when the width changes)."""

    def __init__(self, c_in: int, c_out: int, kernel: int = 3):
        super().__init__()
        self.conv1 = nn.Conv1d(c_in, c_out, kernel, padding=kernel // 2)
        self.conv2 = nn.Conv1d(c_out, c_out, kernel, padding=kernel // 2)
        self.skip = nn.Conv1d(c_in, c_out, 1) if c_in != c_out else nn.Identity()
        self.act = nn.LeakyReLU(0.2)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.act(self.conv2(self.act(self.conv1(x))) + self.skip(x))


class StaticEncoder(nn.Module):
    """(B, joints, values) -> (B, out): an MLP layer per joint, two residual convs across joints."""

    def __init__(self, n_joints: int, values: int, width: int, out: int):
        super().__init__()
        self.mlp = nn.Sequential(nn.Linear(values, width), nn.LeakyReLU(0.2))
        self.blocks = nn.Sequential(ResBlock1d(width, width), ResBlock1d(width, width))
        self.out = nn.Linear(width * n_joints, out)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        h = self.blocks(self.mlp(x).transpose(1, 2))
        return self.out(h.flatten(1))


class RetargetNet(nn.Module):
    """Source features (B, T, F) + target static (B, 20, 3), (B, 15, 6) -> residual rotvecs (B, T, 15, 3)."""

    def __init__(self, feature_size: int, width: int = 128, static_size: int = 64, n_blocks: int = 4):
        super().__init__()
        self.shape_encoder = StaticEncoder(topo.N_FINGER_JOINTS, 3, 32, static_size // 2)
        self.frame_encoder = StaticEncoder(topo.N_ARTICULATED, 6, 32, static_size // 2)
        self.inp = nn.Sequential(nn.Conv1d(feature_size, width, 1), nn.LeakyReLU(0.2))
        self.blocks = nn.ModuleList([ResBlock1d(width + static_size, width) for _ in range(n_blocks)])
        self.head = nn.Linear(width, topo.N_ARTICULATED * 3)
        nn.init.zeros_(self.head.weight)
        nn.init.zeros_(self.head.bias)

    def forward(self, features: torch.Tensor, shape: torch.Tensor, frames: torch.Tensor) -> torch.Tensor:
        code = torch.cat([self.shape_encoder(shape), self.frame_encoder(frames)], -1)  # (B, S)
        h = self.inp(features.transpose(1, 2))  # (B, W, T)
        code_t = code[:, :, None].expand(-1, -1, h.shape[-1])
        for block in self.blocks:
            h = block(torch.cat([h, code_t], 1))
        return self.head(h.transpose(1, 2)).reshape(*features.shape[:2], topo.N_ARTICULATED, 3)


def apply_residual(q_source: torch.Tensor, rotvec: torch.Tensor) -> torch.Tensor:
    """``q_source * exp(rotvec)``: the residual turns each joint within its own TBS frame."""
    delta = roma.rotvec_to_unitquat(rotvec)[..., _XYZW_TO_WXYZ]
    return canonical_quat(quat_multiply(q_source, delta))
