// libFuzzer: the host's mesh import (vds/enc/mesh_import.h), what `vds
// encode-mesh` does with a user's file: the project's PLY check, assimp
// (with its data-structure validation) for OBJ, PLY, glTF, GLB, Collada,
// IQM, MD2, MD3 and MS3D (checked by the project's own readers first), libdraco
// for Draco, then the repair rule. The first byte picks the format the
// file's name says; the rest is the file. Invariants: no crash, sanitizer
// report, hang or allocation beyond libFuzzer's limit; a refusal is a
// std::runtime_error naming the input; an accepted mesh has triangles whose
// indices lie inside its vertices; an MD3 the project's check accepts has
// its tags read (a Quake III player's parts are joined at them).
//
// Seed corpus: when the corpus directory is empty, small valid files are
// written to it first (an OBJ, an ASCII and a binary PLY, a glTF with its
// buffer inline, a GLB, a Draco mesh, a Collada file, an IQM file, an MD3, an
// MD2, an MS3D).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "mesh_md3_check.h"  // encoder/src: the tags a player is joined at
#include "model_seeds.h"
#include "seed_corpus.h"
#include "vds/bytes.h"
#include "vds/enc/mesh_import.h"

namespace {

const char* const kNames[] = {"input.obj", "input.ply", "input.gltf", "input.glb", "input.drc",
                              "input.3ds", "input.off", "input.dae", "input.iqm", "input.md3",
                              "input.md2", "input.ms3d"};
constexpr int kFormats = 12;  // .off: a format the tool refuses

void write(const std::filesystem::path& p, uint8_t pick, const std::string& body) {
  std::ofstream f(p, std::ios::binary);
  f.put(static_cast<char>(pick));
  f.write(body.data(), static_cast<std::streamsize>(body.size()));
}

std::string le32(uint32_t v) {
  std::string s(4, '\0');
  for (int i = 0; i < 4; ++i) s[i] = static_cast<char>(v >> (8 * i));
  return s;
}
std::string lef(float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  return le32(u);
}

void seed(const std::filesystem::path& dir) {
  write(dir / "seed_obj", 0, "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n");
  write(dir / "seed_ply_ascii", 1,
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
        "element face 4\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
        "3 0 2 1\n3 0 1 3\n3 1 2 3\n3 2 0 3\n");
  std::string ply_bin =
      "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 4\nproperty list uchar int vertex_indices\nend_header\n";
  const float v[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (const auto& p : v) ply_bin += lef(p[0]) + lef(p[1]) + lef(p[2]);
  const int f[4][3] = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {2, 0, 3}};
  for (const auto& t : f) ply_bin += std::string(1, '\3') + le32(t[0]) + le32(t[1]) + le32(t[2]);
  write(dir / "seed_ply_binary", 1, ply_bin);
  // glTF 2.0: one triangle, positions and indices in a data: URI buffer.
  std::string buf;
  const float tri[3][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  for (const auto& p : tri) buf += lef(p[0]) + lef(p[1]) + lef(p[2]);
  buf += std::string("\0\0\1\0\2\0\0\0", 8);  // uint16 indices 0 1 2 and padding
  static const char kB64[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string b64;
  for (size_t i = 0; i < buf.size(); i += 3) {
    const uint32_t n = (static_cast<uint8_t>(buf[i]) << 16) | (i + 1 < buf.size() ? static_cast<uint8_t>(buf[i + 1]) << 8 : 0) |
                       (i + 2 < buf.size() ? static_cast<uint8_t>(buf[i + 2]) : 0);
    b64 += kB64[(n >> 18) & 63];
    b64 += kB64[(n >> 12) & 63];
    b64 += i + 1 < buf.size() ? kB64[(n >> 6) & 63] : '=';
    b64 += i + 2 < buf.size() ? kB64[n & 63] : '=';
  }
  const std::string json =
      "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
      "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1}]}],"
      "\"buffers\":[{\"byteLength\":44,\"uri\":\"data:application/octet-stream;base64," + b64 + "\"}],"
      "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":36,\"byteLength\":6}],"
      "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\",\"min\":[0,0,0],\"max\":[1,1,0]},"
      "{\"bufferView\":1,\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\"}]}";
  write(dir / "seed_gltf", 2, json);
  // GLB: the same JSON with the buffer in the BIN chunk.
  std::string glb_json = json;
  const size_t at = glb_json.find(",\"uri\"");
  glb_json.erase(at, glb_json.find('}', at) - at);
  while (glb_json.size() % 4) glb_json += ' ';
  const std::string glb = "glTF" + le32(2) + le32(static_cast<uint32_t>(12 + 8 + glb_json.size() + 8 + buf.size())) +
                          le32(static_cast<uint32_t>(glb_json.size())) + "JSON" + glb_json +
                          le32(static_cast<uint32_t>(buf.size())) + std::string("BIN\0", 4) + buf;
  write(dir / "seed_glb", 3, glb);
  vds::enc::Mesh m;
  for (const auto& p : v) m.positions.push_back({p[0], p[1], p[2]});
  for (const auto& t : f) m.triangles.push_back({uint32_t(t[0]), uint32_t(t[1]), uint32_t(t[2])});
  const std::vector<uint8_t> drc = vds::enc::encode_draco(m, 11, 7);
  write(dir / "seed_drc", 4, std::string(drc.begin(), drc.end()));
  // 3DS: main chunk > editor > object "t" > triangle mesh > vertices, faces.
  auto chunk = [](uint16_t id, const std::string& body) {
    return std::string(1, static_cast<char>(id & 255)) + std::string(1, static_cast<char>(id >> 8)) +
           le32(static_cast<uint32_t>(6 + body.size())) + body;
  };
  auto le16 = [](uint16_t x) { return std::string(1, static_cast<char>(x & 255)) + std::string(1, static_cast<char>(x >> 8)); };
  std::string verts = le16(4);
  for (const auto& p : v) verts += lef(p[0]) + lef(p[1]) + lef(p[2]);
  std::string faces = le16(4);
  for (const auto& t : f) faces += le16(uint16_t(t[0])) + le16(uint16_t(t[1])) + le16(uint16_t(t[2])) + le16(0);
  const std::string mesh3ds = chunk(0x4100, chunk(0x4110, verts) + chunk(0x4120, faces));
  write(dir / "seed_3ds", 5, chunk(0x4D4D, chunk(0x0002, le32(3)) + chunk(0x3D3D, chunk(0x4000, std::string("t\0", 2) + mesh3ds))));
  write(dir / "seed_dae", 7,
        "<?xml version=\"1.0\"?><COLLADA xmlns=\"http://www.collada.org/2005/11/COLLADASchema\" version=\"1.4.1\">"
        "<library_geometries><geometry id=\"g\"><mesh><source id=\"p\"><float_array id=\"pa\" count=\"9\">0 0 0 1 0 0 0 1 0"
        "</float_array><technique_common><accessor source=\"#pa\" count=\"3\" stride=\"3\"><param name=\"X\" type=\"float\"/>"
        "<param name=\"Y\" type=\"float\"/><param name=\"Z\" type=\"float\"/></accessor></technique_common></source>"
        "<vertices id=\"v\"><input semantic=\"POSITION\" source=\"#p\"/></vertices><triangles count=\"1\">"
        "<input semantic=\"VERTEX\" source=\"#v\" offset=\"0\"/><p>0 1 2</p></triangles></mesh></geometry>"
        "</library_geometries><library_visual_scenes><visual_scene id=\"s\"><node><instance_geometry url=\"#g\"/></node>"
        "</visual_scene></library_visual_scenes><scene><instance_visual_scene url=\"#s\"/></scene></COLLADA>");
  // IQM: the header, the text, one mesh, a position array, one triangle.
  {
    std::string text("\0m\0", 3);
    const uint32_t ofs_text = 124, ofs_meshes = ofs_text + 4, ofs_va = ofs_meshes + 24, ofs_pos = ofs_va + 20,
                   ofs_tri = ofs_pos + 36, size = ofs_tri + 12;
    const uint32_t h[27] = {2, size, 0, 4, ofs_text, 1, ofs_meshes, 1, 3, ofs_va, 1, ofs_tri, 0, 0, 0, 0, 0, 0, 0,
                            0, 0, 0, 0, 0, 0, 0, 0};
    std::string iqm("INTERQUAKEMODEL\0", 16);
    for (uint32_t x : h) iqm += le32(x);
    iqm += text + std::string(1, '\0');
    for (uint32_t x : {1u, 1u, 0u, 3u, 0u, 1u}) iqm += le32(x);
    for (uint32_t x : {0u, 0u, 7u, 3u, ofs_pos}) iqm += le32(x);
    for (const auto& p : tri) iqm += lef(p[0]) + lef(p[1]) + lef(p[2]);
    iqm += le32(0) + le32(1) + le32(2);
    write(dir / "seed_iqm", 8, iqm);
  }
  // MD3: one frame, one surface of three vertices and one triangle.
  {
    auto pad = [](std::string s, size_t n) { s.resize(n, '\0'); return s; };
    const uint32_t surface_at = 108 + 56;
    std::string md3 = "IDP3" + le32(15) + pad("t", 64) + le32(0) + le32(1) + le32(0) + le32(1) + le32(0) + le32(108) +
                      le32(surface_at) + le32(surface_at) + le32(0);
    md3 += std::string(56, '\0');  // the frame
    const uint32_t tri = 108, st = tri + 12, xyz = st + 24, end = xyz + 24;
    std::string surface = "IDP3" + pad("s", 64) + le32(0) + le32(1) + le32(0) + le32(3) + le32(1) + le32(tri) +
                          le32(tri) + le32(st) + le32(xyz) + le32(end);
    surface += le32(0) + le32(1) + le32(2);
    for (int i = 0; i < 3; ++i) surface += lef(i == 1 ? 1.0f : 0.0f) + lef(i == 2 ? 1.0f : 0.0f);
    const int16_t xyzs[3][4] = {{0, 0, 0, 0}, {64, 0, 0, 0}, {0, 64, 0, 0}};
    for (const auto& v : xyzs)
      for (int16_t c : v) surface += std::string(1, static_cast<char>(c & 255)) + std::string(1, static_cast<char>((c >> 8) & 255));
    md3 += surface;
    const uint32_t eof = static_cast<uint32_t>(md3.size());
    md3.replace(104, 4, le32(eof));
    write(dir / "seed_md3", 9, md3);
  }
  write(dir / "seed_md2", 10, vds::test::md2_seed());
  write(dir / "seed_ms3d", 11, vds::test::ms3d_seed());
  write(dir / "seed_off", 6, "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 2 0 3\n");
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  vds::test::seed_corpus_if_empty(*argc, *argv, seed);
  return 0;
}

// An MD3 the check accepts: its tags (what a player's parts are joined at)
// read at its first and last frame, finite or refused by name.
void md3_tags(const uint8_t* data, size_t size, const char* name) {
  try {
    vds::enc::check_md3(data, size, name);
    const uint32_t frames = vds::load_le32(data + 76);
    for (const char* tag : {"tag_torso", "tag_head"})
      for (uint32_t f : {0u, frames == 0 ? 0u : frames - 1}) {
        vds::enc::Md3Tag t;
        if (!vds::enc::md3_tag(data, size, name, tag, f, &t)) continue;
        for (int c = 0; c < 3; ++c)
          if (!std::isfinite(t.origin[c]) || !std::isfinite(t.axis[c][0]) || !std::isfinite(t.axis[c][1]) ||
              !std::isfinite(t.axis[c][2]))
            abort();
      }
  } catch (const std::runtime_error& e) {
    if (std::strncmp(e.what(), name, std::strlen(name)) != 0) abort();
  }
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const char* name = kNames[data[0] % kFormats];
  if (std::strcmp(name, "input.md3") == 0) md3_tags(data + 1, size - 1, name);
  try {
    const vds::enc::Mesh raw = vds::enc::load_mesh_bytes(data + 1, size - 1, name);
    for (const auto& t : raw.triangles)
      for (uint32_t i : t)
        if (i >= raw.positions.size()) abort();
    const vds::enc::Mesh fixed = vds::enc::repair_mesh(raw);
    for (const auto& t : fixed.triangles)
      for (uint32_t i : t)
        if (i >= fixed.positions.size()) abort();
  } catch (const std::runtime_error& e) {
    if (std::strncmp(e.what(), name, std::strlen(name)) != 0) abort();  // the refusal names the input
  }
  return 0;
}
