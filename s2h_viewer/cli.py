"""The `s2h` command: view, annotate, retarget, batch, evaluate, train, render, gestures.
Errors print one line naming the file and the problem, never a traceback."""

from __future__ import annotations

import argparse
import dataclasses
import sys
import traceback
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING

from s2h_viewer.errors import S2HError
from s2h_viewer.wording import counted

if TYPE_CHECKING:
    from s2h_viewer.hand.model import HandModel


def _cmd_evaluate(args: argparse.Namespace) -> int:
    from s2h_viewer import samples
    from s2h_viewer.io.files import load_hand_file, load_motion_file
    from s2h_viewer.retarget.evaluation import evaluate, format_markdown, summarise, write_results

    hands = {h.name: h for h in samples.load_sample_hands("all")}
    motions = samples.load_sample_motions() if not args.motion else []
    performer = load_hand_file(args.rig, _rig_options(args)) if args.rig else None
    for path in args.motion or []:  # a motion file on its own rig (a recording: on the hand fitted to it)
        motion, rig = load_motion_file(path, performer, options=_rig_options(args))
        if rig is not None:
            _say_posed_rest(path, rig, "--rig")
            hands[motion.hand_name] = rig
        elif motion.hand_name not in hands:
            hands[motion.hand_name] = samples.sample_performer(motion, path)  # names the file where it is none
        motions.append(motion)

    targets = args.target or samples.hand_names("test")
    for target in targets:  # a target may also be a hand file (a real rig, say)
        if target not in hands:
            hands[target] = load_hand_file(target, _rig_options(args))
    methods = _method_names(args.methods)
    total = len(motions) * len(targets) * len(methods)
    with _progress_bar("evaluate", total, "clip", disable=args.quiet):
        rows = evaluate(motions, hands, targets, methods)
    summary = summarise(rows)
    held_out = set(samples.hand_names("test"))
    kind = "held-out hand" if set(targets) <= held_out else "target hand"
    print(f"{counted(len(motions), 'motion')} x {counted(len(targets), kind)} "
          f"({', '.join(Path(t).name for t in targets)})")
    print(format_markdown(summary))
    for path in write_results(rows, summary, args.out):
        print(f"wrote {path}")
    return 0


@contextmanager
def _progress_bar(desc: str, total: int, unit: str, disable: bool | None) -> Iterator[None]:
    """A tqdm bar on stderr of ``total`` units that follows what the block reports (`retarget.progress`),
    naming the running stage; ``disable`` None: no bar when stderr is not a terminal."""
    from tqdm import tqdm

    from s2h_viewer.retarget.progress import reporting

    with tqdm(total=total, desc=desc, unit=unit, unit_scale=True, file=sys.stderr, disable=disable) as bar:
        def hook(fraction: float, what: str) -> None:
            if what:
                bar.set_postfix_str(what, refresh=False)
            bar.update(round(fraction * total) - bar.n)

        with reporting(hook):
            yield


def _render_comparison(args: argparse.Namespace) -> int:
    """`s2h render --motion`: compare mode off screen, one frame (PNG) or the timeline, or frames
    ``--start`` to ``--end`` of it (MP4, GIF); the frames are checked against the clip before any retarget."""
    from tqdm import tqdm

    from s2h_viewer.io.files import load_hand_file
    from s2h_viewer.render.caption import clip_at, page_caption
    from s2h_viewer.render.compare_scene import ViewOptions, render_comparison
    from s2h_viewer.render.video import VIDEO_SUFFIXES, frame_range
    from s2h_viewer.retarget.comparison import build_comparison, with_distinct_names

    motion, source = _performed(args.motion, args.source, _rig_options(args))
    if Path(args.out).suffix.lower() in VIDEO_SUFFIXES:
        frames = frame_range(motion.n_frames, args.start, args.end, clip=args.motion)
    elif args.start is not None or args.end is not None:
        raise S2HError(f"{args.out}: --start and --end choose the frames of a video (.mp4, .gif); a .png is "
                       f"one --frame")
    else:
        frames = frame_range(motion.n_frames, args.frame or 0, args.frame or 0, clip=args.motion)  # the one frame
    names = args.target or ["iris", "laurel"]
    targets = [load_hand_file(t, _rig_options(args)) for t in names]
    _say_hand_notes([(source, args.source or args.motion), *zip(targets, names)])
    targets = with_distinct_names(targets)  # named as the viewer names them (its corrections sidecars say them)
    methods = _method_names(args.methods or "tbs_copy,asrn")
    options = ViewOptions(camera="default" if args.view == "three_quarter" else args.view, skeleton=args.skeleton,
                          contacts=args.contacts)
    with _progress_bar("retarget", len(targets) * len(methods), "retarget", disable=args.quiet):
        comparison = build_comparison(motion, source, targets, methods)
    comparison = _fixed(comparison, args.corrections or [])
    with tqdm(total=len(frames), desc="render", unit="frame", file=sys.stderr, disable=args.quiet) as bar:
        path = render_comparison(comparison, args.out, frame=frames.start, frames=frames,
                                 progress=lambda done, total: bar.update(done - bar.n), options=options,
                                 caption=lambda f: page_caption(clip_at(motion.name, motion.labels, f), f,
                                                                motion.n_frames, motion.fps, [t.name for t in targets]))
    print(f"wrote {path}")
    return 0


def _fixed(comparison, files: list[str]):
    """``comparison`` with each corrections sidecar of ``files`` applied to the retarget it was made on (its method
    onto its target, by name), as the viewer's Fix > Load corrections: an error naming the file where the picture
    has no such retarget."""
    from s2h_viewer.errors import InputFileError
    from s2h_viewer.io.corrections import load_corrections
    from s2h_viewer.retarget.comparison import corrected_result, source_semantics

    results = list(comparison.results)
    source_asm = source_semantics(comparison.motion, comparison.source)[1] if files else None
    for file in files:
        fixes = load_corrections(file, comparison.n_frames)
        index = next((i for i, r in enumerate(results) if (r.method, r.target.name) == (fixes.method, fixes.target)),
                     None)
        if index is None:
            shown = ", ".join(dict.fromkeys(f"{r.method} -> {r.target.name}" for r in results))
            raise InputFileError(file, f"made on {fixes.method} -> {fixes.target}, which this picture does not hold "
                                       f"(it holds {shown}): add that --target and method")
        results[index] = corrected_result(results[index], fixes.corrections, comparison.motion, comparison.source,
                                          source_asm)
        keys = fixes.corrections.n_keys
        print(f"{file}: {counted(keys, 'correction key')} applied to {fixes.method} -> {fixes.target}")
    return dataclasses.replace(comparison, results=results)


def _cmd_render(args: argparse.Namespace) -> int:
    if args.motion:
        return _render_comparison(args)
    if args.source:
        raise S2HError(NO_MOTION_FOR_SOURCE)
    # a retarget's options without the motion drew the sample hands' gallery, saying nothing of them
    given = [f"--{name}" for name in ("target", "methods", "corrections", "frame", "start", "end", "contacts")
             if getattr(args, name) not in (None, False)]
    if given:
        raise S2HError(f"{', '.join(given)} draw retargets of a motion: give the --motion too (without it, s2h render "
                       f"draws sample hands in one gesture: --hands, --gesture)")
    import numpy as np
    import torch

    from s2h_viewer import samples
    from s2h_viewer.hand.rotations import tbs_euler_to_quat
    from s2h_viewer.io.files import load_hand_file
    from s2h_viewer.motions.fitting import fit_gesture_angles
    from s2h_viewer.motions.gestures import gesture
    from s2h_viewer.render.offscreen import render_hands

    names = samples.hand_names(args.hands) if args.hands in ("all", "train", "test") else args.hands.split(",")
    hands = [load_hand_file(n, _rig_options(args)) for n in names]
    chosen = gesture(args.gesture)
    poses = [tbs_euler_to_quat(torch.as_tensor(fit_gesture_angles(h, [chosen])[0])).numpy() if args.fit
             else tbs_euler_to_quat(torch.as_tensor(np.radians(chosen.angles_deg))).numpy() for h in hands]
    splits = {h["name"]: h["split"] for h in samples.read_index()["hands"]}
    labels = [f"{h.name} ({splits.get(h.name, 'file')})" for h in hands]
    path = render_hands(hands, poses, args.out, labels=labels, columns=args.columns, view=args.view,
                        show_skeleton=args.skeleton, show_frames=args.frames)
    print(f"wrote {path}")
    return 0


def _cmd_train(args: argparse.Namespace) -> int:
    from s2h_viewer import samples
    from s2h_viewer.retarget.asrn.inference import MODELS_DIR
    from s2h_viewer.retarget.asrn.training import default_config, train

    changes = {name: value for name, value in (("contact_weight", args.contact_weight),
                                               ("anatomy_weight", args.anatomy_weight),
                                               ("pose_scripts_per_hand", args.pose_scripts), ("steps", args.steps))
               if value is not None}
    config = default_config(args.kind, seed=args.seed, scripts_per_hand=args.scripts, extra_hands=args.extra_hands,
                            **changes)
    out = Path(args.out) if args.out else MODELS_DIR / f"{args.kind}.pt"
    history = train(config, samples.load_sample_hands("train"), out, resume=args.resume, show_progress=not args.quiet,
                    stop_at=args.stop_at)
    if history:
        print(f"{args.kind}: step {history[-1]['step']}, loss {history[-1]['loss']:.5f} "
              f"(semantic {history[-1]['semantic']:.5f}) -> {out}")
    return 0


def _method_names(text: str) -> list[str]:
    """The comma-separated method names of ``text``, each checked against the registry (one error line naming
    what is not a method: the window would drop it silently, the render would fail half way)."""
    from s2h_viewer.retarget.methods import METHODS

    names = [name.strip() for name in text.split(",") if name.strip()]
    unknown = [name for name in names if name not in METHODS]
    if unknown or not names:
        what = ("names no method" if not names else f"{', '.join(map(repr, unknown))} "
                + ("is not a retargeting method" if len(unknown) == 1 else "are not retargeting methods"))
        raise S2HError(f"--methods {text!r}: {what}; available: {', '.join(METHODS)}")
    return list(dict.fromkeys(names))


def _rig_options(args: argparse.Namespace):
    from s2h_viewer.io.files import RigOptions

    return RigOptions(side=args.side, scheme=args.scheme, joint_map=args.joint_map,
                      animation=getattr(args, "animation", None), fps=getattr(args, "fps", None),
                      unit=getattr(args, "unit", None), hinges_from=getattr(args, "hinges_from", None))


def _performed(motion_file: str, source_file: str | None, options):
    """A motion file and the hand it is performed on: ``source_file`` where given (the rig it was made for, its
    animation read onto that rig's bones), else its own rig or its sample hand. A rig whose rest is a pose (a
    skeleton-only clip, `semantics.rest_pose`) is said on stderr."""
    from s2h_viewer.io.files import load_hand_file, load_motion_file
    from s2h_viewer.samples import sample_performer

    given = load_hand_file(source_file, options) if source_file else None
    motion, rig = load_motion_file(motion_file, given, options)
    source = rig or given or sample_performer(motion, motion_file)
    _say_posed_rest(motion_file, source, "--source")
    return motion, source


def _say_posed_rest(motion_file: str, hand, option: str) -> None:
    """On stderr, where ``hand``'s skeleton rests in a pose (`semantics.rest_pose`): that, and ``option`` to mend it."""
    if hand.meta.get("rest_note"):
        print(f"{motion_file}: {hand.meta['rest_note']}; give the hand file of the rig it was made for: {option} FILE",
              file=sys.stderr)


def _cmd_rig(args: argparse.Namespace) -> int:
    """`s2h rig FILE`: what was recognised; an editable joint-map template where recognition fails."""
    from s2h_viewer.errors import TooFewBonesError, UnrecognisedRigError
    from s2h_viewer.hand import topology as topo
    from s2h_viewer.io.files import (GLTF_FAMILY, joint_map_sidecar, joint_map_template, joint_map_template_path,
                                     list_animations, recognise_file, rig_unit, save_joint_map)
    from s2h_viewer.io.units import UNIT_NAMES

    path = Path(args.file)
    try:
        mapping = recognise_file(path, _rig_options(args))
    except TooFewBonesError:
        raise  # no joint map can make it a hand: no template
    except UnrecognisedRigError as exc:
        side = args.side or "right"
        template = save_joint_map(path, joint_map_template(path, args.side), side,
                                  args.template or joint_map_template_path(path))
        print(f"s2h: error: {exc}", file=sys.stderr)
        print(f"wrote {template}: fill in the empty joints (bone names of {path.name}), then save it as "
              f"{joint_map_sidecar(path, side).name} beside the file (the {side} hand's map, picked up there) or "
              f"pass it with --joint-map; nothing reads the template itself")
        return 2
    print(f"{path}: {mapping.scheme} scheme, {mapping.side} hand (side from {mapping.side_from}), "
          f"confidence {mapping.confidence:.2f}")
    for f in topo.FINGERS:
        bones = [mapping.joints.get(f"{f}_{lv}", "(extrapolated)") for lv in topo.FINGER_LEVELS[f]]
        print(f"  {f:6s} {' > '.join(bones)}")
    print(f"  wrist  {mapping.joints['wrist']}")
    unit = rig_unit(path, mapping, _rig_options(args))
    print(f"  unit   {UNIT_NAMES[unit.unit]} (from {unit.decided_by}"
          + (", unsure: check it or pass --unit)" if not unit.sure else ")"))
    if mapping.palm_bones:
        print(f"  palm bones (their skin moves with the wrist): {', '.join(mapping.palm_bones)}")
    for note in mapping.notes:
        print(f"  note: {note}")
    if path.suffix.lower() in (*GLTF_FAMILY, ".fbx", ".bvh"):
        clips = list_animations(path)
        print(f"  animations: {', '.join(f'[{i}] {c}' for i, c in enumerate(clips)) if clips else 'none'}")
    return 0


def _cmd_annotate(args: argparse.Namespace) -> int:
    import time

    import numpy as np

    from s2h_viewer import samples
    from s2h_viewer.annotate.hinges import LABEL as HINGE_LABEL
    from s2h_viewer.annotate.report import annotation_report
    from s2h_viewer.annotate.solver import solve_tbs_frames
    from s2h_viewer.io.annotation import Annotation, hand_side, save_annotation
    from s2h_viewer.io.files import load_hand_file

    names = args.hands or samples.hand_names("test")
    results = []
    for name in names:
        hand = load_hand_file(name, _rig_options(args))
        start = time.perf_counter()
        solution = solve_tbs_frames(hand)
        if hand.meta.get("annotation") == "solver":  # the loaded hand's frames: checked against any hinges
            set_by = hand.meta["frame_set_by"]
            solution = dataclasses.replace(
                solution, frames=hand.rest_frames.copy(), diagnostics=hand.meta["solver_diagnostics"],
                confidence=np.asarray(hand.meta["frame_confidence"], dtype=float),
                basis=[HINGE_LABEL if by == HINGE_LABEL else basis for by, basis in zip(set_by, solution.basis)])
        results.append((hand, solution, time.perf_counter() - start))
        if args.save:
            path = samples.ASSETS_DIR / "hands" / f"{name}.npz" if Path(name).suffix == "" else Path(name)
            written = save_annotation(Annotation(solution.frames, ["solver"] * len(solution.frames),
                                                 solution.confidence, solution.diagnostics), path, hand_side(hand))
            print(f"wrote {written}")
    print(annotation_report(results, against_truth=args.report))
    return 0


def _say_hand_notes(hands: list[tuple[HandModel, str]]) -> None:
    """Each (hand, file)'s guessed length unit, and for the targets (all but the first, the source) what the
    viewer's banner says on their cells: frames the solver is unsure of or guessed."""
    from s2h_viewer.annotate.trust import frame_warning
    for index, (hand, path) in enumerate(hands):
        if hand.meta.get("unit_note"):
            print(f"{path}: {hand.meta['unit_note']}")
        warning = frame_warning(hand) if index else None
        if warning is not None:
            print(f"{path}: {warning.describe()}")


def _cmd_retarget(args: argparse.Namespace) -> int:
    from s2h_viewer.io.files import check_motion_export, export_sidecar, load_hand_file, save_motion_file
    from s2h_viewer.retarget import retarget

    check_motion_export(args.out)  # before the retarget, not after it
    options = _rig_options(args)
    motion, source = _performed(args.motion, args.source, options)
    target = load_hand_file(args.target, options)
    _say_hand_notes([(source, args.source or args.motion), (target, args.target)])
    if motion.fit is not None:
        print(f"{args.motion}: {motion.fit.describe()}")
    with _progress_bar(f"retarget ({args.method})", motion.n_frames, "frame",
                       disable=args.quiet or None):  # None: no bar when not on a terminal
        retargeted = retarget(motion, source, target, args.method)
    fixes = _corrections(args, retargeted, target) if args.corrections else None
    if fixes is not None:
        from s2h_viewer.retarget.corrections import corrected_motion
        retargeted = corrected_motion(retargeted, fixes.corrections)
    path = save_motion_file(args.out, retargeted, target)
    sidecar = export_sidecar(path, target)
    print(f"{motion.name}: {motion.n_frames} frames, {source.name} -> {target.name} ({args.method}) -> {path}"
          + (f" (TBS frames: {sidecar})" if sidecar else ""))
    from s2h_viewer.io.corrections import is_corrections_file, save_corrections, sidecar_path
    beside = sidecar_path(path)
    if fixes is not None:
        record = save_corrections(beside, dataclasses.replace(
            fixes, clip=motion.name, fps=motion.fps, source=source.name, target=target.name, method=args.method))
        keys = fixes.corrections.n_keys
        print(f"applied {counted(keys, 'correction key')} ({fixes.corrections.describe()}); "
              f"recorded in {record}")
    elif is_corrections_file(beside):  # an earlier export's: kept (it may be their only record)
        print(f"{beside.name} beside it is an earlier export's corrections, left as it was: this motion has none of "
              f"them (--corrections {beside.name} applies them)")
    return 0


def _corrections(args: argparse.Namespace, retargeted, target):
    """``--corrections FILE`` read and checked against the retargeted clip (`io.corrections`); a note where it
    was made on another target or method (its keys are per joint, so they still apply)."""
    from s2h_viewer.io.corrections import load_corrections
    fixes = load_corrections(args.corrections, retargeted.n_frames)
    if (fixes.target, fixes.method) != (target.name, args.method):
        print(f"{args.corrections}: made on {fixes.method} -> {fixes.target}; applied to {args.method} -> "
              f"{target.name}")
    if abs(fixes.fps - retargeted.fps) > 1e-6:
        print(f"{args.corrections}: made on a clip at {fixes.fps:g} fps; this one is at {retargeted.fps:g} fps (its "
              f"keys are frame numbers: applied at the same frames)")
    return fixes


def _cmd_check(args: argparse.Namespace) -> int:
    """`s2h check FILE`: how far each animation's fingers bend sideways (`semantics.flexion`), on its own rig."""
    from dataclasses import replace

    import numpy as np
    import torch

    from s2h_viewer.errors import InputFileError
    from s2h_viewer.hand.kinematics import forward_kinematics
    from s2h_viewer.io.files import list_animations, load_motion_file
    from s2h_viewer.samples import sample_performer
    from s2h_viewer.semantics.flexion import finger_peaks, sideways_peak

    options = _rig_options(args)
    names = list_animations(args.file) if args.animation is None else [str(args.animation)]
    if not names:
        raise InputFileError(args.file, "has no animations to check (s2h check reads the animations of a file)")
    rig = None
    worst = float("nan")
    longest = 0
    for index in range(len(names)):
        chosen = replace(options, animation=index if args.animation is None else args.animation)
        motion, rig = load_motion_file(args.file, rig, chosen)
        if rig is None:
            rig = sample_performer(motion, args.file)
        with torch.no_grad():
            positions = forward_kinematics(rig, torch.as_tensor(motion.q_tbs, dtype=torch.float64)).positions.numpy()
        peak = sideways_peak(positions)
        longest = max(longest, motion.n_frames)
        worst = np.nanmax([worst, peak.degrees]) if not np.isnan(peak.degrees) else worst
        # the pose held at each frame named (" (Sign 3)", " (between poses)"), in a clip of several poses
        held = motion.held_at if len(set(motion.labels)) > 1 else (lambda frame: "")
        print(f"{motion.name}: {motion.n_frames} frames; {peak.describe()}"
              + (held(peak.frame) if peak.frame >= 0 else ""))
        if args.joints:
            for joint, p in finger_peaks(positions).items():
                print(f"    {joint:10s} " + ("does not curl" if np.isnan(p.degrees) else
                                             f"{p.degrees:4.0f} deg sideways at frame {p.frame}{held(p.frame)}"))
    side = rig.meta.get("side", "right") if rig is not None else "right"
    what = f"{len(names)} animation(s)" if args.animation != "all" else "every animation as one clip"
    print(f"{args.file}: {side} hand, {what}; worst sideways flexion at the tightest curls: "
          + ("none (no finger curls)" if np.isnan(worst) else f"{worst:.0f} deg") +
          " (0 = a clean curl toward the palm; authored clips of real avatars reach 8-22)")
    if len(names) > 1 and longest <= POSE_FRAMES:
        # a still pose is all "tightest curl": a finger bent 12 deg, whose axis is loose, counted as a fist's
        print(f"{args.file}: each animation holds one pose (a pose library): `--animation all` reads them as one clip, "
              "each joint at its tightest curls over all of them")
    return 0


#: `s2h check`: animations this short each hold one pose (the Godot pose library's hold 2 frames)
POSE_FRAMES = 5


def _cmd_batch(args: argparse.Namespace) -> int:
    from s2h_viewer.batch.plan import BatchUsageError, TaskOptions
    from s2h_viewer.batch.runner import BatchConfig, run_batch

    if args.workers is not None and args.workers < 1:
        raise BatchUsageError(f"--workers {args.workers}: at least one worker is needed")

    source = args.source  # a file by its whole path: workers may run elsewhere
    source = str(Path(source).resolve()) if source and Path(source).is_file() else source
    config = BatchConfig(args.motions, args.targets, [m for m in args.methods.split(",") if m], args.out,
                         TaskOptions(format=args.format, side=args.side, render=args.pictures, unit=args.unit,
                                     source=source, animation=args.animation),
                         scheduler=args.scheduler, workers=args.workers)
    result = run_batch(config, show_progress=False if args.quiet else None)
    ok = sum(r["status"] == "ok" for r in result.rows)
    not_run = sum(r["status"] == "not run" for r in result.rows)
    warned = sum(bool(r.get("warning")) for r in result.rows if r["status"] == "ok")
    print(f"{counted(len(result.rows), 'task')}: {ok} ok" + (f" ({warned} with a warning)" if warned else "")
          + f", {len(result.failed)} failed" + (f", {not_run} not run" if not_run else "")
          + (f" ({result.skipped} finished by an earlier run)" if result.skipped else "")
          + (f" ({counted(result.redone, 'task')} done again over an earlier run's: made with other inputs or "
             f"options)" if result.redone else "")
          + f", {result.seconds:.1f} s" + (" (interrupted: run it again to finish)" if result.interrupted else ""))
    if result.rigs:
        names = ", ".join(Path(rig).name for rig in result.rigs[:5]) + (", ..." if len(result.rigs) > 5 else "")
        print(f"left out {counted(len(result.rigs), 'file')} of no animation (rigs: clips beside them that lack a "
              f"skin of their own are read onto them): {names}")
    failed = result.failed
    for row in failed[:10]:
        print(f"  failed: {row['motion']} -> {row['target']} ({row['method']}): {row['error']}", file=sys.stderr)
    if len(failed) > 10:
        print(f"  ... and {len(failed) - 10} more (see the summary)", file=sys.stderr)
    also = f" (and the {counted(result.earlier, 'task')} other batches left in {config.out})" if result.earlier else ""
    print(f"wrote {result.summary}{also}\nwrote {result.report}")
    return result.exit_code


def _cmd_view(args: argparse.Namespace) -> int:
    from s2h_viewer.app.main_window import CompareSetup, default_setup, run
    from s2h_viewer.io.files import load_hand_file

    if args.source and not args.motion:
        raise S2HError(NO_MOTION_FOR_SOURCE)
    setup = default_setup()
    if args.motion:
        motion, source = _performed(args.motion, args.source, _rig_options(args))
        setup = CompareSetup(motion, source, setup.targets, path=Path(args.motion), options=_rig_options(args),
                             rig_file=args.source)
    if args.target:
        setup.targets = [load_hand_file(t, _rig_options(args)) for t in args.target]
    if args.methods:
        setup.methods, setup.methods_named = _method_names(args.methods), True
    if setup.motion.fit is not None:
        print(f"{args.motion}: {setup.motion.fit.describe()}")
    return run(setup, _rig_options(args))


#: `s2h render --view`: `render.scene.CAMERA_DIRECTIONS`' names (not imported: `s2h --help` loads no pyvista)
VIEWS = ("three_quarter", "palm", "back", "side")
NO_MOTION_FOR_SOURCE = "--source names the rig a --motion file was made for: give the --motion too"
SOURCE_HELP = ("hand file (or sample name) of the rig the motion was made for, where its file lacks it (a skeleton "
               "with no mesh resting in a pose: s2h says so); a glTF/FBX animation is read onto that rig's bones "
               "(default: the file's own rig, or its sample hand)")


def _add_rig_options(parser: argparse.ArgumentParser,
                     animation_default: str = "the first; `s2h rig FILE` lists them") -> None:
    """The options that say how to read a hand or motion file; ``animation_default``: what no --animation reads."""
    from s2h_viewer.hand.rig_mapping import SCHEMES, SIDES
    from s2h_viewer.io.units import UNITS

    parser.add_argument("--side", choices=SIDES, help="which hand of a character, or override the side a lone "
                                                       "hand's names or geometry give (default: detect)")
    parser.add_argument("--scheme", choices=list(SCHEMES), help="joint naming scheme (default: detect)")
    parser.add_argument("--joint-map", help='JSON file {"wrist": "<bone>", "index_mcp": "<bone>", ...} (default: '
                                            "<stem>.<side>.joints.json beside each hand file, if there)")
    parser.add_argument("--animation", help="which animation (glTF) or take (FBX) of a motion file: name or index "
                                            f"(default: {animation_default}), or `all`: every one in turn, "
                                            "one clip labelled by animation (a pose library)")
    parser.add_argument("--fps", type=float, help="frame rate of a tracking recording that does not say it "
                                                  "(keypoint .npy/.npz; default 30), or to override its own")
    parser.add_argument("--unit", choices=list(UNITS), help="length unit of the rig and motion files (default: "
                                                            "the format's where the hand's size fits it, else "
                                                            "guessed from the size, and said)")
    parser.add_argument("--hinges-from", metavar="FILE",
                        help="a motion or pose file on the same skeleton as the hand files (glTF/FBX): the hinge "
                             "each finger joint turns about in its animations sets that joint's bend axis where the "
                             "solver's is more than 10 deg off (default: a rig file's own animations, if any)")


def _cmd_gestures(args: argparse.Namespace) -> int:
    from s2h_viewer.motions.gestures import GESTURES

    for g in GESTURES.values():
        contacts = ", ".join(f"{a}-{b}" for a, b in sorted(g.contacts)) or "-"
        print(f"{g.name:14s} {g.category:8s} {g.description:55s} contacts: {contacts}")
    return 0


def _add_debug(parser: argparse.ArgumentParser, default=False) -> None:
    parser.add_argument("--debug", action="store_true", default=default,
                        help="on an error, also print the traceback of what went wrong underneath")


def build_parser() -> argparse.ArgumentParser:
    from s2h_viewer.io.units import UNITS

    parser = argparse.ArgumentParser(prog="s2h", description="Transfer hand motion semantics between avatars.")
    _add_debug(parser)
    sub = parser.add_subparsers(dest="command", required=True)

    ev = sub.add_parser("evaluate", help="retarget sample motions onto held-out hands and score each method")
    ev.add_argument("--methods", default="copy,tbs_copy,dm,asrn,asm_opt", help="comma-separated method names")
    ev.add_argument("--motion", action="append", help="motion file (.npz .bvh .glb .gltf .fbx, or a tracking "
                    "recording .json .npy; default: the shipped samples); repeatable")
    ev.add_argument("--target", action="append", help="target sample hand name or hand file (default: the test "
                                                      "split); repeatable")
    ev.add_argument("--rig", help="the rig the --motion files are performed on, where it is not in them (a file "
                    "of poses without a mesh, and the skinned rig they were authored on); default: each file's own")
    ev.add_argument("--out", default="results", help="folder for evaluation.csv and evaluation.md")
    ev.add_argument("--quiet", action="store_true", help="no progress bar")
    _add_rig_options(ev)
    ev.set_defaults(func=_cmd_evaluate)

    rd = sub.add_parser("render", help="render sample hands side by side in one gesture (PNG, off screen)")
    rd.add_argument("--hands", default="all", help="all, train, test, or comma-separated sample names or hand "
                                                    "files (.glb .gltf .fbx .bvh .npz)")
    rd.add_argument("--gesture", default="relaxed", help="gesture name (see `s2h gestures`)")
    rd.add_argument("--no-fit", dest="fit", action="store_false", help="use the authored angles as they are")
    rd.add_argument("--view", default="three_quarter", choices=VIEWS,
                    help="the camera: from the palm and the thumb's side (default), the palm, the back, the thumb's "
                         "side (a pinch's touch)")
    rd.add_argument("--columns", type=int, default=6)
    rd.add_argument("--skeleton", action="store_true", help="draw bones through a see-through skin")
    rd.add_argument("--contacts", action="store_true", help="with --motion: the contact overlay (kept green, lost "
                                                            "red, invented blue), as View > Contact overlay")
    rd.add_argument("--corrections", metavar="FILE", action="append",
                    help="with --motion: a corrections sidecar (Fix > Save corrections, or beside a motion export) "
                         "applied to the retarget it was made on, drawn fixed (repeatable)")
    rd.add_argument("--frames", action="store_true", help="draw each joint's TBS frame (twist red, bend green, "
                                                          "splay blue) through a see-through skin")
    rd.add_argument("--out", default="hands.png", help=".png, or with --motion also .mp4 / .gif (the whole timeline, "
                                                        "or --start to --end)")
    rd.add_argument("--motion", help="compare mode: retarget this motion file and render the grid of methods")
    rd.add_argument("--source", help="with --motion: " + SOURCE_HELP)
    rd.add_argument("--target", action="append", help="with --motion: target hand file or sample name (repeatable)")
    rd.add_argument("--methods", help="with --motion: comma-separated methods (default tbs_copy,asrn)")
    rd.add_argument("--frame", type=int, help="with --motion and a .png: the frame to draw (default 0)")
    rd.add_argument("--start", type=int, help="with --motion and a .mp4 / .gif: the first frame (from 0; default 0)")
    rd.add_argument("--end", type=int, help="with --motion and a .mp4 / .gif: the last frame, included (default: "
                                            "the clip's last)")
    rd.add_argument("--quiet", action="store_true", help="no progress bars")
    _add_rig_options(rd)
    rd.set_defaults(func=_cmd_render)

    vw = sub.add_parser("view", help="the desktop viewer: compare retargeting methods on a timeline")
    vw.add_argument("--motion", help="motion file or tracking recording (default: the shipped gestures clip)")
    vw.add_argument("--source", help="with --motion: " + SOURCE_HELP)
    vw.add_argument("--target", action="append", help="target hand file or sample name (default: iris, laurel)")
    vw.add_argument("--methods", help="comma-separated methods (default: the last used, or tbs_copy,asrn)")
    _add_rig_options(vw)
    vw.set_defaults(func=_cmd_view)

    an = sub.add_parser("annotate", help="find TBS frames by rays cast at each hand's mesh; report and save them")
    an.add_argument("hands", nargs="*", help="hand files (.glb .gltf .fbx .npz) or sample names (default: test split)")
    an.add_argument("--report", action="store_true", help="compare with the ground-truth frames of procedural "
                                                           "hands: mean/max angle error per finger")
    an.add_argument("--save", action="store_true", help="write each hand's annotation sidecar (<stem>.<side>.tbs.json)")
    _add_rig_options(an)
    an.set_defaults(func=_cmd_annotate)

    rt = sub.add_parser("retarget", help="retarget a motion file onto a target hand and export it")
    rt.add_argument("--motion", required=True, help="motion file (.npz .bvh .glb .gltf .fbx), or a tracking "
                    "recording: WebXR/OpenXR joint poses or MediaPipe landmarks (.json), keypoints (.npy .npz)")
    rt.add_argument("--source", help=SOURCE_HELP)
    rt.add_argument("--target", required=True, help="target hand file or sample name")
    rt.add_argument("--method", default="asrn", help="copy, tbs_copy, dm, asrn or asm_opt")
    rt.add_argument("--out", required=True, help="output file: .glb (on the target rig), .bvh, .npz, or .fbx (through "
                                                       "Blender: `make blender`)")
    rt.add_argument("--corrections", metavar="FILE", help="a corrections sidecar (<file name>.corrections.json, written by "
                    "the viewer's motion export or Fix > Save corrections): its per-joint offset keys applied to the "
                    "retarget before it is written, and recorded beside the output")
    rt.add_argument("--quiet", action="store_true", help="no progress bar")
    _add_rig_options(rt)
    rt.set_defaults(func=_cmd_retarget)

    bt = sub.add_parser("batch", help="retarget motion files onto many targets with several methods, on Dask; "
                                      "a summary.csv and a report.html of every task")
    bt.add_argument("--motions", nargs="+", required=True, metavar="PATH",
                    help="motion files or folders of them (.npz .bvh .glb .gltf .fbx, tracking recordings .json "
                         ".npy; folders searched recursively)")
    bt.add_argument("--targets", nargs="+", required=True, metavar="PATH",
                    help="target hand files, folders of them, or shipped sample names")
    bt.add_argument("--methods", default="tbs_copy,asrn", help="comma-separated, of copy, tbs_copy, dm, asrn, "
                                                               "asm_opt (default tbs_copy,asrn)")
    bt.add_argument("--out", required=True, help="output folder: <motion>/<target>/<method>.<format>, summary.csv, "
                                                 "report.html; a rerun into it skips finished tasks")
    bt.add_argument("--format", default="glb", choices=["glb", "bvh", "npz"],
                    help="motion output (default glb: the target's own file with the animation)")
    bt.add_argument("--scheduler", help="address of a running Dask scheduler (tcp://host:8786) whose workers have "
                                        "s2h-viewer installed (default: a local cluster on this machine)")
    bt.add_argument("--workers", type=int, help="local cluster worker processes (default: one per core)")
    bt.add_argument("--no-pictures", dest="pictures", action="store_false",
                    help="skip the worst frame's picture of each task (faster; the report has none)")
    bt.add_argument("--side", choices=["right", "left"], help="which hand of full-body characters (default: detect)")
    bt.add_argument("--source", help="hand file of the rig the motions were made for, for those whose files lack "
                                     "it (a glTF/FBX skeleton with no mesh or resting in a pose, an npz on no "
                                     "shipped hand); a clip it does not fit (other bones) is read onto a rig of no "
                                     "animation beside it, else its own (default: those alone)")
    bt.add_argument("--unit", choices=list(UNITS), help="length unit of every rig and motion file (default: the "
                                                        "format's, else guessed from the hand's size)")
    bt.add_argument("--animation", help="which animation (glTF) or take (FBX) of each motion file of several: name "
                                        "or index, or `all`: every one in turn, one clip labelled by animation (a "
                                        "pose library, scored pose by pose) (default: each its own motion, "
                                        "<file>.<animation>)")
    bt.add_argument("--quiet", action="store_true", help="no progress bar")
    bt.set_defaults(func=_cmd_batch)

    tr = sub.add_parser("train", help="train ASRN or DM on the training hands (CPU, seeded, resumable)")
    tr.add_argument("--kind", choices=["asrn", "dm"], default="asrn", help="which network (default: asrn)")
    tr.add_argument("--steps", type=int, help="training steps (default: the shipped network's, 12000 for asrn, 4000 "
                                              "for dm)")
    tr.add_argument("--seed", type=int, default=0, help="seeds the data and the training (default: 0, the shipped)")
    tr.add_argument("--scripts", type=int, default=6, help="random gesture scripts per training hand (default: 6)")
    tr.add_argument("--pose-scripts", type=int, help="clips through random key poses over the whole pose space per "
                                                     "training hand (default: the shipped network's, 6 for asrn, 0 "
                                                     "for dm)")
    tr.add_argument("--out", help="checkpoint path (default: assets/models/<kind>.pt, replacing the shipped network: "
                                  "pass another path to keep it)")
    tr.add_argument("--extra-hands", type=int, default=16, help="unnamed procedural hands added to the 8 shipped "
                                                                 "training hands (default: 16)")
    tr.add_argument("--contact-weight", type=float, help="weight of the pad contact loss (shipped: 300 for asrn, "
                                                         "0 for dm as in the paper)")
    tr.add_argument("--anatomy-weight", type=float, help="weight of L_ana (shipped: 1.0 for asrn, 0.1 for dm as in "
                                                         "the paper)")
    tr.add_argument("--resume", action="store_true", help="continue from the checkpoint at --out")
    tr.add_argument("--stop-at", type=int, help="end this run at that step (continue later with --resume)")
    tr.add_argument("--quiet", action="store_true")
    tr.set_defaults(func=_cmd_train)

    rg = sub.add_parser("rig", help="what s2h recognises in a rig file (scheme, side, joints, animations); "
                                    "writes an editable joint-map template when it cannot")
    rg.add_argument("file", help="rig file (.glb .gltf .fbx .bvh)")
    rg.add_argument("--template", help="where to write the joint-map template (default: "
                                       "<stem>.joints.template.json beside the file, which nothing loads)")
    _add_rig_options(rg)
    rg.set_defaults(func=_cmd_rig)

    ck = sub.add_parser("check", help="how far the fingers of a motion file's animations bend sideways (any rig: "
                                      "glTF/VRM, FBX, BVH, npz, recordings), each on its own rig")
    ck.add_argument("file", help="an animated avatar or motion file")
    ck.add_argument("--joints", action="store_true", help="also each PIP/DIP joint's worst frame")
    _add_rig_options(ck, animation_default="each animation, a line each")
    ck.set_defaults(func=_cmd_check)

    gs = sub.add_parser("gestures", help="list the gesture library with its contact labels")
    gs.set_defaults(func=_cmd_gestures)
    for subparser in sub.choices.values():
        _add_debug(subparser, default=argparse.SUPPRESS)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except (S2HError, KeyError, OSError) as exc:
        if isinstance(exc, OSError):  # a file the command could not write (its folder's name is a file's, say)
            message = f"{exc.filename}: could not write ({exc.strerror or exc})" if exc.filename else str(exc)
        else:
            message = exc.args[0] if isinstance(exc, KeyError) and exc.args else str(exc)
        print(f"s2h: error: {message}", file=sys.stderr)
        if args.debug:
            original = exc.__cause__ or exc.__context__
            traceback.print_exception(original or exc, file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
