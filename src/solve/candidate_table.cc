// The search's candidate directions and their tabulated factors (CandidateTable, search.h).
#include "solve/search.h"

#include <algorithm>
#include <cmath>

#include "solve/internal.h"

namespace iphong::solve {

std::vector<Vec3d> HemisphereDirections(int count) {
  std::vector<Vec3d> out;
  out.reserve(count);
  const double golden = M_PI * (3 - std::sqrt(5.0));
  for (int i = 0; i < count; ++i) {
    const double z = (i + 0.5) / count;  // uniform in z: equal areas on the sphere
    const double r = std::sqrt(std::max(0.0, 1 - z * z));
    out.emplace_back(r * std::cos(golden * i), r * std::sin(golden * i), z);
  }
  return out;
}

CandidateTable::CandidateTable(const std::vector<Vec3d>& light_dir_cam,
                               const reflectance::ModelOptions& model, double shininess, int count,
                               const std::vector<int>& fold)
    : lights_(static_cast<int>(light_dir_cam.size())),
      fine_(count),
      fold_(fold),
      normals_(HemisphereDirections(count)) {
  const std::vector<Vec3d> coarse = HemisphereDirections(std::max(4, count / 4));
  // The spiral's z is (i + 0.5)/m, and two directions an angle a apart differ in z by at most a,
  // so the nearest coarse direction — within the coarse spacing — is among those whose z lies
  // within twice that spacing (exact, and m/(4·sqrt(2πm)) times fewer comparisons than all).
  const int m = static_cast<int>(coarse.size());
  const double window = 2 * std::sqrt(2 * M_PI / m);
  std::vector<std::vector<int>> owned(m);
  for (int f = 0; f < count; ++f) {
    const double z = normals_[f].z();
    const int lo = std::clamp(static_cast<int>(std::floor((z - window) * m - 0.5)), 0, m - 1);
    const int hi = std::clamp(static_cast<int>(std::ceil((z + window) * m - 0.5)), 0, m - 1);
    int nearest = lo;
    for (int c = lo + 1; c <= hi; ++c) {
      if (coarse[c].dot(normals_[f]) > coarse[nearest].dot(normals_[f])) nearest = c;
    }
    owned[nearest].push_back(f);
  }
  // The fine directions stored grouped by their coarse one, so each group is scored as one range.
  std::vector<Vec3d> fine;
  fine.reserve(count);
  members_.resize(m);
  for (int c = 0; c < m; ++c) {
    for (const int f : owned[c]) {
      members_[c].push_back(static_cast<int>(fine.size()));
      fine.push_back(normals_[f]);
    }
  }
  normals_ = std::move(fine);
  normals_.insert(normals_.end(), coarse.begin(), coarse.end());
  const std::size_t k = lights_;
  diffuse_.resize(normals_.size() * k);
  specular_.resize(normals_.size() * k);
  sums_.resize(3 * normals_.size());
  for (std::size_t c = 0; c < normals_.size(); ++c) {
    double dd = 0, ds = 0, ss = 0;
    for (std::size_t j = 0; j < k; ++j) {
      const reflectance::LightFactors<double> f = reflectance::ShadingFactors<double>(
          normals_[c], internal::ViewCam(), light_dir_cam[j], shininess, model);
      diffuse_[c * k + j] = static_cast<float>(f.diffuse);
      specular_[c * k + j] = static_cast<float>(f.specular);
      // The sums from the stored (float) factors, as the pixels' dot products will see them.
      const double d = diffuse_[c * k + j], s = specular_[c * k + j];
      dd += d * d;
      ds += d * s;
      ss += s * s;
    }
    sums_[3 * c] = dd;
    sums_[3 * c + 1] = ds;
    sums_[3 * c + 2] = ss;
  }
  const std::size_t lanes = kSearchLanes;
  const std::size_t blocks = (normals_.size() + lanes - 1) / lanes;
  diffuse_packed_.assign(blocks * k * lanes, 0.0f);
  specular_packed_.assign(blocks * k * lanes, 0.0f);
  sums_packed_.assign(blocks * 3 * lanes, 0.0);
  for (std::size_t c = 0; c < normals_.size(); ++c) {
    for (std::size_t i = 0; i < 3; ++i) {
      sums_packed_[(c / lanes) * 3 * lanes + i * lanes + c % lanes] = sums_[3 * c + i];
    }
    const std::size_t at = (c / lanes) * k * lanes + c % lanes;
    for (std::size_t j = 0; j < k; ++j) {
      diffuse_packed_[at + j * lanes] = diffuse_[c * k + j];
      specular_packed_[at + j * lanes] = specular_[c * k + j];
      has_lobe_ = has_lobe_ || specular_[c * k + j] != 0;
    }
  }
  if (fold_.size() != k) fold_.clear();
  const int folds = fold_.empty() ? 0 : 1 + *std::max_element(fold_.begin(), fold_.end());
  fold_size_.assign(folds, 0);
  for (const int f : fold_) ++fold_size_[f];
  // Each fold's own lights' sums, then the training lights' as all lights' less those: one pass
  // over the table whatever the number of folds (leave-one-out has K of them).
  fold_sums_.assign(3 * folds * normals_.size(), 0.0);
  for (std::size_t c = 0; c < normals_.size() && folds > 0; ++c) {
    double* own = &fold_sums_[3 * folds * c];
    for (std::size_t j = 0; j < k; ++j) {
      double* f = own + 3 * fold_[j];
      const double d = diffuse_[c * k + j], s = specular_[c * k + j];
      f[0] += d * d, f[1] += d * s, f[2] += s * s;
    }
    for (std::size_t i = 0; i < 3 * static_cast<std::size_t>(folds); ++i) {
      // Sums of non-negative terms (and of d·s ≥ 0): never below zero but for rounding.
      own[i] = std::max(0.0, sums_[3 * c + i % 3] - own[i]);
    }
  }
}

}  // namespace iphong::solve
