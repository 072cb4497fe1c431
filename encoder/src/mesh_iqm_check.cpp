// vds encoder: the IQM check (mesh_iqm_check.h).
#include "mesh_iqm_check.h"

#include <cstring>
#include <stdexcept>

#include "binary_check.h"
#include "vds/bytes.h"

namespace vds::enc {
namespace {

constexpr size_t kHeaderBytes = 124;

// Header fields, by index after the magic (each 4 bytes at 16 + 4 i).
enum Field {
  kVersion, kFileSize, kFlags, kNumText, kOfsText, kNumMeshes, kOfsMeshes, kNumVertexArrays, kNumVertexes,
  kOfsVertexArrays, kNumTriangles, kOfsTriangles, kOfsAdjacency, kNumJoints, kOfsJoints, kNumPoses, kOfsPoses,
  kNumAnims, kOfsAnims, kNumFrames, kNumFrameChannels, kOfsFrames, kOfsBounds, kNumComment, kOfsComment,
  kNumExtensions, kOfsExtensions
};

class Reader {
 public:
  Reader(const uint8_t* d, size_t n, const std::string& name) : d_(d), n_(n), name_(name) {}
  uint32_t field(int f) const { return load_le32(d_ + 16 + 4 * f); }
  uint32_t u32(size_t at) const { return load_le32(d_ + at); }
  // A table of `count` items of `item` bytes at the offset in field `ofs`
  // (nothing to check when count is 0): inside the file, past the header.
  size_t table(int ofs, uint64_t count, uint64_t item, const char* what) const {
    if (count == 0) return 0;
    const uint64_t at = field(ofs), bytes = count * item;
    if (at < kHeaderBytes || at > n_ || bytes > n_ - at)
      refuse_at_byte(name_, std::string(what) + ": " + std::to_string(count) + " of " + std::to_string(item) +
                      " bytes at offset " + std::to_string(at) + " do not fit the file's " + std::to_string(n_) + " bytes",
           16 + 4 * static_cast<size_t>(ofs));
    return static_cast<size_t>(at);
  }
  void text_offset(uint32_t off, size_t at, const char* what) const {
    if (off >= field(kNumText) && !(off == 0 && field(kNumText) == 0))
      refuse_at_byte(name_, std::string(what) + " names text offset " + std::to_string(off) + " of " +
                      std::to_string(field(kNumText)),
           at);
  }
  const std::string& name() const { return name_; }

 private:
  const uint8_t* d_;
  size_t n_;
  const std::string& name_;
};

}  // namespace

void check_iqm(const uint8_t* data, size_t size, const std::string& name) {
  if (size < kHeaderBytes || std::memcmp(data, "INTERQUAKEMODEL", 16) != 0)
    refuse_at_byte(name, "not an Inter-Quake Model (it must start with 'INTERQUAKEMODEL' and a NUL)", 0);
  const Reader r(data, size, name);
  if (r.field(kVersion) != 2) refuse_at_byte(name, "IQM version " + std::to_string(r.field(kVersion)) + " (2 is read)", 16);
  if (r.field(kFileSize) != size)
    refuse_at_byte(name, "the header says the file is " + std::to_string(r.field(kFileSize)) + " bytes, it is " +
                   std::to_string(size), 20);
  const uint32_t nv = r.field(kNumVertexes), nt = r.field(kNumTriangles);
  const uint32_t nj = r.field(kNumJoints), np = r.field(kNumPoses), nf = r.field(kNumFrames);
  // Text: NUL-terminated.
  const size_t text = r.table(kOfsText, r.field(kNumText), 1, "the text");
  if (r.field(kNumText) > 0 && data[text + r.field(kNumText) - 1] != 0)
    refuse_at_byte(name, "the text does not end with a NUL", text + r.field(kNumText) - 1);
  // Vertex arrays: kinds the format defines, each with its element type and width.
  const size_t va = r.table(kOfsVertexArrays, r.field(kNumVertexArrays), 20, "the vertex arrays");
  struct Kind {
    uint32_t format, width;
  };
  // type -> (format, width): position, texcoord, normal, tangent, blendindexes, blendweights, colour.
  const Kind kKinds[7] = {{7, 3}, {7, 2}, {7, 3}, {7, 4}, {1, 4}, {1, 4}, {1, 4}};
  const uint32_t kFormatBytes[2] = {1, 4};  // ubyte, float
  bool seen[7] = {};
  for (uint32_t i = 0; i < r.field(kNumVertexArrays); ++i) {
    const size_t at = va + 20 * static_cast<size_t>(i);
    const uint32_t type = r.u32(at), format = r.u32(at + 8), width = r.u32(at + 12), offset = r.u32(at + 16);
    if (type >= 7) refuse_at_byte(name, "vertex array " + std::to_string(i) + " is of type " + std::to_string(type) + " (0..6 are read)", at);
    if (seen[type]) refuse_at_byte(name, "a second vertex array of type " + std::to_string(type), at);
    seen[type] = true;
    if (format != kKinds[type].format || width != kKinds[type].width)
      refuse_at_byte(name, "vertex array " + std::to_string(i) + " (type " + std::to_string(type) + ") has format " +
                     std::to_string(format) + " x " + std::to_string(width) + ", not the format's " +
                     std::to_string(kKinds[type].format) + " x " + std::to_string(kKinds[type].width),
           at + 8);
    const uint64_t bytes = uint64_t{nv} * width * kFormatBytes[format == 7 ? 1 : 0];
    if (offset < kHeaderBytes || offset > size || bytes > size - offset)
      refuse_at_byte(name, "vertex array " + std::to_string(i) + ": " + std::to_string(bytes) + " bytes at offset " +
                     std::to_string(offset) + " do not fit the file",
           at + 16);
  }
  if (nv > 0 && !seen[0]) refuse_at_byte(name, "no position array", va);
  // Triangles name vertices.
  const size_t tri = r.table(kOfsTriangles, nt, 12, "the triangles");
  for (uint64_t i = 0; i < 3 * uint64_t{nt}; ++i)
    if (r.u32(tri + 4 * i) >= nv)
      refuse_at_byte(name, "triangle " + std::to_string(i / 3) + " names vertex " + std::to_string(r.u32(tri + 4 * i)) + " of " +
                     std::to_string(nv),
           tri + 4 * i);
  if (r.field(kOfsAdjacency) != 0) r.table(kOfsAdjacency, nt, 12, "the adjacency");
  // Meshes: names, and vertex and triangle ranges.
  const size_t meshes = r.table(kOfsMeshes, r.field(kNumMeshes), 24, "the meshes");
  for (uint32_t i = 0; i < r.field(kNumMeshes); ++i) {
    const size_t at = meshes + 24 * static_cast<size_t>(i);
    r.text_offset(r.u32(at), at, "a mesh");
    r.text_offset(r.u32(at + 4), at + 4, "a mesh's material");
    if (uint64_t{r.u32(at + 8)} + r.u32(at + 12) > nv)
      refuse_at_byte(name, "mesh " + std::to_string(i) + "'s vertices lie past the file's " + std::to_string(nv), at + 8);
    if (uint64_t{r.u32(at + 16)} + r.u32(at + 20) > nt)
      refuse_at_byte(name, "mesh " + std::to_string(i) + "'s triangles lie past the file's " + std::to_string(nt), at + 16);
  }
  // Joints and poses: parents before them (-1 for none).
  const size_t joints = r.table(kOfsJoints, nj, 48, "the joints");
  for (uint32_t i = 0; i < nj; ++i) {
    const size_t at = joints + 48 * static_cast<size_t>(i);
    r.text_offset(r.u32(at), at, "a joint");
    const int32_t parent = static_cast<int32_t>(r.u32(at + 4));
    if (parent >= static_cast<int64_t>(i) || parent < -1)
      refuse_at_byte(name, "joint " + std::to_string(i) + " has parent " + std::to_string(parent), at + 4);
  }
  const size_t poses = r.table(kOfsPoses, np, 88, "the poses");
  for (uint32_t i = 0; i < np; ++i) {
    const int32_t parent = static_cast<int32_t>(r.u32(poses + 88 * static_cast<size_t>(i)));
    if (parent >= static_cast<int64_t>(i) || parent < -1)
      refuse_at_byte(name, "pose " + std::to_string(i) + " has parent " + std::to_string(parent), poses + 88 * static_cast<size_t>(i));
  }
  if (nj > 0 && np > 0 && np != nj) refuse_at_byte(name, std::to_string(np) + " poses for " + std::to_string(nj) + " joints", 16 + 4 * kNumPoses);
  const size_t anims = r.table(kOfsAnims, r.field(kNumAnims), 20, "the animations");
  for (uint32_t i = 0; i < r.field(kNumAnims); ++i) {
    const size_t at = anims + 20 * static_cast<size_t>(i);
    r.text_offset(r.u32(at), at, "an animation");
    if (uint64_t{r.u32(at + 4)} + r.u32(at + 8) > nf)
      refuse_at_byte(name, "animation " + std::to_string(i) + "'s frames lie past the file's " + std::to_string(nf), at + 4);
  }
  r.table(kOfsFrames, uint64_t{nf} * r.field(kNumFrameChannels), 2, "the frames");
  if (r.field(kOfsBounds) != 0) r.table(kOfsBounds, nf, 32, "the bounds");
  r.table(kOfsComment, r.field(kNumComment), 1, "the comment");
  r.table(kOfsExtensions, r.field(kNumExtensions), 16, "the extensions");
}

}  // namespace vds::enc
