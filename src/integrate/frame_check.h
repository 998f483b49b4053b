// Which reading of a normal field's x and y axes makes it the normals of a surface.
//
// A light file in another image-plane frame — y down as image rows count, x mirrored, x and y
// swapped — is the commonest slip in hand-made and RTI-derived light files, and a normal map
// from another tool can be in such a frame too. If the true lights are l = T l' for the file's
// l', where T is one of the eight reflections and rotations of the xy plane (the dihedral group:
// it fixes z, so the view (0, 0, 1) too), then every shading the model predicts satisfies
// l'·n' = l·n with n' = Tᵀn: the solve with the file returns Tᵀ times the true normals, whatever
// the model (Woodham's exactly; the default's search samples the sphere unevenly, 0.18° mean
// apart on DiLiGenT ball), and reading the result with T recovers them. So the readings are
// checked on the recovered field without solving again. Two cues, both from geometry, not from the
// photos:
//  - the silhouette: where the mask's edge is an occluding contour the normal lies in the image
//    plane and points outward. Over the edge pixels whose normal is steep (|n_xy| ≥ 0.5) the mean
//    cosine between n_xy and the mask's outward direction is near 1 for the right reading
//    (0.77–0.97 on DiLiGenT and UW objects) and near 0 for a flip or swap, −1 for a half turn.
//    Edge pixels on the image border are a crop, not a contour, and are left out.
//  - integrability: the mean angle between the field and the normals of the surface integrated
//    from it by least squares (on a copy averaged down to at most `max_side` pixels a side). A
//    right field's non-integrable part is its estimation error; a flipped or swapped field adds
//    the surface's mixed second derivatives (a half turn is the same surface upside down, with
//    the same figure: only the silhouette tells it).
// Pixel convention: row 0 is the top row; the camera frame has y up, so a pixel's outward step
// (Δcol, Δrow) is the direction (Δcol, −Δrow).
#pragma once

#include <string>
#include <vector>

#include "core/types.h"

namespace iphong::integrate {

// n → T n for the eight T that fix z.
enum class PlaneReading {
  kAsGiven,
  kYNegated,
  kXNegated,
  kXYNegated,  // a half turn
  kSwapped,    // x ↔ y
  kSwappedNegated,
  kRotated90,   // (x, y) → (−y, x)
  kRotated270,  // (x, y) → (y, −x)
};
constexpr int kPlaneReadings = 8;

// "as given", "y negated", "x negated", "x and y negated", "x and y swapped",
// "x and y swapped and negated", "x and y turned 90 degrees", "x and y turned 270 degrees".
const char* PlaneReadingName(PlaneReading reading);
Vec3f ApplyReading(PlaneReading reading, const Vec3f& v);
Vec3d ApplyReading(PlaneReading reading, const Vec3d& v);

struct FrameCheckOptions {
  int max_side = 256;  // the integrability cue's field is averaged down to this
  // Edge pixels with a steep normal the silhouette cue needs before it speaks.
  int min_silhouette_pixels = 32;
  // A reading is clearly better when its silhouette cosine is this much higher (and at least
  // this high) with no worse integrability, or, with no usable silhouette, when the field read as
  // given is this many times further from its surface. On eight real objects' recovered normals
  // every wrong reading was ≥ 0.62 lower in cosine, and ≥ 1.31 times further from its surface on
  // a silhouette-free crop of each (docs/troubleshooting.md).
  double silhouette_margin = 0.5;
  double integrability_ratio = 1.3;
  int threads = 0;

  std::string Validate() const;
};

struct FrameReadingScore {
  PlaneReading reading = PlaneReading::kAsGiven;
  double silhouette_cos = 0;   // NaN without enough steep edge pixels
  double consistency_deg = 0;  // mean angle to the integrated surface's normals
};

struct FrameCheckResult {
  std::vector<FrameReadingScore> scores;         // one per PlaneReading, in enum order
  std::size_t silhouette_pixels = 0;             // steep edge pixels the silhouette cue used
  PlaneReading better = PlaneReading::kAsGiven;  // kAsGiven unless another is clearly better
  // Empty when the field reads right as given; else one sentence with the reading and the
  // figures, e.g. "read with y negated ... (silhouette 0.91 against 0.05; 5.8 deg from a
  // surface against 19.8)".
  std::string message;
};

// A normal field averaged over factor × factor blocks, fed a band of rows at a time (captures
// solved in bands) or whole: a block is kept when at least half its pixels hold a normal, and its
// normal is the normalized mean of their unit normals. CheckNormalFrame integrates such a field.
class NormalBlockAverage {
 public:
  NormalBlockAverage(int width, int height, int factor);
  // Rows [y0, y0 + rows.height) of the field; `usable` (the same rows) says which pixels hold a
  // normal (zero normals are left out too).
  void AddRows(int y0, const ImageF& rows, const Mask& usable);
  // The averaged field (3 channels, 0 where a block is not kept) and the kept blocks.
  void Result(ImageF* field, Mask* kept) const;

 private:
  int width_, height_, factor_, blocks_w_, blocks_h_;
  std::vector<double> sum_;       // 3 per block
  std::vector<int> used_, seen_;  // pixels with a normal, pixels, per block
};

// The mean angle (degrees) between a field (unit normals, a pixel per unit, orthographic) and the
// normals of the surface integrated from it by least squares (quadratic, back-facing allowed):
// zero for the normals of a surface, the estimation error's non-integrable part otherwise. NaN
// when no pixel has a neighbour.
double IntegrabilityDeg(const ImageF& normals_cam, const Mask& mask, int threads = 0);

// Throws std::invalid_argument when sizes differ or the mask holds a non-finite normal. Normals
// need not be unit (they are normalized); zero normals are left out.
FrameCheckResult CheckNormalFrame(const ImageF& normals_cam, const Mask& mask,
                                  const FrameCheckOptions& options = {});

}  // namespace iphong::integrate
