// vds encoder: the MS3D check (mesh_ms3d_check.h).
#include "mesh_ms3d_check.h"

#include <cstring>
#include <string>
#include <vector>

#include "binary_check.h"
#include "vds/bytes.h"

namespace vds::enc {
namespace {

constexpr uint32_t kMaxVerts = 65534, kMaxTriangles = 65534, kMaxGroups = 255, kMaxMaterials = 128, kMaxJoints = 128,
                   kMaxKeys = 216, kMaxComment = 1u << 20;
constexpr size_t kVertexBytes = 15, kTriangleBytes = 70, kMaterialBytes = 361, kJointBytes = 93, kKeyBytes = 16;

// Reads the file front to back; every read must lie inside it.
class Walk {
 public:
  Walk(const uint8_t* d, size_t size, const std::string& name) : d_(d), size_(size), name_(name) {}
  size_t at() const { return at_; }
  bool done() const { return at_ == size_; }
  // `n` bytes of `what` from here, which must be in the file.
  size_t skip(uint64_t n, const std::string& what) {
    if (n > size_ - at_)
      refuse_at_byte(name_, what + ": " + std::to_string(n) + " bytes, past the file's end (" + std::to_string(size_) + " bytes)",
                     at_);
    const size_t here = at_;
    at_ += static_cast<size_t>(n);
    return here;
  }
  uint32_t u16(const std::string& what) { return load_le16(d_ + skip(2, what)); }
  int32_t i32(const std::string& what) { return load_le32s(d_ + skip(4, what)); }
  // A 16-bit or 32-bit count, at most `limit`.
  uint32_t count16(uint32_t limit, const std::string& what) {
    const size_t here = at_;
    const uint32_t n = u16(what);
    if (n > limit) refuse_at_byte(name_, what + " " + std::to_string(n) + " (at most " + std::to_string(limit) + ")", here);
    return n;
  }
  uint32_t count32(uint32_t limit, const std::string& what) { return field_in(d_, skip(4, what), 0, limit, what, name_); }
  [[noreturn]] void refuse(const std::string& what, size_t where) const { refuse_at_byte(name_, what, where); }

 private:
  const uint8_t* d_;
  size_t size_;
  size_t at_ = 0;
  const std::string& name_;
};

// Comments of groups, materials or joints: (index, length, text) each.
void comments(Walk& w, uint32_t items, const char* of) {
  const uint32_t n = w.count32(1u << 16, std::string("comments of ") + of);
  for (uint32_t c = 0; c < n; ++c) {
    const size_t here = w.at();
    const int32_t index = w.i32(std::string("a comment's ") + of + " index");
    if (index < 0 || static_cast<uint32_t>(index) >= items)
      w.refuse(std::string("a comment on ") + of + " " + std::to_string(index) + " of " + std::to_string(items), here);
    w.skip(w.count32(kMaxComment, "comment length"), "a comment");
  }
}

}  // namespace

void check_ms3d(const uint8_t* d, size_t size, const std::string& name) {
  if (size < 14 || std::memcmp(d, "MS3D000000", 10) != 0)
    refuse_at_byte(name, "not a MilkShape 3D model (it must start with 'MS3D000000')", 0);
  const int32_t version = load_le32s(d + 10);
  if (version != 3 && version != 4) refuse_at_byte(name, "MS3D version " + std::to_string(version) + " (3 and 4 are read)", 10);
  Walk w(d, size, name);
  w.skip(14, "the header");
  const uint32_t verts = w.count16(kMaxVerts, "vertices");
  w.skip(uint64_t{verts} * kVertexBytes, "the vertices");
  const uint32_t tris = w.count16(kMaxTriangles, "triangles");
  for (uint32_t t = 0; t < tris; ++t) {
    const size_t at = w.skip(kTriangleBytes, "triangle " + std::to_string(t));
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = load_le16(d + at + 2 + 2 * k);
      if (v >= verts)
        w.refuse("triangle " + std::to_string(t) + " names vertex " + std::to_string(v) + " of " + std::to_string(verts),
                 at + 2 + 2 * k);
    }
  }
  const uint32_t groups = w.count16(kMaxGroups, "groups");
  std::vector<std::pair<int, size_t>> group_material;  // (index, byte) checked once the materials are counted
  for (uint32_t g = 0; g < groups; ++g) {
    const std::string what = "group " + std::to_string(g);
    w.skip(33, what + "'s name");
    const uint32_t n = w.count16(kMaxTriangles, what + "'s triangles");
    const size_t at = w.skip(2 * uint64_t{n}, what + "'s triangle list");
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t t = load_le16(d + at + 2 * i);
      if (t >= tris) w.refuse(what + " names triangle " + std::to_string(t) + " of " + std::to_string(tris), at + 2 * i);
    }
    const size_t m_at = w.skip(1, what + "'s material");
    group_material.emplace_back(static_cast<int8_t>(d[m_at]), m_at);
  }
  const uint32_t materials = w.count16(kMaxMaterials, "materials");
  for (const auto& [m, at] : group_material)
    if (m < -1 || (m >= 0 && static_cast<uint32_t>(m) >= materials))
      w.refuse("a group names material " + std::to_string(m) + " of " + std::to_string(materials), at);
  w.skip(uint64_t{materials} * kMaterialBytes, "the materials");
  w.skip(12, "the animation's frame rate, time and frame count");
  const uint32_t joints = w.count16(kMaxJoints, "joints");
  for (uint32_t j = 0; j < joints; ++j) {
    const std::string what = "joint " + std::to_string(j);
    const size_t at = w.skip(kJointBytes, what);
    const uint32_t rot = load_le16(d + at + 89), pos = load_le16(d + at + 91);
    if (rot > kMaxKeys || pos > kMaxKeys)
      w.refuse(what + " has " + std::to_string(rot) + " rotation and " + std::to_string(pos) + " translation keys (at most " +
                   std::to_string(kMaxKeys) + " each)",
               at + 89);
    w.skip(uint64_t{rot + pos} * kKeyBytes, what + "'s keys");
  }
  if (w.done()) return;
  // Comments.
  const size_t c_at = w.at();
  if (w.i32("the comments' version") != 1) w.refuse("comments of version " + std::to_string(load_le32s(d + c_at)) + " (1 is read)", c_at);
  comments(w, groups, "groups");
  comments(w, materials, "materials");
  comments(w, joints, "joints");
  const uint32_t model = w.count32(1, "model comments");
  for (uint32_t c = 0; c < model; ++c) w.skip(w.count32(kMaxComment, "comment length"), "the model's comment");
  if (w.done()) return;
  // Vertex weights.
  const size_t v_at = w.at();
  const int32_t vv = w.i32("the vertex weights' version");
  if (vv < 1 || vv > 3) w.refuse("vertex weights of version " + std::to_string(vv) + " (1 to 3 are read)", v_at);
  w.skip(uint64_t{verts} * (vv == 1 ? 6 : vv == 2 ? 10 : 14), "the vertex weights");
  if (w.done()) return;
  // Joint colours.
  const size_t j_at = w.at();
  const int32_t jv = w.i32("the joint colours' version");
  if (jv != 1) w.refuse("joint colours of version " + std::to_string(jv) + " (1 is read)", j_at);
  w.skip(uint64_t{joints} * 12, "the joint colours");
  if (w.done()) return;
  // The model's extra.
  const size_t m_at = w.at();
  const int32_t mv = w.i32("the model extra's version");
  if (mv != 1 && mv != 2) w.refuse("a model extra of version " + std::to_string(mv) + " (1 and 2 are read)", m_at);
  w.skip(12, "the model extra");
  if (!w.done()) w.refuse(std::to_string(size - w.at()) + " bytes after the model's last table", w.at());
}

}  // namespace vds::enc
