// vds encoder: the MD2 check (mesh_md2_check.h).
#include "mesh_md2_check.h"

#include <cstring>
#include <string>

#include "binary_check.h"
#include "vds/bytes.h"

namespace vds::enc {
namespace {

constexpr size_t kHeaderBytes = 68;
constexpr uint32_t kMaxSkins = 32, kMaxVerts = 2048, kMaxTriangles = 4096, kMaxFrames = 512, kMaxSkinSide = 4096;
constexpr uint32_t kFrameHeaderBytes = 40;

// `count` items of `item` bytes at the offset stored at `at`: after the
// header and inside the file.
size_t table(const uint8_t* d, size_t size, size_t at, uint64_t count, uint64_t item, const char* what, const std::string& name) {
  return table_in_file(d, size, 0, at, count, item, static_cast<int64_t>(kHeaderBytes), what, name);
}

}  // namespace

void check_md2(const uint8_t* d, size_t size, const std::string& name) {
  if (size < kHeaderBytes || std::memcmp(d, "IDP2", 4) != 0)
    refuse_at_byte(name, "not a Quake II model (it must start with 'IDP2' and hold a 68-byte header)", 0);
  if (load_le32(d + 4) != 8) refuse_at_byte(name, "MD2 version " + std::to_string(load_le32s(d + 4)) + " (8 is read)", 4);
  const uint32_t skins = field_in(d, 20, 0, kMaxSkins, "skins", name);
  const uint32_t verts = field_in(d, 24, 1, kMaxVerts, "vertices", name);
  const uint32_t sts = field_in(d, 28, 0, 3 * kMaxTriangles, "texture coordinates", name);
  const uint32_t tris = field_in(d, 32, 1, kMaxTriangles, "triangles", name);
  const uint32_t glcmds = field_in(d, 36, 0, INT32_MAX / 4, "GL command words", name);
  const uint32_t frames = field_in(d, 40, 1, kMaxFrames, "frames", name);
  if (sts > 0) {
    field_in(d, 8, 1, kMaxSkinSide, "skin width", name);
    field_in(d, 12, 1, kMaxSkinSide, "skin height", name);
  }
  const uint32_t frame_bytes =
      field_in(d, 16, kFrameHeaderBytes + 4 * verts, INT32_MAX, "frame size (a frame of these vertices needs at least)", name);
  table(d, size, 44, skins, 64, "the skin names", name);
  table(d, size, 48, sts, 4, "the texture coordinates", name);
  const size_t tri_at = table(d, size, 52, tris, 12, "the triangles", name);
  table(d, size, 56, frames, frame_bytes, "the frames", name);
  table(d, size, 60, glcmds, 4, "the GL commands", name);
  const int32_t end = load_le32s(d + 64);
  if (end < static_cast<int32_t>(kHeaderBytes) || static_cast<size_t>(end) > size)
    refuse_at_byte(name, "the end offset " + std::to_string(end) + " lies outside the file's " + std::to_string(size) + " bytes", 64);
  for (uint32_t t = 0; t < tris; ++t) {
    const size_t at = tri_at + 12 * size_t{t};
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = load_le16(d + at + 2 * k);
      if (v >= verts)
        refuse_at_byte(name, "triangle " + std::to_string(t) + " names vertex " + std::to_string(v) + " of " + std::to_string(verts),
                       at + 2 * k);
      const uint32_t s = load_le16(d + at + 6 + 2 * k);
      if (sts > 0 && s >= sts)
        refuse_at_byte(name, "triangle " + std::to_string(t) + " names texture coordinate " + std::to_string(s) + " of " +
                                 std::to_string(sts),
                       at + 6 + 2 * k);
    }
  }
}

}  // namespace vds::enc
