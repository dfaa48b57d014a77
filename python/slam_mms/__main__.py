"""``python -m slam_mms run ...``: ``slam_mms_run`` itself, run in this process.

    python -m slam_mms run --kitti-raw DRIVE_DIR --out DIR [--mode ...] [...]
    python -m slam_mms run --folder DIR --out DIR [...]
    python -m slam_mms run --rosbag FILE.bag --extrinsics FILE.yaml --out DIR [...]
    python -m slam_mms run --out DIR          # simulates the demo drive into DIR/sim first
    python -m slam_mms run --help | --version | --config-keys | --dump-config FILE
    python -m slam_mms merge --drive OUT1 --drive OUT2 [...] --out DIR [...]
    python -m slam_mms fleet --drives D1 D2 ... --out DIR [--scheduler local|sequential|ADDRESS]
                             [--workers N] [...]   (slam_mms_fleet; docs/fleet.md)
    python -m slam_mms version

``run`` takes exactly slam_mms_run's flags (docs/user_guide.md) and runs the app's own C++ entry
point (``slam_mms_run/run_main.cpp``, compiled into the extension): the same files in DIR
(trajectories, maps, georef.json and the WGS-84/projected CSVs, report.json, report.html, plots),
the same messages and the same exit status (0 done; 1 input or processing error, with the outputs
computed so far written; 2 bad command line or config file; 130/143 stopped by SIGINT/SIGTERM).
"""

from __future__ import annotations

import sys
from typing import List, Optional

from . import _C, __version__

_PROG = "python -m slam_mms"


def main(argv: Optional[List[str]] = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    if not args or args[0] in ("-h", "--help"):
        print(__doc__.strip())
        return 0 if args else 2
    command, rest = args[0], args[1:]
    if command == "version":
        print(__version__)
        return 0
    if command == "run":
        # The app writes through C stdio: flush Python's buffers first so the output stays in order.
        sys.stdout.flush()
        sys.stderr.flush()
        return _C.run_app([f"{_PROG} run", *rest])
    if command == "merge":
        sys.stdout.flush()
        sys.stderr.flush()
        return _C.merge_app([f"{_PROG} merge", *rest])
    if command == "fleet":
        from .fleet import main as fleet_main

        return fleet_main(rest, prog=f"{_PROG} fleet")
    print(f"{_PROG}: error: unknown command '{command}' (expected run, merge, fleet or version)",
          file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main())
