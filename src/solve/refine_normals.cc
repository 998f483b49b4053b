#include <atomic>
#include <optional>
#include <stdexcept>

#include "core/parallel.h"
#include "core/timing.h"
#include "solve/assemble.h"

namespace iphong::solve {

NormalResult RefineNormalsWithPlan(const PhotometricData& data, const NormalPlan& plan,
                                   const NormalResult& previous) {
  const NormalOptions& o = plan.options;
  internal::CheckInputs(data, o);
  if (previous.normals.width != data.width || previous.normals.height != data.height ||
      previous.normals.channels != 3 ||
      previous.residual.pixels.size() != data.width * std::size_t(data.height)) {
    throw std::invalid_argument("the earlier result is not of the data's size " +
                                SizeText(data.width, data.height));
  }
  // Woodham has no start to refine: it is its own pass.
  if (plan.requested_model == reflectance::Lobe::kLambert) return SolveNormalsWithPlan(data, plan);
  const auto start = Clock::now();
  const std::size_t pixels = data.pixel_count();
  const bool per_pixel = !previous.model_map.pixels.empty();
  const PixelFitSettings fit = internal::PlanFitSettings(plan);
  PixelFitSettings lambert_fit = fit;
  lambert_fit.model.lobe = reflectance::Lobe::kLambert;
  lambert_fit.ks_prior.reset();
  const WoodhamSettings woodham = internal::WoodhamOf(o);
  std::vector<internal::PixelSolution> solutions(pixels);
  std::vector<signed char> won(per_pixel ? pixels : 0, -1);
  std::atomic<std::size_t> done{0};
  std::atomic<long long> iterations{0};
  ParallelFor(0, pixels, 128, o.threads, [&](std::size_t b, std::size_t e) {
    PixelFitter fitter(data, fit);
    std::optional<PixelFitter> lambert_fitter;
    if (per_pixel) lambert_fitter.emplace(data, lambert_fit);
    std::vector<std::pair<double, int>> order;
    PixelLights lights(data);
    long long local = 0;
    for (std::size_t p = b; p < e; ++p) {
      internal::PixelSolution& s = solutions[p];
      const std::size_t at = static_cast<std::size_t>(data.pixels[p]);
      const bool lambert = per_pixel && previous.model_map.pixels[at] == 0;
      PixelFitter& f = lambert ? *lambert_fitter : fitter;
      if (!f.Prepare(p)) {
        if (f.dark()) {
          s.status = internal::PixelStatus::kDark;
        } else {
          s = Woodham(data, p, woodham, Eigen::Matrix3Xd(), order, lights, true);
        }
        continue;
      }
      if (previous.residual.pixels[at] >= 0) {
        const float* n = previous.normals.pixels.data() + 3 * at;
        s.normal = Vec3d(n[0], n[1], n[2]).normalized();
      } else {
        const internal::PixelSolution w =
            Woodham(data, p, woodham, Eigen::Matrix3Xd(), order, lights, false);
        s.normal = w.status == internal::PixelStatus::kSolved ? w.normal : Vec3d(0, 0, 1);
      }
      if (!s.normal.allFinite()) s.normal = Vec3d(0, 0, 1);
      f.Fit(s);
      if (per_pixel) won[p] = lambert ? 0 : 1;
      local += s.iterations;
    }
    iterations += local;
    const std::size_t now = done += e - b;
    if (o.progress) o.progress(static_cast<double>(now) / pixels);
  });
  NormalResult result;
  result.summary.pixels = pixels;
  result.summary.iterations = iterations.load();
  result.summary.solve_seconds = SecondsSince(start);
  internal::AssembleNormals(data, o, solutions, won, per_pixel, result);
  SetRefinedFields(result, plan, previous);
  return result;
}

void SetRefinedFields(NormalResult& result, const NormalPlan& plan, const NormalResult& previous) {
  const NormalOptions& o = plan.options;
  result.model = o.model;
  result.shininess = o.shininess;
  result.ambient_term = o.ambient_term;
  result.code_offset = o.code_offset;
  result.model_choice = plan.model_choice;
  if (plan.requested_model == reflectance::Lobe::kLambert) return;
  result.ks = previous.ks;
  result.material_estimated = previous.material_estimated;
  result.specular_identifiable = previous.specular_identifiable;
  result.specular_note = previous.specular_note;
}

}  // namespace iphong::solve
