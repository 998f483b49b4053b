// Which reflectance model the data support — Lambert, Oren–Nayar's rough diffuse term, Phong or
// Blinn-Phong, and the lobe's shininess or the facets' slope — decided by how well each predicts
// observations it was not fitted to. On a sample
// of pixels spread over the object, the lights are split in two fixed halves; each model is
// fitted (the global search, search.h) to one half and charged the censored cost of the other
// half's observations (internal::CensoredCost, in units of the pixel's t², so every pixel counts
// alike), then the halves swap. The fitted cost cannot decide: a model with more freedom always
// fits its own data better. A specular model is used only where it predicts better than Lambert.
//
// Beside the mirror lobes the family holds a foil: a lobe of the same widths centred on the
// normal, (N·L)^n (reflectance::Lobe::kNormalCentred), scored once a mirror lobe predicts better
// than Lambert. What a broad mirror lobe gains over
// Lambert may be no highlight at all: the fall-off of lights nearer than the file says, a
// diffuse term sharper than the cosine, shadows and interreflections at grazing light. Such a
// departure follows the normal, and the foil takes it without pulling the normal toward anybody's
// mirror direction; a mirror lobe takes it by tilting the normal, pixel by pixel. So when the foil
// predicts best, the mirror lobe is not taken as a highlight on prediction alone: where one also
// beats Lambert, the plan keeps whichever of the two gives normals that make a surface
// (PlanNormals: a highlight absorbed into tilted normals leaves a field that does not integrate).
//
// The family also holds Oren–Nayar's rough diffuse term (reflectance::OrenNayarDiffuse), its facet
// slope shared by the object as a shininess is. A misfit it absorbs by tilting normals (a
// darkened terminator, a diffuse term falling off at grazing light) wants another slope where the
// surface faces the camera than where it turns away; so where it could be chosen, one slope must
// predict both the sample's frontal and oblique halves within two standard errors of each half's
// best, or the term leaves the choice (ChooseModel; the note says so).
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "reflectance/phong.h"
#include "solve/photometric_data.h"
#include "solve/pixel_fit.h"
#include "solve/shading_weights.h"

namespace iphong::solve {

struct ModelCandidate {
  reflectance::Lobe lobe = reflectance::Lobe::kLambert;
  double shininess = 1;  // the lobe's n; Oren–Nayar's facet slope σ (radians)
  // Each pixel's free ks pulled toward the object's (SharedSpecular) with this weight, in
  // observations of the lobe's peak; 0: free.
  double ks_prior_weight = 0;
  Vec3d ks_prior = Vec3d::Zero();
  Vec3d ambient_term = Vec3d::Zero();  // Ia⊙ka subtracted first (EstimateAmbient) or 0
  double code_offset = 0;              // added to nonzero values first (NormalOptions) or 0
  double heldout_cost = 0;             // mean per pixel, in units of t²; filled by ChooseModel
  double heldout_error = 0;            // its standard error over the pixels
  double fold_angle_deg = 0;           // mean angle between the normals the two halves chose
  // Pixels the cost was measured on: the sample's, or a share of them for a model dropped from
  // the choice early (ChooseModel), whose cost is then the leader's plus its measured excess.
  std::size_t heldout_pixels = 0;
};

// A specular lobe is a highlight only while it is clearly narrower than the diffuse term, whose
// cosine falls to half at 60° from its peak: a lobe as broad can trade places with it (the pixel
// explained by a lobe around a normal tilted half as far), and prediction cannot tell the two
// apart. So lobes are at most half as wide: a half width of 30° in the light's angle.
constexpr double kMaxLobeHalfWidthDeg = 30;

// The half width at half maximum of a lobe, in degrees of the light's direction.
double LobeHalfWidthDeg(reflectance::Lobe lobe, double shininess);
// The shininess whose lobe is kMaxLobeHalfWidthDeg wide: Phong and the foil 4.8, Blinn-Phong 19.9;
// for Oren–Nayar's term the least facet slope refined to, 0.05 rad.
double MinimumShininess(reflectance::Lobe lobe);

// The models tried: Lambert, Oren–Nayar's rough diffuse term at facet slopes 0.1 … 1.6 rad
// (factors of 2; the slope in the shininess' place), then each lobe (Phong, Blinn-Phong and the
// normal-centred foil) from its minimum shininess up in six factors of 2 (half widths 30° down to
// about 4°). With `only` set, that model's alone.
std::vector<ModelCandidate> ModelFamily(std::optional<reflectance::Lobe> only);

// Cross-validation folds over the lights: each fit sees at least this many (or all but one).
constexpr int kMinTrainingLights = 24;
// The number of folds for K lights: the fewest that leave kMinTrainingLights in each fit, at
// least 2; K (leave-one-out) for K ≤ kMinTrainingLights.
int FoldCount(int lights);
// Each light's fold: a shuffled alternation over FoldCount(lights) folds, fixed (one seed), so
// each fold spans the set — what every held-out comparison of a capture uses.
std::vector<int> LightFolds(int lights);

// The mean of a_i − b_i over the n entries (those where use[i] ≠ 0, with `use`) and its standard
// error, the entries taken as independent; {0, 0} for none. Without `b`, the mean of a itself.
// Per-light held-out costs under leave-one-out are not independent (their fits share all but one
// training light): there this error is about 1.4 times too small (bench/pixel_test_calibration).
std::pair<double, double> PairedDifference(const double* a, const double* b, std::size_t n,
                                           const double* use = nullptr);

// The factor a pixel's paired standard error (PairedDifference over its n usable lights) is
// scaled by when each fold holds out one light: √(1 + n/(n − 1)), 1.45 at 12 lights. Those n
// differences come from n fits that share n − 2 of their n − 1 training lights, so they are not
// independent, and their mean spreads more than the error that takes them as independent says.
// This is Nadeau and Bengio's correction for overlapping training sets (Machine Learning 52,
// 2003): the variance of a cross-validated mean is σ²(1/n + n_test/n_train), not σ²/n.
// bench/pixel_test_calibration checks it on captures of one pixel with random lights and noise
// (docs/benchmarks.md). With several lights per fold (more than kMinTrainingLights + 1 lights) the
// formula does not describe the case (it would give 1.73 for two folds, whose training sets are
// disjoint), and the error is taken as stated.
double LeaveOneOutErrorScale(double n);

// Each pixel overrules the object's specular model with Lambert only where Lambert's held-out
// cost is lower by more than this many standard errors of the pixel's paired per-light
// difference (PairedDifference, scaled by LeaveOneOutErrorScale under leave-one-out): the same
// one-standard-error line the object's choice draws between models that predict alike. The object's
// model was chosen on hundreds of pixels; a pixel's comparison rests on its own K lights, and a
// near tie is noise, not evidence. The seven DiLiGenT runs (means in degrees) trade along this
// line: from 0 (any lower cost) to 0.5, 1 and 2 the balls go 1.91 → 1.90 → 1.88 → 1.86 and
// harvest 17.02 → 16.80 → 16.62 → 16.45, while pot1 goes 5.68 → 5.68 → 5.71 → 5.75 and cow 6.46
// → 6.47 → 6.48 → 6.52 (their darkest pixels' near ties are better fitted by Lambert); mean of the
// seven 6.10 / 6.06 / 6.04 / 6.02.
constexpr double kPixelModelSignificance = 1;
// Where the lobe adds less than this fraction of the pixel's brightness to every observation in
// the fit to all its lights — under a photograph's noise of about 1 % — the two models are the
// same there: the pixel is Lambert's, untested.
constexpr double kNegligibleLobe = 0.01;

// `count` indices of 0 … n − 1 (all of them if n ≤ count), ascending, spread without a period:
// the golden-ratio sequence. The sample the choice scores, from the pixels in raster order: an
// even stride there can be a multiple of the row width (a whole-frame 240×240 capture sampled
// 600 pixels from 5 columns).
std::vector<std::size_t> SpreadIndices(std::size_t n, int count);

struct ModelChoiceSettings {
  PixelFitSettings fit;  // saturation, shadow threshold and ambient term of the observations
  int sample = 600;      // pixels scored (NormalOptions::model_sample)
  int search_candidates = 1000;
  int threads = 0;
  // A normal per pixel of the data (masked order) from an earlier solve: each held-out fit then
  // refines it (HeldOutFromStart) instead of searching the hemisphere first.
  const std::vector<Vec3d>* starts = nullptr;
};

// Makes `model` and `settings` the diffuse test: a Lambertian fit that censors observations
// brighter than the model by more than t as it censors darker ones (PixelFitSettings::
// censor_bright), with no ks prior and no weights by N·L, so a lobe the model may lack (or a
// reading that bends the shading) is left out rather than absorbed. The effective light
// distance (near/effective_distance.h) and the reading check (reading_check.h) ask it.
void MakeDiffuseTest(ModelCandidate& model, ModelChoiceSettings& settings);

struct ModelChoice {
  ModelCandidate chosen;
  std::vector<ModelCandidate> scored;  // every model tried, in the order tried
  std::size_t pixels = 0;              // pixels scored
  std::vector<int> fold;               // each light's fold (FoldCount); empty when not tested
  // The integer code step of the observations (IntegerCodeStep); at kMinTestedCodeStep or more
  // every model is also scored as if the images were truncated (code_offset half of it).
  double code_step = 0;
  std::string note;
  // Set when the foil (kNormalCentred) was chosen while a mirror lobe also beat Lambert beyond a
  // standard error: the best such lobe, for the plan to weigh against the foil by integrability.
  std::optional<ModelCandidate> highlight;
  // The fit's weights by N·L under the chosen model (shading_weights.h), measured by the plan
  // (PlanNormals) after the choice; empty when not measured.
  ShadingMisfit shading;
};

// Codes of 10 bits or fewer are tested for truncation: from 11 bits half a code is below 0.025 %
// of the range, under any photograph's noise.
constexpr double kMinTestedCodeStep = 1.0 / 1023;

// The choice scores each model first on every kRaceShare-th pixel of its sample and drops it
// there when its cost exceeds the lowest fully scored model's, paired over those pixels, by more
// than kRaceStandardErrors standard errors. The final choice treats models within one standard
// error of the lowest (on the whole sample, about half the share's) as ties; a model whose excess
// on a quarter of the pixels is 4 of that share's standard errors would have to fall by 3.5 of
// them to come within the tie, a chance of about 2e-4 under the normal approximation. Models are
// raced only when the share holds kRaceMinimumPixels pixels, for the standard error to mean much.
constexpr int kRaceShare = 4;
constexpr double kRaceStandardErrors = 4;
constexpr std::size_t kRaceMinimumPixels = 50;

// Throws nothing; with fewer than 6 lights (no half can be held out) the choice is Lambert.
ModelChoice ChooseModel(const PhotometricData& data, std::vector<ModelCandidate> family,
                        const ModelChoiceSettings& settings);

// Model m's held-out cost (its lobe, shininess, reading of the observations and ks prior; the
// mean and standard error set in m) on each of `pixels` (positions in data), in units of each
// pixel's t², over the folds `fold` (one per light): what ChooseModel compares models by, for
// comparing something else on the same pixels — the lights' distance. A pixel that cannot be
// fitted costs 0.
std::vector<double> PixelHeldOutCosts(const PhotometricData& data, ModelCandidate& m,
                                      const std::vector<std::size_t>& pixels,
                                      const std::vector<int>& fold,
                                      const ModelChoiceSettings& settings);

// The ambient term Ia⊙ka (RGB, image units) when it is not known. Every light adds to the
// ambient, so a pixel's darkest observation is the ambient itself wherever one light is in
// attached or cast shadow, and above it otherwise: the estimate is the 25th percentile over the
// pixels of their darkest observation per channel, right while a quarter of the pixels see one
// light from behind. Zero for a dark-room capture (DiLiGenT: a few thousandths at most).
Vec3d EstimateAmbient(const PhotometricData& data);

}  // namespace iphong::solve
