"""The clips opened in this session, by file: a file opened again unchanged, with the same options, gives back
the same motion and source objects, so compare mode's results cached for them are shown, not computed again."""

from __future__ import annotations

import hashlib
from collections import OrderedDict
from pathlib import Path

from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.motion import Motion

#: clips remembered at most (their motions are small; their results live in compare mode's bounded cache)
REMEMBERED = 8


class OpenedClips:
    """(motion, source) per (file, its bytes, the options it was read with), newest last."""

    def __init__(self) -> None:
        self._clips: OrderedDict[tuple, tuple[Motion, HandModel]] = OrderedDict()
        self._origins: dict[int, tuple[str, str, str]] = {}  # per remembered motion's id: `origin`

    @staticmethod
    def origin_of(path: str | Path, animation: object = None, rig_file: str | Path | None = None
                  ) -> tuple[str, str, str]:
        """What a clip was read from: its file (resolved), its animation ("" for the file's first), the hand file
        it was read onto ("" for its own skeleton or sample), comparable with a batch row's."""
        return (str(Path(path).resolve()), "" if animation is None else str(animation),
                str(Path(rig_file).resolve()) if rig_file else "")

    def origin(self, motion: Motion) -> tuple[str, str, str] | None:
        """`origin_of` the remembered clip whose motion is ``motion``, or None."""
        return self._origins.get(id(motion))

    @staticmethod
    def key(path: str | Path, options: object) -> tuple | None:
        """The file's path and a digest of its bytes (a modification time may not change within a save's second
        on every file system), and the options; None for a file that cannot be read. Taken once per open: `get`
        and `remember` both take it."""
        digest = hashlib.blake2b(digest_size=16)
        try:
            with open(path, "rb") as fh:
                for chunk in iter(lambda: fh.read(1 << 20), b""):
                    digest.update(chunk)
        except OSError:
            return None
        return str(Path(path).resolve()), digest.hexdigest(), repr(options)

    def get(self, key: tuple | None) -> tuple[Motion, HandModel] | None:
        """The clip read before under ``key`` (`key`: the same file, unchanged, with the same options)."""
        if key not in self._clips:
            return None
        self._clips.move_to_end(key)
        return self._clips[key]

    def remember(self, key: tuple | None, motion: Motion, source: HandModel,
                 origin: tuple[str, str, str] | None = None) -> None:
        if key is None:
            return
        if key in self._clips:  # read again: the motion it held goes, with its origin (its id may be reused)
            self._origins.pop(id(self._clips[key][0]), None)
        self._clips[key] = (motion, source)
        self._clips.move_to_end(key)
        if origin is not None:
            self._origins[id(motion)] = origin
        while len(self._clips) > REMEMBERED:
            forgotten, _ = self._clips.popitem(last=False)[1]
            self._origins.pop(id(forgotten), None)
