"""What a batch will do: the motion and target files its paths name, and one task per motion x target x method,
each with the files it writes under the output folder. Pure: no Dask, no torch.

Layout: ``OUT/<motion>/<target>/<method>.<format>``, beside it ``<method>.worst.png`` (the worst frame, source
beside retarget) and ``<method>.row.json`` (the task's summary row, written last: a task whose row says ok,
for the same inputs and options, is finished and skipped by a rerun).
"""

from __future__ import annotations

import dataclasses
import glob
import hashlib
import json
import re
from dataclasses import asdict, dataclass, field
from pathlib import Path

from s2h_viewer.errors import S2HError

FORMATS = ("glb", "bvh", "npz")
#: what a folder is searched for: every file the readers take, and VRM avatars (GLB files by another name), so
#: that a file s2h cannot read yet fails its own tasks, saying why, instead of vanishing from the batch
MOTION_SUFFIXES = (".npz", ".bvh", ".glb", ".gltf", ".fbx", ".vrm", ".json", ".npy")
HAND_SUFFIXES = (".npz", ".glb", ".gltf", ".fbx", ".bvh", ".vrm")


class BatchUsageError(S2HError):
    """A batch that cannot be planned (no motions, an unknown method, a path that is not there): exit 2."""


@dataclass(frozen=True)
class Input:
    """A motion or target of the batch: its file (or a shipped sample hand's name) and the name it goes by; for a
    motion file of several animations (takes), which it reads (`io.files.RigOptions.animation`: an index, a name,
    or every one in turn as one clip), None for a file of one clip."""

    path: str
    name: str
    animation: str | int | None = None
    #: rig files beside a glTF/FBX motion (of no animation, in its folder): a motion whose own skeleton lacks a
    #: mesh or rests in a pose is read onto the first whose bones it animates, after --source (`batch.task`)
    rigs: tuple[str, ...] = ()

    def fingerprint(self) -> list:
        """Size and modification time of the file and of its sidecars (TBS frames, joint map: they change how it
        reads); a sample name: itself. A changed input reruns its tasks."""
        p = Path(self.path)
        if not p.is_file():
            return [self.path]
        files = [p, *sorted(p.parent.glob(f"{glob.escape(p.stem)}.*.json"))]
        return [[f.name, f.stat().st_size, f.stat().st_mtime_ns] for f in files if f.is_file()]


@dataclass(frozen=True)
class TaskOptions:
    format: str = "glb"
    side: str | None = None
    render: bool = True  # the worst frame's picture
    unit: str | None = None  # every rig's length unit (None: the format's, else guessed)
    source: str | None = None  # the hand file of the rig the motions were made for, where their files lack it
    #: which animation (take) of each motion file of several: a name or index, `all` (every one in turn as one
    #: clip: a pose library), None: each its own motion
    animation: str | None = None


@dataclass(frozen=True)
class Task:
    motion: Input
    target: Input
    method: str
    out_dir: str
    options: TaskOptions = field(default_factory=TaskOptions)

    @property
    def folder(self) -> Path:
        return Path(self.out_dir) / self.motion.name / self.target.name

    @property
    def output(self) -> Path:
        return self.folder / f"{self.method}.{self.options.format}"

    @property
    def picture(self) -> Path:
        return self.folder / f"{self.method}.worst.png"

    @property
    def sideways_picture(self) -> Path:
        """The frame a finger bends sideways the most at, where that is past the limit (`sideways_broken`)."""
        return self.folder / f"{self.method}.sideways.png"

    @property
    def row_file(self) -> Path:
        return self.folder / f"{self.method}.row.json"

    @property
    def key(self) -> str:
        """What the task's result depends on: inputs (as files are now), method and options."""
        what = [self.motion.path, self.motion.fingerprint(), self.target.path, self.target.fingerprint(),
                self.method, asdict(self.options)] + ([self.motion.animation] if self.motion.animation is not None
                                                      else []) + [[r, Input(r, "").fingerprint()] for r in
                                                                  self.motion.rigs]
        return hashlib.sha256(json.dumps(what, sort_keys=True, default=str).encode()).hexdigest()[:16]

    def finished_row(self) -> dict | None:
        """The row of an earlier run of this very task (same key: same inputs, method and options) if it
        finished: ok with its output there, or failed on its input files (the same files fail the same way;
        a worker's death or an interruption is tried again). Else None."""
        from s2h_viewer.batch.summary import read_row_json
        row = read_row_json(self.row_file)
        if row is None or row.get("key") != self.key:
            return None
        if row.get("status") == "ok":
            return row if self.output.exists() else None
        return row if row.get("status") == "failed" and row.get("input_error") else None


def names_format(path: Path) -> bool:
    """A JSON file in a searched folder is a motion if it says it is a tracking recording near its start
    (sidecars and summaries beside the motions are not)."""
    from s2h_viewer.io.recordings import JSON_FORMATS

    try:
        with path.open("rb") as stream:
            head = stream.read(4096).decode("utf-8", "replace")
    except OSError:
        return False
    return any(f'"{kind}"' in head for kind in JSON_FORMATS) and '"format"' in head


def _files(paths: list[str], suffixes: tuple[str, ...], what: str, allow_names: bool) -> list[Path | str]:
    """Files named by ``paths`` (folders searched recursively for ``suffixes``, sorted), in the order given."""
    from s2h_viewer.samples import ASSETS_DIR, read_index

    samples = {h["name"]: ASSETS_DIR / h["file"] for h in read_index()["hands"]} if allow_names else {}
    sample_names = list(samples)
    found: list[Path | str] = []
    for raw in paths:
        path = Path(raw)
        if path.is_dir():
            inside = sorted(p for p in path.rglob("*") if p.is_file() and p.suffix.lower() in suffixes
                            and not p.name.startswith(".") and (p.suffix.lower() != ".json" or names_format(p)))
            if not inside:
                raise BatchUsageError(f"{path}: no {what} files ({', '.join(suffixes)}) in this folder")
            found += inside
        elif path.exists():
            found.append(path)  # a file (an unreadable one fails its own tasks, with its error)
        elif allow_names and not path.suffix and raw in samples:
            found.append(samples[raw])  # a shipped sample hand, by name: its file (given twice, it runs once)
        else:
            names = f" or a shipped hand ({', '.join(sample_names)})" if allow_names and not path.suffix else ""
            raise BatchUsageError(f"{raw}: no such file or folder{names}")
    return found


def _named(items: list[Path | str]) -> list[Input]:
    """Each file named by its stem; stems that clash get their parent folders' names before them."""
    inputs: list[Input] = []
    seen: set[str] = set()
    for item in dict.fromkeys(str(i) for i in items):  # each file once
        path = Path(item)
        stem = path.stem if path.suffix else item
        name, parents = stem, list(path.resolve().parent.parts[::-1]) if path.suffix else []
        while name in seen and parents:
            name = f"{parents.pop(0)}__{name}"
        if name in seen:
            raise BatchUsageError(f"{item}: two inputs would be written to the same folder {name!r}")
        seen.add(name)
        inputs.append(Input(str(path.resolve()) if path.suffix else item, name))
    return inputs


#: characters of an animation's name kept in the name of its folder (others become "_")
_SAFE = re.compile(r"[^A-Za-z0-9._-]+")


def _animations(motion: Input, wanted: str | None, searched: bool) -> list[Input]:
    """The motions a file gives: with ``wanted`` (a name, an index, `all`), the file read that way; else each
    animation (take) of a file of several its own motion, named ``<file>.<animation>``. A file whose animations
    cannot be listed (damaged) stays one motion: its tasks fail with the reader's error. A file of none found in a
    ``searched`` folder gives none (a rig beside the clips made on it); one named on its own fails its tasks."""
    from s2h_viewer.io.files import ANIMATED_SUFFIXES, list_animations

    if Path(motion.path).suffix.lower() not in ANIMATED_SUFFIXES:
        return [motion]
    names = None
    if searched or wanted is None:
        try:
            names = list_animations(motion.path)
        except S2HError:
            return [motion]
        if not names and searched:
            return []
    if wanted is not None:
        return [Input(motion.path, motion.name, int(wanted) if wanted.isdigit() else wanted)]
    if len(names) < 2:
        return [motion]
    named: dict[str, int] = {}
    for index, name in enumerate(names):
        base = f"{motion.name}.{_SAFE.sub('_', name.split(' (')[0]).strip('_.') or index}"
        named[base if base not in named else f"{base}_{index}"] = index
    return [Input(motion.path, name, index) for name, index in named.items()]


def _rigs_beside(motion: Path, known: dict[Path, tuple[str, ...]]) -> tuple[str, ...]:
    """The rig files (glTF/FBX of no animation) in a glTF/FBX motion's folder, sorted; ``known`` holds the folders
    searched already (and gets this one): a pose file named on its own was read onto its bare skeleton where the
    same file found in its folder was read onto the rig beside it."""
    from s2h_viewer.io.files import ANIMATED_SUFFIXES, list_animations

    if motion.suffix.lower() not in ANIMATED_SUFFIXES:
        return ()
    folder = motion.parent
    if folder not in known:
        found = []
        for path in sorted(p for p in folder.iterdir() if p.is_file() and p.suffix.lower() in ANIMATED_SUFFIXES):
            try:
                if not list_animations(path):
                    found.append(str(path.resolve()))
            except S2HError:
                continue
        known[folder] = tuple(found)
    return known[folder]


def plan_batch(motions: list[str], targets: list[str], methods: list[str], out_dir: str | Path,
               options: TaskOptions = TaskOptions(), known_methods: tuple[str, ...] = (),
               skipped: list[str] | None = None) -> list[Task]:
    """The batch's tasks, motion-major; a `BatchUsageError` for what no task could run. ``skipped`` gets the
    files of the motion folders that hold no animation (rigs: a folder of clips often holds the rig they were
    made on, and its 8 tasks failed "has no animations"); each glTF/FBX motion knows the rigs beside it
    (`Input.rigs`)."""
    if options.format not in FORMATS:
        raise BatchUsageError(f"--format {options.format}: use one of {', '.join(FORMATS)}")
    unknown = [m for m in methods if known_methods and m not in known_methods]
    if unknown or not methods:
        raise BatchUsageError(f"unknown method {', '.join(unknown) or '(none)'}; available: {', '.join(known_methods)}")
    named = {Path(p).resolve() for p in motions if Path(p).is_file()}
    motion_inputs, rigs = [], []
    for motion in _named(_files(motions, MOTION_SUFFIXES, "motion", allow_names=False)):
        found = _animations(motion, options.animation, Path(motion.path).resolve() not in named)
        if not found:
            rigs.append(motion.path)
        motion_inputs += found
    if not motion_inputs:
        raise BatchUsageError(f"{' '.join(motions)}: no motion files with animations (only rigs)")
    if skipped is not None:
        skipped += rigs
    # the folders searched had every file's animations listed above: their rigs are known, not listed again
    beside = {folder: tuple(r for r in rigs if Path(r).parent == folder)
              for folder in {Path(m.path).parent for m in motion_inputs if Path(m.path).resolve() not in named}}
    motion_inputs = [dataclasses.replace(m, rigs=_rigs_beside(Path(m.path), beside)) for m in motion_inputs]
    target_inputs = _named(_files(targets, HAND_SUFFIXES, "hand", allow_names=True))
    out = str(Path(out_dir))
    return [Task(m, t, method, out, options) for m in motion_inputs for t in target_inputs for method in methods]
