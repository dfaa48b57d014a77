"""Shared fixtures of the slam_mms Python tests (run by ctest as python_pytest).

- `sim_drive`: a 2 s simulated drive (KITTI raw layout with ground truth), made once per session.
- `kitti_0013`: the real KITTI frames in ../shared/data (or $SLAM_MMS_SHARED_DATA); tests using it
  skip with a message where they are absent.
- `slam_mms_run`: the C++ app ($SLAM_MMS_RUN, set by ctest, else build/examples/slam_mms_run).
"""

from __future__ import annotations

import os
import pathlib
import subprocess

import pytest

import slam_mms

REPO = pathlib.Path(__file__).resolve().parents[2]


def _shared_data() -> pathlib.Path:
    for key in ("SLAM_MMS_SHARED_DATA", "SLAM_MMS_SHARED_DATA_DEFAULT"):
        if os.environ.get(key):
            return pathlib.Path(os.environ[key])
    return REPO.parent / "shared" / "data"


@pytest.fixture(scope="session")
def sim_drive(tmp_path_factory) -> pathlib.Path:
    out = tmp_path_factory.mktemp("sim")
    return slam_mms.simulate_drive(out, duration_s=2.0, seed=3, write_scene_cloud=False)


@pytest.fixture(scope="session")
def kitti_0013() -> pathlib.Path:
    d = _shared_data() / "kitti_raw" / "2011_09_26" / "2011_09_26_drive_0013_sync"
    if not (d / "velodyne_points").is_dir():
        pytest.skip(f"real KITTI frames not found at {d} (set SLAM_MMS_SHARED_DATA)")
    return d


@pytest.fixture(scope="session")
def slam_mms_run() -> pathlib.Path:
    exe = pathlib.Path(os.environ.get("SLAM_MMS_RUN", REPO / "build" / "examples" / "slam_mms_run"))
    if not exe.is_file():
        pytest.skip(f"slam_mms_run not built at {exe} (set SLAM_MMS_RUN)")
    return exe


def run_app(exe: pathlib.Path, drive: pathlib.Path, out: pathlib.Path, *args: str) -> pathlib.Path:
    """Runs slam_mms_run on a drive; returns its --out folder."""
    cmd = [str(exe), "--kitti-raw", str(drive), "--out", str(out), *args]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, f"{' '.join(cmd)} failed:\n{proc.stdout}\n{proc.stderr}"
    return out


def read_tum_exact(path: pathlib.Path):
    """A TUM file as written by slam_mms (stamps with 9 fraction digits, %.17g numbers): exact
    int64 stamps and float64 values parsed at full precision."""
    import numpy as np

    stamps, values = [], []
    for line in path.read_text().splitlines():
        if not line.strip() or line.startswith("#"):
            continue
        t, *rest = line.split()
        whole, frac = t.split(".")
        assert len(frac) == 9, f"{path}: stamp {t} does not have 9 fraction digits"
        stamps.append(int(whole) * 1_000_000_000 + int(frac))
        values.append([float(v) for v in rest])
    return np.array(stamps, dtype=np.int64), np.array(values, dtype=np.float64).reshape(-1, 7)
