"""The library's log sink reaches Python's logging; the GIL is released while the library works,
also with library threads logging and Python callbacks running meanwhile."""

from __future__ import annotations

import logging
import threading
import time

import numpy as np
import pytest

import slam_mms

T0 = 1_700_000_000_000_000_000


class _Collect(logging.Handler):
    def __init__(self):
        super().__init__(logging.DEBUG)
        self.records = []

    def emit(self, record):
        self.records.append(record)


@pytest.fixture()
def collected():
    handler = _Collect()
    logger = logging.getLogger("slam_mms")
    old = logger.level
    logger.setLevel(logging.DEBUG)
    logger.addHandler(handler)
    yield handler
    logger.removeHandler(handler)
    logger.setLevel(old)


def test_library_warning_reaches_the_python_logger(collected):
    system = slam_mms.MappingSystem(slam_mms.Options())
    nan_points = np.full((50, 3), np.nan, np.float32)
    system.add_scan(nan_points, T0, T0 + 100_000_000, index=7, source="nan.bin")
    system.finish()
    slam_mms.flush_log()
    warnings = [r for r in collected.records if r.levelno == logging.WARNING]
    assert warnings, f"no warning received; got {[r.getMessage() for r in collected.records]}"
    assert any("nan.bin" in r.getMessage() or "skip" in r.getMessage().lower() for r in warnings)
    assert all(r.name == "slam_mms" for r in collected.records)
    assert system.num_skipped_scans == 1


def test_levels_map_and_messages_from_other_threads_arrive(collected):
    slam_mms.set_min_log_level(slam_mms.LogLevel.DEBUG)
    try:
        threads = [threading.Thread(target=slam_mms._C._log,
                                    args=(slam_mms.LogLevel.ERROR, f"from thread {i}"))
                   for i in range(4)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        slam_mms._C._log(slam_mms.LogLevel.DEBUG, "debug message")
    finally:
        slam_mms.set_min_log_level(slam_mms.LogLevel.INFO)
    deadline = time.time() + 5
    while time.time() < deadline and len(collected.records) < 5:
        time.sleep(0.01)
    got = {(r.levelno, r.getMessage()) for r in collected.records}
    assert {(logging.ERROR, f"from thread {i}") for i in range(4)} <= got
    assert (logging.DEBUG, "debug message") in got


def _count_while(fn):
    """Runs fn() on this thread while another thread counts; returns (fn's result, counts/s
    during fn, counts/s of the counter alone)."""
    stop = threading.Event()
    count = [0]

    def counter():
        while not stop.is_set():
            count[0] += 1

    t = threading.Thread(target=counter)
    t.start()
    time.sleep(0.2)
    c0, t0 = count[0], time.perf_counter()
    time.sleep(0.2)
    alone = (count[0] - c0) / (time.perf_counter() - t0)
    c1, t1 = count[0], time.perf_counter()
    result = fn()
    during = (count[0] - c1) / (time.perf_counter() - t1)
    stop.set()
    t.join()
    return result, during, alone


def test_gil_released_while_run_drive_processes(sim_drive):
    reader = slam_mms.open_drive(sim_drive)
    options = slam_mms.Options()
    options.T_body_lidar = reader.T_body_lidar
    t = time.perf_counter()
    run, during, alone = _count_while(lambda: slam_mms._C._run_drive(reader, options))
    assert time.perf_counter() - t > 0.3 and run.complete
    # Holding the GIL for the whole call would leave the counter at ~0 meanwhile.
    assert during > 0.2 * alone, (during, alone)


def test_gil_released_during_finish_and_callbacks_run(sim_drive):
    reader = slam_mms.open_drive(sim_drive)
    options = slam_mms.Options()
    options.T_body_lidar = reader.T_body_lidar
    system = slam_mms.MappingSystem(options)
    seen = []
    system.set_result_callback(lambda r: seen.append((r.scan_index, threading.get_ident())))
    streams = reader.streams
    system.initialize_pos(streams.initial_state, streams.initial_attitude_sigma_rpy_rad)
    # All streams first: the scans are queued until the POS covers them and processed in finish()
    # only where they are not yet; feed IMU/GNSS up to the first scan, then every scan, so that
    # finish() has the whole drive to process.
    first_end = reader.scan_end_ns(0)
    imu = [s for s in streams.imu_samples if s.stamp_ns <= first_end]
    gnss = [f for f in streams.gnss_fixes if f.stamp_ns <= first_end]
    for s in imu:
        system.add_imu(s)
    for f in gnss:
        system.add_gnss(f)
    for scan in reader:
        system.add_scan(scan)
    for s in streams.imu_samples[len(imu):]:
        system.add_imu(s)
    for f in streams.gnss_fixes[len(gnss):]:
        system.add_gnss(f)
    queued = len(reader) - len(seen)
    t = time.perf_counter()
    _, during, alone = _count_while(system.finish)
    elapsed = time.perf_counter() - t
    assert len(seen) == len(reader)
    assert all(tid == threading.get_ident() for _, tid in seen)
    if elapsed < 0.1:
        pytest.skip(f"finish() took only {elapsed:.3f} s ({queued} scans queued): too short to "
                    "measure; test_gil_released_while_run_drive_processes covers the release")
    assert during > 0.2 * alone, (during, alone)


def test_exception_in_callback_is_raised_not_lost(sim_drive):
    def boom(fed, total):
        raise RuntimeError("stop here")

    with pytest.raises(RuntimeError, match="stop here"):
        slam_mms.run_drive(sim_drive, frames="0:5", progress=boom, evaluate=False)
