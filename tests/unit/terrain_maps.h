// A small synthetic terrain for the terrain tests: a 97 x 81 heightmap of
// rolling hills and a 192 x 160 colour map of stripes, ramps and checks.
#pragma once
#include <cmath>

#include "vds/enc/terrain_map.h"
#include "vds/io/image.h"

namespace vds::test {

inline enc::TerrainMap terrain_test_map() {
  enc::TerrainMap m;
  m.name = "test";
  m.width = 97;
  m.height = 81;
  m.horizontal_scale = 2;
  m.metres_per_unit = 0.05;
  m.heights.resize(static_cast<size_t>(m.width) * m.height);
  for (int y = 0; y < m.height; ++y)
    for (int x = 0; x < m.width; ++x)
      m.heights[static_cast<size_t>(y) * m.width + x] =
          static_cast<uint16_t>(600 + 300 * std::sin(x * 0.08) + 250 * std::cos(y * 0.11 + x * 0.03));
  m.colour = io::Image(192, 160, 3);
  for (int y = 0; y < 160; ++y)
    for (int x = 0; x < 192; ++x) {
      m.colour.at(x, y, 0) = static_cast<uint8_t>(128 + 100 * std::sin(x * 0.3) * std::cos(y * 0.2));
      m.colour.at(x, y, 1) = static_cast<uint8_t>((x * 3 + y) & 255);
      m.colour.at(x, y, 2) = static_cast<uint8_t>(((x / 6 + y / 6) & 1) ? 200 : 40);
    }
  return m;
}

}  // namespace vds::test
