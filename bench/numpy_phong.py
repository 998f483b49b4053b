"""Issue 3's comparison: seed 004's per-pixel `phong_illumination` in numpy against iphong.

The scene is bench_render's (1024x1024, a 262 144-triangle torus, 4 lights, jade). iphong renders
it (rasterization + shading); the numpy baselines shade its ground-truth normals only, so they do
strictly less work. Rates are megapixels of the 1024x1024 image per second, on one thread for the
Python baselines; ratios are against seed 004's function measured in the same run.

    PYTHONPATH=build/python /usr/bin/python3 bench/numpy_phong.py
"""
import time

import numpy as np

import iphong

LIGHTS = [[0.3, 0.4, 0.866], [-0.5, 0.2, 0.8], [0.1, -0.6, 0.7], [-0.2, -0.1, 1.0]]
SCENE = {
    "width": 1024, "height": 1024, "ambient": 0.2,
    "lights": [{"type": "directional", "direction": d, "intensity": 0.5} for d in LIGHTS],
    "objects": [{"shape": "torus", "ring_radius": 0.6, "tube_radius": 0.3,
                 "ring_segments": 512, "tube_segments": 256, "material": "jade"}],
}
PIXELS = 1024 * 1024


class PhongMaterial:  # seed 004
    def __init__(self, ambient, diffuse, specular, shininess):
        self.ambient = np.array(ambient, dtype=np.float32)
        self.diffuse = np.array(diffuse, dtype=np.float32)
        self.specular = np.array(specular, dtype=np.float32)
        self.shininess = shininess


class DirectionalLight:
    def __init__(self, direction, intensity):
        self.direction = np.asarray(direction, float) / np.linalg.norm(direction)
        self.intensity = np.asarray(intensity, float)

    def get_light_direction(self, point):
        return self.direction, np.inf

    def get_intensity(self, point):
        return self.intensity


def phong_illumination(surface_point, surface_normal, view_dir, material, lights, ambient_light):
    """Seed 004's function, as published (including its final clip)."""
    ambient = material.ambient * ambient_light
    diffuse = np.zeros(3, dtype=np.float32)
    specular = np.zeros(3, dtype=np.float32)
    for light in lights:
        light_dir, distance = light.get_light_direction(surface_point)
        light_intensity = light.get_intensity(surface_point)
        n_dot_l = max(0.0, np.dot(surface_normal, light_dir))
        if n_dot_l > 0:
            diffuse += material.diffuse * light_intensity * n_dot_l
            reflect_dir = 2.0 * n_dot_l * surface_normal - light_dir
            reflect_dir = reflect_dir / (np.linalg.norm(reflect_dir) + 1e-6)
            r_dot_v = max(0.0, np.dot(reflect_dir, view_dir))
            specular += material.specular * light_intensity * r_dot_v ** material.shininess
    return np.clip(ambient + diffuse + specular, 0.0, 1.0)


def vectorized(normals, view, material, lights, ambient):
    """The same model over all pixels at once with numpy broadcasting."""
    color = np.broadcast_to(material.ambient * ambient, normals.shape).astype(np.float64)
    for light in lights:
        l = light.direction
        n_dot_l = normals @ l
        lit = n_dot_l > 0
        r = 2.0 * n_dot_l[:, None] * normals - l
        r_dot_v = np.maximum(r @ view, 0.0)
        term = (material.diffuse * n_dot_l[:, None] + material.specular * (r_dot_v ** material.shininess)[:, None])
        color = color + np.where(lit[:, None], light.intensity * term, 0.0)
    return np.clip(color, 0.0, 1.0)


def best_of(f, repeats):
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        result = f()
        times.append(time.perf_counter() - t)
    return min(times), result


def main():
    render_s, out = best_of(lambda: iphong.render(SCENE), 3)
    mask = out["mask"]
    normals = out["normals"][mask].astype(np.float64)
    jade = iphong.materials["jade"]
    material = PhongMaterial(jade.ka, jade.kd, jade.ks, jade.shininess)
    lights = [DirectionalLight(d, [0.5] * 3) for d in LIGHTS]
    view = np.array([0.0, 0.0, 1.0])

    sample = normals[:: max(1, len(normals) // 20000)]
    loop_s, looped = best_of(
        lambda: np.array([phong_illumination(None, n, view, material, lights, 0.2) for n in sample]), 1)
    loop_rate = len(sample) / loop_s  # masked pixels per second
    vec_s, vec = best_of(lambda: vectorized(normals, view, material, lights, 0.2), 3)
    shade_s, shaded = best_of(lambda: iphong.shade(out["normals"], view, jade,
                                                   [iphong.DirectionalLight(direction=d, intensity=0.5) for d in LIGHTS],
                                                   0.2, mask=mask), 3)

    # The numpy and iphong results agree where seed 004's clip does not bite.
    np.testing.assert_allclose(vec[: len(sample) : 1][:10], np.clip(shaded[mask][:10], 0, 1), atol=2e-4)
    np.testing.assert_allclose(looped[:10], vec[:: max(1, len(normals) // 20000)][:10], atol=2e-4)

    # Per-image rates: time for the whole 1024x1024 image (background pixels are free for numpy).
    loop_image_s = len(normals) / loop_rate
    rows = [
        ("seed 004 phong_illumination, per pixel (numpy)", loop_image_s),
        ("same model vectorized over the image (numpy)", vec_s),
        ("iphong.shade on the same normals (all cores)", shade_s),
        ("iphong.render: rasterize + shade (all cores)", render_s),
    ]
    print(f"1024x1024, {len(normals)} object pixels, 4 lights, jade (n = {jade.shininess})")
    print(f"{'':50s} {'ms':>10s} {'Mpix/s':>8s} {'vs seed 004':>12s}")
    for name, seconds in rows:
        print(f"{name:50s} {1e3 * seconds:10.1f} {PIXELS / seconds / 1e6:8.2f} {loop_image_s / seconds:11.0f}x")


if __name__ == "__main__":
    main()
