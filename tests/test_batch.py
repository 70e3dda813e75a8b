"""`s2h batch` on real Dask clusters: a LocalCluster of 2 worker processes, and a scheduler and worker started as
`dask` subprocesses on 127.0.0.1 (ended by their pids). Results against the in-process retarget, a corrupt
target, a worker that dies, reruns, the summary, the report."""

from __future__ import annotations

import csv
import dataclasses
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import torch

from s2h_viewer.batch.cluster import local_cluster
from s2h_viewer.batch.plan import BatchUsageError, TaskOptions, plan_batch
from s2h_viewer.batch.runner import BatchConfig, run_batch
from s2h_viewer.batch.summary import COLUMNS, read_summary
from s2h_viewer.cli import main
from s2h_viewer.io.files import load_hand_file, load_motion_file
from s2h_viewer.io.npz import load_motion
from s2h_viewer.retarget import METHODS, retarget
from s2h_viewer.samples import ASSETS_DIR

PLUGIN = Path(__file__).parent / "batch_plugins" / "crash_once.py"
GESTURES = str(ASSETS_DIR / "motions" / "gestures.npz")
COUNTING = str(ASSETS_DIR / "motions" / "counting.npz")
GODOT_LEFT = str(ASSETS_DIR / "hands" / "real" / "godot_hand_l.gltf")


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """2 worker processes that know the crash_once method; the marker file of each test is its own."""
    import importlib.util
    spec = importlib.util.spec_from_file_location("crash_once", PLUGIN)
    spec.loader.exec_module(importlib.util.module_from_spec(spec))  # the client knows the method too
    os.environ["S2H_CRASH_MARKER"] = str(tmp_path_factory.mktemp("crash") / "crashed")
    try:
        with local_cluster(2, preload=(str(PLUGIN),)) as local:
            yield local
    finally:
        os.environ.pop("S2H_CRASH_MARKER", None)
        METHODS.pop("crash_once", None)  # the registry is global: later tests list every method


@pytest.fixture
def corrupt_target(tmp_path) -> str:
    path = tmp_path / "inputs" / "broken.glb"
    path.parent.mkdir()
    path.write_bytes(b"glTF\x02\x00\x00\x00" + (10_000).to_bytes(4, "little") + b"\x00" * 40)  # declares 10000 bytes
    return str(path)


def summary_without_timings(path: Path) -> list[dict]:
    with open(path, newline="") as f:
        return [{k: v for k, v in row.items() if k != "seconds"} for row in csv.DictReader(f)]


def test_the_plan_names_every_task_and_refuses_what_cannot_run(tmp_path):
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    for folder in ("a", "b"):
        (tmp_path / folder / "clip.npz").write_bytes(Path(GESTURES).read_bytes())
    tasks = plan_batch([str(tmp_path / "a"), str(tmp_path / "b")], ["iris", GODOT_LEFT], ["tbs_copy", "asrn"],
                       tmp_path / "out", known_methods=tuple(METHODS))
    assert len(tasks) == 2 * 2 * 2
    assert [t.motion.name for t in tasks[::4]] == ["clip", "b__clip"]  # the same stem twice: told apart
    assert tasks[0].output == tmp_path / "out" / "clip" / "iris" / "tbs_copy.glb"
    assert len({t.key for t in tasks}) == len(tasks)
    with pytest.raises(BatchUsageError, match="nope.glb: no such file or folder"):  # not a task failing later
        plan_batch([GESTURES], [str(tmp_path / "nope.glb")], ["tbs_copy"], tmp_path, known_methods=tuple(METHODS))
    with pytest.raises(BatchUsageError, match="avatars: no such file or folder or a shipped hand .aster, "):
        plan_batch([GESTURES], ["avatars"], ["tbs_copy"], tmp_path, known_methods=tuple(METHODS))
    assert len(plan_batch([GESTURES], ["iris", str(ASSETS_DIR / "hands" / "iris.npz")], ["tbs_copy"], tmp_path,
                          known_methods=tuple(METHODS))) == 1  # one hand by its name and its file: once
    with pytest.raises(BatchUsageError, match="unknown method nope"):
        plan_batch([GESTURES], ["iris"], ["nope"], tmp_path, known_methods=tuple(METHODS))
    (tmp_path / "empty").mkdir()
    with pytest.raises(BatchUsageError, match="no motion files"):
        plan_batch([str(tmp_path / "empty")], ["iris"], ["tbs_copy"], tmp_path, known_methods=tuple(METHODS))
    with pytest.raises(BatchUsageError, match="--format fbx"):
        plan_batch([GESTURES], ["iris"], ["tbs_copy"], tmp_path, TaskOptions(format="fbx"), tuple(METHODS))


def test_a_batch_on_a_local_cluster_equals_the_in_process_retarget_and_a_rerun_skips_it(cluster, tmp_path,
                                                                                    corrupt_target):
    out = tmp_path / "out"
    config = BatchConfig([GESTURES], ["iris", corrupt_target], ["tbs_copy", "asrn"], str(out),
                         TaskOptions(format="npz"), scheduler=cluster.scheduler_address)
    first = run_batch(config, show_progress=False)
    assert first.exit_code == 1 and first.skipped == 0
    by_task = {(r["target"], r["method"]): r for r in first.rows}
    for method in ("tbs_copy", "asrn"):  # a corrupt target fails its own tasks, with its one-line error
        failed = by_task[("broken", method)]
        assert failed["status"] == "failed" and failed["error"].startswith(corrupt_target)
        assert "\n" not in failed["error"] and not (out / "gestures" / "broken" / f"{method}.npz").exists()
    motion, _ = load_motion_file(GESTURES)
    source, target = load_hand_file("birch"), load_hand_file("iris")
    threads = torch.get_num_threads()
    torch.set_num_threads(1)  # as the workers run (the nanny's OMP_NUM_THREADS=1): the same kernels, bit for bit
    try:
        for method in ("tbs_copy", "asrn"):
            row = by_task[("iris", method)]
            assert row["status"] == "ok" and row["frames"] == motion.n_frames
            written = load_motion(out / "gestures" / "iris" / f"{method}.npz")
            assert np.array_equal(written.q_tbs, retarget(motion, source, target, method).q_tbs)
            assert Path(row["picture"]).stat().st_size > 1000
            assert 0.9 < row["s_finger"] <= 1.0 and 0 <= row["worst_frame"] < motion.n_frames
    finally:
        torch.set_num_threads(threads)
    rows = read_summary(out / "summary.csv")
    assert [r["status"] for r in rows] == ["failed", "failed", "ok", "ok"]  # failures on top
    assert rows[2]["warning"] == ""  # iris's rig is the project's own
    assert list(rows[0]) == list(COLUMNS)
    # beside the clip's sideways figure (its joints' tightest curls), the sideways curve's peak and where it is
    assert 0.0 <= rows[-1]["sideways_anywhere_deg"] <= 90.0 and "@" in rows[-1]["sideways_anywhere_at"]
    page = (out / "report.html").read_text()
    assert page.count("<tr") == 5 and "1 failed" not in page and "2 failed" in page
    # a heading sorts its own column: "S_finger" sorted by kept, each score heading one column off (a user saw it)
    import re
    columns = {label: int(n) for n, label in re.findall(r'<th data-col="(\d+)"[^>]*>([^<]+)</th>', page)}
    last = page.split("<tr")[-1]
    cells = re.findall(r'<td[^>]*data-sort="([^"]*)"|<td[^>]*>', last)
    assert float(cells[columns["S_finger"]]) == pytest.approx(rows[-1]["s_finger"], abs=1e-4)  # the summary's 4
    assert float(cells[columns["kept"]]) == pytest.approx(rows[-1]["kept"], abs=1e-4)  # decimals
    assert float(cells[columns["kept"]]) != pytest.approx(rows[-1]["s_finger"], abs=1e-4)
    assert 'src="gestures/iris/asrn.worst.png"' in page
    # within 1400 pixels: the files under the picture, the seconds under the frames (columns of their own were past it)
    assert "<th>files</th>" not in page and page.count('<div class="files"><a href=') == 4
    assert re.search(rf'data-sort="{rows[-1]["frames"]}">{rows[-1]["frames"]}<br>\d+\.\d s</td>', last)

    row_files = sorted((out / "gestures" / "iris").glob("*.row.json"))
    stamps = [p.stat().st_mtime_ns for p in row_files]
    before = summary_without_timings(out / "summary.csv")
    second = run_batch(config, show_progress=False)
    assert second.skipped == 4 and second.exit_code == 1  # all skipped: the broken file fails the same way
    assert [p.stat().st_mtime_ns for p in row_files] == stamps
    assert summary_without_timings(out / "summary.csv") == before
    Path(corrupt_target).write_bytes(Path(corrupt_target).read_bytes() + b"\x00")  # the file changed: tried again
    third = run_batch(config, show_progress=False)
    assert third.skipped == 2 and [r["status"] for r in third.rows].count("failed") == 2


def test_a_task_whose_worker_dies_is_run_again_and_finishes(cluster, tmp_path):
    marker = Path(os.environ["S2H_CRASH_MARKER"])
    marker.unlink(missing_ok=True)
    result = run_batch(BatchConfig([COUNTING], ["iris"], ["crash_once"], str(tmp_path),
                                   TaskOptions(format="npz", render=False), scheduler=cluster.scheduler_address),
                       show_progress=False)
    assert marker.exists()  # the first attempt killed its worker
    assert result.exit_code == 0 and result.rows[0]["status"] == "ok"
    assert (tmp_path / "counting" / "iris" / "crash_once.npz").exists()


def _start(args: list[str], log: Path) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", *args], stdout=log.open("w"), stderr=subprocess.STDOUT,
                            start_new_session=True)


def _stop(process: subprocess.Popen) -> None:
    """End a process we started, by its pid: SIGTERM, then SIGKILL if it lingers."""
    if process.poll() is None:
        os.kill(process.pid, signal.SIGTERM)
        try:
            process.wait(timeout=20)
        except subprocess.TimeoutExpired:
            os.kill(process.pid, signal.SIGKILL)
            process.wait()


def test_the_cli_on_its_own_local_cluster_and_on_a_scheduler_started_here_give_the_same_summary(tmp_path, capsys):
    args = ["batch", "--motions", COUNTING, "--targets", "iris", GODOT_LEFT, "--methods", "tbs_copy",
            "--format", "bvh", "--no-pictures", "--quiet"]
    assert main([*args, "--out", str(tmp_path / "local"), "--workers", "2"]) == 0
    assert "2 tasks: 2 ok, 0 failed" in capsys.readouterr().out

    scheduler_file = tmp_path / "scheduler.json"
    scheduler = _start(["distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                        "--scheduler-file", str(scheduler_file)], tmp_path / "scheduler.log")
    worker = None
    try:
        deadline = time.monotonic() + 60
        while not scheduler_file.exists() and time.monotonic() < deadline and scheduler.poll() is None:
            time.sleep(0.2)
        import json
        address = json.loads(scheduler_file.read_text())["address"]
        assert address.startswith("tcp://127.0.0.1:")
        worker = _start(["distributed.cli.dask_worker", address, "--host", "127.0.0.1", "--nworkers", "1",
                         "--nthreads", "1", "--no-dashboard"], tmp_path / "worker.log")
        capsys.readouterr()
        talking = [a for a in args if a != "--quiet"]  # not a terminal here: a line per task instead of a bar
        assert main([*talking, "--out", str(tmp_path / "remote"), "--scheduler", address]) == 0
        said = capsys.readouterr().err.splitlines()
        done = [line for line in said if line.startswith("batch: ") and line.endswith("(tbs_copy): ok")]
        assert sorted(line.split()[1] for line in done) == ["1/2", "2/2"], said
    finally:
        for process in (worker, scheduler):
            if process is not None:
                _stop(process)
    local, remote = (summary_without_timings(tmp_path / name / "summary.csv") for name in ("local", "remote"))
    for rows in (local, remote):
        for row in rows:
            row["output"] = Path(row["output"]).name
    assert local == remote and len(local) == 2

def test_an_address_with_no_scheduler_behind_it_is_said_at_once(tmp_path, capsys):
    """Dask's client retried a closed port for 20 s, waited for ever on a web server (the dashboard's port, say)
    and asked for 3 EiB on a server's garbage: each is one line at once."""
    import socketserver
    import threading
    from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer

    class Garbage(socketserver.BaseRequestHandler):
        def handle(self) -> None:
            self.request.sendall(b"SSH-2.0-OpenSSH_9.6\r\n")
    servers = [ThreadingHTTPServer(("127.0.0.1", 0), SimpleHTTPRequestHandler),
               socketserver.ThreadingTCPServer(("127.0.0.1", 0), Garbage)]
    for server in servers:
        threading.Thread(target=server.serve_forever, daemon=True).start()
    web, garbage = (f"tcp://127.0.0.1:{server.server_address[1]}" for server in servers)
    said = {}
    try:
        for address in ("tcp://127.0.0.1:9", web, garbage, "127.0.0.1"):
            assert main(["batch", "--motions", COUNTING, "--targets", "iris", "--out", str(tmp_path / "x"),
                         "--scheduler", address, "--quiet"]) == 2
            said[address] = capsys.readouterr().err.strip()  # ours, said before the client waits
    finally:
        for server in servers:
            server.shutdown()
            server.server_close()
    assert said["tcp://127.0.0.1:9"].endswith("no Dask scheduler there: nothing listens at 127.0.0.1:9")
    assert "says nothing a scheduler would (its dashboard, a web page?)" in said[web]
    assert "answers, but not as a scheduler does (its first bytes: b'SSH-2.0-')" in said[garbage]
    assert "tcp://127.0.0.1:8786" in said["127.0.0.1"]
    assert all(text.count("\n") == 0 and text.startswith("s2h: error: --scheduler ") for text in said.values())
    assert not (tmp_path / "x").exists()


def _live_processes_in_group(pgid: int) -> list[int]:
    """Processes of a process group that still run (zombies left to a non-reaping init are not running)."""
    live = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[2]) == pgid and fields[0] != "Z":
            live.append(int(stat.parent.name))
    return live


def test_ctrl_c_stops_the_cluster_keeps_what_finished_and_leaves_no_partial_file(tmp_path):
    out = tmp_path / "out"
    command = [sys.executable, "-m", "s2h_viewer.cli", "batch", "--motions", GESTURES, COUNTING, "--targets", "iris",
               "laurel", "juniper", "--methods", "tbs_copy,asrn", "--format", "npz", "--no-pictures", "--quiet",
               "--out", str(out), "--workers", "2"]
    # its own process group, as a terminal's job is, and Ctrl+C heard there whoever started the tests (a shell
    # without job control starts a background job, and all it starts, with SIGINT ignored)
    batch = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                             start_new_session=True, preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        deadline = time.monotonic() + 240
        while not list(out.rglob("*.row.json")) and time.monotonic() < deadline and batch.poll() is None:
            time.sleep(0.2)
        assert batch.poll() is None, batch.communicate()
        os.killpg(batch.pid, signal.SIGINT)  # Ctrl+C: the whole group, workers included
        stdout, stderr = batch.communicate(timeout=120)
    finally:
        if batch.poll() is None:
            os.killpg(batch.pid, signal.SIGKILL)
    assert batch.returncode == 130, stderr
    assert "interrupted: run it again to finish" in stdout and "Traceback" not in stderr
    deadline = time.monotonic() + 30  # the workers' nannies end them as the client closes the cluster
    while _live_processes_in_group(batch.pid) and time.monotonic() < deadline:
        time.sleep(0.2)
    assert not _live_processes_in_group(batch.pid)  # no worker outlives it
    assert not [p for p in out.rglob(".*") if p.is_file()]  # no temporary file of a killed write
    rows = read_summary(out / "summary.csv")
    done = [r for r in rows if r["status"] == "ok"]
    assert 1 <= len(done) < 12 and all(Path(r["output"]).stat().st_size > 0 for r in done)
    assert all(r["status"] == "not run" and "interrupted" in r["error"] for r in rows if r["status"] != "ok")
    assert len(done) == sum(1 for p in out.rglob("*.row.json"))  # a task that finished as it stopped is ok here


def test_a_rig_recognised_with_low_confidence_is_flagged_in_its_row(tmp_path):
    from s2h_viewer.batch.task import run_task
    from wild_rigs import meta_hand_skeleton, write_gltf_skeleton
    names, parents, positions = meta_hand_skeleton(ASSETS_DIR / "hands" / "real" / "r_hand_skeletal_lowres.fbx")
    anonymous = [n if n.endswith("_marker") else f"Bone{i:03d}" for i, n in enumerate(names)]  # by topology alone
    oculus = str(write_gltf_skeleton(tmp_path / "anonymous_hand.gltf", anonymous, parents, positions))
    low, good = (run_task(task) for task in plan_batch([COUNTING], [oculus, "iris"], ["tbs_copy"], tmp_path,
                                                      TaskOptions(format="npz", render=False), tuple(METHODS)))
    assert low["status"] == "ok" and good["status"] == "ok" and good["warning"] == ""
    assert "target rig recognised with confidence 0.0" in low["warning"] and "s2h rig" in low["warning"]
    page = (tmp_path / "report.html")
    from s2h_viewer.batch.report import write_report
    assert low["warning"] in write_report([low, good], page).read_text().replace("&#x27;", "'").replace("&quot;", '"')


def test_a_target_whose_frames_are_guessed_is_flagged_in_its_row_as_in_the_viewer(tmp_path):
    """The RPM avatar's index frames are the palm plane's guess: the viewer's banner says so over its cell, and a
    fresh-eyes user found the batch row for the same retarget silent."""
    from s2h_viewer.annotate.trust import frame_warning
    from s2h_viewer.batch.task import run_task
    from s2h_viewer.io.files import RigOptions, load_hand_file
    rpm = ASSETS_DIR / "hands" / "real" / "RPM_Template_Mesh_XR.glb"
    banner = frame_warning(load_hand_file(rpm, RigOptions(side="right"))).banner
    (task,) = plan_batch([COUNTING], [f"{rpm}"], ["tbs_copy"], tmp_path, TaskOptions(format="npz", render=False,
                                                                                    side="right"), tuple(METHODS))
    row = run_task(task)
    assert row["status"] == "ok" and banner.startswith("frames guessed: index")
    assert f"target {banner}: retargets may bend there" in row["warning"]


POSES = str(ASSETS_DIR / "motions" / "real" / "godot_hand_poses_r.gltf")


def test_each_animation_of_a_file_is_a_motion_of_its_own_and_all_reads_them_as_one_clip_of_poses(tmp_path):
    """A user's batch on the 35-pose file retargeted its first animation alone and said nothing: each animation
    (take) is its own motion, named by it; --animation all reads every one as one clip, scored pose by pose."""
    from s2h_viewer.batch.task import POSES_APART, run_task
    from s2h_viewer.io.files import RigOptions

    tasks = plan_batch([POSES, GESTURES], ["iris"], ["tbs_copy"], tmp_path / "each",
                       TaskOptions(format="npz", render=False))
    names = [t.motion.name for t in tasks]
    assert len(tasks) == 36 and names[0] == "godot_hand_poses_r.Cup" and "godot_hand_poses_r.Sign_4" in names
    assert names[-1] == "gestures" and len(set(names)) == 36 and len({t.key for t in tasks}) == 36
    horns = tasks[names.index("godot_hand_poses_r.Horns")]
    row = run_task(horns)
    rig_beside = str(Path(POSES).with_name("godot_hand_r_posed_rig.gltf"))  # its skeleton has no mesh: read on it
    rig = load_hand_file(rig_beside)
    motion, _ = load_motion_file(POSES, rig, options=RigOptions(animation="Horns"))
    assert row["status"] == "ok" and row["animation"] == str(horns.motion.animation) and row["frames"] == motion.n_frames
    assert row["source_path"] == rig_beside
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        written = load_motion(horns.output)
        assert np.allclose(written.q_tbs, retarget(motion, rig, load_hand_file("iris"), "tbs_copy").q_tbs, atol=1e-6)
    finally:
        torch.set_num_threads(threads)
    (whole,) = plan_batch([POSES], ["iris"], ["tbs_copy"], tmp_path / "all",
                          TaskOptions(format="npz", render=False, animation="all"))
    row = run_task(whole)
    kept, held = (int(n) for n in row["poses_kept"].split("/"))
    assert row["status"] == "ok" and held == 35 and kept == 35 - len(row["poses_lost"].split(POSES_APART)) * bool(
        row["poses_lost"])
    assert 0 < row["kept"] <= 1 and row["frames"] > 35 * 2
    (one,) = plan_batch([POSES], ["iris"], ["tbs_copy"], tmp_path / "one", TaskOptions(animation="Peace"))
    assert one.motion.name == "godot_hand_poses_r" and one.motion.animation == "Peace"


def test_a_second_batch_into_a_folder_lists_the_first_ones_rows_too(cluster, tmp_path):
    """A user ran one batch per source rig into one folder: the second's summary listed its own row alone, and the
    first's results, still on disk, were nowhere. The summary and the report list both."""
    out = tmp_path / "out"
    options = TaskOptions(format="npz", render=False)
    first = run_batch(BatchConfig([COUNTING], ["iris"], ["tbs_copy"], str(out), options,
                                  scheduler=cluster.scheduler_address), show_progress=False)
    second = run_batch(BatchConfig([GESTURES], ["iris"], ["tbs_copy"], str(out), options,
                                   scheduler=cluster.scheduler_address), show_progress=False)
    assert first.earlier == 0 and second.earlier == 1 and len(second.rows) == 1 and second.redone == 0
    again = run_batch(BatchConfig([COUNTING], ["iris"], ["tbs_copy"], str(out), dataclasses.replace(options,
                                  side="right"), scheduler=cluster.scheduler_address), show_progress=False)
    assert again.redone == 1 and again.skipped == 0  # made with other options: done again, and said
    rows = read_summary(out / "summary.csv")
    assert sorted(r["motion"] for r in rows) == ["counting", "gestures"] and all(r["status"] == "ok" for r in rows)
    assert 0 < rows[0]["kept"] <= 1
    (out / "counting" / "iris" / "tbs_copy.npz").unlink()  # a result removed by hand is no longer listed
    run_batch(BatchConfig([GESTURES], ["iris"], ["tbs_copy"], str(out), options,
                          scheduler=cluster.scheduler_address), show_progress=False)
    assert [r["motion"] for r in read_summary(out / "summary.csv")] == ["gestures"]


def test_a_rig_in_a_folder_of_clips_is_left_out_and_a_row_is_strict_json(tmp_path):
    """A folder of clips held the rig they were made on: its tasks failed "has no animations". Left out of a
    searched folder (named on its own, it still fails, saying why); a row's unmeasured score is null, not NaN."""
    import json
    import shutil

    from s2h_viewer.batch.summary import row_json
    from s2h_viewer.batch.task import run_task

    folder = tmp_path / "library"
    folder.mkdir()
    rig = ASSETS_DIR / "motions" / "real" / "godot_hand_r_posed_rig.gltf"
    shutil.copy(rig, folder)
    shutil.copy(COUNTING, folder)
    left_out: list[str] = []
    tasks = plan_batch([str(folder)], ["iris"], ["tbs_copy"], tmp_path / "out",
                       TaskOptions(format="npz", render=False), skipped=left_out)
    assert [t.motion.name for t in tasks] == ["counting"] and [Path(p).name for p in left_out] == [rig.name]
    row = run_task(tasks[0]) | {"contact_p": float("nan")}  # as a clip of no contacts scores it
    tasks[0].row_file.write_text(row_json(row))
    written = tasks[0].row_file.read_text()
    assert "NaN" not in written and json.loads(written)["contact_p"] is None
    back = tasks[0].finished_row()
    assert np.isnan(back["contact_p"]) and back["s_finger"] == row["s_finger"]  # read back as scored
    (alone,) = plan_batch([str(folder / rig.name)], ["iris"], ["tbs_copy"], tmp_path / "out", TaskOptions())
    assert "has no animations" in run_task(alone)["error"]
    (tmp_path / "rigs").mkdir()
    shutil.copy(rig, tmp_path / "rigs")
    with pytest.raises(BatchUsageError, match="no motion files with animations"):
        plan_batch([str(tmp_path / "rigs")], ["iris"], ["tbs_copy"], tmp_path / "x")


def test_a_clip_with_no_skin_is_read_onto_the_rig_beside_it(tmp_path):
    """A library folder held the pose library (a skeleton with no mesh) and the rig it was made on: without
    --source the poses were read onto their bare skeleton (frames from the palm plane), S_finger 0.91 where the
    rig gives 0.96. A clip whose own rig lacks a mesh, or rests in a pose, is read onto the first rig beside it
    whose bones it animates, as --source would; the row names it."""
    import shutil

    from s2h_viewer.batch.task import run_task

    folder = tmp_path / "library"
    folder.mkdir()
    for name in ("godot_hand_poses_r.gltf", "godot_hand_r_posed_rig.gltf"):
        shutil.copy(ASSETS_DIR / "motions" / "real" / name, folder)
    options = TaskOptions(format="npz", render=False, animation="Horns")
    (beside,) = plan_batch([str(folder)], ["iris"], ["tbs_copy"], tmp_path / "beside", options)
    (named,) = plan_batch([str(folder / "godot_hand_poses_r.gltf")], ["iris"], ["tbs_copy"], tmp_path / "named",
                          dataclasses.replace(options, source=str(folder / "godot_hand_r_posed_rig.gltf")))
    row, by_source = run_task(beside), run_task(named)
    assert row["source_path"] == by_source["source_path"] == str(folder / "godot_hand_r_posed_rig.gltf")
    assert row["s_finger"] == by_source["s_finger"] and row["warning"] == ""
    np.testing.assert_array_equal(load_motion(beside.output).q_tbs, load_motion(named.output).q_tbs)
    # a clip that lacks nothing is read as it is, whatever --source says: the sample clips re-read on the Meta
    # hand given as --source (for the pinch beside them) had kept 0.81 where their own hand keeps 0.96
    (npz,) = plan_batch([COUNTING], ["iris"], ["tbs_copy"], tmp_path / "npz", dataclasses.replace(
        options, animation=None, source=str(folder / "godot_hand_r_posed_rig.gltf")))
    (plain,) = plan_batch([COUNTING], ["iris"], ["tbs_copy"], tmp_path / "plain", dataclasses.replace(
        options, animation=None))
    row, alone = run_task(npz), run_task(plain)
    assert row["source_path"] == "" and row["warning"] == "" and row["kept"] == alone["kept"]


def test_a_finger_bent_sideways_reads_red_on_the_page_in_the_viewers_words_with_the_thumb_beside_it(tmp_path):
    """TBS Copy of the authored poses onto the VRM robot bends the pinky PIP 59 deg sideways where the source bends
    38: the viewer's Sideways cell is red and says so, and a batch's page gave the 59 alone, neither red nor beside
    the source's, and no thumb figure (an issue 26 goal) at all."""
    from s2h_viewer.batch.report import write_report
    from s2h_viewer.batch.summary import write_summary
    from s2h_viewer.batch.task import run_task
    from s2h_viewer.batch.task import POSES_APART
    from s2h_viewer.io.files import RigOptions
    from s2h_viewer.semantics.flexion import thumb_words
    from s2h_viewer.semantics.signature import held_poses
    real = ASSETS_DIR / "motions" / "real"
    options = TaskOptions(format="npz", side="right", animation="all", source=str(real / "godot_hand_r_posed_rig.gltf"))
    bent, = (run_task(t) for t in plan_batch([str(real / "godot_hand_poses_r.gltf")],
                                            [str(ASSETS_DIR / "hands" / "real" / "debug_robot.vrm")], ["tbs_copy"],
                                            tmp_path, options, tuple(METHODS)))
    clean, = (run_task(t) for t in plan_batch([COUNTING], ["iris"], ["tbs_copy"], tmp_path,
                                             TaskOptions(format="npz", render=False), tuple(METHODS)))
    astray, = (run_task(t) for t in plan_batch([GESTURES], [str(ASSETS_DIR / "hands" / "real" / "debug_robot.vrm")],
                                              ["asrn"], tmp_path, TaskOptions(format="npz", render=False, side="right"),
                                              tuple(METHODS)))  # its claw's thumb brought across the palm
    assert bent["sideways_deg"] > bent["source_sideways_deg"] + 5 > 25 and clean["sideways_deg"] < 25
    assert bent["sideways_words"].startswith("pinky PIP bends") and "(the source bends" in bent["sideways_words"]
    assert "(Sign 3)" in bent["sideways_words"]  # the curve's peak, named by the pose held there
    # each lost pose with the frame it is held at, to go there (a fresh-eyes user had only its name)
    import re
    held = dict(held_poses(load_motion_file(real / "godot_hand_poses_r.gltf", None, RigOptions(animation="all"))[0].labels))
    for line in bent["poses_lost"].split(POSES_APART):
        name, frame = re.match(r"(.+) \(frame (\d+)\): ", line).groups()
        assert held[name] == int(frame), line
    assert 0.0 < bent["thumb_follow"] <= 1.0 and bent["thumb_follow_at"].startswith("thumb_")
    rows = read_summary(write_summary([bent, clean, astray], tmp_path / "summary.csv"))  # as the viewer reads them
    assert rows[0]["sideways_words"] == bent["sideways_words"]
    assert rows[0]["source_sideways_deg"] == pytest.approx(bent["source_sideways_deg"], abs=1e-5)
    page = write_report(rows, tmp_path / "report.html").read_text()
    import html
    red = sorted(float(v) for v in re.findall(r'<td class="num broken" data-sort="([^"]*)">', page))
    assert astray["thumb_follow"] < 0.9 < min(bent["thumb_follow"], clean["thumb_follow"])  # red: the thumb astray
    assert red == pytest.approx(sorted([astray["thumb_follow"], bent["sideways_deg"]]), abs=1e-5)  # and the bend
    assert html.escape(bent["sideways_words"]) in page
    assert f'<div class=warning>{html.escape(bent["warning"])}</div>' in page  # the robot's guessed frames: orange,
    assert f'<div>{html.escape(bent["sideways_words"])}</div>' in page  # as the viewer's banner; the words black
    # a red thumb says why in the note, as the viewer's tooltip does: which angle (the page had the figure alone)
    assert html.escape(thumb_words(astray["thumb_follow"], astray["thumb_follow_at"])) in page
    assert "under 0.9" not in page.split(html.escape(bent["sideways_words"]))[1].split("<tr")[0]  # bent's: 0.95
    # the fingertips it puts on the palm where the source's are not: no column of the page counts them, its note does
    assert rows[0]["invented"] == bent["invented"] > 0 and "-palm on " in bent["invented_words"]
    assert html.escape(bent["invented_words"]) in page
    # a picture of the frame the red figure is at, under the worst frame's (that showed a fist: the note a pinky)
    frame = int(bent["sideways_at"].partition("@")[2])
    assert frame != bent["worst_frame"] and Path(bent["sideways_picture"]).stat().st_size > 1000
    import imageio.v3 as iio  # the bent joint marked red on the source and on the retarget, and only there
    red = [(np.abs(iio.imread(bent[key])[..., :3].astype(int) - (198, 40, 40)).max(-1) < 60)
           for key in ("sideways_picture", "picture")]
    half = red[0].shape[1] // 2
    assert red[0][:, :half].sum() > 30 and red[0][:, half:].sum() > 30 and red[1].sum() == 0
    assert f"the sideways bend, frame {frame}:" in page and 'src="godot_hand_poses_r/debug_robot/tbs_copy.sideways.png"' in page
    assert "<th data-col" in page and ">thumb follows</th>" in page
    assert f'>{bent["thumb_follow"]:.2f}</td>' in page
