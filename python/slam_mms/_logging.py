"""The bridge from the library's log sink to Python's logging (logger ``"slam_mms"``).

The C++ sink only queues messages (it never waits for the GIL, so no lock order with it exists);
they are delivered to ``logging.getLogger("slam_mms")`` when a GIL-releasing call returns
(``add_scan``, ``finish``, ``run_drive``, ...) and, while a long call runs, by a daemon thread
that waits for messages with the GIL released. Library levels map to DEBUG/INFO/WARNING/ERROR;
``slam_mms.set_min_log_level`` sets what the library formats at all (default INFO).
"""

from __future__ import annotations

import atexit
import logging
import threading

from . import _C

logger = logging.getLogger("slam_mms")

_thread: threading.Thread | None = None


def _emit(level: int, message: str) -> None:
    logger.log(level, message)


def _drain() -> None:
    while _C._drain_log(0.5):
        pass


def install_log_handler() -> None:
    """Routes the library's log messages to the ``"slam_mms"`` logger (done at import)."""
    global _thread
    _C._install_log_sink(_emit)
    if _thread is None or not _thread.is_alive():
        _thread = threading.Thread(target=_drain, name="slam_mms-log", daemon=True)
        _thread.start()


def remove_log_handler() -> None:
    """Stops forwarding (the library drops its messages again)."""
    global _thread
    _C._remove_log_sink()
    if _thread is not None:
        _thread.join(timeout=2.0)
        _thread = None


atexit.register(remove_log_handler)
