// What an ICC profile embedded in a picture (TIFF, PNG's iCCP, JPEG) says of how its values
// encode light: the tone reproduction curve of its first channel (rTRC, or kTRC for a grey
// profile), which maps the stored value x in [0, 1] to linear light y. ICC.1:2010 §10.6 'curv'
// (identity, a gamma, or a sampled table) and §10.18 'para' (parametric types 0–4) are read; a
// profile without such a curve (a LUT-based one) says nothing here. The curve is linear when
// y(x) is within 0.01 of x at x = 0.2 and 0.5, and display-encoded (sRGB-like) when y(0.5) is
// what a gamma between 1.6 and 3 gives; anything else says nothing. Raw developers export linear
// TIFFs with a linear profile (darktable's "linear Rec709/Rec2020", RawTherapee's "…_g1.0"), and
// display ones with sRGB, Adobe RGB (gamma 2.2) or ProPhoto (1.8) profiles.
#pragma once

#include <cstddef>
#include <string>

namespace iphong::io {

struct IccTransfer {
  bool found = false;     // a curve was read and is one of the two kinds
  bool linear = false;    // … linear (else display-encoded)
  double gamma = 1;       // log y(0.5) / log 0.5
  std::string statement;  // "ICC profile, linear" or "ICC profile, gamma 2.2"
};

// `size` bytes of a profile as stored; malformed or truncated profiles say nothing (found false).
IccTransfer ReadIccTransfer(const unsigned char* profile, std::size_t size);

}  // namespace iphong::io
