// vds encoder: a Quake III model (MD3) checked before assimp sees it:
// assimp's loader takes the header's counts and offsets as given. The
// layout: id Software's Quake III Arena source (qfiles.h, md3Header_t and
// md3Surface_t): a 108-byte header ("IDP3", version 15), frames of 56
// bytes, tags of 112 bytes per frame, then surfaces, each a 108-byte header
// whose offsets count from its own start: shaders of 68 bytes, triangles of
// three 32-bit indices, texture coordinates of 8 bytes and vertices of 8
// bytes per frame.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

namespace vds::enc {

// Throws std::runtime_error "NAME: what is wrong (byte N)" unless: the
// magic and version 15; counts within the game's limits (1024 frames, 16
// tags, 32 surfaces, 256 shaders, 4096 vertices and 8192 triangles a
// surface); every table of the header and of every surface inside the
// file, surfaces chained inside the file; each surface's magic, its frame
// count the header's, its triangles naming its vertices.
void check_md3(const uint8_t* data, size_t size, const std::string& name);

// A tag: where a part attached to it lies in the model's space. A point p
// of the part is at origin + p.x axis[0] + p.y axis[1] + p.z axis[2].
struct Md3Tag {
  std::array<double, 3> origin{};
  std::array<std::array<double, 3>, 3> axis{};
};
// The tag named `tag` (case ignored) in frame `frame` of a file check_md3
// has accepted: false if it has none; throws as check_md3 does if the
// frame is not in the file or the tag's numbers are not finite.
bool md3_tag(const uint8_t* data, size_t size, const std::string& name, const std::string& tag, uint32_t frame, Md3Tag* out);

}  // namespace vds::enc
