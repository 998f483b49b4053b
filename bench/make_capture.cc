// Writes a synthetic photometric-stereo capture of any size without holding it in memory: a
// plastic sphere filling the frame, K spiral lights (bench_lights.h), one 16-bit PNG per light
// plus mask.png and the DiLiGenT text files, each image shaded by the shared model
// (reflectance::ShadePoints) and written a band of rows at a time (io::ImageRowWriter).
// `iphong render --per-light` holds every image at once: 64 Mpx x 32 lights would be 24 GB.
//
//   make_capture OUT_DIR SIDE_PX LIGHTS
#include <unistd.h>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "bench/bench_lights.h"
#include "io/image_rows.h"
#include "reflectance/shade.h"

using namespace iphong;

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: make_capture OUT_DIR SIDE_PX LIGHTS\n");
    return 2;
  }
  const std::filesystem::path out(argv[1]);
  const int side = std::stoi(argv[2]), k = std::stoi(argv[3]);
  if (side < 8 || k < 3 || !std::filesystem::create_directory(out)) {
    std::fprintf(stderr, "make_capture: %s must be new, SIDE_PX >= 8, LIGHTS >= 3\n", argv[1]);
    return 2;
  }
  const std::vector<Vec3d> lights = bench::SpiralLights(k);
  reflectance::Material material;
  material.ka = Vec3d::Zero();
  material.kd = Vec3d(0.6, 0.5, 0.4);
  material.ks = Vec3d::Constant(0.3);
  material.shininess = 30;
  const double radius = 0.47 * side, centre = 0.5 * side;
  const int band = 256;
  // A row's unit normals (x right, y up, z to the camera) and mask.
  std::vector<float> normals(static_cast<std::size_t>(side) * band * 3);
  std::vector<unsigned char> inside(static_cast<std::size_t>(side) * band);
  const auto fill = [&](int y0, int rows) {
    for (int r = 0; r < rows; ++r)
      for (int x = 0; x < side; ++x) {
        const double u = (x + 0.5 - centre) / radius, v = (centre - (y0 + r + 0.5)) / radius;
        const double z2 = 1 - u * u - v * v;
        const std::size_t p = static_cast<std::size_t>(r) * side + x;
        inside[p] = z2 > 0.01;
        const double z = inside[p] ? std::sqrt(z2) : 1.0;
        normals[3 * p] = inside[p] ? u : 0, normals[3 * p + 1] = inside[p] ? v : 0;
        normals[3 * p + 2] = z;
      }
  };
  {
    io::ImageRowWriter mask((out / "mask.png").string(), side, side, 1, {8, io::Encoding::kLinear});
    for (int y0 = 0; y0 < side; y0 += band) {
      const int rows = std::min(band, side - y0);
      fill(y0, rows);
      ImageF m(side, rows, 1);
      for (std::size_t p = 0; p < m.pixels.size(); ++p) m.pixels[p] = inside[p];
      mask.WriteRows(m);
    }
    mask.Finish();
  }
  std::ofstream names(out / "filenames.txt"), directions(out / "light_directions.txt");
  const bool on_terminal = isatty(fileno(stderr)) != 0;
  for (int j = 0; j < k; ++j) {
    char name[32];
    std::snprintf(name, sizeof name, "%03d.png", j + 1);
    names << name << "\n";
    directions << lights[j].x() << " " << lights[j].y() << " " << lights[j].z() << "\n";
    reflectance::Lighting lighting;
    lighting.lights.push_back(reflectance::Light::Directional(lights[j], Vec3d::Ones()));
    io::ImageRowWriter image((out / name).string(), side, side, 3, {16, io::Encoding::kLinear});
    for (int y0 = 0; y0 < side; y0 += band) {
      const int rows = std::min(band, side - y0);
      fill(y0, rows);
      reflectance::PointsView<float> points;
      points.normals_cam = normals.data();
      points.count = static_cast<std::size_t>(side) * rows;
      const float view[3] = {0, 0, 1};
      points.views_cam = view;
      points.mask = inside.data();
      ImageF rgb(side, rows, 3);
      reflectance::ShadePoints(points, material, lighting, reflectance::ModelOptions{},
                               rgb.pixels.data());
      image.WriteRows(rgb);
    }
    image.Finish();
    // On a terminal one line rewritten; in a log a line every tenth of the images.
    if (on_terminal) {
      std::fprintf(stderr, "\r%d/%d images", j + 1, k);
    } else if ((j + 1) * 10 / k != j * 10 / k || j + 1 == k) {
      std::fprintf(stderr, "%d/%d images\n", j + 1, k);
    }
  }
  if (on_terminal) std::fprintf(stderr, "\n");
  return names && directions ? 0 : 1;
}
