// A capture read a band of rows at a time from its K files, for captures whose observations do
// not fit in memory (solve/bands.h). Each band goes through exactly what LoadObservations does
// to whole images — channels to RGB, --crop, the clipped and black counts, sRGB linearization,
// --downscale — so the observations are bit for bit the same.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "io/dataset.h"
#include "io/image_rows.h"
#include "solve/photometric_data.h"

namespace iphong::io {

class CaptureBands {
 public:
  // Finds and checks the capture as LoadDataset does (the first image's header, the mask); reads
  // no pixels and no ground truth. Every other image's header is checked by the first ReadBand.
  // Throws as LoadDataset.
  CaptureBands(const std::string& directory, const DatasetLoadOptions& options);
  ~CaptureBands();

  const Dataset& dataset() const;  // images empty; image_counts filled by counted reads
  int width() const;
  int height() const;
  // Memory a band holds per row of the working size while it is read and gathered, and beside
  // it (the mask, the readers).
  double BytesPerRow() const;
  double FixedBytes() const;

  // The observations of working rows [y0, y1), pixel indices within the band. `count` adds the
  // band's clipped and black pixels to dataset().image_counts (once per pass over the capture).
  // Throws std::runtime_error naming the file and the rows that fail to decode.
  solve::PhotometricData ReadBand(int y0, int y1, bool count);

 private:
  struct State;
  void OpenReaders();  // every image's header, on the first ReadBand
  std::unique_ptr<State> state_;
};

}  // namespace iphong::io
