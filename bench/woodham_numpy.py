#!/usr/bin/python3
"""Issue 12's speed figure: the whole `iphong normals` (default: model choice, search, fit, files)
against a numpy Woodham script (the images read by iphong.load_dataset, then least squares per
pixel over all lights), on the same capture in the same run. Prints the two wall times and their
ratio. Each is run --repeats times, interleaved, and the least of each compared (the machine is
shared and noisy).

    PYTHONPATH=build/python /usr/bin/python3 bench/woodham_numpy.py [FOLDER] [--repeats 3]
        [--iphong BIN]   (default: DiLiGenT cat and build/iphong)
"""
import argparse
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
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("folder", nargs="?", default=str(ROOT.parent / "shared/data/diligent/cat"))
    parser.add_argument("--repeats", type=int, default=3,
                        help="runs of each, interleaved; the least of each is compared")
    parser.add_argument("--iphong", default=str(ROOT / "build/iphong"))
    args = parser.parse_args()
    numpy_s, iphong_s = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(args.repeats):
            start = time.monotonic()
            numpy_woodham(args.folder)
            numpy_s.append(time.monotonic() - start)
            start = time.monotonic()
            subprocess.run([args.iphong, "normals", args.folder, "-o", tmp + "/out", "-q",
                            "--overwrite"], check=True)
            iphong_s.append(time.monotonic() - start)
    each = lambda times: ", ".join(f"{t:.2f}" for t in times)
    print(f"numpy Woodham {min(numpy_s):.2f} s ({each(numpy_s)}), iphong normals "
          f"{min(iphong_s):.2f} s ({each(iphong_s)}): {min(iphong_s) / min(numpy_s):.2f}x")


if __name__ == "__main__":
    main()
