// Small valid Quake II (MD2) and MilkShape 3D (MS3D) models for the seed
// corpora of the model importer fuzzers (fuzz_mesh_import, fuzz_mesh_colors):
// one triangle each, built here rather than carried.
#pragma once
#include <cstdint>
#include <cstring>
#include <string>

namespace vds::test {

inline std::string le_bytes(uint32_t v, int n) {
  std::string s(static_cast<size_t>(n), '\0');
  for (int i = 0; i < n; ++i) s[static_cast<size_t>(i)] = static_cast<char>(v >> (8 * i));
  return s;
}
inline std::string le_float(float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  return le_bytes(u, 4);
}

// MD2: a skin name, three texture coordinates, one triangle, one frame of
// three vertices, one GL command word (the end of the list).
inline std::string md2_seed() {
  const uint32_t skins = 68, st = skins + 64, tris = st + 12, frames = tris + 12, frame = 40 + 3 * 4, gl = frames + frame,
                 end = gl + 4;
  std::string m = "IDP2" + le_bytes(8, 4) + le_bytes(64, 4) + le_bytes(64, 4) + le_bytes(frame, 4);
  for (uint32_t v : {1u, 3u, 3u, 1u, 1u, 1u, skins, st, tris, frames, gl, end}) m += le_bytes(v, 4);
  std::string skin = "skin.png";
  skin.resize(64, '\0');
  m += skin;
  for (uint32_t v : {0u, 0u, 63u, 0u, 0u, 63u}) m += le_bytes(v, 2);
  for (uint32_t v : {0u, 1u, 2u, 0u, 1u, 2u}) m += le_bytes(v, 2);
  for (float f : {1.0f, 1.0f, 1.0f, 0.0f, 0.0f, 0.0f}) m += le_float(f);
  std::string name = "frame";
  name.resize(16, '\0');
  m += name;
  for (uint32_t v : {0u, 0u, 0u, 0u, 100u, 0u, 0u, 0u, 0u, 100u, 0u, 0u}) m += le_bytes(v, 1);
  return m + le_bytes(0, 4);
}

// MS3D: three vertices, one triangle, one group without a material, no
// joints, then the optional comments, vertex weights, joint colours and
// model extra.
inline std::string ms3d_seed() {
  std::string m = "MS3D000000" + le_bytes(4, 4) + le_bytes(3, 2);
  const float p[3][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  for (const auto& v : p) m += le_bytes(0, 1) + le_float(v[0]) + le_float(v[1]) + le_float(v[2]) + le_bytes(0xFF, 1) + le_bytes(0, 1);
  m += le_bytes(1, 2) + le_bytes(0, 2) + le_bytes(0, 2) + le_bytes(1, 2) + le_bytes(2, 2);
  for (int k = 0; k < 9; ++k) m += le_float(k % 3 == 2 ? 1.0f : 0.0f);
  for (float f : {0.0f, 1.0f, 0.0f, 0.0f, 0.0f, 1.0f}) m += le_float(f);
  m += le_bytes(1, 1) + le_bytes(0, 1);
  m += le_bytes(1, 2) + le_bytes(0, 1) + std::string(32, 'g') + le_bytes(1, 2) + le_bytes(0, 2) + le_bytes(0xFF, 1);
  m += le_bytes(0, 2) + le_float(24) + le_float(0) + le_bytes(1, 4) + le_bytes(0, 2);
  m += le_bytes(1, 4) + le_bytes(0, 4) + le_bytes(0, 4) + le_bytes(0, 4) + le_bytes(0, 4);  // comments
  m += le_bytes(1, 4) + std::string(3 * 6, '\0');                                          // vertex weights
  m += le_bytes(1, 4);                                                                     // joint colours
  m += le_bytes(1, 4) + std::string(12, '\0');                                             // model extra
  return m;
}

}  // namespace vds::test
