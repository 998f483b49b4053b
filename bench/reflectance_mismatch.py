#!/usr/bin/python3
"""Normals from reflectance that is not Phong's: the default, the default with uniform weights
(`--uniform-weights`, Python weigh_by_shading=False) and `--model lambert` on surfaces shaded by
numpy renderings of Oren-Nayar (rough matte; the qualitative model and the full one with its
interreflection term), Burley's diffuse (Disney's, the principled
materials' diffuse) and a GGX lobe over Lambert (tests/python/brdf_zoo.py, written from the
papers). Three surfaces (a sphere, MATLAB's peaks and a torus, 96 x 96, a spatially varying
albedo, tests/python/test_normals_surfaces.py), 24 and 96 lights on a spiral down to 40 degrees
elevation, Gaussian noise 0.002. Prints a Markdown table of mean angular error (degrees).

    PYTHONPATH=build/python /usr/bin/python3 bench/reflectance_mismatch.py [--lights 24 96]
"""
import argparse
import pathlib
import sys

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "python"))
import iphong  # noqa: E402
from brdf_zoo import burley_diffuse, ggx, oren_nayar, oren_nayar_full, render, sphere  # noqa: E402
import test_normals_surfaces as surfaces  # noqa: E402

REFLECTANCES = {
    "Oren-Nayar, slope 0.3": (lambda n, l: oren_nayar(n, l, 0.3), None),
    "Oren-Nayar, slope 0.6": (lambda n, l: oren_nayar(n, l, 0.6), None),
    "Oren-Nayar full model, slope 0.3": (lambda n, l: oren_nayar_full(n, l, 0.3), None),
    "Oren-Nayar full model, slope 0.6": (lambda n, l: oren_nayar_full(n, l, 0.6), None),
    "Burley diffuse, roughness 0": (lambda n, l: burley_diffuse(n, l, 0.0), None),
    "Burley diffuse, roughness 0.5": (lambda n, l: burley_diffuse(n, l, 0.5), None),
    "Burley diffuse, roughness 1": (lambda n, l: burley_diffuse(n, l, 1.0), None),
    "Lambert + GGX 0.15": (lambda n, l: np.clip(n @ l, 0, None), lambda n, l: ggx(n, l, 0.15)),
    "Lambert + GGX 0.35": (lambda n, l: np.clip(n @ l, 0, None), lambda n, l: ggx(n, l, 0.35)),
}


def shape(name):
    if name == "sphere":
        n, mask = sphere(surfaces.SIZE)
        return n, mask, surfaces.scene("peaks")[2]
    return surfaces.scene(name)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--lights", type=int, nargs="+", default=[24, 96])
    parser.add_argument("--shapes", nargs="+", default=["sphere", "peaks", "torus"])
    args = parser.parse_args()
    print("| reflectance | surface | lights | default | uniform weights | `--model lambert` |"
          " model chosen |")
    print("|---|---|---|---|---|---|---|")
    for label, (reflectance, specular) in REFLECTANCES.items():
        for name in args.shapes:
            n, mask, albedo = shape(name)
            truth = (n * mask[..., None]).astype(np.float32)
            for count in args.lights:
                directions = surfaces.lights(count)[0]
                images = render(n, mask, albedo, directions, reflectance, ks=0.5 * np.pi,
                                specular=specular, sigma=0.002)

                def error(**kwargs):
                    r = iphong.estimate_normals(images, directions, None, mask, **kwargs)
                    e = iphong.angular_error(r["normals"], truth, mask)["mean_angular_error_deg"]
                    return e, r["model"]

                default, model = error()
                uniform, _ = error(weigh_by_shading=False)
                lambert, _ = error(model="lambert")
                worse = " (behind Lambert)" if default > lambert else ""
                print(f"| {label} | {name} | {count} | {default:.2f}{worse} | {uniform:.2f} | "
                      f"{lambert:.2f} | {model} |", flush=True)


if __name__ == "__main__":
    main()
