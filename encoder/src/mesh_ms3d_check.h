// vds encoder: a MilkShape 3D model (MS3D, versions 3 and 4) checked before
// assimp sees it. The file has no offsets: its tables follow one another,
// each after a count, so the check walks all of them. The layout (MilkShape
// 3D's published msModel format): "MS3D000000" and a 32-bit version; a
// 16-bit count of vertices of 15 bytes (flags, three floats, bone, reference
// count); a 16-bit count of triangles of 70 bytes (flags, three 16-bit
// vertex indices, three normals, three s and three t, smoothing group,
// group); a 16-bit count of groups (flags, a 32-byte name, a 16-bit count of
// 16-bit triangle indices, a material index, -1 for none); a 16-bit count of
// materials of 361 bytes; the animation's frame rate, time and frame count
// (12 bytes); a 16-bit count of joints (93 bytes, the last four two 16-bit
// key counts, then 16 bytes a rotation key and a translation key). Then,
// optionally and in this order: comments (a 32-bit version, then for groups,
// materials and joints a 32-bit count of (index, length, text), then a
// 32-bit count of model comments of (length, text)); vertex weights (a
// 32-bit version 1, 2 or 3 and 6, 10 or 14 bytes a vertex); joint colours
// (a 32-bit version, 12 bytes a joint); the model's extra (a 32-bit
// version 1 or 2, 12 bytes).
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>

namespace vds::enc {

// Throws std::runtime_error "NAME: what is wrong (byte N)" unless: the magic
// and version 3 or 4; every table whole inside the file, in the order above;
// counts within MilkShape's limits (65,534 vertices and triangles, 255
// groups, 128 materials and joints, 216 keys of each kind a joint, 1 MiB a
// comment); every triangle naming vertices that exist, every group naming
// triangles that exist and a material that exists or none; nothing after
// the last optional table.
void check_ms3d(const uint8_t* data, size_t size, const std::string& name);

}  // namespace vds::enc
