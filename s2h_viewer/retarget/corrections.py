"""Corrections of a retarget: per-joint offset rotations keyed at frames, each blended over its own frame range
with ease in and out, applied on top of a method's motion (the fix a person makes where a retarget reads wrong).

An offset turns a joint in its own TBS frame (``q' = q * offset``), so its children follow and a turn about
the joint's twist, bend or splay axis stays one. Each key is a bump: none at its range's start, easing in to
its turn at its frame (or over the frames it holds: a pose held over a run of frames is fixed on all of them),
easing out to none at its range's end (smoothsteps, flat at both ends: a corrected finger starts and stops moving
gently); a frame no key's range holds is the method's own. Keys whose ranges
overlap compose, in the order of their frames, so a second key changes only its own range and deleting one
gives back exactly what was there without it. Pure numpy / scipy: the viewer, its motion exports and
``s2h retarget --corrections`` apply the same curves."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.motion import Motion
from s2h_viewer.wording import plural

#: the axes a joint can be turned about, in its TBS frame's column order (x twist, y bend, z splay)
AXES: tuple[str, ...] = ("twist", "bend", "splay")


def smoothstep(s: np.ndarray) -> np.ndarray:
    """0 at 0, 1 at 1, flat at both (``3 s^2 - 2 s^3``), clamped outside."""
    s = np.clip(s, 0.0, 1.0)
    return s * s * (3.0 - 2.0 * s)


@dataclass(frozen=True)
class OffsetKey:
    """One joint's turn at ``frame`` (a rotation vector in its TBS frame, radians), whole over ``hold`` (first,
    last; None: ``frame`` alone), eased in from ``start`` and out to ``end`` (``start <= hold <= end``; no offset
    from this key at and outside them but on its held frames)."""

    frame: int
    rotvec: tuple[float, float, float]
    start: int
    end: int
    hold: tuple[int, int] | None = None

    @property
    def held(self) -> tuple[int, int]:
        """The first and last frames it holds its whole turn over."""
        return self.hold if self.hold is not None else (self.frame, self.frame)

    @property
    def rotation(self) -> Rotation:
        return Rotation.from_rotvec(np.asarray(self.rotvec, dtype=np.float64))

    def weights(self, frames: np.ndarray) -> np.ndarray:
        """Its share of its turn at each of ``frames``: 0 outside its range, 1 on its held frames, smoothsteps
        between."""
        first, last = self.held
        rising = smoothstep((frames - self.start) / max(first - self.start, 1))
        falling = smoothstep((self.end - frames) / max(self.end - last, 1))
        weights = np.where(frames < first, rising, np.where(frames > last, falling, 1.0))
        weights[(frames < self.start) | (frames > self.end)] = 0.0
        return weights


@dataclass(frozen=True)
class JointCorrection:
    """One joint's keys, by frame (at least one, one per frame)."""

    joint: int  # articulated index (`topology.ARTICULATED_NAMES`)
    keys: tuple[OffsetKey, ...]

    @property
    def name(self) -> str:
        return topo.ARTICULATED_NAMES[self.joint]

    def key_at(self, frame: int) -> OffsetKey | None:
        return next((k for k in self.keys if k.frame == frame), None)

    def offsets(self, n_frames: int, keys: tuple[OffsetKey, ...] | None = None) -> Rotation:
        """(n_frames,) the offset at every frame: its keys' (or ``keys``') eased turns composed in frame order."""
        frames = np.arange(n_frames)
        offset = Rotation.identity(n_frames)
        for key in self.keys if keys is None else keys:
            offset = offset * Rotation.from_rotvec(key.weights(frames)[:, None] * np.asarray(key.rotvec))
        return offset

    def offset_at(self, frame: int) -> Rotation:
        return self.offsets(frame + 1)[frame]


@dataclass(frozen=True)
class Corrections:
    """Every corrected joint of one retarget (one `JointCorrection` each, by joint); empty: no corrections."""

    joints: tuple[JointCorrection, ...] = ()

    def __bool__(self) -> bool:
        return bool(self.joints)

    @property
    def n_keys(self) -> int:
        return sum(len(c.keys) for c in self.joints)

    def of(self, joint: int) -> JointCorrection | None:
        return next((c for c in self.joints if c.joint == joint), None)

    def offset_at(self, joint: int, frame: int) -> Rotation:
        """The joint's offset at ``frame`` (identity where it has none)."""
        correction = self.of(joint)
        return Rotation.identity() if correction is None else correction.offset_at(frame)

    def _with(self, joint: int, keys: tuple[OffsetKey, ...]) -> "Corrections":
        kept = [c for c in self.joints if c.joint != joint]
        if keys:
            kept.append(JointCorrection(joint, tuple(sorted(keys, key=lambda k: k.frame))))
        return Corrections(tuple(sorted(kept, key=lambda c: c.joint)))

    def with_turn(self, joint: int, frame: int, turn: Rotation, start: int, end: int,
                  hold: tuple[int, int] | None = None) -> "Corrections":
        """The joint turned by ``turn`` (in its TBS frame) at ``frame`` on top of its offset there: a new key there
        held over ``hold`` and eased over ``start`` .. ``end``, or the key already there (its frames kept) turned
        further. Only the frames of that key's range change."""
        correction = self.of(joint)
        keys = correction.keys if correction is not None else ()
        old = next((k for k in keys if k.frame == frame), None)
        if old is not None:
            placeholder = dataclasses.replace(old, rotvec=(0.0, 0.0, 0.0))
        else:
            hold = None if hold is None else (min(int(hold[0]), frame), max(int(hold[1]), frame))
            first, last = hold or (frame, frame)
            placeholder = OffsetKey(int(frame), (0.0, 0.0, 0.0), int(min(start, first)), int(max(end, last)), hold)
        order = sorted([k for k in keys if k.frame != frame] + [placeholder], key=lambda k: k.frame)
        at = order.index(placeholder)
        after = JointCorrection(joint, tuple(order)).offsets(frame + 1, tuple(order[at + 1:]))[frame]
        own = old.rotation if old is not None else Rotation.identity()
        # the keys compose as ``ahead * this * after``: ``ahead * new * after = ahead * own * after * turn`` is the
        # joint at ``frame`` turned by ``turn`` on top of what it was
        new = own * after * turn * after.inv()
        order[at] = dataclasses.replace(placeholder, rotvec=tuple(float(v) for v in new.as_rotvec()))
        return self._with(joint, tuple(order))

    def without_key(self, joint: int, frame: int) -> "Corrections":
        """The joint's key at ``frame`` taken away (its curve too if it was the last key)."""
        correction = self.of(joint)
        if correction is None:
            return self
        return self._with(joint, tuple(k for k in correction.keys if k.frame != frame))

    def without_joint(self, joint: int) -> "Corrections":
        return self._with(joint, ())

    def with_range(self, joint: int, frame: int, start: int, end: int) -> "Corrections":
        """The joint's key at ``frame`` eased over ``start`` .. ``end`` instead (kept around its frame; the frames
        it holds, within them)."""
        correction = self.of(joint)
        key = correction.key_at(frame) if correction is not None else None
        if key is None:
            return self
        start, end = min(start, frame), max(end, frame)
        hold = None if key.hold is None else (max(key.hold[0], start), min(key.hold[1], end))
        key = dataclasses.replace(key, start=start, end=end, hold=None if hold == (frame, frame) else hold)
        return self._with(joint, tuple(key if k.frame == frame else k for k in correction.keys))

    def apply(self, q_tbs: np.ndarray) -> np.ndarray:
        """(T, 15, 4) TBS quaternions (w, x, y, z) with every joint's offsets applied (a new array)."""
        q = np.array(q_tbs, dtype=np.float32, copy=True)
        for correction in self.joints:
            base = q[:, correction.joint].astype(np.float64)
            turned = (Rotation.from_quat(base, scalar_first=True) * correction.offsets(len(q))).as_quat(
                scalar_first=True)
            turned[np.einsum("tk,tk->t", turned, base) < 0] *= -1.0  # the original's hemisphere: no sign flips
            q[:, correction.joint] = turned
        return q

    def frames(self) -> np.ndarray:
        """Every keyed frame, sorted, once each (the error curve's key marks)."""
        return np.unique([k.frame for c in self.joints for k in c.keys]).astype(np.int64)

    def describe(self) -> str:
        """'index PIP: keys at frame 40 (blended over 30-50), frame 60 (blended over 50-70); pinky DIP: key at frame 12
        (blended over 2-22)'."""
        return "; ".join(f"{topo.joint_label(c.name)}: {describe_keys(c)}" for c in self.joints)


def describe_keys(correction: JointCorrection) -> str:
    """'keys at frame 40 (blended over 30-50), frame 60 (held over 55-66, blended over 50-70)' (a fresh-eyes user read
    'key at 200 held 200-211 over 192-219' as a riddle)."""
    keys = ", ".join(f"frame {k.frame} ({'held over {}-{}, '.format(*k.hold) if k.hold else ''}blended over "
                     f"{k.start}-{k.end})" for k in correction.keys)
    return f"{plural('key', len(correction.keys))} at {keys}"


def key_span(labels: np.ndarray, frame: int, ease_in: int, ease_out: int) -> tuple[int, int, tuple[int, int] | None]:
    """The start, end and held frames of a new key at ``frame`` of a clip whose frames are ``labels`` (the pose held
    at each, "" between; all "" in a clip of none): on a pose held over several frames, the whole pose; between
    poses, ``frame`` alone. It eases in and out over at most ``ease_in`` / ``ease_out`` frames, never into a pose:
    a fix on one frame of a held OK would otherwise fade across the OK itself and, at the default ease, into the
    poses either side of it."""
    label, last = labels[frame], len(labels) - 1
    first = held_last = frame
    while label and first > 0 and labels[first - 1] == label:
        first -= 1
    while label and held_last < last and labels[held_last + 1] == label:
        held_last += 1
    start, end = first, held_last
    while start > max(0, first - ease_in) and not labels[start - 1]:
        start -= 1
    while end < min(last, held_last + ease_out) and not labels[end + 1]:
        end += 1
    return start, end, (first, held_last) if first < held_last else None


def corrected_motion(motion: Motion, corrections: Corrections) -> Motion:
    """``motion`` with ``corrections`` applied, its meta saying which (the viewer's and `s2h retarget`'s one way)."""
    return dataclasses.replace(motion, q_tbs=corrections.apply(motion.q_tbs),
                               meta={**motion.meta, "corrections": corrections.describe()})


def turn_about(axis: str, degrees: float) -> Rotation:
    """A turn of ``degrees`` about one of the joint's own axes (`AXES`)."""
    return Rotation.from_rotvec(np.radians(degrees) * np.eye(3)[AXES.index(axis)])
