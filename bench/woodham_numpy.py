#!/usr/bin/python3
"""Issue 12's speed figure: the whole `iphong normals` (default: model choice, search, fit, files)
against a numpy Woodham script (the images read by iphong.load_dataset, then least squares per
pixel over all lights), on the same capture in the same run. Prints the two wall times and their
ratio.

    PYTHONPATH=build/python /usr/bin/python3 bench/woodham_numpy.py [FOLDER]  (default: DiLiGenT cat)
"""
import pathlib
import subprocess
import sys
import tempfile
import time

import numpy as np

import iphong

ROOT = pathlib.Path(__file__).resolve().parents[1]


def numpy_woodham(folder):
    d = iphong.load_dataset(folder)
    images = np.asarray(d["images"], dtype=np.float64)  # K, H, W, 3
    mask = np.asarray(d["mask"], dtype=bool)
    gray = (images / np.asarray(d["light_intensities"])[:, None, None, :]).mean(-1)[:, mask]
    b = np.linalg.lstsq(np.asarray(d["light_directions"]), gray, rcond=None)[0]
    return b / np.maximum(np.linalg.norm(b, axis=0), 1e-12)


def main():
    folder = sys.argv[1] if len(sys.argv) > 1 else str(ROOT.parent / "shared/data/diligent/cat")
    start = time.monotonic()
    numpy_woodham(folder)
    numpy_s = time.monotonic() - start
    with tempfile.TemporaryDirectory() as tmp:
        start = time.monotonic()
        subprocess.run([str(ROOT / "build/iphong"), "normals", folder, "-o", tmp + "/out", "-q"],
                       check=True)
        iphong_s = time.monotonic() - start
    print(f"numpy Woodham {numpy_s:.2f} s, iphong normals {iphong_s:.2f} s: "
          f"{iphong_s / numpy_s:.2f}x")


if __name__ == "__main__":
    main()
