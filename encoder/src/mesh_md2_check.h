// vds encoder: a Quake II model (MD2) checked before assimp sees it: assimp's
// loader takes the header's offsets as given. The layout: id Software's
// Quake II source (qfiles.h, dmdl_t): a 68-byte header of 17 little-endian
// 32-bit fields ("IDP2", version 8, skin width and height, frame size, the
// counts of skins, vertices, texture coordinates, triangles, GL commands and
// frames, the offsets of those tables and of the end), skin names of 64
// bytes, texture coordinates of two 16-bit integers, triangles of three
// 16-bit vertex and three 16-bit texture coordinate indices, frames of a
// 40-byte header (scale, translation, name) and 4 bytes a vertex, GL
// commands of 4 bytes.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>

namespace vds::enc {

// Throws std::runtime_error "NAME: what is wrong (byte N)" unless: the magic
// and version 8; counts within the game's limits (32 skins, 2048 vertices,
// 4096 triangles, 512 frames; 3 texture coordinates a triangle), at least
// one frame, vertex and triangle; a frame size that holds a frame's vertices;
// a skin of 1 to 4096 texels a side when there are texture coordinates (they
// are divided by it); every table inside the file and the end offset within
// it; every triangle naming vertices and texture coordinates that exist.
void check_md2(const uint8_t* data, size_t size, const std::string& name);

}  // namespace vds::enc
