"""Shared fixtures: shipped sample hands/motions and quick procedural hands (no mesh unless needed)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from s2h_viewer import samples
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.procedural import generate_hand

from own_display import start_own_display

# before any test module asks for a display (the window's tests skip without one)
start_own_display()

# Every test on one thread: the same results on any machine whatever its cores, and no threads spinning for
# a busy 2-core machine (the training test took 531 s with torch's two threads there, 51 s with one).
torch.set_num_threads(1)


@pytest.fixture(scope="session")
def sample_hands() -> dict[str, HandModel]:
    return {h.name: h for h in samples.load_sample_hands("all")}


@pytest.fixture(scope="session")
def rigify_files(tmp_path_factory):
    """The Rigify character Blender writes (tests/rigify_character.py) as GLB and as FBX, made once per test
    process: the Blender tests of two modules read it."""
    from rigify_character import rigify_characters
    return rigify_characters(tmp_path_factory.mktemp("rigify"))


@pytest.fixture(scope="session")
def skeleton_hands() -> list[HandModel]:
    """Four procedural hands, one per rig convention, skeleton only (fast)."""
    return [generate_hand(seed, with_mesh=False, rig_convention=c)
            for seed, c in zip(range(4), ("tbs", "y_along_bone", "z_along_bone", "neg_x_along_bone"))]


@pytest.fixture
def rng() -> torch.Generator:
    return torch.Generator().manual_seed(1234)


def random_tbs_motion(n_frames: int, generator: torch.Generator, max_deg: float = 60.0) -> torch.Tensor:
    """(T, 15, 4) float64 rotations of bounded angle about random axes."""
    axis = torch.randn(n_frames, 15, 3, generator=generator, dtype=torch.float64)
    axis = axis / axis.norm(dim=-1, keepdim=True)
    angle = torch.rand(n_frames, 15, 1, generator=generator, dtype=torch.float64) * np.radians(max_deg)
    return torch.cat([torch.cos(angle / 2), axis * torch.sin(angle / 2)], -1)
