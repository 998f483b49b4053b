#!/usr/bin/python3
"""Whole-run speed: `iphong normals` with `--model lambert` and with the default on the same capture,
interleaved in one session, and the default's wall time as a ratio of Lambert's (issue 30's figure:
the machine is shared and noisy, so only ratios measured in one run are compared). With
`--baseline BIN` another build's default run joins the rotation (before/after a change), with
`--variant FLAGS` the default with those flags (e.g. `--variant=--no-pixel-test`).

    /usr/bin/python3 bench/whole_run.py FOLDER [--repeats 3] [--baseline OLD_IPHONG]
    /usr/bin/python3 bench/whole_run.py --make 1664 12    (a 2.8-megapixel, 12-light sphere made
                                                           by build/bench/make_capture, then removed)
Prints each run's wall times and the stages metrics.json reports (load, model choice, solve), the
least of the repeats, and the ratio to the Lambert run's least."""
import argparse
import json
import pathlib
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]


def run(binary, folder, out, flags):
    start = time.monotonic()
    result = subprocess.run([binary, "normals", str(folder), "-o", str(out), "--overwrite", *flags],
                            capture_output=True, text=True)
    seconds = time.monotonic() - start
    if result.returncode != 0:
        sys.exit(f"whole_run.py: {binary} on {folder}: {result.stderr.strip()}")
    metrics = json.loads((out / "metrics.json").read_text())
    return seconds, metrics


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("folder", nargs="?", help="a capture iphong reads")
    parser.add_argument("--make", nargs=2, type=int, metavar=("SIDE_PX", "LIGHTS"),
                        help="make a synthetic capture with build/bench/make_capture instead")
    parser.add_argument("--iphong", default=str(ROOT / "build" / "iphong"))
    parser.add_argument("--baseline", help="another iphong binary whose default run joins the rotation")
    parser.add_argument("--variant", action="append", default=[], metavar="FLAGS",
                        help="the default with these flags joins the rotation (repeatable), e.g. "
                             "--variant=--no-pixel-test")
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--threads", default="0")
    args = parser.parse_args()
    if (args.folder is None) == (args.make is None):
        parser.error("give a FOLDER or --make SIDE_PX LIGHTS")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        folder = pathlib.Path(args.folder) if args.folder else tmp / "capture"
        if args.make:
            maker = ROOT / "build" / "bench" / "make_capture"
            subprocess.run([str(maker), str(folder), *map(str, args.make)], check=True,
                           stdout=subprocess.DEVNULL)
        runs = [("lambert", args.iphong, ["--model", "lambert"]), ("default", args.iphong, [])]
        for variant in args.variant:
            runs.append((f"default {variant}", args.iphong, variant.split()))
        if args.baseline:
            runs.append(("default, baseline build", args.baseline, []))
        times = {name: [] for name, _, _ in runs}
        stages = {}
        for repeat in range(args.repeats):
            for name, binary, flags in runs:
                seconds, metrics = run(binary, folder, tmp / "out", flags + ["--threads", args.threads])
                times[name].append(seconds)
                stages[name] = metrics
                print(f"  {name}: {seconds:.2f} s", file=sys.stderr, flush=True)
        pixels = stages["lambert"].get("pixels")
        print(f"{folder}: {pixels} pixels, {args.repeats} repeat(s), interleaved\n")
        print("| run | wall (least) | each | load | model choice | solve | vs lambert |")
        print("|---|---|---|---|---|---|---|")
        base = min(times["lambert"])
        for name, _, _ in runs:
            m = stages[name]
            least = min(times[name])
            each = ", ".join(f"{t:.2f}" for t in times[name])
            print(f"| {name} | {least:.2f} s | {each} | {m.get('load_seconds', 0):.2f} s | "
                  f"{m.get('model_seconds', 0):.2f} s | "
                  f"{m.get('init_seconds', 0) + m.get('solve_seconds', 0):.2f} s | "
                  f"{least / base:.2f}x |")


if __name__ == "__main__":
    main()
