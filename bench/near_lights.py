#!/usr/bin/python3
"""Near lights, measured: what the near-light loop costs against the distant solve on the same
capture, and what it gains.

1. Near-light renders (`iphong render --per-light` of fixtures/scenes/near_*.json, the layout with
   light_positions.txt): `iphong normals` with the positions, against the same images read as
   directions only with distant lights (--light-distance inf) and with `--model lambert`.
2. DiLiGenT with directions only (../shared/data, or $IPHONG_DATA_DIR): the default (an
   effective distance chosen by held-out prediction), against --light-distance inf and
   --model lambert, with each run's D.

Times are each whole command's wall time and the solve's own (metrics.json), in the same run;
the ratio is the near run's solve against the distant run's.

Usage: /usr/bin/python3 bench/near_lights.py [--iphong build/iphong] [--threads N] [--only NAME]
"""
import argparse
import json
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
DATA = pathlib.Path(os.environ.get("IPHONG_DATA_DIR", ROOT.parent / "shared" / "data"))
sys.path.insert(0, str(ROOT / "bench"))
from accuracy import objects  # noqa: E402  (the same object list as bench/accuracy.py)


def normals(iphong, folder, out, flags):
    start = time.monotonic()
    result = subprocess.run([iphong, "normals", str(folder), "-o", str(out), "--json", *flags],
                            capture_output=True, text=True)
    seconds = time.monotonic() - start
    if result.returncode != 0:
        sys.exit(f"near_lights.py: {folder} {' '.join(flags)}: {result.stderr.strip()}")
    return json.loads(result.stdout), seconds


def solve_seconds(m):
    """The solve's own time, without reading the images and writing the pictures."""
    if "near_lights" in m:
        return m["near_lights"]["seconds"]
    if "effective_distance" in m:
        return m["effective_distance"]["seconds"]
    return m["init_seconds"] + m["model_seconds"] + m["solve_seconds"]


def cell(m):
    return f"{m['mean_angular_error_deg']:.2f} ({m['median_angular_error_deg']:.2f})"


def renders(args, tmp):
    print("| capture | `--model lambert` | distant lights | **near lights** | near solve s | "
          "distant solve s | ratio | distance mm (found / true mean) |")
    print("|---|---|---|---|---|---|---|---|")
    for scene in sorted((ROOT / "fixtures" / "scenes").glob("near_*.json")):
        if args.only and args.only not in scene.stem:
            continue
        folder = tmp / scene.stem
        code = subprocess.run([args.iphong, "render", str(scene), "-o", str(folder), "--per-light",
                               "--quiet"], capture_output=True, text=True)
        if code.returncode != 0:
            sys.exit(f"near_lights.py: render {scene}: {code.stderr.strip()}")
        common = ["--threads", args.threads, "--ignore-material"]
        near, _ = normals(args.iphong, folder, tmp / "near", common)
        lambert, _ = normals(args.iphong, folder, tmp / "lambert", common + ["--model", "lambert"])
        distant_folder = tmp / (scene.stem + "-distant")
        shutil.copytree(folder, distant_folder, ignore=shutil.ignore_patterns(".iphong*"))
        (distant_folder / "light_positions.txt").unlink()
        distant, _ = normals(args.iphong, distant_folder, tmp / "distant",
                             common + ["--light-distance", "inf"])
        for out in ["near", "lambert", "distant"]:
            shutil.rmtree(tmp / out)
        ns, ds = solve_seconds(near), solve_seconds(distant)
        rmse = near["near_lights"].get("depth_rmse_mm")
        print(f"| {scene.stem} | {cell(lambert)} | {cell(distant)} | **{cell(near)}** | {ns:.1f} | "
              f"{ds:.1f} | {ns / ds:.2f}x | {near['near_lights']['distance_mm']:.1f}"
              f"{'' if rmse is None else f' (depth RMSE {rmse:.2f})'} |", flush=True)


def diligent(args, tmp):
    print()
    print("| object | `--model lambert` | D = inf | **default** | D chosen (px, object sizes, "
          "test) | default solve s | D = inf solve s | ratio |")
    print("|---|---|---|---|---|---|---|---|")
    for name, folder, _ in objects():
        if args.only and args.only not in name:
            continue
        common = ["--threads", args.threads]
        lambert, _ = normals(args.iphong, folder, tmp / "a", common + ["--model", "lambert"])
        distant, _ = normals(args.iphong, folder, tmp / "b", common + ["--light-distance", "inf"])
        default, _ = normals(args.iphong, folder, tmp / "c", common)
        for out in "abc":
            shutil.rmtree(tmp / out)
        e = default["effective_distance"]
        d = e["distance_px"]
        chosen = "inf" if d == "inf" else f"{d:.0f} px, {d / e['object_size_px']:.1f}, {e['test']}"
        ns, ds = solve_seconds(default), solve_seconds(distant)
        print(f"| {name} | {cell(lambert)} | {cell(distant)} | **{cell(default)}** | {chosen} | "
              f"{ns:.1f} | {ds:.1f} | {ns / ds:.2f}x |", flush=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--iphong", default=str(ROOT / "build" / "iphong"))
    parser.add_argument("--threads", default="0")
    parser.add_argument("--only", default="")
    parser.add_argument("--skip-diligent", action="store_true")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as t:
        tmp = pathlib.Path(t)
        renders(args, tmp)
        if not args.skip_diligent:
            diligent(args, tmp)


if __name__ == "__main__":
    main()
