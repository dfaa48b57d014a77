"""Fleet processing on Dask: many drives, one process per drive, then the multi-drive adjustment.

    slam_mms_fleet --drives D1 D2 ... --out DIR [--scheduler local|sequential|ADDRESS] [--workers N]
    python -m slam_mms fleet ...                      (the same command)

Stage 1 runs each drive as one task: ``slam_mms_run --kitti-raw D --out DIR/drives/<name> --mode
full --drive-result [run args]`` in a separate process (``python -m slam_mms run`` with the
worker's interpreter, or the ``--run-exe`` binary), so a crash or a signal handler stays in that
process. Stage 2 is the adjustment, ``slam_mms_merge --drive DIR/drives/<a> ... --out DIR``, over
the drives that finished (at least two), writing DIR/merged/. DIR/fleet.json records the run.

Output: DIR is a file system path (local, or shared by every worker), or an fsspec URL of an
object store (``s3://bucket/city``, ``gs://...``, ``file:///...``, ``memory://`` for the
sequential path): each task then works in a local scratch folder (``--scratch``, default the
system temp folder) and copies its results to the store when it is done (a drive's whole output
folder, its logs), the adjustment fetches what it reads (each drive's report.json and
drive_result/) and puts DIR/merged/ back; resume reads the store. The store's credentials come
from fsspec's own configuration (environment variables, config files) on each worker.

Schedulers: ``local`` (a dask.distributed LocalCluster with N single-threaded worker processes),
a scheduler address such as ``tcp://host:8786`` (an existing Dask cluster; every worker must see
the drives and DIR at the same paths, docs/fleet.md), or ``sequential`` (no Dask: the same tasks
one after the other in this process, the plain path).

Resumable: a drive whose DIR/drives/<name>/report.json says ``"complete": true``, which has
drive_result/drive_result.json and whose recorded command (fleet_task.json) is the one it would
run now is not run again (status ``resumed``). A failed drive is reported with its exit status and
the tail of its stderr (DIR/logs/<name>.stderr.txt); the other drives go on.

A drive is ``PATH`` or ``PATH::ARGS``, ARGS being extra slam_mms_run arguments for that drive
only, split like a shell line (``/data/d1::--gnss-outage 20:30``), or an entry of a JSON drives
file (``--drives-file``): ``[{"path": ..., "name": ..., "run_args": [...]}, ...]``. The input kind
follows the path: a ``.bag`` file is ``--rosbag``, a folder with scans.csv ``--folder``, any other
folder ``--kitti-raw``. Names come from the path's last component (made unique with ``_2``,
``_3``, ... in the order given) unless given.
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib.util
import json
import os
import pathlib
import re
import shlex
import shutil
import socket
import subprocess
import sys
import tempfile
import time
from typing import Any, Callable, Dict, Iterable, List, Optional, Sequence, Tuple, Union

PathLike = Union[str, "os.PathLike[str]"]
Progress = Callable[[str], None]

FLEET_JSON_VERSION = 1
_STDERR_TAIL_LINES = 15
# Dask's nanny sets these in its workers (thread counts 1, a malloc trim threshold). A thread
# count changes how sums are split, so the last digits of a run; the trim threshold changed them
# only while the sliding window's factor order depended on heap addresses (fixed). Every path
# gives a drive process the client's values (thread counts 1 where unset, no trim threshold where
# unset), so the sequential and the Dask path run under one environment.
_THREAD_ENV = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
_CLIENT_ENV = ("MALLOC_TRIM_THRESHOLD_",)


class FleetError(RuntimeError):
    """A fleet that cannot start: bad drive list, output folder or scheduler."""


@dataclasses.dataclass(frozen=True)
class FleetDrive:
    """One drive of a fleet: its input path, its output name and its own slam_mms_run args."""

    path: str
    name: Optional[str] = None
    run_args: Tuple[str, ...] = ()

    @classmethod
    def parse(cls, spec: str) -> "FleetDrive":
        """``PATH`` or ``PATH::ARGS`` (ARGS split like a shell line) as a FleetDrive."""
        path, sep, args = spec.partition("::")
        if not path:
            raise FleetError(f"drive '{spec}': no path before '::'")
        return cls(path=path, run_args=tuple(shlex.split(args)) if sep else ())


@dataclasses.dataclass
class DriveTask:
    """What one stage-1 task runs (picklable: it is sent to a Dask worker)."""

    name: str
    path: str
    out_dir: str
    log_dir: str
    args: List[str]  # slam_mms_run's arguments, without the program
    run_exe: Optional[str] = None
    timeout_s: Optional[float] = None
    env: Dict[str, Optional[str]] = dataclasses.field(default_factory=dict)  # None: unset
    # An object store: out_dir and log_dir are URLs there; the run works in a local scratch
    # folder under `scratch` (None: the system temp folder) and copies its files up at the end.
    scratch: Optional[str] = None


@dataclasses.dataclass
class DriveOutcome:
    """The result of one drive: ``status`` is ``done``, ``resumed`` or ``failed``."""

    name: str
    path: str
    status: str
    out_dir: str
    wall_s: float = 0.0
    returncode: Optional[int] = None
    worker: str = ""
    host: str = ""
    message: str = ""
    command: List[str] = dataclasses.field(default_factory=list)

    @property
    def ok(self) -> bool:
        return self.status in ("done", "resumed")


@dataclasses.dataclass
class MergeTask:
    """What the stage-2 task runs."""

    drive_dirs: List[str]
    out_dir: str
    log_dir: str
    args: List[str]
    merge_exe: Optional[str] = None
    timeout_s: Optional[float] = None
    env: Dict[str, Optional[str]] = dataclasses.field(default_factory=dict)
    scratch: Optional[str] = None  # as DriveTask.scratch


@dataclasses.dataclass
class MergeOutcome:
    """The adjustment's result: ``status`` is ``done``, ``failed`` or ``skipped``."""

    status: str
    wall_s: float = 0.0
    returncode: Optional[int] = None
    report: Optional[str] = None
    worker: str = ""
    host: str = ""
    message: str = ""
    command: List[str] = dataclasses.field(default_factory=list)


@dataclasses.dataclass
class FleetResult:
    """What run_fleet did; also written as DIR/fleet.json."""

    out: str
    scheduler: str
    workers: int
    drives: List[DriveOutcome]
    stage1_wall_s: float
    stage2_wall_s: float
    merge: MergeOutcome
    dashboard: Optional[str] = None

    @property
    def failed(self) -> List[DriveOutcome]:
        return [d for d in self.drives if d.status == "failed"]

    @property
    def ok(self) -> bool:
        """Every drive finished and the adjustment ran (or was not asked for)."""
        return not self.failed and self.merge.status in ("done", "not requested")

    def to_json(self) -> Dict[str, Any]:
        return {
            "version": FLEET_JSON_VERSION,
            "out": self.out,
            "scheduler": self.scheduler,
            "workers": self.workers,
            "dashboard": self.dashboard,
            "stage1_wall_s": self.stage1_wall_s,
            "stage2_wall_s": self.stage2_wall_s,
            "drives": [dataclasses.asdict(d) for d in self.drives],
            "merge": dataclasses.asdict(self.merge),
            "merge_report": self.merge.report,
            "counts": {s: sum(d.status == s for d in self.drives)
                       for s in ("done", "resumed", "failed")},
        }


# ---- the tasks (run on a worker, or in this process for the sequential path) ----------------


def _where() -> Tuple[str, str]:
    """(worker address or "local", host name) of the process running a task."""
    worker = "local"
    try:
        from distributed import get_worker

        worker = get_worker().address
    except (ImportError, ValueError):
        pass
    return worker, socket.gethostname()


def _tail(path: str, lines: int = _STDERR_TAIL_LINES) -> str:
    try:
        text = pathlib.Path(path).read_text(errors="replace")
    except OSError:
        return ""
    # Progress lines may be drawn with carriage returns: keep each line's last state.
    rows = [r.split("\r")[-1] for r in text.splitlines()]
    return "\n".join([r for r in rows if r.strip()][-lines:])


def _program(exe: Optional[str], command: str) -> List[str]:
    return [exe] if exe else [sys.executable, "-m", "slam_mms", command]


def _task_env() -> Dict[str, Optional[str]]:
    """The environment overrides of the drive processes, taken on the client (None: unset)."""
    env: Dict[str, Optional[str]] = {k: os.environ.get(k, "1") for k in _THREAD_ENV}
    env.update({k: os.environ.get(k) for k in _CLIENT_ENV})
    return env


def _run_logged(cmd: List[str], log_stem: str, timeout_s: Optional[float],
                env: Dict[str, Optional[str]]) -> Tuple[int, str]:
    """Runs cmd with stdout/stderr in LOG_STEM.stdout.txt / .stderr.txt; (exit status, note)."""
    full = {k: v for k, v in os.environ.items() if env.get(k, v) is not None}
    full.update({k: v for k, v in env.items() if v is not None})
    with open(log_stem + ".stdout.txt", "wb") as out, open(log_stem + ".stderr.txt", "wb") as err:
        try:
            proc = subprocess.run(cmd, stdout=out, stderr=err, stdin=subprocess.DEVNULL,
                                  timeout=timeout_s, env=full)
        except subprocess.TimeoutExpired:
            return -1, f"stopped after the {timeout_s:g} s timeout"
        except OSError as e:
            return -1, f"could not start {cmd[0]}: {e}"
    return proc.returncode, ""


def _swap_out(args: Sequence[str], out: str) -> List[str]:
    """args with the value of --out replaced."""
    res, i = [], 0
    while i < len(args):
        if args[i] == "--out" and i + 1 < len(args):
            res += ["--out", out]
            i += 2
            continue
        res.append(args[i])
        i += 1
    return res


def _upload_logs(local_logs: str, url: str) -> None:
    fs, root = _url_fs(url)
    fs.makedirs(root, exist_ok=True)
    for name in sorted(os.listdir(local_logs)):
        fs.put_file(os.path.join(local_logs, name), root.rstrip("/") + "/" + name)


class _Stage:
    """Where a task's process writes: the task's own folders, or, with an object store, a local
    scratch folder (``close`` copies the logs up and removes it)."""

    def __init__(self, out_dir: str, log_dir: str, scratch: Optional[str], what: str) -> None:
        self.store = _is_url(out_dir)
        self.out_url, self.log_url = out_dir, log_dir
        self.scratch = _scratch(scratch, what) if self.store else None
        self.out_dir = os.path.join(self.scratch, "out") if self.scratch else out_dir
        self.log_dir = os.path.join(self.scratch, "logs") if self.scratch else log_dir

    def logs(self, name: str) -> Tuple[str, str]:
        """(local log stem, the stem to show: in the store where there is one)."""
        local = os.path.join(self.log_dir, name)
        return local, (_join(self.log_url, name) if self.store else local)

    def close(self) -> None:
        try:
            if self.store and os.path.isdir(self.log_dir):
                _upload_logs(self.log_dir, self.log_url)
        finally:
            if self.scratch:
                shutil.rmtree(self.scratch, ignore_errors=True)


def _staged(stage: _Stage, outcome: Any, what: str, body: Callable[[], None]) -> None:
    """Runs body, then stage.close(); a store that refuses a copy fails the outcome."""
    t0 = time.monotonic()
    try:
        try:
            body()
        finally:
            stage.close()
    except (OSError, FleetError) as e:
        outcome.status = "failed"
        outcome.message = f"{what}: copying from or to {stage.out_url} failed: {e}"
    outcome.wall_s = time.monotonic() - t0


def run_drive_task(task: DriveTask) -> DriveOutcome:
    """Stage 1 for one drive: slam_mms_run in a subprocess; never raises for a failed drive."""
    worker, host = _where()
    st = _Stage(task.out_dir, task.log_dir, task.scratch, task.name)
    cmd = _program(task.run_exe, "run") + _swap_out(task.args, st.out_dir)
    outcome = DriveOutcome(name=task.name, path=task.path, status="failed", out_dir=task.out_dir,
                           worker=worker, host=host, command=cmd)

    def body() -> None:
        if not os.path.exists(task.path):
            outcome.message = f"drive {task.name}: input {task.path} not found on {host}"
            return
        os.makedirs(st.log_dir, exist_ok=True)
        # A rerun starts clean: no stale submaps or files of an earlier, unfinished run.
        shutil.rmtree(st.out_dir, ignore_errors=True)
        log_stem, shown = st.logs(task.name)
        rc, note = _run_logged(cmd, log_stem, task.timeout_s, task.env)
        outcome.returncode = rc
        if rc == 0 and _finished(st.out_dir):
            _write_json(os.path.join(st.out_dir, "fleet_task.json"),
                        {"input": task.path, "args": _resume_key(task.args)})
            if st.store:
                _put_tree(st.out_dir, task.out_dir)
            outcome.status = "done"
            return
        why = note or (f"exit status {rc}" if rc != 0 else "exit status 0 but no complete "
                       "report.json and drive_result/drive_result.json")
        outcome.message = _failure_message(
            f"drive {task.name} ({task.path}) failed on {host}: {why}", log_stem, shown)

    _staged(st, outcome, f"drive {task.name} on {host}", body)
    return outcome


def merge_task(task: MergeTask) -> MergeOutcome:
    """Stage 2: slam_mms_merge over the finished drives in a subprocess; never raises."""
    worker, host = _where()
    st = _Stage(task.out_dir, task.log_dir, task.scratch, "merge")
    outcome = MergeOutcome(status="failed", worker=worker, host=host)

    def body() -> None:
        drive_dirs = list(task.drive_dirs)
        if st.store:
            # What the adjustment reads of each drive: its report (ground truth, outages) and
            # its drive result, under the drive's name (the merge names drives by folder).
            drive_dirs = []
            for url in task.drive_dirs:
                local = os.path.join(st.scratch, "drives", url.rstrip("/").rsplit("/", 1)[-1])
                os.makedirs(local, exist_ok=True)
                fs, p = _url_fs(_join(url, "report.json"))
                fs.get_file(p, os.path.join(local, "report.json"))
                _get_tree(_join(url, "drive_result"), os.path.join(local, "drive_result"))
                drive_dirs.append(local)
        cmd = _program(task.merge_exe, "merge")
        for d in drive_dirs:
            cmd += ["--drive", d]
        cmd += ["--out", st.out_dir, *task.args]
        outcome.command = cmd
        os.makedirs(st.log_dir, exist_ok=True)
        shutil.rmtree(os.path.join(st.out_dir, "merged"), ignore_errors=True)
        log_stem, shown = st.logs("merge")
        rc, note = _run_logged(cmd, log_stem, task.timeout_s, task.env)
        outcome.returncode = rc
        report = os.path.join(st.out_dir, "merged", "report.json")
        if rc == 0 and os.path.isfile(report):
            if st.store:
                _put_tree(os.path.join(st.out_dir, "merged"), _join(task.out_dir, "merged"))
                report = _join(task.out_dir, "merged", "report.json")
            outcome.status = "done"
            outcome.report = report
            return
        outcome.message = _failure_message(
            f"adjustment failed on {host}: {note or f'exit status {rc}'}", log_stem, shown)

    _staged(st, outcome, f"adjustment on {host}", body)
    return outcome


def _failure_message(what: str, log_stem: str, shown_stem: Optional[str] = None) -> str:
    """`what`, the log file to read (shown_stem, default log_stem) and the end of its stderr."""
    message = f"{what}; log {shown_stem or log_stem}.stderr.txt"
    tail = _tail(log_stem + ".stderr.txt")
    return message + "\n" + tail if tail else message


# ---- planning --------------------------------------------------------------------------------


def _exists(url_or_path: str) -> bool:
    if not _is_url(url_or_path):
        return os.path.isfile(url_or_path)
    try:
        fs, p = _url_fs(url_or_path)
        return bool(fs.exists(p))
    except (OSError, FleetError):
        return False


def _finished(out_dir: str) -> bool:
    """A drive output (folder or URL) with a complete report.json and
    drive_result/drive_result.json."""
    data = _store_read(_join(out_dir, "report.json"))
    try:
        complete = data is not None and json.loads(data).get("complete") is True
    except (ValueError, AttributeError):
        return False
    return complete and _exists(_join(out_dir, "drive_result", "drive_result.json"))


def _resume_key(args: Sequence[str]) -> List[str]:
    """A drive's run arguments without its --out folder (DIR may have been moved)."""
    key, skip = [], False
    for a in args:
        if skip:
            skip = False
        elif a == "--out":
            skip = True
        elif not a.startswith("--out="):
            key.append(a)
    return key


def _recorded_args(out_dir: str) -> Optional[List[str]]:
    data = _store_read(_join(out_dir, "fleet_task.json"))
    try:
        return list(json.loads(data)["args"]) if data is not None else None
    except (ValueError, KeyError, TypeError):
        return None


def _input_flag(path: str) -> str:
    p = pathlib.Path(path)
    if p.suffix == ".bag":
        return "--rosbag"
    if (p / "scans.csv").is_file():
        return "--folder"
    return "--kitti-raw"


def _name_of(path: str) -> str:
    stem = pathlib.PurePath(path.rstrip("/")).name or "drive"
    if stem.endswith(".bag"):
        stem = stem[:-4]
    return re.sub(r"[^A-Za-z0-9._-]", "_", stem)


def _as_drives(drives: Iterable[Union[PathLike, FleetDrive]]) -> List[FleetDrive]:
    """FleetDrives with absolute paths and unique names (``_2``, ``_3`` ... for repeats)."""
    out: List[FleetDrive] = []
    used: Dict[str, int] = {}
    for d in drives:
        fd = d if isinstance(d, FleetDrive) else FleetDrive(path=os.fspath(d))
        path = os.path.abspath(os.fspath(fd.path))
        if fd.name is not None:
            name = fd.name
            if not re.fullmatch(r"[A-Za-z0-9._-]+", name) or name in (".", ".."):
                raise FleetError(f"drive {path}: name '{name}' must be letters, digits, '.', "
                                 "'_' or '-'")
            if name in used:
                raise FleetError(f"drive {path}: name '{name}' is used twice")
        else:
            base = _name_of(path)
            name, k = base, 1
            while name in used:
                k += 1
                name = f"{base}_{k}"
        used[name] = 1
        out.append(FleetDrive(path=path, name=name, run_args=tuple(fd.run_args)))
    return out


def read_drives_file(path: PathLike) -> List[FleetDrive]:
    """A JSON drives file: a list of ``"PATH"`` strings or ``{"path", "name", "run_args"}``."""
    try:
        entries = json.loads(pathlib.Path(path).read_text())
    except (OSError, ValueError) as e:
        raise FleetError(f"drives file {path}: {e}") from e
    if not isinstance(entries, list):
        raise FleetError(f"drives file {path}: expected a JSON list of drives")
    drives = []
    for i, e in enumerate(entries):
        if isinstance(e, str):
            drives.append(FleetDrive.parse(e))
        elif isinstance(e, dict) and isinstance(e.get("path"), str):
            extra = set(e) - {"path", "name", "run_args"}
            if extra:
                raise FleetError(f"drives file {path}: entry {i}: unknown keys {sorted(extra)}")
            args = e.get("run_args", [])
            if isinstance(args, str):
                args = shlex.split(args)
            drives.append(FleetDrive(path=e["path"], name=e.get("name"),
                                     run_args=tuple(str(a) for a in args)))
        else:
            raise FleetError(f"drives file {path}: entry {i}: expected a path or an object "
                             "with \"path\"")
    return drives


def _write_json(path: str, data: Any) -> None:
    text = json.dumps(data, indent=2, sort_keys=True) + "\n"
    if _is_url(path):
        fs, p = _url_fs(path)
        fs.makedirs(p.rsplit("/", 1)[0], exist_ok=True)
        fs.pipe_file(p, text.encode())
        return
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, path)


# ---- an object store as DIR (fsspec) -----------------------------------------------------------


def _is_url(path: str) -> bool:
    return "://" in path


def _url_fs(url: str):
    """(fsspec file system, path in it) of a URL; FleetError where fsspec cannot open it."""
    try:
        import fsspec
    except ImportError as e:
        raise FleetError(f"{url}: an object store needs fsspec (apt-get install python3-fsspec)"
                         ) from e
    try:
        return fsspec.core.url_to_fs(url)
    except (ImportError, ValueError) as e:  # an unknown protocol, or its package is missing
        raise FleetError(f"{url}: {e}") from e


def _join(base: str, *parts: str) -> str:
    """A path or URL joined with '/' (os.path.join for paths)."""
    if not _is_url(base):
        return os.path.join(base, *parts)
    return "/".join([base.rstrip("/"), *parts])


def _store_read(url_or_path: str) -> Optional[bytes]:
    """A file's bytes from a path or a URL; None where it cannot be read."""
    try:
        if _is_url(url_or_path):
            fs, p = _url_fs(url_or_path)
            return fs.cat_file(p)
        return pathlib.Path(url_or_path).read_bytes()
    except (OSError, FleetError):  # FileNotFoundError is an OSError
        return None


def _put_tree(local_dir: str, url: str) -> None:
    """Copies every file under local_dir to url/<relative path>, replacing what was there. File by
    file: fsspec's recursive put nests or not by version and trailing slash."""
    fs, root = _url_fs(url)
    if fs.exists(root):
        fs.rm(root, recursive=True)
    for dirpath, _dirs, files in os.walk(local_dir):
        rel = os.path.relpath(dirpath, local_dir)
        target = root if rel == "." else root.rstrip("/") + "/" + rel.replace(os.sep, "/")
        fs.makedirs(target, exist_ok=True)
        for name in sorted(files):
            fs.put_file(os.path.join(dirpath, name), target.rstrip("/") + "/" + name)


def _get_tree(url: str, local_dir: str) -> None:
    """Copies every file under url into local_dir (the same relative paths)."""
    fs, root = _url_fs(url)
    root = root.rstrip("/")
    for remote in sorted(fs.find(root)):
        rel = remote[len(root):].lstrip("/")
        local = os.path.join(local_dir, *rel.split("/"))
        os.makedirs(os.path.dirname(local), exist_ok=True)
        fs.get_file(remote, local)


def _scratch(base: Optional[str], what: str) -> str:
    """A fresh local folder for one task's files (removed by the task)."""
    root = base or tempfile.gettempdir()
    os.makedirs(root, exist_ok=True)
    return tempfile.mkdtemp(prefix=f"slam_mms_fleet_{what}_", dir=root)


# ---- the fleet -------------------------------------------------------------------------------


def _local_cluster(workers: int, dashboard_address: Optional[str]):
    from distributed import Client, LocalCluster

    if dashboard_address is not None and importlib.util.find_spec("bokeh") is None:
        dashboard_address = None  # the dashboard needs bokeh
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                           dashboard_address=dashboard_address)
    return cluster, Client(cluster)


def run_fleet(drives: Sequence[Union[PathLike, FleetDrive]], out: PathLike,
              scheduler: Optional[str] = "local", workers: Optional[int] = None,
              run_args: Sequence[str] = (), merge: bool = True, merge_args: Sequence[str] = (),
              client: Any = None, progress: Optional[Progress] = None,
              run_exe: Optional[str] = None, merge_exe: Optional[str] = None,
              timeout_s: Optional[float] = None,
              dashboard_address: Optional[str] = ":8787",
              scratch: Optional[PathLike] = None) -> FleetResult:
    """Runs each drive as a task (stage 1), then the adjustment over the finished drives.

    ``drives``: paths or :class:`FleetDrive`; ``out``: the output folder DIR (a local or shared
    file system path, or an fsspec URL of an object store: DIR/drives/<name>/, DIR/logs/,
    DIR/merged/, DIR/fleet.json); ``scratch``: with an object store, the local folder under
    which each task stages its files (default the system temp folder);
    ``scheduler``: ``"local"`` (LocalCluster, ``workers`` processes, default one per CPU up to
    the number of drives), a scheduler address (``tcp://host:8786``), or ``"sequential"``/None
    (no Dask); ``client``: an existing ``distributed.Client`` instead (not closed here);
    ``run_args``: slam_mms_run arguments for every drive (after ``--mode full --drive-result``;
    a drive's own args follow); ``merge_args``: slam_mms_merge arguments; ``run_exe`` /
    ``merge_exe``: the app binaries (default ``python -m slam_mms run|merge`` with the worker's
    interpreter); ``timeout_s``: per process; ``progress``: called with each text progress line.
    Failed drives do not raise: see :attr:`FleetResult.failed`. Raises :class:`FleetError` for a
    bad drive list, output folder or scheduler.
    """
    say = progress or (lambda _line: None)
    out_s = os.fspath(out)
    fleet = _as_drives(drives)
    if not fleet:
        raise FleetError("no drives given")
    scratch_s = os.path.abspath(os.fspath(scratch)) if scratch is not None else None
    if _is_url(out_s):
        out_dir = out_s.rstrip("/")
        # The store first: an unknown protocol, a missing package or no write access fails here,
        # before any drive runs.
        fs, root = _url_fs(out_dir)
        probe = root.rstrip("/") + "/.slam_mms_fleet_write_test"
        try:
            fs.makedirs(root, exist_ok=True)  # a folder where the store has them (file://)
            fs.pipe_file(probe, b"")
            fs.rm(probe)
        except Exception as e:  # the store's own exception types
            raise FleetError(f"--out {out_dir}: cannot write into it: {e}") from e
    else:
        out_dir = os.path.abspath(out_s)
    drives_dir = _join(out_dir, "drives")
    log_dir = _join(out_dir, "logs")
    if not _is_url(out_dir):
        os.makedirs(drives_dir, exist_ok=True)

    # Plan: which drives are finished already (resume), which run.
    outcomes: Dict[str, DriveOutcome] = {}
    tasks: List[DriveTask] = []
    for d in fleet:
        drive_out = _join(drives_dir, d.name)
        args = [_input_flag(d.path), d.path, "--out", drive_out, "--mode", "full",
                "--drive-result", *run_args, *d.run_args]
        if _finished(drive_out) and _recorded_args(drive_out) == _resume_key(args):
            outcomes[d.name] = DriveOutcome(
                name=d.name, path=d.path, status="resumed", out_dir=drive_out,
                message=f"drive {d.name}: finished in an earlier run, not run again")
            say(f"fleet: {d.name} resumed (finished in an earlier run)")
            continue
        if _finished(drive_out):
            say(f"fleet: {d.name} runs again (its options or input changed)")
        tasks.append(DriveTask(name=d.name, path=d.path, out_dir=drive_out, log_dir=log_dir,
                               args=args, run_exe=run_exe, timeout_s=timeout_s,
                               env=_task_env(), scratch=scratch_s))

    sched = "sequential" if scheduler in (None, "sequential") else str(scheduler)
    own_cluster = None
    dashboard: Optional[str] = None
    n_workers = 1
    if client is not None:
        sched = f"client {getattr(getattr(client, 'scheduler', None), 'address', '?')}"
    elif sched != "sequential" and (tasks or merge):
        try:
            import distributed  # noqa: F401
        except ImportError as e:
            raise FleetError(f"--scheduler {sched} needs dask.distributed (apt-get install "
                             "python3-distributed, or pip install distributed); --scheduler "
                             "sequential runs without it") from e
        if sched == "local":
            n = workers or max(1, min(os.cpu_count() or 1, len(tasks) or 1))
            own_cluster, client = _local_cluster(n, dashboard_address)
        else:
            from distributed import Client

            try:
                client = Client(sched, timeout="30s")
            except (OSError, TimeoutError) as e:
                raise FleetError(f"--scheduler {sched}: cannot connect: {e}") from e
    try:
        if client is not None:
            n_workers = len(client.scheduler_info().get("workers", {}))
            if importlib.util.find_spec("bokeh") is not None and (
                    own_cluster is None or dashboard_address is not None):
                dashboard = getattr(client, "dashboard_link", None)
            say(f"fleet: scheduler {sched}, {n_workers} workers, "
                + (f"dashboard {dashboard}" if dashboard else "no dashboard (it needs bokeh)"))
        else:
            say("fleet: sequential, in this process")

        t0 = time.monotonic()
        total = len(fleet)

        def record(o: DriveOutcome) -> None:
            outcomes[o.name] = o
            if o.status == "failed":
                say(f"fleet: {o.name} FAILED: {o.message}")
            else:
                say(f"fleet: {o.name} done in {o.wall_s:.1f} s on {o.worker}")
            n_res = sum(x.status == "resumed" for x in outcomes.values())
            n_fail = sum(x.status == "failed" for x in outcomes.values())
            say(f"fleet: {len(outcomes)}/{total} drives done ({n_res} resumed, {n_fail} "
                f"failed), elapsed {time.monotonic() - t0:.1f} s")

        if client is None:
            for t in tasks:
                say(f"fleet: {t.name} running")
                record(run_drive_task(t))
        elif tasks:
            from distributed import as_completed

            stamp = _stamp()
            futures = {client.submit(run_drive_task, t, key=f"fleet-drive-{t.name}-{stamp}",
                                     pure=False): t for t in tasks}
            for fut in as_completed(list(futures)):
                t = futures[fut]
                try:
                    o = fut.result()
                except Exception as e:  # the task itself broke (a worker died, ...)
                    o = DriveOutcome(name=t.name, path=t.path, status="failed",
                                     out_dir=t.out_dir,
                                     message=f"drive {t.name} ({t.path}): task failed: {e!r}")
                record(o)
        stage1 = time.monotonic() - t0
        ordered = [outcomes[d.name] for d in fleet]

        def result(m: MergeOutcome, stage2: float) -> FleetResult:
            r = FleetResult(out=out_dir, scheduler=sched, workers=n_workers, drives=ordered,
                            stage1_wall_s=stage1, stage2_wall_s=stage2, merge=m,
                            dashboard=dashboard)
            _write_json(_join(out_dir, "fleet.json"), r.to_json())
            return r

        ok = [o for o in ordered if o.ok]
        if not merge:
            return result(MergeOutcome(status="not requested"), 0.0)
        if len(ok) < 2:
            m = MergeOutcome(status="skipped", message=f"adjustment skipped: {len(ok)} drive(s) "
                             "finished, it needs at least 2")
            say(f"fleet: {m.message}")
            return result(m, 0.0)
        result(MergeOutcome(status="running"), 0.0)  # fleet.json after stage 1
        say(f"fleet: adjustment of {len(ok)} drives")
        mt = MergeTask(drive_dirs=[o.out_dir for o in ok], out_dir=out_dir, log_dir=log_dir,
                       args=list(merge_args), merge_exe=merge_exe, timeout_s=timeout_s,
                       env=_task_env(), scratch=scratch_s)
        t1 = time.monotonic()
        if client is None:
            m = merge_task(mt)
        else:
            fut = client.submit(merge_task, mt, key=f"fleet-merge-{_stamp()}", pure=False)
            try:
                m = fut.result()
            except Exception as e:
                m = MergeOutcome(status="failed", message=f"adjustment task failed: {e!r}")
        stage2 = time.monotonic() - t1
        say(f"fleet: adjustment done in {m.wall_s:.1f} s, {m.report}" if m.status == "done"
            else f"fleet: {m.message}")
        return result(m, stage2)
    finally:
        if own_cluster is not None:
            client.close()
            own_cluster.close()


def _stamp() -> str:
    """A task key suffix unique to this call (a reused client keeps earlier keys)."""
    return f"{socket.gethostname()}-{os.getpid()}-{time.time_ns()}"


# ---- the command line ------------------------------------------------------------------------


def _parser(prog: str) -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog=prog, description="Runs drives as Dask tasks (one process each), then the "
        "multi-drive adjustment (docs/fleet.md).")
    p.add_argument("--drives", nargs="+", default=[], metavar="D",
                   help="drives: PATH or PATH::ARGS (slam_mms_run args for that drive, e.g. "
                   "'/data/d1::--gnss-outage 20:30')")
    p.add_argument("--drives-file", metavar="FILE", help="a JSON list of drives: \"PATH\" or "
                   "{\"path\": ..., \"name\": ..., \"run_args\": [...]}")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (shared by all "
                   "workers on a cluster), or an fsspec URL of an object store (s3://bucket/"
                   "path, ...)")
    p.add_argument("--scratch", metavar="DIR", help="with an object store: the local folder "
                   "where each task stages its files (default: the system temp folder)")
    p.add_argument("--scheduler", default="local", metavar="S", help="local (default; a "
                   "LocalCluster), sequential (no Dask) or a scheduler address tcp://HOST:8786")
    p.add_argument("--workers", type=int, default=None, metavar="N", help="LocalCluster workers "
                   "(default: one per CPU, at most one per drive)")
    p.add_argument("--config", metavar="FILE", help="slam_mms_run --config FILE for every drive")
    p.add_argument("--run-arg", action="append", default=[], metavar="ARG",
                   help="one more slam_mms_run argument for every drive; repeat; write "
                   "--run-arg=--flag=value for flags")
    p.add_argument("--merge-arg", action="append", default=[], metavar="ARG",
                   help="one more slam_mms_merge argument; repeat (--merge-arg=--threads=1)")
    p.add_argument("--no-merge", action="store_true", help="stage 1 only")
    p.add_argument("--run-exe", metavar="EXE", help="slam_mms_run binary (default: python -m "
                   "slam_mms run with the worker's interpreter)")
    p.add_argument("--merge-exe", metavar="EXE", help="slam_mms_merge binary (default: python "
                   "-m slam_mms merge)")
    p.add_argument("--timeout", type=float, default=None, metavar="S",
                   help="stop a drive's (or the adjustment's) process after S seconds")
    p.add_argument("--dashboard-address", default=":8787", metavar="ADDR",
                   help="LocalCluster dashboard address (needs bokeh; default :8787)")
    return p


def main(argv: Optional[Sequence[str]] = None, prog: str = "slam_mms_fleet") -> int:
    """The command line; returns 0 all done, 1 a drive or the adjustment failed, 2 bad usage."""
    p = _parser(prog)
    try:
        a = p.parse_args(list(sys.argv[1:] if argv is None else argv))
    except SystemExit as e:
        return int(e.code or 0)
    try:
        drives = [FleetDrive.parse(s) for s in a.drives]
        if a.drives_file:
            drives += read_drives_file(a.drives_file)
        if not drives:
            raise FleetError("no drives: give --drives and/or --drives-file")
        if a.workers is not None and a.workers < 1:
            raise FleetError("--workers must be at least 1")
        run_args = ([f"--config={os.path.abspath(a.config)}"] if a.config else []) + a.run_arg
        r = run_fleet(drives, a.out, scheduler=a.scheduler, workers=a.workers,
                      run_args=run_args, merge=not a.no_merge, merge_args=a.merge_arg,
                      progress=lambda line: print(line, flush=True), run_exe=a.run_exe,
                      merge_exe=a.merge_exe, timeout_s=a.timeout,
                      dashboard_address=a.dashboard_address, scratch=a.scratch)
    except FleetError as e:
        print(f"{prog}: error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"{prog}: stopped", file=sys.stderr)
        return 130
    print(f"fleet: {sum(d.ok for d in r.drives)}/{len(r.drives)} drives finished, stage 1 "
          f"{r.stage1_wall_s:.1f} s, adjustment {r.merge.status} ({r.stage2_wall_s:.1f} s); "
          f"{_join(r.out, 'fleet.json')}", flush=True)
    return 0 if r.ok else 1


if __name__ == "__main__":
    sys.exit(main())
