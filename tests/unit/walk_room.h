// A small walkthrough scene built in code for the walkthrough stream's
// tests and fuzzer: a room of 512 x 512 x 256 units, each wall a 4 x 4
// grid of quads in vertex colours, and a camera path that turns and moves
// inside it.
#pragma once
#include <array>
#include <cmath>
#include <cstdint>

#include "vds/enc/camera_path.h"
#include "vds/enc/scene.h"

namespace vds::test {

inline vds::enc::Scene walk_room() {
  vds::enc::Scene s;
  s.name = "room";
  vds::enc::SceneTexture t;
  t.name = "colours";
  t.vertex_colour = true;
  s.textures.push_back(t);
  s.overbright = false;
  // Walls: origin corner, two edge vectors (4 quads along each), inward normal.
  struct Wall {
    std::array<float, 3> o, u, v, n;
  };
  const Wall walls[] = {{{-256, -256, 0}, {512, 0, 0}, {0, 512, 0}, {0, 0, 1}},     // floor
                        {{-256, -256, 256}, {0, 512, 0}, {512, 0, 0}, {0, 0, -1}},  // ceiling
                        {{-256, -256, 0}, {0, 0, 256}, {512, 0, 0}, {0, 1, 0}},     // y = -256
                        {{-256, 256, 0}, {512, 0, 0}, {0, 0, 256}, {0, -1, 0}},     // y = 256
                        {{-256, -256, 0}, {0, 512, 0}, {0, 0, 256}, {1, 0, 0}},     // x = -256
                        {{256, -256, 0}, {0, 0, 256}, {0, 512, 0}, {-1, 0, 0}}};    // x = 256
  uint32_t k = 0;
  for (const Wall& w : walls) {
    vds::enc::SceneSurface f;
    f.texture = 0;
    f.first_index = static_cast<uint32_t>(s.indices.size());
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 4; ++i) {
        const uint32_t base = static_cast<uint32_t>(s.vertices.size());
        for (int c = 0; c < 4; ++c) {
          const float a = (i + (c == 1 || c == 2)) / 4.0f, b = (j + (c >= 2)) / 4.0f;
          vds::enc::SceneVertex v;
          for (int d = 0; d < 3; ++d) v.pos[static_cast<size_t>(d)] = w.o[static_cast<size_t>(d)] + a * w.u[static_cast<size_t>(d)] + b * w.v[static_cast<size_t>(d)];
          v.normal = w.n;
          ++k;
          v.color = {static_cast<uint8_t>(60 + (k * 37) % 190), static_cast<uint8_t>(60 + (k * 91) % 190),
                     static_cast<uint8_t>(60 + (k * 53) % 190), 255};
          s.vertices.push_back(v);
        }
        for (uint32_t q : {0u, 1u, 2u, 0u, 2u, 3u}) s.indices.push_back(base + q);
      }
    f.index_count = static_cast<uint32_t>(s.indices.size()) - f.first_index;
    s.surfaces.push_back(f);
  }
  s.min = {-256, -256, 0};
  s.max = {256, 256, 256};
  return s;
}

// `frames` frames at 20 frames/s: a slow turn while moving across the room.
inline vds::enc::CameraPath walk_room_path(size_t frames) {
  vds::enc::CameraPath p;
  for (size_t f = 0; f < frames; ++f) {
    const double t = static_cast<double>(f) / 20;
    p.frames.push_back({-120 + 40 * t, -60 + 25 * t, 100 + 5 * std::sin(t), std::fmod(30 + 45 * t, 360.0), 5 * std::sin(t * 2)});
  }
  return p;
}

}  // namespace vds::test
