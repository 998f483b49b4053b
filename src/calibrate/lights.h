// Light calibration: the light directions (and intensities, and point-light positions) of a
// capture, from photos of a mirror sphere, of a matte sphere, or of any object whose normals are
// known; and, for captures with known directions but untrusted intensities, the intensities
// jointly with the normals (semi-calibrated photometric stereo).
//
// Frame (SPEC.md): x right, y up, z toward the camera; L is the unit vector from the surface
// toward the light. Pixel (col, row) has its centre at (col + 0.5, row + 0.5), row 0 at the top.
// Orthographic camera (the default): V = (0, 0, 1) and positions are in pixels, (x_px, −y_px, z),
// sphere centres at z = 0. Perspective camera (Intrinsics): the eye at the origin looking down −z,
// V per pixel, positions in units of the sphere radius.
//
// Mirror sphere: a highlight at the surface point with normal N means L = 2(N·V)N − V. The
// reflected directions of an orthographic mirror ball's pixels are spread evenly over the sphere
// of directions (each pixel spans 4/r² sr: the equal-area property), so the light is the
// intensity-weighted mean of the highlight pixels' reflected directions, unbiased for any
// symmetric highlight, however close to the rim.
#pragma once

#include <functional>

#include <string>
#include <vector>

#include "core/types.h"
#include "solve/normals.h"
#include "solve/photometric_data.h"

namespace iphong::calibrate {

// Pinhole intrinsics in pixels; fx = 0 is the orthographic camera.
struct Intrinsics {
  double fx = 0, fy = 0, cx = 0, cy = 0;
  bool perspective() const { return fx > 0; }
  std::string Check() const;  // "" or what is wrong
};

// One sphere's outline in the image.
struct SphereOutline {
  double center_x_px = 0, center_y_px = 0, radius_px = 0;  // the circle (orthographic view)
  double fit_rms_px = 0;         // RMS distance of the outline's points from the circle
  double visible_fraction = 1;   // of the circle's circumference inside the image
  std::vector<Vec2d> points_px;  // the outline used for the fit (pixel edges, not on the border)
};

struct SphereSearch {
  int max_spheres = 2;          // a common rig has two
  double min_radius_px = 6;     // smaller regions are specks, not spheres
  double max_rms_ratio = 0.03;  // a region further than this × r from a circle is not a sphere
  std::string Check() const;
};

// The spheres in a mask, largest first: each 8-connected region at least min_radius_px in
// radius, its outline fitted with a circle (points on the image border left out, so a clipped
// sphere is fitted to what is visible). Throws std::invalid_argument with one line: no region
// (no sphere), a region that is not round, a sphere less than half visible. Warnings: more regions
// than max_spheres, a sphere clipped by the image edge.
std::vector<SphereOutline> FindSpheres(const Mask& mask, const SphereSearch& search,
                                       std::vector<std::string>* warnings);

// Without a mask: the spheres' outlines in the photos themselves. The mean of the images (the
// sphere against its background, whatever the light) is tone-mapped (square root of the 99th
// percentile) and searched for circles (cv::HoughCircles); each is refined by fitting a circle to
// the Canny edges within a few pixels of it, which must cover 60 % of its circumference (UW's
// chrome sphere, dark and on a stand: 71 %). A second sphere is taken only with at least 0.7 of
// the first's votes and a radius within 30 % of it. Throws std::invalid_argument when no circle
// is found or its edges are not round; always warns that the sphere was found this way.
std::vector<SphereOutline> FindSpheresInImages(const std::vector<const ImageF*>& images,
                                               const SphereSearch& search,
                                               std::vector<std::string>* warnings);

// "" or why a circle given by hand cannot be a sphere in width × height images (less than half
// of it inside).
std::string CheckCircle(const SphereOutline& circle, int width, int height);

// A sphere in the camera frame. Orthographic: centre (cx, −cy, 0) and radius r in pixels.
// Perspective: the cone of rays tangent to the outline gives the centre's direction and the
// ratio distance/radius; the radius is 1.
struct SphereGeometry {
  Vec3d center_cam = Vec3d::Zero();
  double radius = 1;
  Intrinsics camera;
  SphereOutline outline;

  // The surface point seen at pixel position (x_px, y_px) (continuous, centres at +0.5): its
  // unit normal, the unit view vector there (toward the eye) and the point. False off the sphere.
  bool At(double x_px, double y_px, Vec3d* normal_cam, Vec3d* view_cam, Vec3d* point_cam) const;
  // Where a camera-frame point projects, in pixels.
  Vec2d Project(const Vec3d& point_cam) const;
};
SphereGeometry SphereFromOutline(const SphereOutline& outline, const Intrinsics& camera);

// The spheres' unit normals per pixel (3 channels, 0 elsewhere) and where they are, leaving out
// the pixels within a pixel of an outline, which mix in the background: what a matte sphere is
// calibrated from.
ImageF SphereNormalMap(const std::vector<SphereGeometry>& spheres, int width, int height,
                       Mask* on_sphere);

struct MirrorOptions {
  double threshold = 0.5;       // the highlight: pixels above this fraction of the sphere's peak
  double saturation = 1.0;      // values at or above are clipped
  double min_contrast = 4.0;    // the peak over the sphere's median: below it, no highlight
  double same_light_deg = 0.5;  // two images closer than this are reported as the same light
  int threads = 0;
  std::string Check() const;
};

struct Highlight {
  bool found = false;
  std::string problem;        // why none was found
  double x_px = 0, y_px = 0;  // intensity-weighted centre in the image
  Vec3d light_dir_cam = Vec3d::Zero();
  Vec3d point_cam = Vec3d::Zero();  // the surface point reflecting it
  double spread_deg = 0;       // the highlight's RMS radius in directions (how big the light looks)
  double uncertainty_deg = 0;  // the centre's standard error from pixel quantization
  double uncertainty_px = 0;
  int pixels = 0, saturated_pixels = 0;
  int blobs = 0;             // separate highlights at least a tenth as strong as the one taken
  Rgb energy = Rgb::Zero();  // Σ (value − the sphere's median) over the sphere
};

// A finding about one image (image ≥ 0, 0-based; other ≥ 0 for a pair) or the whole capture.
struct CalibrationNote {
  int image = -1, other = -1;
  std::string text;
};

struct MirrorCalibration {
  std::vector<SphereGeometry> spheres;
  std::vector<std::vector<Highlight>> highlights;  // [image][sphere]
  std::vector<Vec3d> light_dir_cam;                // per image (see CalibrateMirror)
  std::vector<Rgb> light_intensities;              // mean 1 per channel, or all 1
  bool intensities_measured = false;
  std::vector<Vec3d> light_position_cam;  // with two spheres and every ray pair converging
  std::vector<double> triangulation_gap;  // closest distance between the two rays, per image
  std::string positions_note;             // why there are no positions
  std::vector<CalibrationNote> warnings;
  std::vector<int> failed;  // images without a highlight on some sphere (see Highlight::problem)
  double seconds = 0;
};

// Per image and sphere the highlight; per image the direction: the spheres' mean, or, with point
// positions, the direction from the midpoint of the sphere centres toward the light. Positions
// need two spheres whose reflected rays meet (closest distance under a tenth of the distance to
// the light, and an angle between them over three times their summed uncertainties) in every
// image. Intensities: the highlights' energy (a mirror ball maps equal solid
// angles to equal areas, so the sum over the sphere is the light's irradiance) when no highlight
// pixel is clipped, else all 1 with a warning. Per-image failures are reported, not thrown.
MirrorCalibration CalibrateMirror(const std::vector<const ImageF*>& images,
                                  const std::vector<SphereGeometry>& spheres,
                                  const MirrorOptions& options);

struct KnownNormalOptions {
  bool uniform_albedo = false;  // a calibration sphere: one albedo; else one per pixel
  double saturation = 1.0;      // observations at or above are clipped and left out; at most 1,
                                // not in a pixel with values above 1 (HDR: none clipped there)
  double min_cos = 0.2;         // observations used only where N·L exceeds this (attached shadow)
  int rounds = 50;              // alternations between albedo and lights
  double tolerance = 1e-5;      // stop when no direction moves more than this (radians, 0.0006°)
  int threads = 0;
  std::string Check() const;
};

struct KnownNormalCalibration {
  std::vector<Vec3d> light_dir_cam;
  std::vector<Rgb> light_intensities;  // each channel's mean over the lights is 1
  std::vector<double> residual;        // per light: RMS relative residual of the inliers
  std::vector<int> pixels_used;        // per light
  std::vector<int> failed;  // lights no pixel is lit by (as the normals say): no direction
  int rounds = 0;
  bool converged = false;
  // The largest direction change in the last round. Alternation converges linearly: on
  // DiLiGenT ball it still moves 0.002° a round after 50 rounds, about 0.04° in all.
  double last_move_deg = 0;
  std::vector<CalibrationNote> warnings;
  double seconds = 0;
};

// Lambertian photometric stereo run backwards: I_pj = ρ_p ⊙ E_j (N_p·L_j) with the normals
// known, the albedo (per pixel, or one) and the lights unknown, by alternating least squares.
// Robust to shadows and highlights: an observation counts only where the current estimate
// predicts N·L > min_cos, it is not clipped, and Tukey's biweight (scale from the median absolute
// residual) keeps it. With an unknown albedo the lights' colour is unobservable: each channel's
// intensities are scaled to mean 1. Throws std::invalid_argument on mismatched sizes, fewer than
// 3 images or fewer than 10 pixels with a normal.
KnownNormalCalibration CalibrateFromNormals(const std::vector<const ImageF*>& images,
                                            const ImageF& normal_cam, const Mask& mask,
                                            const KnownNormalOptions& options);

struct IntensityOptions {
  double discard_dark = 0.3;    // per pixel, its darkest observations (shadows) left out
  double discard_bright = 0.1;  // and its brightest (highlights)
  int rounds = 3;
  std::size_t max_pixels = 50000;  // more are subsampled evenly: K numbers need far fewer
  // Over this median relative residual of Lambert on the kept observations, the images do not
  // follow the model the estimate assumes, and it is refused (see intensities.cc).
  double max_residual = 0.05;
  // Under this eigenvalue gap another set of intensities explains the images almost as well, and
  // what Lambert leaves unexplained decides between them; refused (see intensities.cc).
  double min_eigen_gap = 8;
  int threads = 0;
  std::string Check() const;
};

struct IntensityEstimate {
  std::vector<Rgb> light_intensities;  // each channel's mean over the lights is 1
  double eigen_gap = 0;  // second smallest over smallest eigenvalue: how well determined
  int rounds = 0;
  double lambert_residual = 0;  // median relative residual of the kept observations
  // Half a code step when the images are integer codes better explained as truncated: the
  // estimate was made on the codes at their middle (solve::AtCodeMiddle); else 0.
  double code_offset = 0;
  double seconds = 0;
};

// Semi-calibrated photometric stereo (Cho et al., TPAMI 2018): with y_pj = I_pj / E_j = L_j·m_p,
// eliminating m_p by least squares leaves Σ_p ‖P⊥_p diag(i_p) u‖² with u_j = 1/E_j, minimized by
// the smallest eigenvector of a K × K matrix, per channel, with no alternation to converge. Each
// pixel keeps its middle observations (discard_dark, discard_bright) and is weighted by how well
// Lambert explains them, 1/(r_p² + median r²), since the intensities are a per-image constant
// best measured where the model holds. Integer codes of 10 bits or fewer are taken as recorded
// and at the middle of their intervals (truncated, solve::NormalOptions::code_offset), and the
// estimate whose Lambert residual is smaller is kept (DiLiGenT's truncated 8-bit crops: cat's
// intensities 3.0 % off as recorded, 2.2 % at the middle). Uses data's directions, not its
// intensities. Throws
// std::invalid_argument when data is invalid, and when the images are too far from Lambertian
// for the estimate (no positive solution, or a residual over max_residual).
IntensityEstimate EstimateIntensities(const solve::PhotometricData& data,
                                      const IntensityOptions& options);

// The estimate's largest error per light and channel where calibrated intensities were known
// (each channel's mean 1): 6.5-7.9 % on DiLiGenT ball and cat and their crops, 3.3 % on a
// rendered bunny. An estimate within this of equal lights does not show that they differ.
inline constexpr double kEstimateLargestError = 0.08;

// What an accepted estimate is worth, measured where calibrated intensities were known
// (docs/guides/calibrating-lights.md): said wherever an estimate is made with none to compare
// against (the command line's warning, the Python docstring).
inline constexpr const char* kUncheckedEstimateNote =
    "where calibrated intensities were known, the estimate's normals were 1.2-3.7 deg from "
    "theirs (DiLiGenT ball and cat, their crops, a rendered bunny), because a fall-off or "
    "reflectance that varies with the light's direction reads as intensity and the photos cannot "
    "tell the two apart";

// Estimated intensities against given ones (a light_intensities.txt): how far apart they are,
// each scaled to mean 1 per channel (per light and channel, |estimated / given − 1|), and how far
// apart they put the normals: a run under each (`options`, its model choice made under that set),
// the mean angle over the pixels both solve — which bounds how much better or worse either run's
// mean error can be than the other's. Neither run can say which set is right;
// the normals' figure is what a user needs to hear when they disagree. `solve`, when given, is the
// caller's whole run (the effective distance's, say), so the figure compares the runs it reports;
// else solve::EstimateNormals with `options`.
struct IntensityComparison {
  double median_relative = 0, max_relative = 0;
  double normals_moved_deg = 0;
  double seconds = 0;
};
IntensityComparison CompareIntensities(
    const solve::PhotometricData& data, const std::vector<Rgb>& given,
    const std::vector<Rgb>& estimated, const solve::NormalOptions& options,
    const std::function<solve::NormalResult(const solve::PhotometricData&)>& solve = {});

// Directions from two points of view: the closest point between two rays and their gap.
Vec3d ClosestPoint(const Vec3d& origin_a, const Vec3d& dir_a, const Vec3d& origin_b,
                   const Vec3d& dir_b, double* gap);

}  // namespace iphong::calibrate
