// Which images disagree with the others, from what the solved normals predict. A light file whose
// lines are out of order, one light's direction or intensity miscalibrated, or an image taken
// after the object moved leaves the other images' normals almost where they were (the censoring
// sets the odd observations aside as if shadowed), so the normals alone do not show it. What
// shows it is how badly each image agrees with a render of the result: at pixel p the model's
// luminance kd·d_j + ks·s_j (reflectance/phong.h, at the solved normal, kd and ks of the result)
// against the observation y_j = lum((I_j + c − Ia⊙ka)/E_j), in units of the pixel's censoring
// threshold t_p (a fraction of its brightness, internal::CensoredCost):
//   m_j = median over the sample's pixels of |y_pj − model_pj| / t_p   (usable observations).
// Under a few lights one wrong image pulls the normals far enough that the others disagree
// instead (a light file's intensity off by 2 under 12 lights named three other images), so
// there the model is each pixel's refitted without image j (leave-one-out: a local fit from the
// solved normal, pixel_fit.h) that censors observations brighter than it by more than t as the
// solve censors darker ones, so that a second wrong image cannot pull it either; among more
// lights the pull is small and the solve's own model is compared.
// Images legitimately differ (oblique lights cast shadows and interreflect more), so an image is
// judged against the others by the robust modified z-score of Iglewicz and Hoaglin (1993),
//   M_j = 0.6745 · (m_j − median_i m_i) / median_i |m_i − median m|,
// and said to disagree where M_j > kImageDisagreementZ and m_j > 1: an outlier among the images
// at whose typical pixel the model misses by more than the solver's own shadow threshold.
// Camera frame; the lights as the data hold them (distant, or point lights seen from each
// pixel's point).
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "solve/normals.h"
#include "solve/photometric_data.h"

namespace iphong::solve {

// The modified z-score beyond which an image is an outlier. Iglewicz and Hoaglin's line for a
// normal population is 3.5; a capture's images have a heavier tail (the score of an image the
// model fits reaches 16 on DiLiGenT's ball, where its misfit of 0.4 keeps it unnamed), and a
// wrong image's pull gave a right one 3.5 at a misfit of 0.94 (docs/troubleshooting.md has the
// runs), so the line is drawn wider; the wrong images named scored 7 to 475.
constexpr double kImageDisagreementZ = 6;

struct ImageCheckOptions {
  std::size_t sample = 4096;  // pixels spread over the mask (every one when it has fewer)
  // The observations as the solve read them (NormalOptions' of the same names).
  double saturation = 0.995;
  double shadow_threshold = 0.1;
  // An image with fewer usable observations among the sample gets no verdict.
  std::size_t min_pixels = 30;
  // Up to this many images, each is compared with the fit to the others.
  int heldout_images = 24;
  // Known coefficients (material.json's ks; the held-out fits keep it), else ks is fitted.
  std::optional<Vec3d> known_ks;
  int threads = 0;
  // "" or what is wrong.
  std::string Validate() const;
};

struct ImageCheck {
  std::size_t pixels = 0;      // sample pixels with a solved normal
  std::vector<double> misfit;  // m_j per image; NaN without a verdict (too few observations)
  std::vector<double> score;   // M_j per image; NaN without a verdict
  std::vector<std::size_t> observations;  // usable observations per image among the sample
  double typical_misfit = 0;              // median_j m_j
  std::vector<int> disagreeing;           // the images said to disagree, ascending (0-based)
  bool heldout = false;                   // each image against the fit to the others
  double seconds = 0;
  // False with fewer than 6 images with a verdict (the spread of a handful says little), no
  // normals (one or two images: the ambiguity's prior solve) or no sample pixel.
  bool checked = false;
};

// `result` is a solve of `data` (its images' pixel grid, its model, shininess, ambient term and
// code offset). Throws std::invalid_argument on invalid options or a result of another size.
ImageCheck CheckImages(const PhotometricData& data, const NormalResult& result,
                       const ImageCheckOptions& options = {});

}  // namespace iphong::solve
