"""Corrections of a retarget: per-joint offset rotations keyed at frames and blended over a frame range with
ease in and out, applied on top of a method's motion (the fix a person makes where a retarget reads wrong).

An offset turns a joint in its own TBS frame (``q' = q * offset``), so its children follow and a turn about
the joint's twist, bend or splay axis stays one. Between two keys of a joint the offset goes from one to
the other; from its range's start to the first key it eases in from none, from the last key to the range's
end it eases out; outside the range there is none. Every ease is a smoothstep (flat at both ends), so a
corrected finger starts and stops moving gently. Pure numpy / scipy: the viewer, its motion exports and
``s2h retarget --corrections`` apply the same curves."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from s2h_viewer.hand import topology as topo

#: the axes a joint can be turned about, in its TBS frame's column order (x twist, y bend, z splay)
AXES: tuple[str, ...] = ("twist", "bend", "splay")


def smoothstep(s: np.ndarray) -> np.ndarray:
    """0 at 0, 1 at 1, flat at both (``3 s^2 - 2 s^3``), clamped outside."""
    s = np.clip(s, 0.0, 1.0)
    return s * s * (3.0 - 2.0 * s)


@dataclass(frozen=True)
class OffsetKey:
    """The offset of one joint at one frame: a rotation vector in the joint's TBS frame (radians)."""

    frame: int
    rotvec: tuple[float, float, float]

    @property
    def rotation(self) -> Rotation:
        return Rotation.from_rotvec(np.asarray(self.rotvec, dtype=np.float64))


@dataclass(frozen=True)
class JointCorrection:
    """One joint's offset curve: its keys (by frame, at least one) inside ``start`` .. ``end`` (no offset at
    and outside these frames unless a key sits on them)."""

    joint: int  # articulated index (`topology.ARTICULATED_NAMES`)
    keys: tuple[OffsetKey, ...]
    start: int
    end: int

    @property
    def name(self) -> str:
        return topo.ARTICULATED_NAMES[self.joint]

    def offsets(self, n_frames: int) -> Rotation:
        """(n_frames,) the offset at every frame of the clip."""
        frames = np.arange(n_frames)
        rotvecs = np.zeros((n_frames, 3))
        first, last = self.keys[0], self.keys[-1]
        easing_in = (frames >= self.start) & (frames <= first.frame)
        span = max(first.frame - self.start, 1)
        rotvecs[easing_in] = smoothstep((frames[easing_in] - self.start) / span)[:, None] * np.asarray(first.rotvec)
        easing_out = (frames >= last.frame) & (frames <= self.end)
        span = max(self.end - last.frame, 1)
        rotvecs[easing_out] = smoothstep((self.end - frames[easing_out]) / span)[:, None] * np.asarray(last.rotvec)
        for key in self.keys:  # each key's own offset at its frame (also on the range's ends)
            if 0 <= key.frame < n_frames:
                rotvecs[key.frame] = key.rotvec
        offsets = Rotation.from_rotvec(rotvecs)
        for a, b in zip(self.keys, self.keys[1:]):  # between keys: from one offset to the next, eased
            between = frames[(frames > a.frame) & (frames < b.frame)]
            if len(between):
                step = (a.rotation.inv() * b.rotation).as_rotvec()
                s = smoothstep((between - a.frame) / (b.frame - a.frame))
                turned = a.rotation * Rotation.from_rotvec(s[:, None] * step)
                offsets = _replace(offsets, between, turned)
        return offsets

    def offset_at(self, frame: int) -> Rotation:
        return self.offsets(frame + 1)[frame]


def _replace(rotations: Rotation, where: np.ndarray, values: Rotation) -> Rotation:
    quats = rotations.as_quat()
    quats[where] = values.as_quat()
    return Rotation.from_quat(quats)


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

    def _with(self, correction: JointCorrection | None, joint: int) -> "Corrections":
        kept = [c for c in self.joints if c.joint != joint] + ([correction] if correction is not None else [])
        return Corrections(tuple(sorted(kept, key=lambda c: c.joint)))

    def with_turn(self, joint: int, frame: int, turn: Rotation, start: int, end: int) -> "Corrections":
        """The joint turned by ``turn`` (in its TBS frame) at ``frame`` on top of its offset there: a key at
        ``frame`` (replacing one there). A new curve spans ``start`` .. ``end``; an existing one widens to
        them if the key falls outside it."""
        offset = (self.offset_at(joint, frame) * turn).as_rotvec()
        key = OffsetKey(int(frame), tuple(float(v) for v in offset))
        correction = self.of(joint)
        if correction is None:
            return self._with(JointCorrection(joint, (key,), min(start, frame), max(end, frame)), joint)
        keys = tuple(sorted([k for k in correction.keys if k.frame != frame] + [key], key=lambda k: k.frame))
        inside = correction.start <= frame <= correction.end
        return self._with(JointCorrection(joint, keys, correction.start if inside else min(correction.start, start),
                                          correction.end if inside else max(correction.end, end)), joint)

    def without_key(self, joint: int, frame: int) -> "Corrections":
        """The joint's key at ``frame`` taken away (its curve too if it was the last key)."""
        correction = self.of(joint)
        if correction is None:
            return self
        keys = tuple(k for k in correction.keys if k.frame != frame)
        return self._with(dataclasses.replace(correction, keys=keys) if keys else None, joint)

    def without_joint(self, joint: int) -> "Corrections":
        return self._with(None, joint)

    def with_range(self, joint: int, start: int, end: int) -> "Corrections":
        """The joint's curve blended over ``start`` .. ``end`` (kept around its keys)."""
        correction = self.of(joint)
        if correction is None:
            return self
        start, end = min(start, correction.keys[0].frame), max(end, correction.keys[-1].frame)
        return self._with(dataclasses.replace(correction, start=start, end=end), joint)

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
        """Every keyed frame, sorted, once each (the timeline's key marks)."""
        return np.unique([k.frame for c in self.joints for k in c.keys]).astype(np.int64)

    def describe(self) -> str:
        """'index PIP (1 key, frames 20-60), pinky DIP (2 keys, frames 0-90)'."""
        return ", ".join(f"{spaced_joint(c.name)} ({len(c.keys)} key{'s' * (len(c.keys) != 1)}, frames "
                         f"{c.start}-{c.end})" for c in self.joints)


def spaced_joint(name: str) -> str:
    """'index_pip' -> 'index PIP' (as the heatmap names joints)."""
    finger, _, level = name.partition("_")
    return f"{finger} {level.upper()}"


def turn_about(axis: str, degrees: float) -> Rotation:
    """A turn of ``degrees`` about one of the joint's own axes (`AXES`)."""
    return Rotation.from_rotvec(np.radians(degrees) * np.eye(3)[AXES.index(axis)])
