// Pieces shared by the material fitter's files (not part of the public interface).
#pragma once

#include <vector>

#include "material/fit.h"

namespace ceres {
class CostFunction;
}

namespace iphong::material::internal {

// The fitted pixels and, per pixel and light (pixel-major), what every model needs: the diffuse
// factor max(N·L, 0), each lobe's cosine (0 where the shared model switches the lobe off), whether
// the observation is usable (not saturated), and per pixel and channel the censoring threshold.
struct Sample {
  const solve::PhotometricData* data = nullptr;
  int lights = 0;
  int threads = 0;  // the sums over the sample's observations (LinearFit) use this many
  std::vector<std::size_t> pixel;  // index into data's pixels
  std::vector<Vec3d> normal;
  std::vector<int> group;  // albedo group of each sample pixel
  int groups = 0;
  std::vector<double> diffuse;
  std::vector<double> cos_phong, cos_blinn;
  std::vector<unsigned char> usable;
  std::vector<Vec3d> threshold;

  std::size_t size() const { return pixel.size(); }
  const float* y(std::size_t p, int j) const { return data->pixel(pixel[p]) + 3 * j; }
  double cosine(reflectance::Lobe lobe, std::size_t i) const {
    return lobe == reflectance::Lobe::kBlinnPhong ? cos_blinn[i] : cos_phong[i];
  }
};

// The fitted pixels of FitMaterial: those with a normal (and a region label with kPerRegion),
// every k-th so that at most options.max_pixels remain. `with_normal` receives the data indices
// of all pixels with a normal, `group_of` their albedo group (−1 for none). Throws
// std::invalid_argument when no pixel has a normal.
Sample BuildSample(const solve::PhotometricData& data, const std::vector<Vec3d>& normals_cam,
                   const MaterialFitOptions& options, std::vector<std::size_t>* with_normal,
                   std::vector<int>* group_of);

// The factors, usable flags and thresholds of the pixels `s.pixel` (with `s.normal`) set.
void FillFactors(Sample& s, double saturation, double shadow_threshold, int threads);

// The model's specular factor from a stored cosine: reflectance::LobePower, 0 where off.
double LobeFactor(double cosine, double shininess);

// The shared coefficients of one model and the albedos they imply.
struct Coefficients {
  Vec3d ambient = Vec3d::Zero();
  Vec3d ks = Vec3d::Zero();
  double shininess = 0;
  std::vector<Vec3d> kd;  // per group; 0 where the group has no lit observation
  std::vector<unsigned char> kd_known;
  double rss = 0;
};

// The least-squares (a, ks, kd) for a fixed shininess over the observations flagged in `used`
// (pixel-major, like Sample::usable), a, ks ≥ 0: per channel the albedos are eliminated and a
// 2×2 system remains.
Coefficients LinearFit(const Sample& s, reflectance::Lobe lobe, double shininess,
                       const std::vector<unsigned char>& used);

// The albedos alone for given shared coefficients (a, ks, n) over the `used` observations.
Coefficients AlbedoFit(const Sample& s, reflectance::Lobe lobe, const Vec3d& ambient,
                       const Vec3d& ks, double shininess, const std::vector<unsigned char>& used);

// The global least-squares shininess: the profile cost over a grid n = 2^(k/2) in [1, 4096],
// then golden-section search around the best grid point (with `near_shininess` > 0, a previous
// answer, the grid is its ±2 steps). Lambert: LinearFit alone.
Coefficients ProfileFit(const Sample& s, reflectance::Lobe lobe,
                        const std::vector<unsigned char>& used, double near_shininess = 0);

// Flags in `used` (among `allowed`) the observations the coefficients do not censor: no channel
// darker than predicted by more than the pixel's threshold. Returns how many were censored.
std::size_t Censor(const Sample& s, reflectance::Lobe lobe, const Coefficients& c,
                   const std::vector<unsigned char>& allowed, std::vector<unsigned char>* used);

// The model's prediction of observation (p, j): a + E_j (kd d + ks s).
Vec3d Predict(const Sample& s, reflectance::Lobe lobe, const Coefficients& c, std::size_t p, int j);

// One pixel's residuals y − a − E (kd d + ks s(n)) over `lights` (3 per light) as a Ceres cost
// of (ambient 3, ks 3, log n 1) with kd eliminated inside, or of (…, kd 3) when not: the
// derivatives are Ceres's automatic ones through the shared model (refine.cc).
ceres::CostFunction* PixelCost(const Sample& s, std::size_t p, std::vector<int> lights,
                               reflectance::Lobe lobe, bool eliminate_kd);

// Ceres's refinement (refine.cc) of the coefficients `c` of a censored fit over the `used`
// observations: (a, ks, log n) with the albedos eliminated inside each pixel's residuals
// (variable projection, exact derivatives through the elimination) or, with `eliminate_kd`
// false, one parameter block per group. Updates `c`; returns the fit with standard errors.
ModelFit Refine(const Sample& s, reflectance::Lobe lobe, bool eliminate_kd,
                const std::vector<unsigned char>& used, int threads, Coefficients* c);

// The lobe as the data show it (predict.cc): binned (observation − ambient − diffuse)/(E·ks).
std::vector<LobeBin> LobeBins(const Sample& s, const Coefficients& c, reflectance::Lobe lobe,
                              const std::vector<unsigned char>& used);

// kd for every pixel in `with_normal` (data indices), by chunks: the closed form with the shared
// coefficients of `c`, censored once like the fit. NaN where nothing lit the pixel.
std::vector<Vec3d> PixelAlbedos(const solve::PhotometricData& data,
                                const std::vector<Vec3d>& normals,
                                const std::vector<std::size_t>& with_normal, reflectance::Lobe lobe,
                                const Coefficients& c, const MaterialFitOptions& options);

}  // namespace iphong::material::internal
