"""Turn a list of gestures into a smooth motion: eased transitions, holds, small smooth noise, seeded."""

from __future__ import annotations

import numpy as np
import torch
from scipy.ndimage import gaussian_filter1d

from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.motion import Motion
from s2h_viewer.hand.rotations import tbs_euler_to_quat
from s2h_viewer.motions.fitting import clamp_to_limits, fit_gesture_angles
from s2h_viewer.motions.gestures import GESTURES, gesture


def _smootherstep(t: np.ndarray) -> np.ndarray:
    return t * t * t * (t * (6 * t - 15) + 10)


def synthesize(names: list[str], hand: HandModel | None = None, fps: float = 30.0, seed: int = 0,
               hold: tuple[float, float] = (0.5, 0.9), transition: tuple[float, float] = (0.35, 0.6),
               noise_deg: float = 1.0, name: str = "", fitted: dict[str, np.ndarray] | None = None) -> Motion:
    """A motion through the named gestures (starting from "relaxed"), fitted to ``hand`` if given.

    ``fitted`` (from `fit_library`) saves refitting when one hand performs many scripts.
    """
    sequence = [gesture(n) for n in ["relaxed", *names]]
    if fitted is not None:
        keys = np.stack([fitted[g.name] for g in sequence])
    elif hand is not None:
        keys = fit_gesture_angles(hand, sequence)
    else:
        keys = np.stack([np.radians(g.angles_deg) for g in sequence])
    meta = {"script": list(names), "seed": seed, "hold": list(hold), "transition": list(transition),
            "noise_deg": noise_deg}
    return perform(keys, [g.name for g in sequence], np.random.default_rng(seed), fps, hold, transition, noise_deg,
                   name=name or "+".join(names), hand_name=hand.name if hand else "", meta=meta)


def perform(keys: np.ndarray, key_names: list[str], rng: np.random.Generator, fps: float = 30.0,
            hold: tuple[float, float] = (0.5, 0.9), transition: tuple[float, float] = (0.35, 0.6),
            noise_deg: float = 1.0, name: str = "", hand_name: str = "", meta: dict | None = None) -> Motion:
    """A motion through (K, 15, 3) key angles (radians): each held, then eased into the next.

    Angles are interpolated per joint with a smootherstep ease (zero velocity and acceleration at
    key poses); noise is Gaussian-filtered so it reads as tremor, not jitter, and everything is
    clamped back into the anatomical limits. Hold frames are labelled with their key's name.
    """
    frames, labels = [], []
    for i, key in enumerate(keys):
        if i > 0:
            n = max(2, round(rng.uniform(*transition) * fps))
            t = _smootherstep(np.arange(1, n + 1) / n)[:, None, None]
            frames.append(keys[i - 1] + t * (key - keys[i - 1]))
            labels += [""] * n
        n = max(1, round(rng.uniform(*hold) * fps))
        frames.append(np.repeat(key[None], n, 0))
        labels += [key_names[i]] * n
    angles = np.concatenate(frames)

    if noise_deg > 0:
        noise = gaussian_filter1d(rng.normal(size=angles.shape), sigma=0.15 * fps, axis=0)
        noise *= np.radians(noise_deg) / max(noise.std(), 1e-12)
        noise[..., 0] = 0.0  # no twist: it has no anatomical range
        angles = angles + noise
    angles = clamp_to_limits(torch.as_tensor(angles)).numpy()
    q = tbs_euler_to_quat(torch.as_tensor(angles)).numpy().astype(np.float32)
    return Motion(q_tbs=q, fps=fps, name=name, hand_name=hand_name, labels=np.array(labels, dtype=object),
                  meta=meta or {})


def fit_library(hand: HandModel) -> dict[str, np.ndarray]:
    """Every gesture of the library fitted to one hand: name -> (15, 3) radians."""
    gestures = list(GESTURES.values())
    return dict(zip(GESTURES, fit_gesture_angles(hand, gestures)))


def resynthesize(motion: Motion, hand: HandModel) -> Motion | None:
    """The same gesture script, timing and noise performed by another hand (its contacts fitted to it):
    the semantic ground truth a retarget of ``motion`` onto ``hand`` should match. None if unknown: no script, or
    one that performs another number of frames than the clip holds (a clip cut since it was made: `s2h evaluate`
    on the first 60 frames of the gestures clip stopped on a traceback, comparing them with 378)."""
    meta = motion.meta
    if "script" not in meta:
        return None
    reference = synthesize(meta["script"], hand, fps=motion.fps, seed=meta["seed"], hold=tuple(meta["hold"]),
                           transition=tuple(meta["transition"]), noise_deg=meta["noise_deg"], name=motion.name)
    return reference if reference.n_frames == motion.n_frames else None


def gesture_contacts(labels: np.ndarray) -> np.ndarray:
    """(T, 15) bool ground-truth contacts from per-frame gesture labels ("" frames: none)."""
    out = np.zeros((len(labels), 15), dtype=bool)
    for i, label in enumerate(labels):
        if label:
            out[i] = GESTURES[label].contact_vector()
    return out
