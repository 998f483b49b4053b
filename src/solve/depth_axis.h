// Which axis of a light file points toward the camera, from what the photos say. Woodham's least
// squares is equivariant under any orthogonal change of the lights' frame: its observations are
// chosen by their values, not by their lights, so lights read in a frame T (l' = Tᵀl) give the
// normals Tᵀn. A visible surface faces the camera, so under the right frame the unconstrained
// least-squares normals have n_z > 0 almost everywhere; a file whose depth axis is its x or y (a
// dome described with z up, its y toward the camera) gives normals of which about half face away.
// The shares measured on real captures as given and with their axes exchanged:
// docs/troubleshooting.md. The readings that keep z (y down, x mirrored, x and y swapped)
// are the normal field's frame check (integrate/frame_check.h); z negated is said by the light
// file's own check (most lights behind the object).
#pragma once

#include <cstddef>
#include <string>

#include "solve/photometric_data.h"

namespace iphong::solve {

struct DepthAxisCheck {
  std::size_t pixels = 0;  // pixels with a least-squares normal (the spread sample's)
  double facing_away = 0;  // their fraction with n_z < 0, as given
  int best_axis = 2;       // 0 x, 1 y, 2 z: the file's axis the normals face along most
  int best_sign = 1;       // ±1: which way along it
  double best_facing = 0;  // the fraction facing away from that axis (0 when none is better)
  // Empty unless another axis is clearly the depth axis: at least kDepthAxisShare of the normals
  // face away as given and at most a fifth as many away from the other axis. One sentence then,
  // e.g. "Woodham's normals face away from the camera at 50% of 20000 pixels; with the lights' y
  // as the depth axis (toward the camera) at 0.0%".
  std::string message;

  std::string BestAxisName() const {  // "x", "-y", "z", …
    return std::string(best_sign < 0 ? "-" : "") + "xyz"[best_axis];
  }
};
constexpr double kDepthAxisShare = 0.2;

// The counts behind a check, added up over pieces of a capture (bands of rows): a pixel's
// normal depends on its own observations only.
class DepthAxisCounts {
 public:
  // Woodham (woodham.h, its default discards) on every `stride`-th masked pixel of `data`.
  // Distant lights only (near data adds nothing).
  void Add(const PhotometricData& data, std::size_t stride = 1);
  DepthAxisCheck Result() const;

 private:
  std::size_t pixels_ = 0;
  std::size_t away_[3][2] = {{0, 0}, {0, 0}, {0, 0}};  // normals with s·n_a < 0, s = +1, −1
};

// Woodham on up to `sample` masked pixels spread over the capture (every one when it has fewer).
DepthAxisCheck CheckDepthAxis(const PhotometricData& data, std::size_t sample = 20000);

}  // namespace iphong::solve
