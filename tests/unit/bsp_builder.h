// A small Quake III BSP (IBSP 46) built in memory for the scene tests and
// the BSP fuzzer's seed: a room of polygon faces, a mesh face, a 3x3 patch
// (one biquadratic piece) and a billboard, two textures (one sky), one
// lightmap, and entities with two spawn points. Lumps not used by the
// reader are empty.
#pragma once
#include <array>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace vds::test {

struct BspBuilder {
  struct Vertex {
    float pos[3], uv[2], lm[2], normal[3];
    uint8_t color[4];
  };
  struct Face {
    int32_t texture, type, vertex, n_vertices, meshvert, n_meshverts, lightmap, size[2];
  };
  std::string entities =
      "{\n\"classname\" \"worldspawn\"\n}\n{\n\"classname\" \"info_player_deathmatch\"\n\"origin\" \"16 32 24\"\n"
      "\"angle\" \"90\"\n}\n{\n\"classname\" \"info_player_start\"\n\"origin\" \"-8 0 24\"\n}\n";
  std::vector<std::pair<std::string, std::array<uint32_t, 2>>> textures = {{"textures/base_wall/concrete", {0, 1}},
                                                                           {"textures/skies/sky", {0x4, 1}}};
  std::vector<Vertex> vertices;
  std::vector<int32_t> meshverts;
  std::vector<Face> faces;
  int lightmaps = 1;

  BspBuilder() {
    // A quad (polygon, fan of 4 vertices as 2 triangles by mesh vertices).
    add_quad(0, {0, 0, 0}, {64, 0, 0}, {64, 64, 0}, {0, 64, 0}, 1, 0);
    add_quad(1, {0, 0, 64}, {0, 64, 64}, {64, 64, 64}, {64, 0, 64}, 1, -3);
    add_quad(0, {0, 0, 0}, {0, 0, 64}, {64, 0, 64}, {64, 0, 0}, 3, 0);
    // A 3x3 patch: a bump of height 32 over a 64 x 64 square.
    const int32_t first = static_cast<int32_t>(vertices.size());
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i)
        vertices.push_back(v(32.f * i, 32.f * j, (i == 1 && j == 1) ? 32.f : 0.f));
    faces.push_back({0, 2, first, 9, 0, 0, 0, {3, 3}});
    // A billboard.
    faces.push_back({0, 4, first, 1, 0, 0, -1, {0, 0}});
  }

  static Vertex v(float x, float y, float z) {
    Vertex r{};
    r.pos[0] = x, r.pos[1] = y, r.pos[2] = z;
    r.uv[0] = x / 64, r.uv[1] = y / 64;
    r.lm[0] = x / 128, r.lm[1] = y / 128;
    r.normal[2] = 1;
    r.color[0] = r.color[1] = r.color[2] = r.color[3] = 255;
    return r;
  }

  void add_quad(int32_t texture, std::array<float, 3> a, std::array<float, 3> b, std::array<float, 3> c,
                std::array<float, 3> d, int32_t type, int32_t lightmap) {
    const int32_t first = static_cast<int32_t>(vertices.size()), mv = static_cast<int32_t>(meshverts.size());
    for (const auto& p : {a, b, c, d}) vertices.push_back(v(p[0], p[1], p[2]));
    meshverts.insert(meshverts.end(), {0, 1, 2, 0, 2, 3});
    faces.push_back({texture, type, first, 4, mv, 6, lightmap, {0, 0}});
  }

  std::vector<uint8_t> build() const {
    std::vector<std::vector<uint8_t>> lumps(17);
    auto put = [](std::vector<uint8_t>& o, const void* p, size_t n) {
      o.insert(o.end(), static_cast<const uint8_t*>(p), static_cast<const uint8_t*>(p) + n);
    };
    lumps[0].assign(entities.begin(), entities.end());
    lumps[0].push_back(0);
    for (const auto& [name, fc] : textures) {
      char n[64] = {};
      std::memcpy(n, name.data(), name.size() < 63 ? name.size() : 63);
      put(lumps[1], n, 64);
      put(lumps[1], fc.data(), 8);
    }
    // One model, the world, with every face.
    float bounds[6] = {0, 0, 0, 64, 64, 64};
    put(lumps[7], bounds, 24);
    const int32_t model[4] = {0, static_cast<int32_t>(faces.size()), 0, 0};
    put(lumps[7], model, 16);
    for (const Vertex& x : vertices) {
      put(lumps[10], x.pos, 12), put(lumps[10], x.uv, 8), put(lumps[10], x.lm, 8), put(lumps[10], x.normal, 12);
      put(lumps[10], x.color, 4);
    }
    put(lumps[11], meshverts.data(), meshverts.size() * 4);
    for (const Face& f : faces) {
      const int32_t head[8] = {f.texture, -1, f.type, f.vertex, f.n_vertices, f.meshvert, f.n_meshverts, f.lightmap};
      put(lumps[13], head, 32);
      const uint8_t zero[64] = {};
      put(lumps[13], zero, 64);  // lightmap placement and size, origin, vectors, normal
      put(lumps[13], f.size, 8);
    }
    lumps[14].assign(static_cast<size_t>(lightmaps) * 128 * 128 * 3, 200);
    std::vector<uint8_t> out = {'I', 'B', 'S', 'P', 46, 0, 0, 0};
    out.resize(8 + 17 * 8);
    for (int l = 0; l < 17; ++l) {
      while (out.size() % 4) out.push_back(0);
      const uint32_t off = static_cast<uint32_t>(out.size()), len = static_cast<uint32_t>(lumps[l].size());
      std::memcpy(&out[8 + 8 * l], &off, 4);
      std::memcpy(&out[12 + 8 * l], &len, 4);
      out.insert(out.end(), lumps[l].begin(), lumps[l].end());
    }
    return out;
  }
};

}  // namespace vds::test
