"""The packaging path of scripts/install_python.sh: a venv made with --system-site-packages from
Debian's interpreter, `pip install --no-build-isolation --no-deps --no-index ./python` with the
CMake-built module, then `import slam_mms` from outside the repository (the step that broke once
when pyproject.toml named a readme outside python/)."""

from __future__ import annotations

import os
import pathlib
import subprocess
import sys

import slam_mms

REPO = pathlib.Path(__file__).resolve().parents[2]


def test_pip_installs_the_package_into_a_venv(tmp_path):
    module = pathlib.Path(sys.modules["slam_mms._slam_mms"].__file__).resolve()
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", str(venv)], check=True,
                   timeout=120)
    env = dict(os.environ, SLAM_MMS_PYTHON_MODULE=str(module), PIP_NO_INDEX="1")
    env.pop("PYTHONPATH", None)  # the installed package, not the source tree
    pip = [str(venv / "bin" / "python"), "-m", "pip", "install", "--no-build-isolation",
           "--no-deps", "--no-index", str(REPO / "python")]
    proc = subprocess.run(pip, env=env, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    proc = subprocess.run([str(venv / "bin" / "python"), "-c",
                           "import slam_mms, numpy; print(slam_mms.__version__, "
                           "slam_mms.__file__)"], env=env, cwd="/", capture_output=True,
                          text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    version, path = proc.stdout.split()
    assert version == slam_mms.__version__
    assert str(venv) in path  # imported from the venv, not from the source tree
    # The console script of pyproject.toml's [project.scripts].
    proc = subprocess.run([str(venv / "bin" / "slam_mms_fleet"), "--help"], env=env, cwd="/",
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0 and "--scheduler" in proc.stdout, proc.stderr
