"""Killed writes leave no stale temp files for long; long clips stream in windows and batches whose size
does not change the result."""

from __future__ import annotations

import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
import torch
from conftest import random_tbs_motion

from s2h_viewer.hand.motion import Motion
from s2h_viewer.hand.rotations import tbs_euler_to_quat
from s2h_viewer.io.npz import load_motion, save_motion
from s2h_viewer.retarget import asm_opt
from s2h_viewer.retarget.asm_opt import AsmOptConfig, optimise_asm
from s2h_viewer.retarget.asrn import inference
from s2h_viewer.retarget.asrn.inference import MODELS_DIR, load_network, run_network
from s2h_viewer.retarget.progress import reporting
from s2h_viewer.retarget.windows import stream_windows

ROOT = Path(__file__).resolve().parent.parent


def _writer_inside_atomic_path(target: Path) -> tuple[subprocess.Popen, Path]:
    """A child process stopped inside `atomic_path` for ``target`` with half a file written; its temp path."""
    code = textwrap.dedent(f"""
        import time
        from s2h_viewer.io.atomic import atomic_path
        with atomic_path({str(target)!r}) as tmp:
            tmp.write_text("half a file")
            print(tmp, flush=True)
            time.sleep(120)
    """)
    child = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True, cwd=ROOT)
    return child, Path(child.stdout.readline().strip())


def test_the_next_write_removes_temp_files_of_killed_writes_but_not_of_running_ones(tmp_path, rng):
    target = tmp_path / "clip.npz"
    running, live = _writer_inside_atomic_path(target)
    killed, stale = _writer_inside_atomic_path(target)
    killed.send_signal(signal.SIGKILL)
    killed.wait()
    try:
        assert stale.exists() and live.exists() and not target.exists()
        save_motion(Motion(q_tbs=random_tbs_motion(3, rng).numpy(), name="whole"), target)
        assert not stale.exists(), "the killed write's temp file is still there"
        assert live.exists(), "a running write's temp file was removed"
        assert load_motion(target).name == "whole"
    finally:
        running.kill()
        running.wait()


@pytest.mark.parametrize("n_frames,window,overlap,batch", [(5, 8, 2, 1), (8, 8, 2, 3), (100, 8, 2, 1), (100, 8, 2, 7),
                                                           (1000, 50, 10, 4), (1001, 64, 0, 2)])
def test_stream_hands_out_every_frame_once_in_order_with_weights_summing_to_one(n_frames, window, overlap, batch):
    length = max(n_frames, window)
    finished = []

    def run(starts, first, end):
        assert all(first <= s and s + window <= end for s in starts)
        return np.ones((len(starts), window, 2))

    stream_windows(length, window, overlap, run, lambda a, b, v: finished.append((a, b, v.copy())), batch)
    assert finished[0][0] == 0 and finished[-1][1] == length
    assert all(b == a2 for (_, b, _), (a2, _, _) in zip(finished, finished[1:]))
    values = np.concatenate([v for _, _, v in finished])
    np.testing.assert_allclose(values, 1.0)


def test_asrn_output_does_not_depend_on_how_many_frames_go_in_a_batch(sample_hands, rng, monkeypatch):
    model, config = load_network(str(MODELS_DIR / "asrn.pt"))
    q = random_tbs_motion(301, rng).numpy().astype(np.float32)
    source, target = sample_hands["birch"], sample_hands["juniper"]
    whole = run_network(model, "asrn", source, q, target, window=config.window)
    monkeypatch.setattr(inference, "FRAMES_PER_BATCH", 3 * config.window)
    batched = run_network(model, "asrn", source, q, target, window=config.window)
    np.testing.assert_allclose(batched, whole, atol=2e-5)
    reported = []
    with reporting(lambda fraction, what: reported.append(fraction)):
        run_network(model, "asrn", source, q[:7], target, window=config.window)  # shorter than a window
    assert reported[-1] == 1.0


def test_asm_opt_chunks_match_each_chunk_optimised_alone_where_they_do_not_overlap(sample_hands, rng):
    config = AsmOptConfig(steps=4, chunk=48, chunk_overlap=12)
    q = random_tbs_motion(100, rng, max_deg=30).numpy().astype(np.float32)
    source, target = sample_hands["birch"], sample_hands["juniper"]
    out = optimise_asm(q, source, target, config=config)
    assert out.shape == q.shape and np.isfinite(out).all()
    alone = asm_opt._optimise_chunk(q[:48], source, target, q[:48], config)
    expected = tbs_euler_to_quat(torch.as_tensor(alone[:36])).numpy()
    np.testing.assert_allclose(out[:36], expected, atol=1e-5)
