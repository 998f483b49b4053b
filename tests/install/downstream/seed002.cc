// Seed 002's worked example shaded through an installed iphong's public API: a Phong surface
// (ka 0.1, kd (0.9, 0, 0), ks (0.5, 0.5, 0.4), n 10) under two lights of 0.5, the second behind
// the surface. The seed prints I = (0.39272, 0.13292, 0.12634), rounding each step. With a path
// argument the colour also goes through an EXR file and back (io: OpenImageIO linked too).
#include <cmath>
#include <cstdio>

#include "core/version.h"
#include "io/image_io.h"
#include "reflectance/lighting.h"
#include "reflectance/material.h"
#include "reflectance/shade.h"

int main(int argc, char** argv) {
  using namespace iphong;
  reflectance::Material material;
  material.ka = Vec3d(0.1, 0.1, 0.1);
  material.kd = Vec3d(0.9, 0.0, 0.0);
  material.ks = Vec3d(0.5, 0.5, 0.4);
  material.shininess = 10;
  reflectance::Lighting lighting;
  lighting.ambient = Rgb(1, 1, 1);
  lighting.lights = {
      reflectance::Light::Directional(Vec3d(0.57735, 0.57735, 0.57735), Rgb(0.5, 0.5, 0.5)),
      reflectance::Light::Directional(Vec3d(0, 0, -1), Rgb(0.5, 0.5, 0.5))};
  // The seed's V points from the viewer to the surface; iphong's toward the viewer.
  const Vec3d view_cam = -Vec3d(0.23570, 0.23570, -0.94281).normalized();
  const Vec3d color = reflectance::Shade(Vec3d(0, 0, 1), view_cam, Vec3d::Zero().eval(), material,
                                         lighting, reflectance::ModelOptions{});
  const Vec3d seed(0.39272, 0.13292, 0.12634);
  const double worst = (color - seed).cwiseAbs().maxCoeff();
  std::printf("iphong %s: I = [%.5f %.5f %.5f], largest difference from seed 002 %.1e\n",
              kVersion, color[0], color[1], color[2], worst);
  if (worst >= 2e-5) return 1;
  if (argc > 1) {
    ImageF pixel(1, 1, 3);
    for (int c = 0; c < 3; ++c) pixel.pixels[c] = static_cast<float>(color[c]);
    io::WriteImage(argv[1], pixel);
    const ImageF back = io::ReadImage(argv[1]);
    for (int c = 0; c < 3; ++c)
      if (back.pixels.size() != 3 || back.pixels[c] != pixel.pixels[c]) return 1;
    std::printf("read back from %s\n", argv[1]);
  }
  return 0;
}
