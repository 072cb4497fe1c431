// Internal interfaces between the renderer's source files (render.cpp: frame
// and band driver; render_clip.cpp: clipping; render_setup.cpp: polygon
// setup and span loops). Not part of the public API.
#pragma once
#include <cstddef>
#include <cstdint>

#include "vds/fixed.h"
#include "vds/render.h"

namespace vds::detail {

// q = 1/z scale: q = round(2^30 near / z) - (that >> 15), i.e. about
// (2^30 - 2^15) near / z. The 2^15 margin below 2^30 keeps interpolated q
// (exact at span starts, stepped with rounded gradients) below 2^30, so the
// 16-bit depth q >> 14 never exceeds 65535.
constexpr int kQFracBits = 30;
constexpr int kDepth16Shift = 14;
constexpr int32_t kQMax = (int32_t{1} << kQFracBits) - 1;

// Attributes carried through clipping: texture coordinates (u, v in Q16.16
// texels) or colours (R, G, B in Q8.8).
constexpr int kMaxAttribs = 3;

struct ClipVertex {
  int32_t x, y, z;  // camera space, Q16.16
  int32_t a[kMaxAttribs];
};

struct ScreenVertex {
  int32_t x, y;  // Q24.8 pixels
  int32_t q;     // 1/z scale above
  int32_t a[kMaxAttribs];
};

// A face's corners, plus one per clip plane (near, far, 4 guard planes).
constexpr int kMaxPolyVerts = kMaxFaceCorners + 6;

// Outcode bits of a camera-space vertex.
enum : uint8_t {
  kOutNear = 1,
  kOutFar = 2,
  kOutLeft = 4,
  kOutRight = 8,
  kOutTop = 16,
  kOutBottom = 32,
  kOutAll = 63,
  // Not a plane: the cached screen position is not valid (the vertex is in
  // front of the near plane only when this bit is clear).
  kNoProjection = 64,
  // Not an outcode: a cached vertex not projected this frame (no triangle
  // drawn names it).
  kUnprojected = 128,
};

// Camera constants of a frame.
struct FrameCamera {
  const Camera* cam;
  int32_t near_raw, far_raw;
  int64_t guard;  // guard band half-width in pixels
};

uint8_t outcode(const FrameCamera& fc, const ClipVertex& v);
// q of a camera-space depth z >= near (see kQFracBits).
int32_t depth_q(const FrameCamera& fc, int32_t z);
// Clips the polygon in[0..n) against every plane whose outcode bit is set
// in `planes`; the result (at most kMaxPolyVerts vertices) goes to out and
// its size is returned. `tmp` is scratch of kMaxPolyVerts vertices.
int clip_polygon(const FrameCamera& fc, uint8_t planes, const ClipVertex* in, int n, ClipVertex* out,
                 ClipVertex* tmp, int num_attribs);

// What a polygon is drawn with.
struct MaterialCtx {
  const Mesh* mesh;
  int num_attribs;  // 0 flat, 2 texture, 3 gouraud, 0 view_mapped, 2 mesh_colors
  uint32_t tri;     // the face's number in the mesh (mesh_colors, Mesh::views)
  uint32_t first;   // its first corner's vertex (Mesh::views)
  int corners;      // its corners (Mesh::corners): more than 3, rasterised as one polygon
  int point_span = 0;  // RenderConfig::point_face_span
};

// The band being drawn.
struct BandTarget {
  int32_t y0, y1;            // rows [y0, y1)
  int32_t width;
  int32_t height;            // the frame's rows
  uint8_t* color;            // row y0
  uint32_t color_stride;     // bytes
  void* depth;               // row y0, `width` entries per row
  PixelFormat format;
  DepthFormat depth_format;
};

// The per-pixel reciprocal of the span loops (render_setup.cpp), for tests:
// about 2^62 / (w << *z) with *z = clz(w), w >= 1.
int32_t span_reciprocal(uint32_t w, int* z);

// Repeat addressing applies: requested and both sizes powers of two.
bool texture_repeats(const Texture& t);

// What a polygon's set-up depends on: the same for every band of a frame.
struct PolygonTarget {
  int32_t width, height;  // the frame's
  PixelFormat format;
  DepthFormat depth_format;
};

// Draws a convex polygon (a triangle or a clipped triangle) into the band:
// culling, setup and spans. n in [3, kMaxPolyVerts].
void draw_polygon(const BandTarget& band, const MaterialCtx& mat, const ScreenVertex* v, int n, RenderStats& stats);

// The same in two steps, so that one set-up can serve every band a polygon
// crosses: prepare_polygon does everything that does not depend on the band
// (culling, planes, span function), draw_prepared the band's spans. The
// picture is the same as draw_polygon's. PreparedPolygon is opaque here
// (render_setup.cpp); storage for it: prepared_polygon_bytes(), aligned to
// prepared_polygon_align().
struct PreparedPolygon;
size_t prepared_polygon_bytes();
size_t prepared_polygon_align();
void prepare_polygon(const PolygonTarget& target, const MaterialCtx& mat, const ScreenVertex* v, int n, PreparedPolygon* pp);
void draw_prepared(const BandTarget& band, const PreparedPolygon& pp, RenderStats& stats);
// The end (exclusive) of the rows a prepared polygon can cover.
int32_t prepared_row_end(const PreparedPolygon& pp);

}  // namespace vds::detail
