"""``report.html``: the batch as one static page a person can skim: failures on top, then the least kept, a table
sortable by any column (click its head) and filtered by a text box, each row with its worst frame's picture
(source beside retarget) and links to its files. Links are relative, so the folder can be moved or shared whole.
"""

from __future__ import annotations

import html
import math
import os
from pathlib import Path

from s2h_viewer.batch.summary import worst_first
from s2h_viewer.batch.task import POSES_APART
from s2h_viewer.io.atomic import atomic_path
from s2h_viewer.render.compare_scene import BANNER_COLOUR
from s2h_viewer.semantics.flexion import THUMB_FOLLOWS_FROM, SidewaysPeak, thumb_words
from s2h_viewer.semantics.signature import sideways_broken
from s2h_viewer.wording import counted

_NAMES = (("motion", "motion"), ("target", "target"), ("method", "method"), ("status", "status"))
_SCORES = (("kept", "kept"), ("s_finger", "S_finger"), ("s_palm", "S_palm"), ("contact_p", "contact P"),
           ("contact_r", "contact R"), ("violations_added", "viol. added"), ("sideways_deg", "sideways deg"),
           ("thumb_follow", "thumb follows"), ("worst_frame", "worst frame"), ("frames", "frames, seconds"))
#: what a score's heading says under the pointer (its words cost the page width it had to spare)
_TITLES = {"kept": "share of frames whose signature (each finger extended, bent or curled, the thumb's touches, "
                   "no finger bent sideways, no invented fingertip-to-fingertip contact) is the source's",
           "contact_p": "pad contacts made that the source makes", "contact_r": "pad contacts of the source kept",
           "violations_added": "share of joint angles over 5 deg further outside the anatomical limits than the "
                               "source's own",
           "sideways_deg": "the worst sideways bend of a PIP/DIP at its tightest curls (0: a clean curl); red past 25 "
                           "and past the source's own + 5",
           "thumb_follow": "the least correlation of a thumb angle (the metacarpal across and out of the palm, the MCP "
                           "and IP bends) with the source's (1: it does what the source's does); red under 0.9"}

#: a warning's colours: the viewer's banner's (orange; an error is red)
_WARNING_CSS = f".warning {{ color: {BANNER_COLOUR}; }}"

_STYLE = """
body { font: 13px system-ui, sans-serif; margin: 1em; color: #222; }
h1 { font-size: 1.3em; margin: 0 0 .3em; }
.counts span { margin-right: 1.2em; }
.failed-count { color: #b00020; font-weight: 600; }
input { font: inherit; padding: .3em .5em; width: 38em; max-width: 95%; margin: .6em 0; }  /* its placeholder whole */
table { border-collapse: collapse; }
th { position: sticky; top: 0; background: #f0f0f0; cursor: pointer; user-select: none; white-space: nowrap;
     font-size: 12px; }
th, td { border: 1px solid #ccc; padding: .2em .4em; vertical-align: middle; }
th { white-space: normal; max-width: 6em; }
th.sorted-asc::after { content: " \\25B2"; } th.sorted-desc::after { content: " \\25BC"; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
td.broken { color: #c62828; background: #ffcdd2; font-weight: 600; }  /* a finger bent sideways: the viewer's red */
tr.failed td { background: #fde7ea; }
tr.not-run td { background: #f3f3f3; color: #777; }
td.note { min-width: 12em; max-width: 24em; }
td:nth-child(-n+2) { min-width: 6em; max-width: 11em; overflow-wrap: break-word; }  /* motion, target: wrap at _ */
.error { color: #b00020; } .note div + div { margin-top: .3em; }
details ul { margin: .2em 0; padding-left: 1.2em; color: #222; } summary { cursor: pointer; }
.failures { color: #b00020; margin: .4em 0; } .failures ul { margin: .2em 0; } .failures .tasks { color: #555; }
img { height: 120px; display: block; }
.files { font-size: .9em; } .files a { margin-right: .6em; } .also { font-size: .9em; color: #555; }
"""

_SCRIPT = """
const table = document.getElementById('rows');
const body = table.tBodies[0];
document.getElementById('filter').addEventListener('input', e => {
  const words = e.target.value.toLowerCase().split(/\\s+/).filter(Boolean);
  for (const row of body.rows) {
    const text = row.dataset.text;
    row.hidden = !words.every(w => text.includes(w));
  }
});
table.tHead.addEventListener('click', e => {
  const th = e.target.closest('th');
  if (!th || th.dataset.col === undefined) return;
  const col = Number(th.dataset.col);
  const asc = !th.classList.contains('sorted-asc');
  for (const h of table.tHead.rows[0].cells) h.classList.remove('sorted-asc', 'sorted-desc');
  th.classList.add(asc ? 'sorted-asc' : 'sorted-desc');
  const key = r => r.cells[col].dataset.sort;
  const rows = Array.from(body.rows);
  rows.sort((a, b) => {
    const x = key(a), y = key(b), nx = parseFloat(x), ny = parseFloat(y);
    const c = (!isNaN(nx) && !isNaN(ny)) ? nx - ny : x.localeCompare(y);
    return asc ? c : -c;
  });
  rows.forEach(r => body.appendChild(r));
});
"""


def _relative(path: str, folder: Path) -> str:
    return Path(os.path.relpath(Path(path).resolve(), folder.resolve())).as_posix()


def _value(row: dict, key: str) -> tuple[str, str]:
    """(shown text, sort key) of one cell."""
    value = row.get(key, "")
    if isinstance(value, float):
        if math.isnan(value):
            return "n/a", ""
        text = f"{value:.1f}" if key == "sideways_deg" else f"{value:.2f}" if key == "thumb_follow" else f"{value:.3f}"
        if key == "kept" and row.get("poses_kept"):
            text += f" ({row['poses_kept']} poses)"
        return text, repr(value)
    if key == "frames":  # and how long the task took, under them: a column of its own made the page too wide
        try:
            took = f"{float(row['seconds']):.1f} s"  # a float here, a string read back from a summary
        except (KeyError, TypeError, ValueError):
            took = ""
        return "\n".join(t for t in (str(value), took) if t), str(value)
    return str(value), str(value)


def _failure_groups(rows: list[dict]) -> str:
    """One line per distinct error, with how many tasks it failed: three bad files in a big batch read as
    three lines here, not as a screen of red rows."""
    groups: dict[str, int] = {}
    for row in rows:
        if row.get("status") == "failed":
            groups[row.get("error") or "no error recorded"] = groups.get(row.get("error") or "no error recorded", 0) + 1
    if not groups:
        return ""
    items = "".join(f"<li>{html.escape(error)} <span class=tasks>({counted(count, 'task')})</span></li>"
                    for error, count in sorted(groups.items(), key=lambda g: -g[1]))
    return f'<div class="failures"><b>Failures</b><ul>{items}</ul></div>'


def _image(picture: str, folder: Path, alt: str) -> str:
    """A picture of the row's, linked to itself ("" if none)."""
    if not picture:
        return ""
    src = html.escape(_relative(picture, folder))
    return f'<a href="{src}"><img loading="lazy" alt="{html.escape(alt)}" src="{src}"></a>'


def _poses_lost(row: dict) -> str:
    """The poses a retarget of a clip of poses lost, folded under how many ("" if it lost none): 20 lost poses
    written out had made the note column a page tall."""
    if not row.get("poses_lost"):
        return ""
    lost = str(row["poses_lost"]).split(POSES_APART)
    held = str(row.get("poses_kept", "")).partition("/")[2]
    items = "".join(f"<li>{html.escape(pose)}</li>" for pose in lost)
    return (f'<details><summary>{len(lost)}{f" of {held}" if held else ""} poses lost</summary>'
            f"<ul>{items}</ul></details>")


def sideways_note(row: dict) -> str:
    """The row's worst sideways bend in the viewer's words, with the source's and the curve's peak
    (`RetargetScores.sideways_words`); from a summary written before those, "ring DIP bends 40 deg sideways at frame
    212" from its sideways columns ("" if no finger curls)."""
    if row.get("sideways_words"):
        return str(row["sideways_words"])
    joint, _, frame = str(row.get("sideways_at") or "").partition("@")
    degrees = row.get("sideways_deg")
    if not joint or not isinstance(degrees, float) or math.isnan(degrees):
        return ""
    return SidewaysPeak(degrees, joint, int(frame)).describe()


def _broken(row: dict, key: str) -> bool:
    """Whether a score cell is drawn red, as in the viewer: the sideways bend past the limit and the source's own
    (`sideways_broken`), a thumb following the source's under `THUMB_FOLLOWS_FROM`."""
    value = row.get(key)
    if not isinstance(value, float):
        return False
    return (key == "sideways_deg" and sideways_broken(value, row.get("source_sideways_deg", math.nan))
            or key == "thumb_follow" and value < THUMB_FOLLOWS_FROM)


def _cell(row: dict, key: str, numeric: bool) -> str:
    text, sort = _value(row, key)
    # a long name breaks after its underscores, not anywhere: "debug_robo" over "t" (the page's width is tight)
    shown = "<br>".join(html.escape(line).replace("_", "_<wbr>" if key in ("motion", "target") else "_")
                        for line in text.split("\n"))
    css = " ".join(c for c, wanted in (("num", numeric), ("broken", _broken(row, key))) if wanted)
    klass = f' class="{css}"' if css else ""
    return f'<td{klass} data-sort="{html.escape(sort)}">{shown}</td>'


def write_report(rows: list[dict], path: str | Path, title: str = "s2h batch") -> Path:
    path = Path(path)
    folder = path.parent
    rows = worst_first(rows)
    failed = sum(r.get("status") == "failed" for r in rows)
    not_run = sum(r.get("status") == "not run" for r in rows)
    ok = len(rows) - failed - not_run
    warned = sum(r.get("status") == "ok" and bool(r.get("warning")) for r in rows)
    head = "".join(f'<th data-col="{i}">{html.escape(label)}</th>' for i, (_, label) in enumerate(_NAMES))
    head += '<th>error / note</th><th>worst frame: source | retarget; files</th>'  # not sortable: 2 columns
    head += "".join(f'<th data-col="{len(_NAMES) + 2 + i}"'
                    + (f' title="{html.escape(_TITLES[key])}"' if key in _TITLES else "") + f">{html.escape(label)}</th>"
                    for i, (key, label) in enumerate(_SCORES))
    lines = []
    for row in rows:
        cells = [_cell(row, key, numeric=False) for key, _ in _NAMES]
        # an error or a warning in red, the sideways bend in black: it was red too, under a target's warning
        invented = row.get("invented_words") if row.get("invented") else ""  # palm contacts too: no column has them
        thumb = (thumb_words(row["thumb_follow"], str(row.get("thumb_follow_at") or ""))
                 if _broken(row, "thumb_follow") else "")  # a red figure says why, as the sideways one does
        note = "".join(f'<div{f" class={kind}" if kind else ""}>{html.escape(text)}</div>'
                       for text, kind in ((row.get("error"), "error"), (row.get("warning"), "warning"),
                                          (sideways_note(row), ""), (thumb, ""), (invented, "")) if text)
        cells.append(f'<td class="note">{note}{_poses_lost(row)}</td>')
        picture = row.get("picture") or ""
        links = [f'<a href="{html.escape(_relative(row[k], folder))}">{label}</a>'
                 for k, label in (("output", "output"), ("motion_path", "motion"), ("target_path", "target"))
                 if row.get(k) and (k == "output" or Path(row[k]).is_file())]
        image = _image(picture, folder, f'frame {row.get("worst_frame", "")}')
        if row.get("sideways_picture"):  # where the note's finger bends sideways: the worst frame's showed a fist
            frame = str(row.get("sideways_at") or "").partition("@")[2]
            image += (f'<div class="also">the sideways bend, frame {html.escape(frame)}:</div>'
                      + _image(row["sideways_picture"], folder, f"frame {frame}"))
        cells.append(f'<td>{image}<div class="files">{" ".join(links)}</div></td>')  # the files under the pictures
        measured = row.get("status") == "ok"  # a task that failed or did not run measured nothing: no "n/a"
        cells += [_cell(row, key, numeric=True) if measured or key == "frames" else '<td class=num data-sort=""></td>'
                  for key, _ in _SCORES]
        text = " ".join(str(row.get(k, "")) for k in ("motion", "target", "method", "status", "error", "warning",
                                                          "poses_lost")).lower()
        css = {"failed": ' class="failed"', "not run": ' class="not-run"'}.get(row.get("status"), "")
        lines.append(f'<tr{css} data-text="{html.escape(text)}">{"".join(cells)}</tr>')
    page = f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>{html.escape(title)}</title><style>{_STYLE}{_WARNING_CSS}</style></head>
<body>
<h1>{html.escape(title)}</h1>
<div class="counts"><span>{len(rows)} tasks</span><span>{ok} ok{f" ({warned} with a warning)" if warned else ""}</span>
<span class="{'failed-count' if failed else ''}">{failed} failed</span>{f'<span>{not_run} not run (interrupted: run the batch again)</span>' if not_run else ''}</div>
{_failure_groups(rows)}
<input id="filter" type="search" placeholder="filter: words of motion, target, method, status, error, warning or pose">
<table id="rows"><thead><tr>{head}</tr></thead><tbody>
{chr(10).join(lines)}
</tbody></table>
<script>{_SCRIPT}</script>
</body></html>
"""
    with atomic_path(path) as tmp:
        tmp.write_text(page, encoding="utf-8")
    return path
