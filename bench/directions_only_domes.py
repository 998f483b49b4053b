#!/usr/bin/python3
"""Domes read with directions only: the effective distance on an independent renderer.

Spheres and ellipsoids rendered by tests/python/test_near_lights.py's numpy ray caster (a pinhole
camera, LEDs on a dome round the object's centre, SPEC.md's near-light model; matte, or Phong
ks 0.35 n 25), exact and with noise σ 0.002, written with directions only (toward each light
from the object's centre, as DiLiGenT's files give them). Each capture is solved by the default
(D and the lights' centre chosen by held-out prediction), with `light_distance="inf"` and with
`model="lambert"`; prints each run's mean angular error against the ground truth and the D
chosen. The true D is the dome's radius seen at the object's distance: radius · 700 / 500 px
(350 px for 250 mm). The near-light guide's tables come from here.

    PYTHONPATH=build/python /usr/bin/python3 bench/directions_only_domes.py \\
        [--shapes sphere,ellipsoid] [--lights 12,24] [--radii 150,250] [--phong 0,1]
"""
import argparse
import pathlib
import shutil
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "python"))

import iphong  # noqa: E402
import test_near_lights as scene  # noqa: E402  (the numpy renderer the tests use)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shapes", default="sphere,ellipsoid")
    parser.add_argument("--lights", default="12,24")
    parser.add_argument("--radii", default="150,250", help="dome radii, mm")
    parser.add_argument("--phong", default="0,1", help="0: matte, 1: Phong ks 0.35 n 25")
    args = parser.parse_args()
    print("| shape | lights | reflectance | dome mm | true D px | σ | D chosen px | default ° "
          "| `inf` ° | `lambert` ° |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    totals = [0.0, 0.0, 0.0]
    with tempfile.TemporaryDirectory() as tmp:
        folder = pathlib.Path(tmp) / "capture"
        for shape in args.shapes.split(","):
            for count in (int(c) for c in args.lights.split(",")):
                for phong in (p == "1" for p in args.phong.split(",")):
                    for radius in (float(r) for r in args.radii.split(",")):
                        for sigma in (0.0, 0.002):
                            shutil.rmtree(folder, ignore_errors=True)  # our own temporary folder
                            normals, _, mask = scene.write_capture(
                                folder, shape, scene.dome(count, radius, 0), phong, sigma)
                            for f in ["light_positions.txt", "camera.json"]:
                                (folder / f).unlink()
                            d = iphong.load_dataset(folder)
                            data = (d["images"], d["light_directions"], d["light_intensities"],
                                    d["mask"])
                            errors = []
                            for kw in [{}, {"light_distance": "inf"}, {"model": "lambert"}]:
                                r = iphong.estimate_normals(*data, **kw)
                                errors.append(iphong.angular_error(r["normals"], normals, mask)[
                                    "mean_angular_error_deg"])
                                if not kw:
                                    chosen = r["effective_distance"]["distance_px"]
                            totals = [t + e for t, e in zip(totals, errors)]
                            true_px = radius * scene.F / -scene.CENTRE[2]
                            print(f"| {shape} | {count} | {'Phong' if phong else 'matte'} | "
                                  f"{radius:.0f} | {true_px:.0f} | {sigma} | {chosen:.0f} | "
                                  f"{errors[0]:.2f} | {errors[1]:.2f} | {errors[2]:.2f} |",
                                  flush=True)
    print(f"| sum | | | | | | | {totals[0]:.2f} | {totals[1]:.2f} | {totals[2]:.2f} |")


if __name__ == "__main__":
    main()
