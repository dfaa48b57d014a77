"""slam_mms.fleet (issue 24 item 3): drives as Dask tasks, then the adjustment.

Three short simulated drives (the same 8 s demo drive, as is and with two GNSS outages) run
through the sequential path and through a LocalCluster with 2 workers: the same files bit for bit
(trajectories, drive results with their covariances, the adjustment's report). A run depends on
its command line and its thread count, not on where the process's heap puts things (the sliding
window removes a leaving state's factors in the order they were added; before, the last digits
moved with the allocation pattern: docs/fleet.md), and num_threads: 1 with a solve time limit a
loaded machine cannot reach takes the wall clock out. Then resume (finished drives not rerun, their
files untouched; a drive whose options changed runs again) and failures (a missing drive and a
drive the app rejects fail with messages naming them, the other drive finishes, the adjustment is
skipped with fewer than 2 drives). About 1 to 2 minutes on 2 cores.
"""

from __future__ import annotations

import importlib.util
import json
import os
import pathlib
import shutil
import subprocess
import sys
from typing import Any, Dict

import numpy as np
import pytest
from conftest import read_tum_exact

import slam_mms
from slam_mms import fleet

# Deterministic runs: one thread (MappingSystem's note: exact with num_threads = 1) and a window
# solve limit far above what an 8 s drive needs, so a loaded machine cannot stop a solve early.
DET_CONFIG = "num_threads: 1\nlocalizer:\n  window:\n    max_solve_time_s: 100\n"
MERGE_ARGS = ["--threads=1"]


@pytest.fixture(scope="module")
def fleet_inputs(tmp_path_factory):
    """(drive folder, config file) made once for this module."""
    root = tmp_path_factory.mktemp("fleet_in")
    drive = slam_mms.simulate_drive(root / "sim", scenario="demo", duration_s=8.0, seed=7,
                                    write_scene_cloud=False)
    config = root / "det.yaml"
    config.write_text(DET_CONFIG)
    return drive, config


def _drives(drive: pathlib.Path):
    return [fleet.FleetDrive(path=str(drive)),
            fleet.FleetDrive.parse(f"{drive}::--gnss-outage 3:3"),
            fleet.FleetDrive.parse(f"{drive}::--gnss-outage 1:4")]


def _run(drives, out, config, **kw) -> fleet.FleetResult:
    lines = []
    r = fleet.run_fleet(drives, out, run_args=[f"--config={config}"], merge_args=MERGE_ARGS,
                        progress=lines.append, **kw)
    r.lines = lines  # type: ignore[attr-defined]
    return r


@pytest.fixture(scope="module")
def sequential_run(fleet_inputs, tmp_path_factory):
    drive, config = fleet_inputs
    return _run(_drives(drive), tmp_path_factory.mktemp("fleet_seq"), config,
                scheduler="sequential")


def _flat(report: Any, prefix: str = "") -> Dict[str, Any]:
    """The merged report as {path: leaf}, without wall times, command line and paths (they
    differ by design)."""
    if isinstance(report, dict):
        items = [(k, v) for k, v in report.items()
                 if not k.endswith("wall_s") and k not in ("command_line", "path")]
    elif isinstance(report, list):
        items = list(enumerate(report))
    else:
        return {prefix: report}
    out: Dict[str, Any] = {}
    for k, v in items:
        out.update(_flat(v, f"{prefix}/{k}"))
    return out


def _same_trajectory(a: pathlib.Path, b: pathlib.Path) -> None:
    """The same file, bit for bit (and a real trajectory)."""
    ta, _ = read_tum_exact(a)
    assert len(ta) > 10, a
    assert a.read_bytes() == b.read_bytes(), f"{b} differs from {a}"


def _mtimes(root: pathlib.Path) -> Dict[str, int]:
    return {str(p.relative_to(root)): p.stat().st_mtime_ns for p in root.rglob("*") if p.is_file()}


# ---- drive lists, names --------------------------------------------------------------------


def test_drive_specs_and_unique_names(tmp_path):
    d = fleet.FleetDrive.parse("/data/a/drive_0001_sync::--gnss-outage 20:30 --frames 0:99")
    assert d.path == "/data/a/drive_0001_sync"
    assert d.run_args == ("--gnss-outage", "20:30", "--frames", "0:99")
    assert fleet.FleetDrive.parse("/data/b.bag").run_args == ()
    names = [x.name for x in fleet._as_drives(["/x/d1", "/y/d1/", "/z/d1", "/r/run.bag"])]
    assert names == ["d1", "d1_2", "d1_3", "run"]
    with pytest.raises(fleet.FleetError, match="used twice"):
        fleet._as_drives([fleet.FleetDrive("/a", name="n"), fleet.FleetDrive("/b", name="n")])
    f = tmp_path / "drives.json"
    f.write_text(json.dumps(["/a/x", {"path": "/b/y", "name": "why",
                                      "run_args": "--gnss-outage 1:2"}]))
    got = fleet.read_drives_file(f)
    assert got[1] == fleet.FleetDrive("/b/y", "why", ("--gnss-outage", "1:2"))
    f.write_text(json.dumps([{"path": "/a", "nmae": "typo"}]))
    with pytest.raises(fleet.FleetError, match="entry 0: unknown keys"):
        fleet.read_drives_file(f)
    if importlib.util.find_spec("s3fs") is None:  # an object store whose package is missing
        with pytest.raises(fleet.FleetError, match="s3://bucket/out: .*s3fs"):
            fleet.run_fleet(["/a"], "s3://bucket/out", scheduler="sequential")


# ---- (a) the Dask path equals the sequential path ---------------------------------------------


def test_sequential_run(sequential_run):
    r = sequential_run
    assert r.ok, [d.message for d in r.drives] + [r.merge.message]
    assert [d.status for d in r.drives] == ["done", "done", "done"]
    assert r.scheduler == "sequential" and r.workers == 1
    data = json.loads((pathlib.Path(r.out) / "fleet.json").read_text())
    assert data["counts"] == {"done": 3, "resumed": 0, "failed": 0}
    assert data["merge_report"] == str(pathlib.Path(r.out) / "merged" / "report.json")
    assert data["stage1_wall_s"] > 0 and data["stage2_wall_s"] > 0
    assert all(d["worker"] == "local" and d["wall_s"] > 0 for d in data["drives"])
    assert any("3/3 drives done (0 resumed, 0 failed)" in line for line in r.lines)


def test_local_cluster_matches_sequential(fleet_inputs, sequential_run, tmp_path_factory):
    pytest.importorskip("distributed", reason="dask.distributed is not installed "
                        "(apt-get install python3-distributed)")
    drive, config = fleet_inputs
    out = tmp_path_factory.mktemp("fleet_dsk")
    r = _run(_drives(drive), out, config, scheduler="local", workers=2, dashboard_address=None)
    assert r.ok, [d.message for d in r.drives] + [r.merge.message]
    assert r.scheduler == "local" and r.workers == 2
    assert all(d.worker.startswith("tcp://") for d in r.drives)
    seq = pathlib.Path(sequential_run.out)
    dsk = pathlib.Path(r.out)
    compared = 0
    for d in sequential_run.drives:
        a = (seq / "drives" / d.name / "ground_truth.tum").read_bytes()
        assert a == (dsk / "drives" / d.name / "ground_truth.tum").read_bytes()
        for f in ("full.tum", "full_level1.tum"):
            _same_trajectory(seq / "drives" / d.name / f, dsk / "drives" / d.name / f)
            compared += 1
        for f in (f"{d.name}.tum", f"{d.name}_before.tum"):
            _same_trajectory(seq / "merged" / f, dsk / "merged" / f)
            compared += 1
    assert compared == 12
    for d in sequential_run.drives:
        f = pathlib.Path("drives") / d.name / "drive_result" / "drive_result.json"
        assert (seq / f).read_bytes() == (dsk / f).read_bytes(), f
    rep_s = json.loads((seq / "merged" / "report.json").read_text())
    rep_d = json.loads((dsk / "merged" / "report.json").read_text())
    assert len(rep_s["drives"]) == 3
    assert rep_s["overlaps"]["accepted"] >= 3
    flat_s, flat_d = _flat(rep_s), _flat(rep_d)
    assert flat_s.keys() == flat_d.keys()
    nums = [k for k, v in flat_s.items() if isinstance(v, float)]
    assert len(nums) > 20
    assert flat_d == flat_s  # every number exactly


# ---- (b) resume --------------------------------------------------------------------------------


def test_resume_does_not_rerun_finished_drives(fleet_inputs, sequential_run, tmp_path):
    drive, config = fleet_inputs
    out = tmp_path / "resume"
    shutil.copytree(sequential_run.out, out)
    drives_dir = out / "drives"
    before = _mtimes(drives_dir)
    r = _run(_drives(drive), out, config, scheduler="sequential", merge=False)
    assert [d.status for d in r.drives] == ["resumed", "resumed", "resumed"]
    assert _mtimes(drives_dir) == before
    assert r.ok and r.merge.status == "not requested"
    data = json.loads((out / "fleet.json").read_text())
    assert [d["status"] for d in data["drives"]] == ["resumed", "resumed", "resumed"]
    assert any("resumed (finished in an earlier run)" in line for line in r.lines)

    # Other options for the second drive: it runs again, the first stays.
    changed = [_drives(drive)[0], fleet.FleetDrive.parse(f"{drive}::--gnss-outage 3:3 "
                                                         "--frames 0:25")]
    first = drives_dir / r.drives[0].name
    before_first = _mtimes(first)
    r = _run(changed, out, config, scheduler="sequential", merge=False)
    assert [d.status for d in r.drives] == ["resumed", "done"]
    assert _mtimes(first) == before_first


# ---- (c) failures --------------------------------------------------------------------------------


def test_bad_drives_fail_alone(fleet_inputs, tmp_path):
    drive, config = fleet_inputs
    empty = tmp_path / "empty_drive"
    empty.mkdir()
    missing = tmp_path / "no_such_drive"
    out = tmp_path / "bad"
    cmd = [sys.executable, "-m", "slam_mms", "fleet", "--scheduler", "sequential", "--drives",
           str(missing), str(empty), f"{drive}::--frames 0:20", "--out", str(out),
           "--config", str(config)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert "no_such_drive FAILED" in proc.stdout and str(missing) in proc.stdout
    assert "adjustment skipped: 1 drive(s) finished" in proc.stdout
    data = json.loads((out / "fleet.json").read_text())
    by_name = {d["name"]: d for d in data["drives"]}
    assert by_name["no_such_drive"]["status"] == "failed"
    assert "not found" in by_name["no_such_drive"]["message"]
    bad = by_name["empty_drive"]
    assert bad["status"] == "failed" and bad["returncode"] == 1, bad
    assert "empty_drive" in bad["message"] and "exit status 1" in bad["message"]
    assert by_name[drive.name]["status"] == "done"
    assert data["merge"]["status"] == "skipped" and data["merge_report"] is None
    assert (out / "logs" / "empty_drive.stderr.txt").stat().st_size > 0


def test_cli_usage_errors(tmp_path):
    run = [sys.executable, "-m", "slam_mms", "fleet"]
    proc = subprocess.run(run + ["--out", str(tmp_path)], capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == 2 and "no drives" in proc.stderr
    proc = subprocess.run(run + ["--drives", "a", "--out", str(tmp_path), "--workers", "0"],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2 and "--workers" in proc.stderr
    proc = subprocess.run(run + ["--drives", "a", "--out", "nosuchprotocol://bucket/x"],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2 and "nosuchprotocol://bucket/x" in proc.stderr, proc.stderr
    assert fleet.main(["--help"]) == 0


# ---- (d) an object store as the output ---------------------------------------------------------


def _store_files(url: str) -> Dict[str, bytes]:
    import fsspec

    fs, root = fsspec.core.url_to_fs(url)
    root = root.rstrip("/")
    return {p[len(root) + 1:]: fs.cat_file(p) for p in fs.find(root)}


def _check_store_run(r, url: str, sequential_run, scratch: pathlib.Path) -> None:
    """The store holds what a folder run writes, with the same results bit for bit."""
    assert r.ok, [d.message for d in r.drives] + [r.merge.message]
    files = _store_files(url)
    seq = pathlib.Path(sequential_run.out)
    for d in sequential_run.drives:
        for f in ("report.json", "full.tum", "map_full.las", "fleet_task.json",
                  "drive_result/drive_result.json", "drive_result/submaps/000000_map.pcd"):
            assert f"drives/{d.name}/{f}" in files, f
        for f in ("full.tum", "full_level1.tum", "drive_result/drive_result.json"):
            assert files[f"drives/{d.name}/{f}"] == (seq / "drives" / d.name / f).read_bytes(), f
        assert f"logs/{d.name}.stderr.txt" in files
        for f in (f"{d.name}.tum", f"{d.name}_before.tum"):
            assert files[f"merged/{f}"] == (seq / "merged" / f).read_bytes(), f
    assert "logs/merge.stderr.txt" in files and "fleet.json" in files
    assert r.merge.report == url + "/merged/report.json"
    rep_s = json.loads((seq / "merged" / "report.json").read_text())
    assert _flat(json.loads(files["merged/report.json"])) == _flat(rep_s)
    assert json.loads(files["fleet.json"])["merge"]["status"] == "done"
    assert list(scratch.iterdir()) == []  # every task removed its staging folder


def test_object_store_sequential_and_resume(fleet_inputs, sequential_run, tmp_path):
    """memory:// (fsspec's in-process store: a real non-file protocol for the sequential path)."""
    pytest.importorskip("fsspec", reason="fsspec is not installed (apt-get install python3-fsspec)")
    import fsspec

    drive, config = fleet_inputs
    url = f"memory://slam_mms_fleet_test/{os.getpid()}"
    scratch = tmp_path / "scratch"
    try:
        r = _run(_drives(drive), url, config, scheduler="sequential", scratch=scratch)
        _check_store_run(r, url, sequential_run, scratch)
        before = _store_files(url)
        r = _run(_drives(drive), url, config, scheduler="sequential", merge=False,
                 scratch=scratch)
        assert [d.status for d in r.drives] == ["resumed", "resumed", "resumed"]
        after = _store_files(url)
        assert {k: v for k, v in after.items() if k != "fleet.json"} == \
            {k: v for k, v in before.items() if k != "fleet.json"}
    finally:
        fs, root = fsspec.core.url_to_fs(url)
        if fs.exists(root):
            fs.rm(root, recursive=True)


def test_object_store_on_a_local_cluster(fleet_inputs, sequential_run, tmp_path):
    """file:// through fsspec, shared by the worker processes like a bucket."""
    pytest.importorskip("fsspec", reason="fsspec is not installed (apt-get install python3-fsspec)")
    pytest.importorskip("distributed", reason="dask.distributed is not installed")
    drive, config = fleet_inputs
    url = (tmp_path / "bucket").as_uri()
    scratch = tmp_path / "scratch"
    r = _run(_drives(drive), url, config, scheduler="local", workers=2, dashboard_address=None,
             scratch=scratch)
    assert all(d.worker.startswith("tcp://") for d in r.drives)
    _check_store_run(r, url, sequential_run, scratch)
