// vds encoder: a PLY file checked before any importer sees it. The header's
// element counts are checked against the bytes the body can hold before
// anything is allocated, then the body is walked once in constant memory:
// every list must lie inside the file, every face's vertex indices inside
// the vertex element, and the file must hold every element it declares.
// The PLY format: Greg Turk, "The PLY Polygon File Format" (1994).
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>

namespace vds::enc {

// The most vertices one face may list (a polygon's fan triangulation is
// done by the importer; more is not a mesh a user meant).
constexpr uint32_t kPlyMaxFaceVertices = 256;

// Throws std::runtime_error "NAME: what is wrong (where)" for a file that
// is not a well-formed PLY mesh: where is a header line, or the element
// and the byte offset (binary) or line (ASCII) of the body. Returns the
// number of vertices and faces declared.
struct PlyCounts {
  uint64_t vertices = 0, faces = 0;
};
PlyCounts check_ply(const uint8_t* data, size_t size, const std::string& name);

// True if the bytes start like a PLY file ("ply" and a line end).
bool looks_like_ply(const uint8_t* data, size_t size);

}  // namespace vds::enc
