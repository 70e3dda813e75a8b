"""The `s2h` command: evaluate, render, gestures. Errors print one line, never a traceback."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from s2h_viewer.errors import S2HError


def _cmd_evaluate(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from s2h_viewer import samples
    from s2h_viewer.io.npz import load_motion
    from s2h_viewer.retarget.evaluation import evaluate, format_markdown, summarise, write_results

    hands = {h.name: h for h in samples.load_sample_hands("all")}
    motions = [load_motion(p) for p in args.motion] if args.motion else samples.load_sample_motions()
    targets = args.target or samples.hand_names("test")
    unknown = [t for t in targets if t not in hands]
    if unknown:
        raise S2HError(f"unknown target hand(s): {', '.join(unknown)}; have {', '.join(hands)}")
    methods = args.methods.split(",")
    total = len(motions) * len(targets) * len(methods)
    with tqdm(total=total, desc="evaluate", unit="clip", file=sys.stderr, disable=args.quiet) as bar:
        def step(what: str) -> None:
            bar.set_postfix_str(what)
            bar.update()
        rows = evaluate(motions, hands, targets, methods, progress=step)
    summary = summarise(rows)
    print(f"{len(motions)} motions x {len(targets)} held-out hands ({', '.join(targets)})")
    print(format_markdown(summary))
    for path in write_results(rows, summary, args.out):
        print(f"wrote {path}")
    return 0


def _cmd_render(args: argparse.Namespace) -> int:
    import numpy as np
    import torch

    from s2h_viewer import samples
    from s2h_viewer.hand.rotations import tbs_euler_to_quat
    from s2h_viewer.motions.fitting import fit_gesture_angles
    from s2h_viewer.motions.gestures import gesture
    from s2h_viewer.render.offscreen import render_hands

    names = samples.hand_names(args.hands) if args.hands in ("all", "train", "test") else args.hands.split(",")
    hands = [samples.load_sample_hand(n) for n in names]
    chosen = gesture(args.gesture)
    poses = [tbs_euler_to_quat(torch.as_tensor(fit_gesture_angles(h, [chosen])[0])).numpy() if args.fit
             else tbs_euler_to_quat(torch.as_tensor(np.radians(chosen.angles_deg))).numpy() for h in hands]
    splits = {h["name"]: h["split"] for h in samples.read_index()["hands"]}
    labels = [f"{h.name} ({splits.get(h.name, '?')})" for h in hands]
    path = render_hands(hands, poses, args.out, labels=labels, columns=args.columns, view=args.view,
                        show_skeleton=args.skeleton, show_frames=args.frames)
    print(f"wrote {path}")
    return 0


def _cmd_gestures(args: argparse.Namespace) -> int:
    from s2h_viewer.motions.gestures import GESTURES

    for g in GESTURES.values():
        contacts = ", ".join(f"{a}-{b}" for a, b in sorted(g.contacts)) or "-"
        print(f"{g.name:14s} {g.category:8s} {g.description:55s} contacts: {contacts}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="s2h", description="Transfer hand motion semantics between avatars.")
    sub = parser.add_subparsers(dest="command", required=True)

    ev = sub.add_parser("evaluate", help="retarget sample motions onto held-out hands and score each method")
    ev.add_argument("--methods", default="copy,tbs_copy", help="comma-separated method names")
    ev.add_argument("--motion", action="append", help="motion npz (default: the shipped samples); repeatable")
    ev.add_argument("--target", action="append", help="target hand name (default: the test split); repeatable")
    ev.add_argument("--out", default="results", help="folder for evaluation.csv and evaluation.md")
    ev.add_argument("--quiet", action="store_true", help="no progress bar")
    ev.set_defaults(func=_cmd_evaluate)

    rd = sub.add_parser("render", help="render sample hands side by side in one gesture (PNG, off screen)")
    rd.add_argument("--hands", default="all", help="all, train, test, or comma-separated names")
    rd.add_argument("--gesture", default="relaxed", help="gesture name (see `s2h gestures`)")
    rd.add_argument("--no-fit", dest="fit", action="store_false", help="use the authored angles as they are")
    rd.add_argument("--view", default="three_quarter", choices=["three_quarter", "palm", "back"])
    rd.add_argument("--columns", type=int, default=6)
    rd.add_argument("--skeleton", action="store_true", help="draw bones through a see-through skin")
    rd.add_argument("--frames", action="store_true", help="draw each joint's TBS frame (twist red, bend green, "
                                                          "splay blue) through a see-through skin")
    rd.add_argument("--out", default="hands.png")
    rd.set_defaults(func=_cmd_render)

    gs = sub.add_parser("gestures", help="list the gesture library with its contact labels")
    gs.set_defaults(func=_cmd_gestures)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except (S2HError, KeyError) as exc:
        message = exc.args[0] if isinstance(exc, KeyError) and exc.args else str(exc)
        print(f"s2h: error: {message}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
