// Normal recovery: per-pixel unit normals, RGB albedo and specular coefficients from K ≥ 3 images
// under known lights, by inverting the shared Phong model (reflectance/phong.h).
//
// `lambert`: Woodham's least squares (woodham.h), the baseline. Otherwise, per pixel:
// 1. The model: with known coefficients (material.json) the given one; else the lobe and its
//    shininess the data support, chosen by held-out prediction among Lambert, Oren–Nayar's rough
//    diffuse term, Phong, Blinn-Phong and a foil centred on the normal (model_choice.h; between the
//    foil and a highlight the normals' integrability decides, highlight_check.h), ks then free per
//    pixel and channel.
// 2. A global search over candidate normals on the visible hemisphere (search.h), scored by the
//    censored cost of the observations, so the fit cannot start in a wrong basin.
// 3. A local Levenberg–Marquardt fit from the winner (pixel_fit.h): two unknowns on a chart of
//    the normal, kd and ks eliminated in closed form; shadows are censored observations
//    (internal::CensoredCost), saturated ones unused.
// Frame: SPEC.md's camera frame, orthographic view V = (0, 0, 1).
#pragma once

#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "reflectance/material.h"
#include "solve/model_choice.h"
#include "solve/photometric_data.h"

namespace iphong::solve {

struct NormalOptions {
  // The lobe. Estimated coefficients: the family the shininess (and, with choose_model, the lobe)
  // is chosen from; kLambert: Woodham alone.
  reflectance::Lobe model = reflectance::Lobe::kPhong;
  // Estimated coefficients: choose among Lambert, Oren–Nayar's rough diffuse term, Phong,
  // Blinn-Phong and the normal-centred foil by held-out prediction (model_choice.h) instead of
  // using `model`'s family alone.
  bool choose_model = true;
  // Woodham: fractions of each pixel's observations dropped, darkest and brightest first.
  double discard_dark = 0.3;
  double discard_bright = 0.1;
  // Observations with a channel at or above this value are treated as saturated and unused; at
  // most 1, only in pixels whose values stay within 1 (PixelSaturation: a float capture with
  // values above 1 was not clipped there).
  double saturation = 0.995;
  // Shadow censoring: an observation darker than the model by more than this fraction of the
  // pixel's brightness costs no more (internal::CensoredCost). Noise is ~1% of the brightness,
  // a cast shadow removes the whole direct term: 0.1 lies between (measured: docs/accuracy.md).
  double shadow_threshold = 0.1;
  int irls_rounds = 4;  // censoring rounds of the local fit
  // Candidate normals of the global search (search.h): ~1000 spaces them 4.5° apart, finer than
  // the narrowest lobe the choice offers is wide.
  int search_candidates = 1000;
  // Pixels the model choice scores. Its decisions are paired differences of held-out costs
  // whose standard error falls as 1/√sample; 600 is where more stopped changing the choice on
  // DiLiGenT, at about half the time of 1000 (docs/accuracy.md).
  int model_sample = 600;
  // Pixels the whole-object decisions see (PlanSampleIndices): the model choice scores
  // model_sample of them and the ambient estimate is a quartile over them, so 2^17 costs nothing
  // in accuracy and keeps a capture of any size to a fixed first pass.
  std::size_t plan_sample = 131072;
  // Estimated coefficients: each pixel also chooses between Lambert and the object's specular
  // model by its own held-out prediction (the same halves of the lights), so a region Lambert
  // predicts clearly better (kPixelModelSignificance) — dark, or matte on a glossy object — is
  // Lambertian.
  bool per_pixel_model = true;
  // Fit the normal to all three channels (each with its own coefficients). Off: to their
  // luminance, exact under the model and about twice as fast, a little less accurate on photos.
  bool color_residuals = true;
  int max_iterations = 10;  // per pixel and round
  // Estimated coefficients: weight each observation by the object's held-out misfit at its N·L
  // toward the terminator (shading_weights.h), measured by the plan on its sample. The weights
  // the fits use are `shading_weights`, which the plan sets (empty: all alike).
  bool weigh_by_shading = true;
  ShadingWeights shading_weights;

  // Added to every nonzero channel of every observation before anything else (image units).
  // Images stored as integer codes were either rounded (code k stands for k ± ½ a step) or
  // truncated (k … k + 1: on average half a step brighter than k, a bias of 15 % at 3 codes of
  // 8 bits); with the model chosen, the plan decides which by held-out prediction and sets this
  // to 0 or half a step (ModelChoice::code_step). Zero codes stay zero: they are shadows.
  double code_offset = 0;

  // Known coefficients (material.json). Otherwise the model is chosen and ks is free per pixel.
  bool material_known = false;
  Vec3d ambient_term = Vec3d::Zero();  // Ia ⊙ ka, subtracted from every image
  Vec3d ks = Vec3d::Zero();
  double shininess = 1;
  // A known uniform albedo kd: what one or two images need (RecoverNormals).
  std::optional<Vec3d> known_albedo;

  int threads = 0;
  // Called with the fraction done (0..1) from worker threads; must be thread-safe.
  std::function<void(double)> progress;

  std::string Validate() const;
};

struct NormalSummary {
  bool success = false;
  std::string message;
  double init_seconds = 0;   // Woodham (lambert) or reading the observations
  double model_seconds = 0;  // choosing the model by held-out prediction
  double solve_seconds = 0;  // global search and local fits
  long long iterations = 0;  // local-fit iterations, summed
  std::size_t pixels = 0;
  std::size_t dark_pixels = 0;             // dark in every image: no normal (flagged)
  std::size_t underdetermined_pixels = 0;  // fewer than 3 usable lights (flagged)
};

struct NormalResult {
  ImageF normals;   // 3 channels, unit xyz in the camera frame; 0 outside the mask
  ImageF albedo;    // 3 channels, kd
  ImageF specular;  // 3 channels, each pixel's ks; empty for lambert
  ImageF residual;  // 1 channel: RMS model residual per pixel; −1 where no normal was found
  reflectance::Lobe model = reflectance::Lobe::kPhong;  // the lobe used
  Vec3d ks = Vec3d::Zero();  // known, or the median ks of the pixels not given to Lambert
  double shininess = 1;
  Vec3d ambient_term = Vec3d::Zero();  // Ia ⊙ ka (known; 0 when estimated)
  double code_offset = 0;              // NormalOptions::code_offset, as used
  bool material_estimated = false;
  bool specular_identifiable = true;  // false: the choice found no specular model predicts better
  std::string specular_note;
  ModelChoice model_choice;  // estimated coefficients: every model's held-out score
  // per_pixel_model: 1 where the specular model won, 0 where Lambert did, −1 elsewhere.
  ImageF model_map;
  // One or two images only: the angle the data alone leaves open per pixel (few_images.h).
  ImageF ambiguity_deg;
  NormalSummary summary;
};

// Throws std::invalid_argument for invalid data or options (one-line message). The same as
// PlanNormals on the plan sample, SolveNormalsWithPlan on every pixel and FinishNormals.
NormalResult EstimateNormals(const PhotometricData& data, const NormalOptions& options);

// The same recovery in pieces — bands of rows streamed from the files, Dask blocks — with the
// same result as in one piece. What the whole object decides (the model, its shininess, the
// ambient term, the ks prior, the folds) is decided once on the plan sample; then every pixel is
// fitted on its own with it, so a pixel's result depends on its own observations and the plan
// only, never on which piece it came in.

// The plan sample: every masked pixel up to NormalOptions::plan_sample (every DiLiGenT object),
// else that many at an even stride over the masked pixels in row-major order.
// Positions, in the masked-pixel order, of the plan sample's pixels (ascending).
std::vector<std::size_t> PlanSampleIndices(std::size_t masked_pixels, std::size_t plan_sample);
// The observations of the pixels at `indices` (positions in data's masked-pixel order).
PhotometricData SubsetObservations(const PhotometricData& data,
                                   const std::vector<std::size_t>& indices);
// Appends those observations to `to` (same lights), their pixel indices shifted by
// `pixel_offset` (a band's first pixel in the whole image).
void AppendObservations(PhotometricData& to, const PhotometricData& from,
                        const std::vector<std::size_t>& indices, std::size_t pixel_offset);
// Appends the specular coefficients of the solved pixels among `indices` (positions in data's
// order) of a result of SolveNormalsWithPlan on `data`, but those its per-pixel test gave to
// Lambert (model_map 0): what FinishNormals takes.
void AppendSampleSpecular(const NormalResult& result, const PhotometricData& data,
                          const std::vector<std::size_t>& indices, std::vector<Vec3f>& ks);
// Whether PlanNormals decides anything from the sample: not for Woodham nor known coefficients.
bool NeedsPlanSample(const NormalOptions& options);

struct NormalPlan {
  NormalOptions options;  // as asked, with the model, shininess and ambient term decided
  reflectance::Lobe requested_model = reflectance::Lobe::kPhong;
  ModelChoice model_choice;  // estimated coefficients: every model's held-out score
  double model_seconds = 0;

  // Makes `m` the plan's model: its lobe, shininess, ambient term and reading of integer codes in
  // `options`, and `m` itself as the choice's (whose ks prior the fits take).
  void Use(const ModelCandidate& m);
};

// Whether the images differ anywhere, over one or more sets of observations of a capture:
// images identical at every pixel carry no shading (the light did not change between them, or
// one photo was saved under every name). Black everywhere is not this mistake: such pixels are
// flagged dark, as in any shadow. PlanNormals checks its sample; bands without a plan sample
// check every band.
class ImageVariation {
 public:
  void Add(const PhotometricData& data);
  // Throws std::invalid_argument when two or more images were added, some pixel is lit and no
  // pixel differs between them.
  void Check() const;

 private:
  bool varies_ = false, lit_ = false;
  std::size_t pixels_ = 0;
  int images_ = 0;
};

// The whole-object decisions, from the plan sample's observations. With `starts` (a normal per
// pixel of the sample, from an earlier solve) the model choice refines them instead of searching
// (ModelChoiceSettings::starts). Throws std::invalid_argument for invalid data or options.
NormalPlan PlanNormals(const PhotometricData& sample, const NormalOptions& options,
                       const std::vector<Vec3d>* starts = nullptr);

// Every pixel of `data` fitted with the plan (images of data.width × data.height). The
// whole-object summaries — ks, material_estimated, the notes — are left to FinishNormals.
NormalResult SolveNormalsWithPlan(const PhotometricData& data, const NormalPlan& plan);

// A later pass of an iterative solve (near lights: the surface moved, and with it the lights each
// pixel sees): every pixel of `data` refitted by the local fit alone from `previous`'s normal,
// with the plan's model and the model each pixel took there (previous.model_map), no search.
// Pixels `previous` did not solve start from Woodham's normal. `previous` must be a result on
// data's image size; the whole-object summaries are copied from it.
NormalResult RefineNormalsWithPlan(const PhotometricData& data, const NormalPlan& plan,
                                   const NormalResult& previous);
// The whole-object fields RefineNormalsWithPlan gives its result (the plan's model and terms, its
// model choice; the previous result's ks and notes, but for Woodham, whose pass is a solve of its
// own), for results assembled from pieces refitted elsewhere (Dask blocks).
void SetRefinedFields(NormalResult& result, const NormalPlan& plan, const NormalResult& previous);

// Fills the whole-object summaries: ks is the per-channel median of the specular coefficients
// of the solved plan-sample pixels that kept the lobe (`sample_ks`, one per such pixel,
// AppendSampleSpecular); known ks when known.
void FinishNormals(NormalResult& result, const NormalPlan& plan,
                   const std::vector<Vec3f>& sample_ks);

// Any number of images: EstimateNormals for three or more; for one or two the global solver with
// priors (EstimateNormalsFewImages), which needs the coefficients known (material_known) and
// `known_albedo`; its albedo is then that kd inside the mask and ambiguity_deg is set.
NormalResult RecoverNormals(const PhotometricData& data, const NormalOptions& options);

}  // namespace iphong::solve
