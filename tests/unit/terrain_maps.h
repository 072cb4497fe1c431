// A small synthetic terrain for the terrain tests: a 97 x 81 heightmap of
// rolling hills and a 192 x 160 colour map of stripes, ramps and checks;
// a circular flight over any map and a small client for streams over it.
#pragma once
#include <cmath>

#include "vds/enc/terrain_map.h"
#include "vds/enc/terrain_stream.h"
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

// A lap round the map's centre at `altitude` metres (or, with altitude 0,
// rising and falling between 70 and 110 m), looking 30 degrees down.
inline enc::CameraPath terrain_test_flight(const enc::TerrainCoding& t, int frames, double altitude = 0) {
  constexpr double kPi = 3.14159265358979323846;
  enc::CameraPath path;
  path.hfov_deg = 70;
  path.fps = 20;
  const double w = t.grid.cells_x * t.cell_m, d = t.grid.cells_y * t.cell_m;
  for (int f = 0; f < frames; ++f) {
    const double a = 2 * kPi * f / frames;
    enc::CameraPose p;
    p.x = w * (0.5 + 0.3 * std::cos(a));
    p.y = d * (0.5 + 0.3 * std::sin(a));
    p.z = altitude != 0 ? altitude : 70 + 40 * std::sin(a) * std::sin(a);
    p.yaw_deg = std::fmod(a * 180 / kPi + 90 + 360, 360);
    p.pitch_deg = -30;
    path.frames.push_back(p);
  }
  return path;
}

// A small client: 96 x 64 frames, a 12,000-byte store, small caches.
inline enc::TerrainStreamOptions terrain_test_client(double rate_bytes_per_s) {
  enc::TerrainStreamOptions o;
  o.width = 96;
  o.height = 64;
  o.store_units = 6000;
  o.cache_log2 = 3;
  o.max_cells = 24;
  o.link.rate_bytes_per_s = rate_bytes_per_s;
  return o;
}

}  // namespace vds::test
