#!/usr/bin/python3
"""Accuracy report: `iphong normals` on every object with ground truth in the real data
(../shared/data, or $IPHONG_DATA_DIR), with --model lambert and with the default, as a Markdown
table of mean and median angular error (degrees) and wall time per run.

Usage: /usr/bin/python3 bench/accuracy.py [--iphong build/iphong] [--threads N] [--lights K]
                                          [-- extra flags]
Extra flags after `--` go to the default run only (to compare a change against lambert).
`--lights K` runs each object on K of its lights instead (spread by farthest points from the most
frontal one; a folder of links, the per-light text files cut to match): the shared captures all
have 96 or more lights, and with 24 or fewer the model choice and the per-pixel test hold out one
light at a time, a regime only such a subset shows on real photographs."""
import argparse
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
DATA = pathlib.Path(os.environ.get("IPHONG_DATA_DIR", ROOT.parent / "shared" / "data"))


def objects():
    """(name, folder, is DiLiGenT): the photographs first, then captures other projects rendered
    (rps-bunny-lambert), which the mean leaves out."""
    for group in ["diligent", "diligent-crop8"]:
        for folder in sorted((DATA / group).glob("*")):
            if (folder / "Normal_gt.mat").is_file():
                label = "16-bit" if group == "diligent" else "8-bit crop"
                yield f"{folder.name} ({label})", folder, True
    for folder in sorted(DATA.glob("*")):
        if (folder / "Normal_gt.mat").is_file():
            yield f"{folder.name} (rendered by another project)", folder, False


def light_subset(folder, k, into):
    """A K-light copy of `folder` under `into` (links to its files; the per-light text files, those
    with one line per image of filenames.txt, cut to the chosen lights)."""
    import numpy as np
    names = (folder / "filenames.txt").read_text().split()
    directions = np.loadtxt(folder / "light_directions.txt", ndmin=2)
    if len(directions) != len(names) or not 3 <= k <= len(names):
        sys.exit(f"accuracy.py: {folder}: cannot take {k} of its {len(names)} lights")
    pick = [int(np.argmax(directions[:, 2]))]
    while len(pick) < k:
        apart = np.arccos(np.clip(directions @ directions[pick].T, -1, 1)).min(axis=1)
        apart[pick] = -1  # a light listed twice is not taken twice
        pick.append(int(np.argmax(apart)))
    pick.sort()
    out = into / f"{folder.parent.name}-{folder.name}"
    out.mkdir(parents=True)
    for f in folder.iterdir():
        lines = f.read_text().splitlines() if f.suffix == ".txt" else None
        if lines is not None and len([x for x in lines if x.strip()]) == len(names):
            rows = [x for x in lines if x.strip()]
            (out / f.name).write_text("".join(rows[i] + "\n" for i in pick))
        elif f.name not in names or names.index(f.name) in pick:
            (out / f.name).symlink_to(f)
    return out


def run(iphong, folder, flags):
    with tempfile.TemporaryDirectory() as tmp:
        start = time.monotonic()
        result = subprocess.run([iphong, "normals", str(folder), "-o", str(pathlib.Path(tmp) / "out"),
                                 "--json", *flags], capture_output=True, text=True)
        seconds = time.monotonic() - start
    if result.returncode != 0:
        sys.exit(f"accuracy.py: {folder}: {result.stderr.strip()}")
    metrics = json.loads(result.stdout)
    return metrics["mean_angular_error_deg"], metrics["median_angular_error_deg"], seconds


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--iphong", default=str(ROOT / "build" / "iphong"))
    parser.add_argument("--threads", default="0")
    parser.add_argument("--lights", type=int, help="run on this many of each object's lights")
    parser.add_argument("extra", nargs="*", help="flags for the default run (after --)")
    args = parser.parse_args()
    found = list(objects())
    if not found:
        sys.exit(f"accuracy.py: no object with Normal_gt.mat under {DATA}")
    common = ["--threads", args.threads]
    print("| object | lambert mean (median) | default mean (median) | lambert s | default s |")
    print("|---|---|---|---|---|")
    totals = [0.0, 0.0]
    rows = []
    subsets = tempfile.TemporaryDirectory() if args.lights else None
    for name, folder, diligent in found:
        if subsets:
            folder = light_subset(folder, args.lights, pathlib.Path(subsets.name))
            name += f", {args.lights} lights"
        lm, lmed, ls = run(args.iphong, folder, common + ["--model", "lambert"])
        dm, dmed, ds = run(args.iphong, folder, common + args.extra)
        if diligent:
            totals[0] += lm
            totals[1] += dm
        row = f"| {name} | {lm:.2f} ({lmed:.2f}) | {dm:.2f} ({dmed:.2f}) | {ls:.1f} | {ds:.1f} |"
        if diligent:
            print(row, flush=True)
        else:
            rows.append(row)  # after the mean
    n = sum(1 for *_, diligent in found if diligent)
    if n:
        print(f"| mean of the {n} DiLiGenT runs | {totals[0] / n:.2f} | {totals[1] / n:.2f} | | |")
    for row in rows:
        print(row)


if __name__ == "__main__":
    main()
