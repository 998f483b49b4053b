#include "solve/bands.h"

#include <algorithm>
#include <array>
#include <stdexcept>

#include "core/timing.h"

namespace iphong::solve {
namespace {

// The plan-sample positions that fall in a band of `count` masked pixels starting at masked
// position `position`, as positions within the band; advances `next` past them.
std::vector<std::size_t> SampleInBand(std::vector<std::size_t>::const_iterator& next,
                                      std::vector<std::size_t>::const_iterator end,
                                      std::size_t position, std::size_t count) {
  std::vector<std::size_t> local;
  for (; next != end && *next < position + count; ++next) local.push_back(*next - position);
  return local;
}

// The per-pixel images of a result, in one list for cutting and pasting rows.
template <typename Result>
auto PixelImages(Result& r) {
  return std::array{&r.normals, &r.albedo, &r.specular, &r.residual, &r.model_map};
}

}  // namespace

NormalResult ResultFields(const NormalResult& whole) {
  NormalResult r;
  r.model = whole.model;
  r.ks = whole.ks;
  r.shininess = whole.shininess;
  r.ambient_term = whole.ambient_term;
  r.code_offset = whole.code_offset;
  r.material_estimated = whole.material_estimated;
  r.specular_identifiable = whole.specular_identifiable;
  r.specular_note = whole.specular_note;
  r.model_choice = whole.model_choice;
  r.summary = whole.summary;
  return r;
}

NormalResult ResultRows(const NormalResult& whole, int y0, int y1) {
  NormalResult band = ResultFields(whole);
  const auto from = PixelImages(whole);
  const auto to = PixelImages(band);
  for (std::size_t i = 0; i < from.size(); ++i) {
    const ImageF& image = *from[i];
    if (image.pixels.empty()) continue;
    ImageF rows(image.width, y1 - y0, image.channels);
    const std::size_t row = std::size_t(image.width) * image.channels;
    std::copy(image.pixels.begin() + std::ptrdiff_t(y0 * row),
              image.pixels.begin() + std::ptrdiff_t(y1 * row), rows.pixels.begin());
    *to[i] = std::move(rows);
  }
  return band;
}

void PasteResultRows(NormalResult& whole, const NormalResult& band, int y0, int width, int height) {
  const auto from = PixelImages(band);
  const auto to = PixelImages(whole);
  for (std::size_t i = 0; i < from.size(); ++i) {
    const ImageF& rows = *from[i];
    if (rows.pixels.empty()) continue;
    ImageF& image = *to[i];
    if (image.pixels.empty()) image = ImageF(width, height, rows.channels, 0.0f);
    const std::size_t row = std::size_t(width) * rows.channels;
    std::copy(rows.pixels.begin(), rows.pixels.end(),
              image.pixels.begin() + std::ptrdiff_t(y0 * row));
  }
}

NormalResult EstimateNormalsInBands(const BandSource& source, int band_rows,
                                    const NormalOptions& options,
                                    const std::function<void(int, const NormalResult&)>& write,
                                    const BandProgress& progress, NormalPlan* plan_out) {
  if (auto m = options.Validate(); !m.empty()) throw std::invalid_argument(m);
  if (band_rows < 1 || source.width < 1 || source.height < 1 || !source.read) {
    throw std::invalid_argument("bands need a size, a reader and at least one row each");
  }
  const std::vector<std::size_t> sample =
      PlanSampleIndices(source.masked_pixels, options.plan_sample);

  // Pass 1: the plan sample's observations, in the masked-pixel order EstimateNormals uses.
  // Woodham and known coefficients decide nothing for the whole object: no first pass.
  const bool planned = NeedsPlanSample(options);
  const auto start = Clock::now();
  PhotometricData sampled;
  std::size_t position = 0;  // masked pixels before this band
  auto next = sample.cbegin();
  for (int y0 = 0; planned && y0 < source.height; y0 += band_rows) {
    const int y1 = std::min(source.height, y0 + band_rows);
    const PhotometricData band = source.read(y0, y1, true);
    if (y0 == 0) {
      sampled.width = source.width;
      sampled.height = source.height;
      sampled.images = band.images;
      sampled.light_directions = band.light_directions;
      sampled.light_intensities = band.light_intensities;
    }
    AppendObservations(sampled, band,
                       SampleInBand(next, sample.cend(), position, band.pixel_count()),
                       static_cast<std::size_t>(y0) * source.width);
    position += band.pixel_count();
    if (progress.rows) progress.rows(1, y1);
  }
  const auto check_count = [&] {
    if (position != source.masked_pixels) {
      throw std::invalid_argument("the bands hold " + std::to_string(position) +
                                  " masked pixels, the source said " +
                                  std::to_string(source.masked_pixels));
    }
  };
  if (planned) check_count();
  if (planned && progress.sample) progress.sample(sampled);
  const double sample_seconds = SecondsSince(start);
  NormalPlan plan;
  if (planned) plan = PlanNormals(sampled, options);
  sampled = PhotometricData();  // freed before the fit

  // Pass 2: every band with the plan; the sample pixels' ks for the object's median.
  NormalResult total;
  total.summary.init_seconds = sample_seconds;
  total.summary.model_seconds = plan.model_seconds;
  std::vector<Vec3f> sample_ks;
  // Without a plan sample no plan has seen the images: each band is checked for them instead.
  ImageVariation variation;
  position = 0;
  next = sample.cbegin();
  for (int y0 = 0; y0 < source.height; y0 += band_rows) {
    const int y1 = std::min(source.height, y0 + band_rows);
    const PhotometricData band = source.read(y0, y1, !planned);
    if (!planned && y0 == 0) plan = PlanNormals(SubsetObservations(band, {}), options);
    if (!planned) variation.Add(band);
    NormalResult r = SolveNormalsWithPlan(band, plan);
    AppendSampleSpecular(r, band, SampleInBand(next, sample.cend(), position, band.pixel_count()),
                         sample_ks);
    position += band.pixel_count();
    NormalSummary& s = total.summary;
    s.solve_seconds += r.summary.solve_seconds + r.summary.init_seconds;
    s.iterations += r.summary.iterations;
    s.pixels += r.summary.pixels;
    s.dark_pixels += r.summary.dark_pixels;
    s.underdetermined_pixels += r.summary.underdetermined_pixels;
    if (y0 == 0) {
      total.model = r.model;
      total.shininess = r.shininess;
      total.ambient_term = r.ambient_term;
      total.code_offset = r.code_offset;
      total.model_choice = r.model_choice;
    }
    write(y0, r);
    if (progress.rows) progress.rows(2, y1);
  }
  if (!planned) check_count();
  variation.Check();
  FinishNormals(total, plan, sample_ks);
  if (plan_out) *plan_out = plan;
  NormalSummary& s = total.summary;
  s.success = true;
  s.message = "solved " + std::to_string(s.pixels - s.dark_pixels - s.underdetermined_pixels) +
              " of " + std::to_string(s.pixels) + " pixels in bands of " +
              std::to_string(band_rows) + " rows";
  return total;
}

}  // namespace iphong::solve
