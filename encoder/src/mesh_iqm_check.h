// vds encoder: an Inter-Quake Model (IQM, version 2) checked before assimp
// sees it: assimp's loader takes the header's counts and offsets as given.
// The layout: Lee Salzman's IQM format description (iqm.txt, version 2):
// a 124-byte header of 27 little-endian 32-bit fields after a 16-byte magic,
// then the tables it points to.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>

namespace vds::enc {

// Throws std::runtime_error "NAME: what is wrong (byte N)" unless: the magic
// and version 2; the stated size is the file's; every table (text, meshes,
// vertex arrays and each array's data, triangles, adjacency, joints, poses,
// animations, frames, bounds, comment, extensions) lies inside the file;
// every vertex array is a kind of the format with the element type and
// width it defines (position, normal: 3 floats; texcoord: 2 floats;
// tangent: 4 floats; blend indexes, blend weights, colour: 4 bytes), at most
// one of each; a position array exists; every mesh's vertices and
// triangles lie inside the file's; every triangle's indices name vertices;
// every name is an offset into the text, which ends with a NUL; joint and
// pose parents come before them; animations' frames lie inside the frames.
void check_iqm(const uint8_t* data, size_t size, const std::string& name);

}  // namespace vds::enc
