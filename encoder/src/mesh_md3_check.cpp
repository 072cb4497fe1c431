// vds encoder: the MD3 check (mesh_md3_check.h).
#include "mesh_md3_check.h"

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "binary_check.h"
#include "vds/bytes.h"

namespace vds::enc {
namespace {

constexpr size_t kHeaderBytes = 108;
constexpr size_t kSurfaceBytes = 108;
constexpr uint32_t kMaxFrames = 1024, kMaxTags = 16, kMaxSurfaces = 32, kMaxShaders = 256, kMaxVerts = 4096,
                   kMaxTriangles = 8192;

// `count` items of `item` bytes at `base` + the offset stored at `field`:
// inside the file.
void table(const uint8_t* d, size_t size, size_t base, size_t field, uint64_t count, uint64_t item, const char* what,
           const std::string& name) {
  table_in_file(d, size, base, field, count, item, 0, what, name);
}

uint32_t count(const uint8_t* d, size_t at, uint32_t limit, const char* what, const std::string& name) {
  return field_in(d, at, 0, limit, what, name);
}

}  // namespace

void check_md3(const uint8_t* d, size_t size, const std::string& name) {
  if (size < kHeaderBytes || std::memcmp(d, "IDP3", 4) != 0)
    refuse_at_byte(name, "not a Quake III model (it must start with 'IDP3')", 0);
  if (load_le32(d + 4) != 15) refuse_at_byte(name, "MD3 version " + std::to_string(load_le32(d + 4)) + " (15 is read)", 4);
  const uint32_t frames = count(d, 76, kMaxFrames, "frames", name);
  const uint32_t tags = count(d, 80, kMaxTags, "tags", name);
  const uint32_t surfaces = count(d, 84, kMaxSurfaces, "surfaces", name);
  table(d, size, 0, 92, frames, 56, "the frames", name);
  table(d, size, 0, 96, uint64_t{tags} * frames, 112, "the tags", name);
  const int32_t eof = static_cast<int32_t>(load_le32(d + 104));
  if (eof < 0 || static_cast<size_t>(eof) > size)
    refuse_at_byte(name, "the end offset " + std::to_string(eof) + " lies past the file's " + std::to_string(size) + " bytes", 104);
  size_t at = static_cast<size_t>(static_cast<int32_t>(load_le32(d + 100)));
  for (uint32_t s = 0; s < surfaces; ++s) {
    if (static_cast<int32_t>(at) < 0 || at > size || size - at < kSurfaceBytes)
      refuse_at_byte(name, "surface " + std::to_string(s) + " at byte " + std::to_string(at) + " lies past the file", 100);
    const uint8_t* h = d + at;
    if (std::memcmp(h, "IDP3", 4) != 0) refuse_at_byte(name, "surface " + std::to_string(s) + " does not start with 'IDP3'", at);
    if (load_le32(h + 72) != frames)
      refuse_at_byte(name, "surface " + std::to_string(s) + " has " + std::to_string(load_le32(h + 72)) + " frames, the model " +
                     std::to_string(frames),
           at + 72);
    const uint32_t shaders = count(d, at + 76, kMaxShaders, "shaders", name);
    const uint32_t verts = count(d, at + 80, kMaxVerts, "vertices", name);
    const uint32_t tris = count(d, at + 84, kMaxTriangles, "triangles", name);
    table(d, size, at, at + 88, tris, 12, "the triangles", name);
    table(d, size, at, at + 92, shaders, 68, "the shaders", name);
    table(d, size, at, at + 96, verts, 8, "the texture coordinates", name);
    table(d, size, at, at + 100, uint64_t{verts} * frames, 8, "the vertices", name);
    const size_t tri_at = at + static_cast<size_t>(static_cast<int32_t>(load_le32(h + 88)));
    for (uint64_t i = 0; i < 3 * uint64_t{tris}; ++i) {
      const int32_t v = static_cast<int32_t>(load_le32(d + tri_at + 4 * i));
      if (v < 0 || static_cast<uint32_t>(v) >= verts)
        refuse_at_byte(name, "surface " + std::to_string(s) + " triangle " + std::to_string(i / 3) + " names vertex " +
                       std::to_string(v) + " of " + std::to_string(verts),
             tri_at + 4 * i);
    }
    const int32_t end = static_cast<int32_t>(load_le32(h + 104));
    if (end < static_cast<int32_t>(kSurfaceBytes) || static_cast<size_t>(end) > size - at)
      refuse_at_byte(name, "surface " + std::to_string(s) + " ends at offset " + std::to_string(end) + ", past the file", at + 104);
    at += static_cast<size_t>(end);
  }
}

bool md3_tag(const uint8_t* d, size_t size, const std::string& name, const std::string& tag, uint32_t frame, Md3Tag* out) {
  const uint32_t frames = load_le32(d + 76), tags = load_le32(d + 80);
  if (frame >= frames) refuse_at_byte(name, "no frame " + std::to_string(frame) + " (the model has " + std::to_string(frames) + ")", 76);
  const size_t base = static_cast<size_t>(static_cast<int32_t>(load_le32(d + 96)));
  for (uint32_t t = 0; t < tags; ++t) {
    const size_t at = base + (size_t{frame} * tags + t) * 112;  // inside the file after check_md3
    if (at > size || size - at < 112) refuse_at_byte(name, "the tags lie past the file", 96);
    char n[65] = {};
    std::memcpy(n, d + at, 64);
    std::string have(n);
    if (have.size() != tag.size() ||
        !std::equal(have.begin(), have.end(), tag.begin(), [](char a, char b) { return std::tolower(a) == std::tolower(b); }))
      continue;
    float f[12];
    for (int k = 0; k < 12; ++k) f[k] = std::bit_cast<float>(load_le32(d + at + 64 + 4 * k));
    for (int k = 0; k < 12; ++k)
      if (!std::isfinite(f[k])) refuse_at_byte(name, "tag '" + tag + "' holds a number that is not finite", at + 64 + 4 * k);
    for (int c = 0; c < 3; ++c) {
      out->origin[c] = f[c];
      for (int r = 0; r < 3; ++r) out->axis[r][c] = f[3 + 3 * r + c];
    }
    return true;
  }
  return false;
}

}  // namespace vds::enc
