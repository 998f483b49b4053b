#!/usr/bin/python3
"""`iphong normals` in memory against in bands of rows, on synthetic captures of growing size.

For each size (Mpx, a square) a capture of 32 lights is written by bench/make_capture (a sphere,
16-bit PNG, one band at a time) into WORK, then solved twice with the same model: with a memory
limit the whole capture fits in (in memory), and with --memory-limit LIMIT (in bands). Prints wall
time, time per Mpx and peak RSS (GNU time) of each, and checks the two normal maps are identical.

  /usr/bin/python3 bench/bands.py [--sizes 1 4 16 64] [--limit-gb 2] [--model lambert]
                                  [--work /tmp/iphong-bands]
The in-memory run is left out (—) where the whole capture would not fit in 20 GB.
"""
import argparse
import json
import math
import pathlib
import re
import shutil
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
BUILD = ROOT / "build"


def timed(args):
    done = subprocess.run(["/usr/bin/time", "-f", "TIME %e %M", *map(str, args)],
                          capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"failed: {' '.join(map(str, args))}\n{done.stderr}")
    seconds, kb = re.search(r"TIME ([\d.]+) (\d+)", done.stderr).groups()
    return float(seconds), int(kb) * 1024, done.stdout


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sizes", type=float, nargs="+", default=[1, 4, 16, 64])
    parser.add_argument("--lights", type=int, default=32)
    parser.add_argument("--limit-gb", type=float, default=2.0)
    parser.add_argument("--model", default="lambert")
    parser.add_argument("--work", default="/tmp/iphong-bands")
    parser.add_argument("--keep", action="store_true", help="keep the captures for another run")
    a = parser.parse_args()
    work = pathlib.Path(a.work)
    work.mkdir(exist_ok=True)
    rows = []
    for mpx in a.sizes:
        side = int(round(math.sqrt(mpx * 1e6)))
        capture = work / f"capture_{side}_{a.lights}"
        if not capture.exists():
            generate, _, _ = timed([BUILD / "bench" / "make_capture", capture, side, a.lights])
            print(f"{side}x{side} x {a.lights}: written in {generate:.1f} s", file=sys.stderr)
        results = {}
        for mode, limit in (("memory", 20.0), ("bands", a.limit_gb)):
            out = work / f"out_{mode}_{side}"
            shutil.rmtree(out, ignore_errors=True)
            seconds, rss, stdout = timed([BUILD / "iphong", "normals", capture, "-o", out,
                                          "--model", a.model, "--memory-limit", limit, "--json"])
            banded = "bands" in json.loads(stdout)
            if mode == "memory" and banded:
                results[mode] = None  # over 20 GB whole: solved in bands anyway
            else:
                results[mode] = (seconds, rss, json.loads(stdout).get("bands", {}).get("rows"))
        same = "—"
        if results["memory"]:
            same = "yes" if subprocess.run(
                ["oiiotool", "--fail", "0", "--warn", "0", work / f"out_memory_{side}/normals.exr",
                 work / f"out_bands_{side}/normals.exr", "--diff"],
                capture_output=True).returncode == 0 else "NO"
        rows.append((side, mpx, results, same))
        if not a.keep:
            shutil.rmtree(capture)
        for mode in ("memory", "bands"):
            shutil.rmtree(work / f"out_{mode}_{side}", ignore_errors=True)
    print(f"| size | lights | in memory: s (s/Mpx), peak RSS | bands ({a.limit_gb:g} GB): s "
          f"(s/Mpx), peak RSS, rows | identical |")
    print("|---|---|---|---|---|")
    for side, mpx, r, same in rows:
        m = r["memory"]
        b = r["bands"]
        mem = f"{m[0]:.1f} ({m[0] / mpx:.2f}), {m[1] / 1e9:.2f} GB" if m else "—"
        band = f"{b[0]:.1f} ({b[0] / mpx:.2f}), {b[1] / 1e9:.2f} GB, {b[2]}"
        print(f"| {side}² ({mpx:g} Mpx) | {a.lights} | {mem} | {band} | {same} |")


if __name__ == "__main__":
    main()
