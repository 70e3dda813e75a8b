"""The shipped sample hands and motions under assets/, listed by assets/index.json."""

from __future__ import annotations

import json
from pathlib import Path

from s2h_viewer.errors import InputFileError
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.motion import Motion
from s2h_viewer.io.npz import load_hand, load_motion

ASSETS_DIR = Path(__file__).resolve().parent.parent / "assets"
INDEX_PATH = ASSETS_DIR / "index.json"


def read_index() -> dict:
    """The asset index: ``{"hands": [{name, file, split, ...}], "motions": [{name, file, hand, ...}]}``."""
    try:
        return json.loads(INDEX_PATH.read_text())
    except FileNotFoundError:
        raise InputFileError(INDEX_PATH, "asset index not found (run `make assets`)") from None
    except json.JSONDecodeError as exc:
        raise InputFileError(INDEX_PATH, f"invalid JSON ({exc})") from None


def hand_names(split: str = "all") -> list[str]:
    """Names of the sample hands in a split ("train", "test" or "all")."""
    return [h["name"] for h in read_index()["hands"] if split in ("all", h["split"])]


def load_sample_hand(name: str) -> HandModel:
    for entry in read_index()["hands"]:
        if entry["name"] == name:
            return load_hand(ASSETS_DIR / entry["file"])
    raise KeyError(f"no sample hand {name!r}; have {', '.join(hand_names())}")


def sample_performer(motion: Motion, motion_file: str | Path) -> HandModel:
    """The shipped sample hand a motion without a rig of its own (an npz) is posed on, by its ``hand_name``; an
    `InputFileError` naming ``motion_file`` where no sample hand has that name."""
    try:
        return load_sample_hand(motion.hand_name)
    except KeyError:
        raise InputFileError(motion_file, f"is posed on the hand {motion.hand_name!r}, not a shipped sample hand "
                                          f"({', '.join(hand_names())}): name its hand with --source") from None


def load_sample_hands(split: str = "all") -> list[HandModel]:
    return [load_sample_hand(n) for n in hand_names(split)]


def load_sample_motions() -> list[Motion]:
    return [load_motion(ASSETS_DIR / m["file"]) for m in read_index()["motions"]]
