"""`s2h render --motion`: compare mode off screen (no Qt), a PNG of one frame or a GIF/MP4 of the clip."""

from __future__ import annotations

import imageio.v2 as imageio
import numpy as np

from s2h_viewer.cli import main
from s2h_viewer.io.npz import save_motion
from s2h_viewer.motions.synthesis import synthesize


def test_render_compare_writes_a_frame_and_a_whole_clip(sample_hands, tmp_path):
    motion = synthesize(["fist", "v_sign"], sample_hands["birch"], seed=1, name="two")
    clip = save_motion(motion, tmp_path / "two.npz")
    png, gif = tmp_path / "frame.png", tmp_path / "clip.gif"
    common = ["render", "--motion", str(clip), "--target", "laurel", "--methods", "tbs_copy,asrn", "--quiet"]
    assert main([*common, "--frame", "20", "--out", str(png)]) == 0
    image = imageio.imread(png)[..., :3]
    assert len(np.unique(image.reshape(-1, 3), axis=0)) > 50  # hands and a colour scale, not a blank frame
    assert main([*common, "--out", str(gif)]) == 0
    frames = imageio.mimread(gif, memtest=False)
    assert len(frames) == motion.n_frames
    assert not np.array_equal(frames[0], frames[len(frames) // 2])  # the hands move
