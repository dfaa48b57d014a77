"""The OXTS records of the shared data's KITTI drives (kitti_oxts/*.tar.gz), for the scripts here."""
import glob
import os
import tarfile

import numpy as np


def records(path):
    """One drive's records (tar.gz of its oxts/data/*.txt), in time order: an N x 30 array."""
    with tarfile.open(path) as t:
        rows = []
        for m in t.getmembers():
            if "/oxts/data/" in m.name and m.name.endswith(".txt"):
                rows.append((m.name, np.array(t.extractfile(m).read().split(), float)))
    rows.sort(key=lambda r: r[0])
    return np.array([r[1] for r in rows])


def drive_files(data):
    """Every drive's archive under DATA/kitti_oxts, sorted; exits naming DATA where there is none."""
    files = sorted(glob.glob(os.path.join(data, "kitti_oxts", "*.tar.gz")))
    if not files:
        raise SystemExit(f"no kitti_oxts/*.tar.gz under {data}")
    return files
