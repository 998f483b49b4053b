"""Reflectance models other renderers and real materials follow, written here in numpy from their
papers (not from iphong's model, which is Phong): what the solver meets when the data were not
made by its own model. Every function returns the radiance factor of a unit-albedo surface under
a unit light, cos(theta_l) included, for unit normals n (..., 3), one unit light direction l (3,)
and the orthographic view v = (0, 0, 1); 0 where the light is behind the surface.

- Oren-Nayar (1994, the "qualitative" model), rough matte surfaces (plaster, clay, stone, the
  Moon): cos(theta_l) (A + B max(0, cos(phi_l - phi_v)) sin(alpha) tan(beta)),
  A = 1 - 0.5 s^2 / (s^2 + 0.33), B = 0.45 s^2 / (s^2 + 0.09), alpha = max(theta_l, theta_v),
  beta = min(theta_l, theta_v), s the facets' slope deviation (radians). It brightens toward
  grazing incidence where the light is on the viewer's side, and s = 0 is Lambert.
- Burley's diffuse (Disney 2012, the diffuse of Blender's and Unreal's principled materials):
  cos(theta_l) (1 + (F90 - 1)(1 - cos theta_l)^5)(1 + (F90 - 1)(1 - cos theta_v)^5),
  F90 = 0.5 + 2 r cos^2(theta_d), theta_d the angle between l and the half vector, r the
  roughness: darker toward grazing incidence when smooth (F90 < 1), brighter when rough.
- GGX microfacets (Walter et al. 2007) with Schlick's Fresnel (F0) and the Smith-Schlick masking
  (k = alpha / 2): D G F / (4 cos theta_v), a specular lobe that is not Phong's."""
import numpy as np

VIEW = np.array([0.0, 0.0, 1.0])


def _oren_nayar_angles(n, l):
    """The paper's angles: cos θi, cos(φi − φr) (from the two directions' projections on the
    tangent plane), α = max(θi, θr) and β = min(θi, θr)."""
    cos_l = np.clip(n @ l, -1, 1)
    cos_v = np.clip(n @ VIEW, -1, 1)
    theta_l, theta_v = np.arccos(cos_l), np.arccos(cos_v)
    pl = l - cos_l[..., None] * n
    pv = VIEW - cos_v[..., None] * n
    norms = np.linalg.norm(pl, axis=-1) * np.linalg.norm(pv, axis=-1)
    cos_phi = np.where(norms > 1e-12, np.sum(pl * pv, -1) / np.maximum(norms, 1e-12), 0.0)
    return cos_l, cos_phi, np.maximum(theta_l, theta_v), np.minimum(theta_l, theta_v)


def oren_nayar(n, l, slope):
    s2 = slope ** 2
    a = 1 - 0.5 * s2 / (s2 + 0.33)
    b = 0.45 * s2 / (s2 + 0.09)
    cos_l, cos_phi, alpha, beta = _oren_nayar_angles(n, l)
    value = cos_l * (a + b * np.clip(cos_phi, 0, None) * np.sin(alpha) * np.tan(beta))
    return np.where(cos_l > 0, value, 0.0)


def oren_nayar_full(n, l, slope, rho=0.5):
    """Oren and Nayar's full model (SIGGRAPH 1994, eqs. 22-24 with the interreflection term L2),
    per unit albedo: the qualitative model above drops C3 and L2. L2 grows with the albedo; it is
    taken at rho (the zoo's renders multiply by each pixel's albedo after)."""
    s2 = slope ** 2
    cos_l, cos_phi, alpha, beta = _oren_nayar_angles(n, l)
    c1 = 1 - 0.5 * s2 / (s2 + 0.33)
    b = 0.45 * s2 / (s2 + 0.09)
    c2 = np.where(cos_phi >= 0, b * np.sin(alpha), b * (np.sin(alpha) - (2 * beta / np.pi) ** 3))
    c3 = 0.125 * s2 / (s2 + 0.09) * (4 * alpha * beta / np.pi ** 2) ** 2
    direct = cos_l * (c1 + cos_phi * c2 * np.tan(beta)
                      + (1 - np.abs(cos_phi)) * c3 * np.tan((alpha + beta) / 2))
    bounce = 0.17 * rho * cos_l * s2 / (s2 + 0.13) * (1 - cos_phi * (2 * beta / np.pi) ** 2)
    return np.where(cos_l > 0, direct + bounce, 0.0)


def burley_diffuse(n, l, roughness):
    h = (l + VIEW) / np.linalg.norm(l + VIEW)
    cos_l = np.clip(n @ l, 0, None)
    cos_v = np.clip(n @ VIEW, 0, None)
    f90 = 0.5 + 2 * roughness * (l @ h) ** 2
    return cos_l * (1 + (f90 - 1) * (1 - cos_l) ** 5) * (1 + (f90 - 1) * (1 - cos_v) ** 5)


def ggx(n, l, alpha, f0=0.04):
    h = (l + VIEW) / np.linalg.norm(l + VIEW)
    cos_l = np.clip(n @ l, 0, None)
    cos_v = np.clip(n @ VIEW, 1e-6, None)
    cos_h = np.clip(n @ h, 0, None)
    a2 = alpha ** 2
    d = a2 / (np.pi * (cos_h ** 2 * (a2 - 1) + 1) ** 2)
    k = alpha / 2
    g = cos_l / (cos_l * (1 - k) + k) * cos_v / (cos_v * (1 - k) + k)
    f = f0 + (1 - f0) * (1 - max(float(h @ VIEW), 0.0)) ** 5
    return np.where(cos_l > 0, d * g * f / (4 * cos_v), 0.0)


def sphere(size):
    """Unit normals of a sphere filling 95 % of a size x size image (x right, y up), its mask."""
    c = (np.arange(size) + 0.5) / size * 2 - 1
    x, y = np.meshgrid(c, -c)
    mask = x * x + y * y < 0.9
    n = np.stack([x, y, np.sqrt(np.clip(1 - x * x - y * y, 0, None))], -1)
    return n, mask


def render(normals, mask, albedo, lights, reflectance, ks=0.0, specular=None, sigma=0.0, seed=0):
    """K float32 images (K, H, W, 3): albedo x reflectance(n, l) + ks x specular(n, l), unit light
    intensities, Gaussian noise of standard deviation sigma, clipped at 0, black outside the mask."""
    rng = np.random.default_rng(seed)
    images = []
    for l in lights:
        image = albedo * reflectance(normals, l)[..., None]
        if specular is not None:
            image = image + ks * specular(normals, l)[..., None]
        image = image + sigma * rng.standard_normal(image.shape)
        images.append(np.clip(image, 0, None) * mask[..., None])
    return np.asarray(images, np.float32)
