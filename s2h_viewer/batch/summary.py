"""``summary.csv``: one row per task, in the plan's order, failures first (then tasks an interrupted batch did
not run); read back by the viewer. Status: ok, failed, or "not run".

Scores are written with 6 decimals; a score with nothing to measure (no contacts: DESIGN.md section 5) is
empty, not "nan".
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

from s2h_viewer.errors import InputFileError, reading, require_readable_file
from s2h_viewer.io.atomic import atomic_path

COLUMNS = ("motion", "target", "method", "status", "error", "warning", "frames", "seconds", "kept", "poses_kept",
           "poses_lost", "s_palm", "s_finger", "contact_p", "contact_r", "palm_r", "violations", "violations_added",
           "sideways_deg", "sideways_at", "sideways_anywhere_deg", "sideways_anywhere_at", "source_sideways_deg",
           "sideways_words", "thumb_follow", "thumb_follow_at", "invented", "invented_words", "worst_frame", "worst_error",
           "output", "picture", "sideways_picture", "motion_path",
           "target_path", "animation", "source_path")
COUNTS = ("frames", "worst_frame", "invented")
SCORES = ("kept", "s_palm", "s_finger", "contact_p", "contact_r", "palm_r", "violations", "violations_added",
          "sideways_deg", "sideways_anywhere_deg", "source_sideways_deg", "thumb_follow", "worst_error")


def row_json(row: dict) -> str:
    """A task's row as strict JSON (a score with nothing to measure as null: a bare NaN is not JSON)."""
    return json.dumps({k: None if isinstance(v, float) and math.isnan(v) else v for k, v in row.items()}, indent=1,
                      allow_nan=False)


def read_row_json(path: Path) -> dict | None:
    """A row written by `row_json` (its null scores NaN again, as scored), None if unreadable or not a row."""
    try:
        row = json.loads(Path(path).read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(row, dict):
        return None
    return row | {k: math.nan for k in SCORES if k in row and row[k] is None}


def _cell(value) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return ""
    if isinstance(value, float):
        return f"{value:.6f}"  # the viewer rounds to 3: 4 here turned its 0.023 into 0.022
    return str(value)


def ordered(rows: list[dict]) -> list[dict]:
    """Failures first, then tasks not run, then the rest, each group in the plan's order (the sort is stable)."""
    return sorted(rows, key=lambda r: {"failed": 0, "not run": 1}.get(r.get("status"), 2))


def worst_first(rows: list[dict]) -> list[dict]:
    """Failures first, then tasks not run, then by the share of frames whose signature is kept from the lowest,
    then by S_finger (a row with no score after those with one): S_finger averages one wrong finger away, and a
    batch ranked by it put a retarget keeping 0.60 below one keeping 0.68."""
    def key(row: dict) -> tuple:
        kept, score = row.get("kept", math.nan), row.get("s_finger", math.nan)
        return ({"failed": 0, "not run": 1}.get(row.get("status"), 2), math.isnan(kept), kept, math.isnan(score),
                score)
    return sorted(rows, key=key)


def write_summary(rows: list[dict], path: str | Path) -> Path:
    path = Path(path)
    with atomic_path(path) as tmp, open(tmp, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(COLUMNS)
        for row in ordered(rows):
            writer.writerow([_cell(row.get(c)) for c in COLUMNS])
    return path


def read_summary(path: str | Path) -> list[dict]:
    """The rows of a batch's ``summary.csv`` (scores as floats, NaN where empty; frame counts as ints), for the
    viewer."""
    path = require_readable_file(path)
    with reading(path, "a batch summary"):
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
    if not rows and path.read_text().strip() and not path.read_text().startswith("motion,"):
        raise InputFileError(path, "not a batch summary (its first line should name the columns motion, "
                                   "target, method, ...)")
    missing = [c for c in ("motion", "target", "method", "status") if rows and c not in rows[0]]
    if missing:
        raise InputFileError(path, f"not a batch summary: no column {', '.join(missing)}")
    for row in rows:
        for key in COUNTS:
            if str(row.get(key) or "").isdigit():
                row[key] = int(row[key])
        for key in SCORES:
            try:
                row[key] = float(row.get(key) or "nan")
            except ValueError:
                raise InputFileError(path, f"{key} {row[key]!r} of {row['motion']} -> {row['target']} "
                                           f"({row['method']}) is not a number") from None
    return rows
