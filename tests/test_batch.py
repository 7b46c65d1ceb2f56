"""``ibr batch`` (issue #15): idempotent jobs on a local process pool and on a Dask LocalCluster.

Each batch is a few ``ibr stereo`` / ``ibr interpolate`` command lines on 48 x 36 synthetic views
(about 1 s per job, mostly interpreter start-up). The workers are killed with SIGKILL mid-batch:
every job must still be committed exactly once (``commits.log``), leave no staging folder or
temporary file, and give the same pixels as an undisturbed run.
"""

from __future__ import annotations

import json
import re
import multiprocessing
import os
import shutil
import signal
import time
from pathlib import Path

import numpy as np
import pytest

import cli
from ibr.io import read_image, save_view
from ibr.sequence import load_jobs, run_batch
from ibr.sequence.jobs import STAGE_PREFIX
from ibr.synth import camera_path, make_scene, render_path

N_STEREO = 3


def _make_batch(folder: Path, views) -> Path:
    """Views and a batch file in ``folder``: 3 stereo jobs, 1 interpolate job (folder output), 1 failing job."""
    (folder / "views").mkdir(parents=True)
    (folder / "out").mkdir()  # an output's folder must exist, as for the command run alone
    for v in views:
        save_view(v, folder / "views" / f"{v.name}.json")
    jobs = [{"id": f"stereo-{i}", "argv": ["stereo", f"views/{views[i].name}.json", "--mode", "sbs",
                                          "-o", f"out/stereo_{i}.png"]} for i in range(N_STEREO)]
    jobs.append({"id": "mid", "command": f"ibr interpolate views/{views[0].name}.json views/{views[1].name}.json "
                                         "--frames 3 --out out/mid"})
    jobs.append({"id": "broken", "argv": ["stereo", "views/missing.json", "-o", "out/broken.png"]})
    path = folder / "jobs.json"
    path.write_text(json.dumps({"format": "ibr-batch", "version": 1, "jobs": jobs}, indent=1))
    return path


@pytest.fixture(scope="module")
def views():
    cams = camera_path("room", N_STEREO, width=48, height=36)
    return render_path(make_scene("room"), cams, supersample=1, name="v")


@pytest.fixture(scope="module")
def reference(tmp_path_factory, views):
    """One undisturbed local-pool run: its folder and report."""
    folder = tmp_path_factory.mktemp("reference")
    jobs = load_jobs(_make_batch(folder, views))
    report = run_batch(jobs, records=folder / ".ibr-batch", workers=2)
    return folder, report


def _outputs(folder: Path) -> dict[str, np.ndarray]:
    return {str(p.relative_to(folder)): read_image(p) for p in sorted((folder / "out").rglob("*.png"))}


def _assert_clean(folder: Path) -> None:
    leftovers = [p.name for p in (folder / "out").rglob("*") if p.name.startswith(".")]
    assert leftovers == []                       # no staging folder, no temporary file


def _commits(folder: Path, run_id: str) -> list[str]:
    lines = (folder / ".ibr-batch" / "commits.log").read_text().splitlines()
    return sorted(json.loads(x)["id"] for x in lines if json.loads(x)["run"] == run_id)


EXPECTED_DONE = sorted([f"stereo-{i}" for i in range(N_STEREO)] + ["mid"])


# --------------------------------------------------------------------------- job files
def test_load_jobs_infers_outputs_and_refuses_bad_files(tmp_path):
    path = tmp_path / "j.json"
    path.write_text(json.dumps([{"command": "ibr stereo a.json --mode sbs -o out/a.png"},
                                ["warp", "a.json", "--to", "b.json", "--out=w.png"]]))
    a, b = load_jobs(path)
    assert a.argv == ("stereo", "a.json", "--mode", "sbs", "-o", "out/a.png") and a.outputs == ("out/a.png",)
    assert b.outputs == ("w.png",) and a.cwd == str(tmp_path.resolve()) and a.id != b.id
    cases = [
        ([{"argv": ["stereo", "a.json"]}], "no output found"),
        ([{"argv": ["batch", "x.json", "-o", "y"]}], "cannot run 'ibr batch'"),
        ([{"argv": ["view", "p.png", "--serve", "--site", "s"]}], r"ibr view --serve serves a page until .* --site DIR"),
        ([{"id": "x", "argv": ["warp", "a", "-o", "p.png"]}, {"id": "x", "argv": ["warp", "b", "-o", "q.png"]}],
         "id 'x'"),
        ([{"argv": ["warp", "a", "-o", "p.png"]}, {"argv": ["warp", "b", "-o", "./p.png"]}], "also an output"),
        ([{"argv": ["warp", "a", "-o", "p.png"], "outputs": ["q.png"]}], "does not appear"),
        ([{"argv": ["warp", "a", "-o", "p.png"], "colour": 1}], "unknown key"),
        ([{"argv": ["warp", "a", "-o", "p.png"], "idd": "x"}], "unknown key 'idd' \\(did you mean 'id'\\?\\)"),
        ([{"command": "ibr warp a -o 'p 2.png"}], r"jobs\[0\]: command: No closing quotation"),
        ([], "non-empty list"),
    ]
    for doc, message in cases:
        path.write_text(json.dumps(doc))
        with pytest.raises(ValueError, match=message):
            load_jobs(path)
    with pytest.raises(FileNotFoundError):
        load_jobs(tmp_path / "missing.json")


def test_a_job_never_overwrites_its_own_input(tmp_path, views):
    """Run alone, ``ibr warp A --to A -o A_color.png`` is refused; in a batch the command writes
    into a staging folder and cannot see it, so the batch itself must refuse: directly, through a
    link, and through an output folder that holds an input. The input stays as it was."""
    save_view(views[0], tmp_path / "a.json")
    color = next(tmp_path.glob("*_color.png"))
    before = color.read_bytes()
    (tmp_path / "link.png").symlink_to(color.name)
    # view b's colour file is where the folder job writes its first frame
    save_view(views[1], tmp_path / "b.json")
    doc = json.loads((tmp_path / "b.json").read_text())
    (tmp_path / "frames").mkdir()
    first = "frames/frame_000_t0.000.png"
    (tmp_path / doc["color"]).rename(tmp_path / first)
    doc["color"] = first
    (tmp_path / "b.json").write_text(json.dumps(doc))
    b_before = (tmp_path / first).read_bytes()
    jobs = [{"id": "direct", "argv": ["warp", "a.json", "--to", "a.json", "-o", color.name]},
            {"id": "link", "argv": ["warp", "a.json", "--to", "a.json", "-o", "link.png"]},
            {"id": "folder", "argv": ["interpolate", "b.json", "a.json", "--frames", "2", "--out", "frames"]},
            {"id": "fine", "argv": ["interpolate", "b.json", "a.json", "--frames", "2", "--out", "other"]}]
    path = tmp_path / "jobs.json"
    path.write_text(json.dumps({"format": "ibr-batch", "version": 1, "jobs": jobs}))
    report = run_batch(load_jobs(path), records=tmp_path / ".ibr-batch", workers=1)
    status = {r["id"]: (r["status"], r["error"]) for r in report.results}
    assert status["direct"][0] == "failed" and "is an input of the job" in status["direct"][1]
    assert status["link"][0] == "failed" and "is an input of the job" in status["link"][1]
    # (the command sees its final output folder through IBR_BATCH_FINALS and refuses it first)
    assert status["folder"][0] == "failed" and re.search("is an input of the job|is the input", status["folder"][1])
    assert color.read_bytes() == before and (tmp_path / first).read_bytes() == b_before
    assert status["fine"][0] == "done", status["fine"]  # the same job into another folder
    assert sorted(p.name for p in (tmp_path / "other").iterdir()) == ["frame_000_t0.000.png", "frame_001_t1.000.png"]
    assert not [p for p in tmp_path.rglob(".*") if p.name.startswith(STAGE_PREFIX)]


# --------------------------------------------------------------------------- local pool
def test_local_pool_runs_reports_failures_and_reruns_nothing(reference):
    folder, report = reference
    status = {r["id"]: r["status"] for r in report.results}
    assert status == {**{i: "done" for i in EXPECTED_DONE}, "broken": "failed"}
    broken = next(r for r in report.results if r["id"] == "broken")
    assert "missing.json" in broken["error"] and broken["returncode"] == 1
    assert _commits(folder, report.run_id) == EXPECTED_DONE
    outs = _outputs(folder)
    assert len(outs) == N_STEREO + 3 and outs["out/stereo_0.png"].shape == (36, 96, 3)
    _assert_clean(folder)
    table = report.table()
    assert "4 done, 0 skipped" in table and "1 failed" in table and "broken" in table

    again = run_batch(load_jobs(folder / "jobs.json"), records=folder / ".ibr-batch", workers=2)
    assert again.counts == {"done": 0, "skipped": 4, "failed": 1}
    assert _commits(folder, again.run_id) == []                # a second run does no work


def test_a_changed_input_or_a_deleted_output_reruns_only_its_job(tmp_path, reference):
    from ibr.io import write_image

    folder = tmp_path / "copy"                                  # the finished batch, moved elsewhere
    shutil.copytree(reference[0], folder)
    color = next((folder / "views").glob("*_0002_color.png"))
    write_image(color, 255 - read_image(color))                 # input of stereo-2 only
    (folder / "out" / "stereo_1.png").unlink()                  # output of stereo-1
    rerun = run_batch(load_jobs(folder / "jobs.json"), records=folder / ".ibr-batch", workers=2)
    assert sorted(r["id"] for r in rerun.results if r["status"] == "done") == ["stereo-1", "stereo-2"]
    assert rerun.counts["skipped"] == 2


def test_cli_batch_writes_the_table_and_the_report(tmp_path, views, capsys):
    path = _make_batch(tmp_path, views)
    doc = json.loads(path.read_text())
    doc["jobs"] = doc["jobs"][:1] + doc["jobs"][-1:]            # one good job, one broken
    path.write_text(json.dumps(doc))
    assert cli.main(["batch", str(path), "--workers", "1"]) == 1  # a failed job: exit code 1
    out = capsys.readouterr()
    assert "1 done, 0 skipped (up to date), 1 failed" in out.out and "jobs/s" in out.err
    report = json.loads((tmp_path / "jobs.report.json").read_text())
    assert report["counts"] == {"done": 1, "skipped": 0, "failed": 1}


def test_local_pool_survives_a_killed_worker(tmp_path, views, reference):
    path = _make_batch(tmp_path, views)
    killed = []

    def kill_one(result):
        # every worker, at the first result, once a job is inside its command (its staging folder
        # exists): killing at the first result alone could find both workers between jobs (the
        # first two jobs take the same time, so both finish together), which interrupts nothing
        if not killed:
            deadline = time.monotonic() + 30
            while not any(tmp_path.rglob(f"{STAGE_PREFIX}*")) and time.monotonic() < deadline:
                time.sleep(0.001)
            victims = multiprocessing.active_children()
            assert victims
            for victim in victims:
                os.kill(victim.pid, signal.SIGKILL)
                killed.append(victim.pid)

    report = run_batch(load_jobs(path), records=tmp_path / ".ibr-batch", workers=2, on_result=kill_one)
    assert killed
    assert report.counts == {"done": 4, "skipped": 0, "failed": 1}
    assert any(r["interrupted_attempts"] or r["recovered"] for r in report.results)  # a job was cut short
    assert _commits(tmp_path, report.run_id) == EXPECTED_DONE  # exactly once each
    _assert_clean(tmp_path)
    ref = _outputs(reference[0])
    got = _outputs(tmp_path)
    assert got.keys() == ref.keys() and all(np.array_equal(got[k], ref[k]) for k in ref)


# --------------------------------------------------------------------------- Dask
def test_dask_cluster_killed_worker_exactly_once_and_same_pixels(tmp_path, views, reference):
    distributed = pytest.importorskip("distributed")
    path = _make_batch(tmp_path, views)
    records = tmp_path / ".ibr-batch"
    # 4 workers on this 2-core machine: oversubscribed on purpose
    with distributed.LocalCluster(n_workers=4, threads_per_worker=1, processes=True, dashboard_address=":0",
                                  silence_logs=50) as cluster, distributed.Client(cluster) as client:
        killed = []

        def kill_busy_worker(result):
            if killed:
                return
            # wait until a job is inside its command (its staging folder exists) and a worker holds
            # it: at the first result the other workers could be between jobs (a fast machine
            # finished the first jobs together and nothing was killed)
            deadline = time.monotonic() + 30
            busy = []
            while time.monotonic() < deadline:
                busy = [addr for addr, keys in client.processing().items() if keys]
                if busy and any(tmp_path.rglob(f"{STAGE_PREFIX}*")):
                    break
                time.sleep(0.001)
            if busy:
                pid = client.run(os.getpid, workers=[busy[0]])[busy[0]]
                os.kill(pid, signal.SIGKILL)
                killed.append(pid)

        report = run_batch(load_jobs(path), records=records, scheduler=client, on_result=kill_busy_worker)
        assert killed
        assert report.where.startswith("dask tcp://")
        assert any(r["interrupted_attempts"] or r["recovered"] for r in report.results)  # a job was cut short
        assert report.counts == {"done": 4, "skipped": 0, "failed": 1}
        assert _commits(tmp_path, report.run_id) == EXPECTED_DONE   # exactly once each
        _assert_clean(tmp_path)
        ref = _outputs(reference[0])
        got = _outputs(tmp_path)
        assert got.keys() == ref.keys() and all(np.array_equal(got[k], ref[k]) for k in ref)

        again = run_batch(load_jobs(path), records=records, scheduler=cluster.scheduler_address)  # by address
        assert again.counts == {"done": 0, "skipped": 4, "failed": 1}
        assert _commits(tmp_path, again.run_id) == []
    shutil.rmtree(tmp_path / "out")


def test_report_and_records_never_replace_the_batch_s_files(tmp_path, views, capsys):
    """``ibr batch jobs.json --report jobs.json`` replaced the job file with the report;
    ``--records views`` with a job whose id is a view's name wrote its record over that view.
    Both are refused before any job runs, as a records path that is a file."""
    path = _make_batch(tmp_path, views)
    doc = json.loads(path.read_text())
    doc["jobs"] = doc["jobs"][:1]
    doc["jobs"][0]["id"] = views[0].name  # its record would be views/<name>.json: the job's input
    path.write_text(json.dumps(doc))
    before = {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}
    for extra, match in ((["--report", str(path)], "--report: .* is the batch file"),
                         (["--records", str(tmp_path / "views")], "--records: .* is an input of job"),
                         (["--records", str(path)], "--records: .* is a file")):
        assert cli.main(["batch", str(path), "--workers", "1", *extra]) == 1
        assert re.search(match, capsys.readouterr().err)
    assert {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()} == before


def test_a_failed_commit_replaces_nothing(tmp_path, views):
    """A stitch-like job with two outputs, one of them an existing folder: the command succeeded
    in its staging folder, then the commit replaced the first output and failed on the second,
    leaving a half-committed result and the staging folder. Nothing is moved now unless
    every file can be, and the staging folder is removed."""
    path = _make_batch(tmp_path, views)
    out = tmp_path / "out"
    (out / "stereo_0.png").write_bytes(b"old")
    (out / "holes.png").mkdir()  # an existing folder where a file output goes
    doc = json.loads(path.read_text())
    doc["jobs"] = [{"id": "two", "argv": ["warp", f"views/{views[0].name}.json", "--to", f"views/{views[1].name}.json",
                                          "-o", "out/stereo_0.png", "--holes-out", "out/holes.png"]}]
    path.write_text(json.dumps(doc))
    report = run_batch(load_jobs(path), records=tmp_path / ".ibr-batch", workers=1)
    # the command sees the final paths (IBR_BATCH_FINALS) and refuses the folder itself
    assert report.counts["failed"] == 1 and "holes.png is a folder, expected a file name" in report.results[0]["error"]
    assert (out / "stereo_0.png").read_bytes() == b"old" and (out / "holes.png").is_dir()
    assert not any(tmp_path.rglob(f"{STAGE_PREFIX}*"))
    # and the commit itself moves nothing unless every staged file can be moved
    from ibr.sequence.jobs import _commit

    stage = out / f"{STAGE_PREFIX}x-1"
    stage.mkdir()
    (stage / "stereo_0.png").write_bytes(b"new")
    (stage / "holes.png").write_bytes(b"new")
    with pytest.raises(IsADirectoryError, match="holes.png is an existing folder"):
        _commit([stage])
    assert (out / "stereo_0.png").read_bytes() == b"old"


def test_a_job_s_own_input_checks_see_the_final_outputs(tmp_path):
    """``ibr import nerf transforms.json --out images`` with the depth files in images/ is
    refused run alone ("its file r_0_depth.exr is the input"), but through ``ibr batch`` the
    command wrote into a staging folder, passed, and the commit replaced the depth files the
    transforms.json names (halved depths). The command now checks the final paths too."""
    src = Path(__file__).parent / "data" / "import" / "blender_rgb"
    (tmp_path / "images").mkdir()
    for f in src.iterdir():
        if f.suffix in (".png", ".exr"):
            shutil.copy(f, tmp_path / "images" / f.name)
    t = json.loads((src / "transforms.json").read_text())
    for fr in t["frames"]:
        fr["file_path"], fr["depth_file_path"] = "images/" + fr["file_path"], "images/" + fr["depth_file_path"]
    t["depth_unit_scale_factor"] = 0.5
    (tmp_path / "transforms.json").write_text(json.dumps(t))
    before = {p.name: p.read_bytes() for p in (tmp_path / "images").iterdir()}
    assert cli.main(["import", "nerf", str(tmp_path / "transforms.json"), "--out", str(tmp_path / "images")]) == 1
    jobs = [{"id": "imp", "argv": ["import", "nerf", "transforms.json", "--out", "images"]}]
    path = tmp_path / "jobs.json"
    path.write_text(json.dumps({"format": "ibr-batch", "version": 1, "jobs": jobs}))
    report = run_batch(load_jobs(path), records=tmp_path / ".ibr-batch", workers=1)
    assert report.counts["failed"] == 1 and "is the input" in report.results[0]["error"]
    assert {p.name: p.read_bytes() for p in (tmp_path / "images").iterdir()} == before


def test_a_failed_job_leaves_no_new_folders_and_cwd_must_exist(tmp_path, views):
    """A failed job with ``-o newdir/deeper/x.png`` left newdir/deeper/ behind, and a job whose
    ``cwd`` did not exist got that folder created by the staging of its outputs."""
    path = _make_batch(tmp_path, views)
    doc = json.loads(path.read_text())
    doc["jobs"] = [{"id": "bad", "argv": ["stereo", "views/missing.json", "-o", "newdir/deeper/x.png"]}]
    path.write_text(json.dumps(doc))
    report = run_batch(load_jobs(path), records=tmp_path / ".ibr-batch", workers=1)
    assert report.counts["failed"] == 1 and not (tmp_path / "newdir").exists()
    doc["jobs"] = [{"id": "nowhere", "cwd": "no/such/folder", "argv": ["stereo", "a.json", "-o", "x.png"]}]
    path.write_text(json.dumps(doc))
    with pytest.raises(ValueError, match="'cwd' .*no/such/folder is not an existing folder"):
        load_jobs(path)
    assert not (tmp_path / "no").exists()


def test_failures_name_the_paths_as_the_job_wrote_them_and_missing_folders_are_refused(tmp_path, views, capsys):
    """A job's error named the hidden staging path (``-o: /…/out/.ibr-batch-warp-…/m1.txt has the
    extension '.txt'``), and ``mesh … --obj nodir/x7.obj`` reported done and created nodir/,
    which ``ibr mesh`` run alone refuses. Now the messages are the command's own, with the job's
    paths, and a missing output folder is refused with the direct command's message (nothing is
    created for the staging: the staged path keeps the missing folder)."""
    for v in views[:2]:
        save_view(v, tmp_path / f"{v.name}.json")
    (tmp_path / "out").mkdir()
    a, b = (f"{v.name}.json" for v in views[:2])
    jobs = [{"id": "txt", "argv": ["warp", a, "--to", b, "-o", "out/m1.txt"]},
            {"id": "json", "argv": ["mesh", a, "--obj", "jobs.json"]},
            {"id": "nodir", "argv": ["mesh", a, "--obj", "nodir/x7.obj"]},
            {"id": "export", "argv": ["import", "export-nerf", a, "--out", "nodir2/t.json"]},
            {"id": "deep", "argv": ["warp", a, "--to", b, "-o", "out/no/such/w.png"]},
            {"id": "fine", "argv": ["warp", a, "--to", b, "-o", "out/w.png"]}]
    path = tmp_path / "jobs.json"
    path.write_text(json.dumps({"format": "ibr-batch", "version": 1, "jobs": jobs}))
    before = path.read_bytes()
    report = run_batch(load_jobs(path), records=tmp_path / ".ibr-batch", workers=2)
    error = {r["id"]: r["error"] for r in report.results}
    assert error["txt"] == ("ibr warp: error: -o: out/m1.txt has the extension '.txt'; "
                            "expected one of .png, .jpg, .jpeg, .tif, .tiff, .exr, .pfm")
    assert error["json"] == "ibr mesh: error: --obj: jobs.json has the extension '.json'; expected one of .obj"
    for job, option, out in (("nodir", "--obj", "nodir/x7.obj"), ("export", "--out", "nodir2/t.json"),
                             ("deep", "-o", "out/no/such/w.png")):
        assert cli.main([*next(j["argv"] for j in jobs if j["id"] == job)[:-2], option, str(tmp_path / out)]) == 1
        alone = capsys.readouterr().err.strip().replace(str(tmp_path) + os.sep, "")
        assert error[job] == alone, (error[job], alone)  # the same message as the command run alone
        assert "does not exist" in alone and STAGE_PREFIX not in error[job]
    assert error["fine"] == "" and (tmp_path / "out" / "w.png").is_file()
    assert not (tmp_path / "nodir").exists() and not (tmp_path / "nodir2").exists()
    assert not (tmp_path / "out" / "no").exists() and path.read_bytes() == before
    assert not [p for p in tmp_path.rglob(f"{STAGE_PREFIX}*")]


def test_batch_sees_every_form_of_an_output_option(tmp_path, views, capsys):
    """A misspelt ``--objj out/x.obj`` was reported as "no output found" instead of the command's
    own usage error; the attached ``-oout/k8.png`` was not seen as an output. ``ibr batch`` parses
    each job with ibr's own parser: usage errors are refused up front with the command's message,
    and outputs are found as the command reads them (attached, ``=`` and abbreviated forms)."""
    save_view(views[0], tmp_path / "a.json")
    save_view(views[1], tmp_path / "b.json")
    (tmp_path / "out").mkdir()
    path = tmp_path / "jobs.json"
    path.write_text(json.dumps([["mesh", "a.json", "--objj", "out/x.obj"]]))
    assert cli.main(["batch", str(path), "--workers", "1"]) == 1
    err = capsys.readouterr().err
    assert "jobs[0]: ibr mesh: " in err and "unrecognized arguments: --objj out/x.obj" in err
    assert "no output found" not in err
    path.write_text(json.dumps([["interpolate", "a.json", "b.json"]]))  # its default --out is not on the line
    with pytest.raises(ValueError, match="jobs\\[0\\]: no output found"):
        load_jobs(path, parser=cli.build_parser())
    path.write_text(json.dumps([["warp", "a.json", "--to", "b.json", "-oout/k8.png"],
                                ["warp", "a.json", "--to", "b.json", "--output=out/k9.png"],
                                ["warp", "b.json", "--to", "a.json", "-o", "out/k10.png", "--depth-o", "out/k10.exr"]]))
    assert [j.outputs for j in load_jobs(path)][0] == ("out/k8.png",)  # the library sees -oVALUE too
    assert cli.main(["batch", str(path), "--workers", "1"]) == 0
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["k10.exr", "k10.png", "k8.png", "k9.png"]
    record = json.loads(next((tmp_path / ".ibr-batch").glob("warp-*.json")).read_text())
    assert record["outputs"]
    records = [json.loads(p.read_text()) for p in (tmp_path / ".ibr-batch").glob("warp-*.json")]
    assert sorted(o for r in records for o in r["outputs"]) == ["out/k10.exr", "out/k10.png", "out/k8.png", "out/k9.png"]


def test_inputs_and_none_values_of_output_options_are_not_outputs(tmp_path):
    """canvas --video CLIP is the clip shown on the plane (an input: staged, the job failed with
    "video: file not found"), and --depth-out none writes no file (staged as a path, the job failed
    with "--depth-out: none has no extension"); with and without ibr's parser."""
    from cli import build_parser

    path = tmp_path / "j.json"
    path.write_text(json.dumps([
        ["canvas", "a.json", "--video", "clip.mp4", "--center", "0", "0", "3", "--normal", "0", "0", "-1",
         "--size", "1", "1", "-o", "frames"],
        ["stitch", "a.json", "b.json", "-o", "p.png", "--depth-out", "none"],
        ["stitch", "a.json", "b.json", "-o", "q.png", "--depth-out", "q_depth.exr"]]))
    for parser in (build_parser(), None):
        canvas, stitch, both = load_jobs(path, parser=parser) if parser else load_jobs(path)
        assert canvas.outputs == ("frames",) and stitch.outputs == ("p.png",)
        assert both.outputs == ("q.png", "q_depth.exr")


def test_a_folder_named_none_is_still_an_output():
    """'none' names no file only for stitch's --depth-out; interpolate --out none is a folder."""
    from cli import build_parser
    from ibr.sequence.jobs import _job_from

    job = _job_from({"command": "interpolate a.json b.json --out none"}, 0, Path("."), build_parser())
    assert job.outputs == ("none",)


def test_a_commit_whose_log_line_was_lost_is_logged_by_the_recovering_attempt(tmp_path, views):
    """A worker killed between the job's record (the commit) and its commits.log line: the next
    attempt of the same run finds the record, reports the job done (recovered) and writes the
    missing line once (the kill landed there once in CI: stereo-1 done, no line)."""
    from ibr.sequence.jobs import run_job

    path = _make_batch(tmp_path, views)
    job = load_jobs(path)[0]
    records = tmp_path / ".ibr-batch"
    first = run_job(job, "run-1", records)
    assert first["status"] == "done" and _commits(tmp_path, "run-1") == [job.id]
    (records / "commits.log").write_text("")  # as if the worker died right after the record
    again = run_job(job, "run-1", records)
    assert again["status"] == "done" and again["recovered"]
    assert _commits(tmp_path, "run-1") == [job.id]
    assert run_job(job, "run-1", records)["recovered"] and _commits(tmp_path, "run-1") == [job.id]  # once
    assert run_job(job, "run-2", records)["status"] == "skipped" and _commits(tmp_path, "run-2") == []
