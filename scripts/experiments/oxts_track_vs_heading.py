#!/usr/bin/env python3
"""Checks a KITTI raw drive's OXTS records for agreement between the direction of travel from the
GNSS positions (the track) and from the INS (heading + crab angle, and the course of vn/ve).

    scripts/experiments/oxts_track_vs_heading.py DRIVE_DIR [--half-window N]

Prints, every 5 records, the track over records i-N..i+N (N = 3 by default), the heading (yaw), the
crab angle atan2(vl, vf), the course atan2(vn, ve), and track - (yaw + crab); then the mean and the
largest difference. All angles in degrees, ENU (0 = east, counter-clockwise), as KITTI's devkit.
A difference here is in the ground truth itself: a method that fits the positions cannot also
match the heading (see docs/results.md, real KITTI frames).
"""
import glob
import math
import os
import sys


def main(argv):
    if len(argv) < 2 or argv[1] in ("-h", "--help"):
        print(__doc__, file=sys.stderr)
        return 2
    drive = argv[1]
    half = 3
    if len(argv) == 4 and argv[2] == "--half-window":
        half = int(argv[3])
    files = sorted(glob.glob(os.path.join(drive, "oxts", "data", "*.txt")))
    if len(files) < 2 * half + 1:
        print(f"{drive}: need at least {2 * half + 1} OXTS records, found {len(files)}",
              file=sys.stderr)
        return 1
    rows = []
    for f in files:
        with open(f) as fh:
            fields = fh.read().split()
        if len(fields) != 30:
            print(f"{f}: expected 30 fields, found {len(fields)}", file=sys.stderr)
            return 1
        rows.append([float(x) for x in fields])
    lat0, lon0 = rows[0][0], rows[0][1]
    earth = 6378137.0

    def east_north(r):
        return (math.radians(r[1] - lon0) * earth * math.cos(math.radians(lat0)),
                math.radians(r[0] - lat0) * earth)

    pos = [east_north(r) for r in rows]
    diffs = []
    print("record  track     yaw    crab  yaw+crab  course  track-(yaw+crab)")
    for i in range(half, len(rows) - half, 5):
        de = pos[i + half][0] - pos[i - half][0]
        dn = pos[i + half][1] - pos[i - half][1]
        if math.hypot(de, dn) < 1.0:
            continue  # standing still: no track
        track = math.degrees(math.atan2(dn, de))
        yaw = math.degrees(rows[i][5])
        crab = math.degrees(math.atan2(rows[i][9], rows[i][8]))
        course = math.degrees(math.atan2(rows[i][6], rows[i][7]))
        d = (track - yaw - crab + 180.0) % 360.0 - 180.0
        diffs.append(d)
        print(f"{i:6d} {track:7.3f} {yaw:7.3f} {crab:6.3f} {yaw + crab:8.3f} {course:7.3f} {d:8.3f}")
    if not diffs:
        print("no moving records")
        return 1
    print(f"mean track-(yaw+crab): {sum(diffs) / len(diffs):.3f} deg, "
          f"largest: {max(diffs, key=abs):.3f} deg over {len(diffs)} records")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
