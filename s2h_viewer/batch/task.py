"""One batch task, in whatever process runs it: read the motion and target (cached per process), retarget,
score, write the output, the worst frame's picture and the summary row, each atomically (the row last).

No Dask here: the cluster calls `run_task`, and so can a test or a loop in one process. A task never raises:
a file that cannot be read, or any other failure, becomes a failed row with its one-line error.
"""

from __future__ import annotations

import time
import traceback
from collections import OrderedDict
from dataclasses import replace
from pathlib import Path

import numpy as np

from s2h_viewer.batch.plan import Input, Task
from s2h_viewer.batch.summary import row_json
from s2h_viewer.errors import S2HError
from s2h_viewer.hand.topology import JOINT_NAMES, joint_label
from s2h_viewer.io.atomic import atomic_path

#: inputs each worker keeps loaded (hands with their meshes and solved frames, motions with their rigs)
CACHE_SIZE = 24
_cache: OrderedDict[tuple, object] = OrderedDict()


def _cached(key: tuple, load):
    if key in _cache:
        _cache.move_to_end(key)
        return _cache[key]
    value = load()
    _cache[key] = value
    while len(_cache) > CACHE_SIZE:
        _cache.popitem(last=False)
    return value


def _load_motion(task: Task):
    """The motion, the hand it is performed on and that hand's file ("": its own, or its sample hand). --source is
    "the rig every motion was made for, where their files lack it": a clip that lacks nothing is read as it is (an
    npz on its shipped sample hand, a glTF/FBX whose skeleton has a mesh and rests straight); one that lacks its rig
    is read onto --source, else the first rig beside it (`plan.Input.rigs`) whose bones it animates, else on its
    own skeleton (its row's warning says why that may be wrong). A fresh-eyes user's --source of the Meta hand
    re-read the sample clips on it (kept 0.96 -> 0.81) and failed the Godot poses ("has no bones ...")."""
    from s2h_viewer.io.files import ANIMATED_SUFFIXES

    source = task.options.source
    if Path(task.motion.path).suffix.lower() not in ANIMATED_SUFFIXES:
        try:
            return (*_read_motion(task, None), "")
        except S2HError:  # an npz on no shipped sample hand: performed on --source, if given
            if source is None:
                raise
            return (*_read_motion(task, source), source)
    own = _read_motion(task, task.motion.path)
    if own[1].mesh is not None and not own[1].meta.get("rest_note"):
        return (*own, "")  # a rig of its own that lacks nothing
    for rig in ([source] if source else []) + [r for r in task.motion.rigs if r != source]:
        try:
            return (*_read_motion(task, rig), rig)
        except S2HError:  # not its rig (other bones): the next, else its own
            continue
    return (*own, "")


def _read_motion(task: Task, source: str | None):
    """The motion read onto the rig file ``source`` (None: its own, or its sample hand's), and that hand. A glTF
    file's animations are read together, once: each task of one read the whole file again (its JSON parsed 6 s a
    time for the 35 poses), and so did its rig."""
    from s2h_viewer.io.files import GLTF_FAMILY, load_hand_file, load_motion_file
    from s2h_viewer.io.gltf import load_every_gltf_animation
    from s2h_viewer.samples import sample_performer

    path, animation, options = task.motion.path, task.motion.animation, _rig_options(task)
    performer = None if source is None else _cached(
        ("hand", source, repr(Input(source, "").fingerprint()), task.options.side, task.options.unit),
        lambda: load_hand_file(source, options))
    fingerprint = repr(task.motion.fingerprint())
    if isinstance(animation, int) and Path(path).suffix.lower() in GLTF_FAMILY:
        every = _cached(("animations", path, fingerprint, task.options.side, task.options.unit, source),
                        lambda: load_every_gltf_animation(path, performer))
        if animation < len(every):
            return every[animation], performer

    def load():
        motion, rig = load_motion_file(path, performer, replace(options, animation=animation))
        return motion, rig or sample_performer(motion, path)

    return _cached(("motion", path, animation, fingerprint, task.options.side, task.options.unit, source), load)


def _load_target(task: Task):
    from s2h_viewer.io.files import load_hand_file

    return _cached(("hand", task.target.path, repr(task.target.fingerprint()), task.options.side,
                    task.options.unit), lambda: load_hand_file(task.target.path, _rig_options(task)))


def _rig_options(task: Task):
    """The `io.files.RigOptions` every file of the task is read with."""
    from s2h_viewer.io.files import RigOptions
    return RigOptions(side=task.options.side, unit=task.options.unit)


def base_row(task: Task) -> dict:
    return {"motion": task.motion.name, "target": task.target.name, "method": task.method, "key": task.key,
            "motion_path": task.motion.path, "target_path": task.target.path, "output": "", "picture": "",
            "animation": "" if task.motion.animation is None else str(task.motion.animation),
            "source_path": task.options.source or ""}


def run_task(task: Task) -> dict:
    """Do one task and return its summary row (also written to ``task.row_file``)."""
    start = time.perf_counter()
    row = base_row(task)
    try:
        row |= _retarget_and_write(task)
        row["status"], row["error"] = "ok", ""
    except S2HError as exc:  # a file that cannot be read or is not a hand: the same files fail the same way
        row["status"], row["error"], row["input_error"] = "failed", str(exc), True
    except KeyError as exc:  # an unknown method or joint, raised with its message
        row["status"], row["error"] = "failed", str(exc.args[0] if exc.args else exc)
    except Exception as exc:  # a bug or a library's surprise: one line in the summary, the traceback in the row
        row["status"], row["error"] = "failed", f"{type(exc).__name__}: {' '.join(str(exc).split())}"
        row["traceback"] = traceback.format_exc()
    row["seconds"] = round(time.perf_counter() - start, 3)
    with atomic_path(task.row_file) as tmp:
        tmp.write_text(row_json(row))
    return row


def _retarget_and_write(task: Task) -> dict:
    from s2h_viewer.io.files import save_motion_file
    from s2h_viewer.retarget import retarget
    from s2h_viewer.semantics.metrics import score_retarget_frames
    from s2h_viewer.semantics.signature import lost_pose_lines, pose_differences

    motion, source, source_path = _load_motion(task)
    target = _load_target(task)
    warning = "; ".join(w for w in (rig_warning(source, "source"), rig_warning(target, "target"),
                                    frames_warning(target)) if w)
    given = task.options.source
    if given and source_path != given and (source_path or source.mesh is None or source.meta.get("rest_note")):
        read_on = f"read on {Path(source_path).name}, beside it" if source_path else "read on its own skeleton"
        warning = "; ".join(w for w in (f"--source {Path(given).name} does not fit it (other bones): {read_on}",
                                        warning) if w)
    moved = retarget(motion, source, target, task.method)
    scores, frame_error = score_retarget_frames(source, motion.q_tbs, target, moved.q_tbs)
    poses = pose_differences(source, motion.q_tbs, target, moved.q_tbs, motion.labels)  # {} for a clip of no poses
    lost = {name: what for name, what in poses.items() if what}
    worst = int(np.argmax(frame_error)) if len(frame_error) else 0
    save_motion_file(task.output, moved, target)
    row = {"frames": motion.n_frames, "kept": scores.signature_kept,
           "poses_kept": f"{len(poses) - len(lost)}/{len(poses)}" if poses else "",
           "poses_lost": POSES_APART.join(f"{name}: {', '.join(what)}"
                                          for name, what in lost_pose_lines(lost, motion.labels)),
           "s_palm": scores.s_palm, "s_finger": scores.s_finger,
           "contact_p": scores.contact_precision, "contact_r": scores.contact_recall,
           "palm_r": scores.palm_contact_recall, "violations": scores.violation_rate,
           "violations_added": scores.added_violation_rate,
           "sideways_deg": scores.sideways_deg, "sideways_at": scores.sideways_at,
           "sideways_anywhere_deg": scores.sideways_anywhere_deg, "sideways_anywhere_at": scores.sideways_anywhere_at,
           "source_sideways_deg": scores.source_sideways_deg, "sideways_words": scores.sideways_words(motion.held_at),
           "thumb_follow": scores.thumb_follow, "thumb_follow_at": scores.thumb_follow_at,
           "invented": scores.invented_contacts, "invented_words": scores.invented_words(),
           "worst_frame": worst, "worst_error": float(frame_error[worst]) if len(frame_error) else 0.0,
           "output": str(task.output), "warning": warning, "source_path": source_path}
    if task.options.render:
        _render_frame(task, source, motion, target, moved, worst, task.picture)
        row["picture"] = str(task.picture)
        joint, _, bent = scores.sideways_at.partition("@")
        if scores.sideways_broken and int(bent) != worst:  # the worst frame's picture showed a fist, the note a pinky
            _render_frame(task, source, motion, target, moved, int(bent), task.sideways_picture, joint,
                          f"{joint_label(joint)} {scores.sideways_deg:.0f} deg sideways")
            row["sideways_picture"] = str(task.sideways_picture)
    return row


#: between the poses of a row's ``poses_lost`` (what each lost is said with "; " and ", ")
POSES_APART = " | "

#: a rig recognised with less confidence than this is flagged in the task's row (its hand may be misread)
LOW_RIG_CONFIDENCE = 0.5


def rig_warning(hand, role: str) -> str:
    """A line for the row when ``hand``'s bones were recognised with low confidence, or its skeleton rests in a
    pose (`semantics.rest_pose`), else ""."""
    if hand.meta.get("rest_note"):
        return f"{role}: {hand.meta['rest_note']}; give the hand file of the rig it was made for: s2h batch --source"
    confidence = hand.meta.get("rig_confidence")
    if confidence is None or confidence >= LOW_RIG_CONFIDENCE:
        return ""
    how = hand.meta.get("rig_scheme", "")
    return (f"{role} rig recognised with confidence {confidence:.2f} ({how} scheme): its joints may be misread; "
            f"check with `s2h rig {hand.source}` or give a joint map")


def frames_warning(target) -> str:
    """A line for the row when ``target``'s TBS frames are unsure or guessed (`annotate.trust`), as the viewer's
    banner over its cell says (a fresh-eyes user read it in the viewer and found the batch's row silent), else ""."""
    from s2h_viewer.annotate.trust import frame_warning
    warning = frame_warning(target)
    return "" if warning is None else f"target {warning.banner}: retargets may bend there; check its frames in Annotate"


#: characters of a target's name the worst frame's picture holds in its 300-pixel cell
PICTURE_NAME = 22


def _render_frame(task: Task, source, motion, target, moved, frame: int, path: Path, joint: str = "",
                  what: str = "") -> None:
    """One frame, source beside retarget, each filling its cell, off screen, to ``path``; ``joint`` marked red on
    both, the skin see-through, and ``what`` it does said under the retarget's name."""
    from s2h_viewer.render.offscreen import render_hands
    from s2h_viewer.retarget.methods import METHODS

    bones = ["\n(no skin: its bones)" if hand.mesh is None else "\n(a mitten: its bones)"
             if hand.meta.get("unparted_fingers") else "" for hand in (source, target)]
    name = task.target.name if len(task.target.name) <= PICTURE_NAME else task.target.name[:PICTURE_NAME - 3] + "..."
    said = f"\n{what}" if what else ""
    render_hands([source, target], [motion.q_tbs[frame], moved.q_tbs[frame]], path,
                 labels=[f"source, frame {frame}{bones[0]}", f"{METHODS[task.method].label} ->\n{name}{bones[1]}{said}"],
                 columns=2, view="palm", cell_size=(300, 320), fit_each=True,
                 marked=JOINT_NAMES.index(joint) if joint else None)
