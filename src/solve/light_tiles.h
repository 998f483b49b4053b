// Near lights and the global search. The search (search.h) tabulates the model's factors of its
// candidate normals once for a set of light directions; under near lights every pixel sees its
// own directions L_j(X) (photometric_data.h). Pixels whose directions all lie within a tolerance
// of one set share that set's table: the table only places the search's start, and the local fit
// (pixel_fit.h) then uses the pixel's own lights exactly. A start that far off still lies in the
// right basin as long as it puts a highlight within half its lobe's half width.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

#include "core/parallel.h"
#include "core/types.h"
#include "reflectance/phong.h"
#include "solve/photometric_data.h"

namespace iphong::solve {

struct LightTile {
  std::vector<std::size_t> pixels;      // positions in the data's masked-pixel order
  std::vector<Vec3d> light_directions;  // K, unit, from the pixels' mean surface point
};

// How far a table's directions may be from a pixel's: half the lobe's half width in the light's
// angle, at least 1° (the candidates are 4.5° apart: finer buys nothing) and at most 8° (a
// Lambertian pixel's cost has one broad basin, but shadows' edges move with the light).
double TileToleranceDeg(reflectance::Lobe lobe, double shininess);

// Distant lights: one tile of `pixels` (every pixel when null) with the shared directions. Near
// lights: a quadtree over the image, each square split until every light's direction at each of
// its pixels' surface points is within tolerance_deg of its direction at their mean point.
std::vector<LightTile> MakeLightTiles(const PhotometricData& data, double tolerance_deg,
                                      const std::vector<std::size_t>* pixels = nullptr);

// Calls body(tile, tables, begin, end) for chunks [begin, end) of at most `chunk` of each tile's
// pixel list, from up to `threads` threads; a tile's tables are made (make(tile), once) when its
// first chunk starts and released after its last, so only the tiles in progress hold tables.
// make and body must not throw.
template <typename Make, typename Body>
void ForEachTileChunk(const std::vector<LightTile>& tiles, std::size_t chunk, int threads,
                      Make make, Body body) {
  using Tables = decltype(make(std::size_t{}));
  struct Slot {
    std::once_flag once;
    std::shared_ptr<const Tables> tables;
    std::mutex mutex;
    std::size_t left = 0;
  };
  chunk = std::max<std::size_t>(chunk, 1);
  std::vector<std::pair<std::size_t, std::size_t>> chunks;  // (tile, first pixel)
  std::unique_ptr<Slot[]> slots(new Slot[tiles.size()]);
  for (std::size_t t = 0; t < tiles.size(); ++t) {
    for (std::size_t b = 0; b < tiles[t].pixels.size(); b += chunk) {
      chunks.emplace_back(t, b);
      ++slots[t].left;
    }
  }
  ParallelFor(0, chunks.size(), 1, threads, [&](std::size_t first, std::size_t last) {
    for (std::size_t c = first; c < last; ++c) {
      const auto [t, b] = chunks[c];
      Slot& slot = slots[t];
      std::call_once(slot.once, [&] { slot.tables = std::make_shared<const Tables>(make(t)); });
      std::shared_ptr<const Tables> tables;
      {
        std::lock_guard<std::mutex> lock(slot.mutex);
        tables = slot.tables;
      }
      body(t, *tables, b, std::min(tiles[t].pixels.size(), b + chunk));
      std::lock_guard<std::mutex> lock(slot.mutex);
      if (--slot.left == 0) slot.tables.reset();
    }
  });
}

}  // namespace iphong::solve
