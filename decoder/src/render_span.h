// The span stage of the renderer: a polygon's set-up as the span loops
// read it (PolySetup, filled by prepare_polygon in render_setup.cpp) and
// the loop chosen for its material and target (select_span, in
// render_span.cpp). Internal to the client library.
#pragma once
#include <cstdint>

#include "render_fixed.h"
#include "render_internal.h"

namespace vds::detail {

// ---------------------------------------------------------------------------
// Texture access
// ---------------------------------------------------------------------------
struct TexCtx {
  const uint8_t* base;
  uint32_t stride;
  int32_t wmask, hmask;  // repeat
  int32_t wmax, hmax;    // clamp
  const uint8_t* cb;
  const uint8_t* cr;
  uint32_t cstride;
  int32_t cwmask, chmask, cwmax, chmax;
};

// A mesh-colors face as the span loops sample it (Shading::mesh_colors).
struct LatticeCtx {
  const uint8_t* y;
  const uint8_t* cb;
  const uint8_t* cr;
  LatticeFace face;
  int32_t res;  // R
};

struct PolySetup;
using SpanFn = void (*)(const BandTarget&, const PolySetup&, int32_t, int32_t, int32_t);

struct PolySetup {
  int32_t xr, yr;  // reference pixel of the planes
  Plane q;         // depth (and the divisor unless proj)
  Plane w;         // proj: the divisor g x + h y + i
  Plane n[3];      // numerators
  int nn;
  bool proj;
  // result = N / W * 2^b0 before the per-span scalings (docs/renderer.md).
  int b0;
  uint32_t flat;   // flat colour in the output format
  TexCtx tex;
  LatticeCtx lat;  // mesh_colors
  // Fast span set-up (fast == true): the planes' own scale serves the whole
  // polygon (chosen from the values at its vertices with a margin), so a span
  // start comes from the row-unit planes below and the steps are fixed. A
  // span whose start and end values stay inside [wlo, whi] (divisor) and
  // +-kNumLimit (numerators) uses them; any other takes the per-span path.
  bool fast;
  int32_t fast_shb;
  int32_t fast_dq, fast_dw, fast_dn[3];
  // The fast start values: each plane in row units with 32-bit
  // coefficients, c + step dx + g dy from the reference pixel (the step
  // above, c and g the plane's value there and its y step rounded to row
  // units), evaluated exactly in 64 bits: a product and a sum, not the
  // planes' 64-bit ones. A start is then off the plane by at most half a
  // row unit for each pixel it lies from the reference pixel and one more;
  // the reference pixel lies on the frame, so by less than the frame's
  // width and height.
  int32_t fast_xr, fast_yr;  // their reference pixel: the planes' own, moved onto the frame
  int32_t fast_cq, fast_gq, fast_cw, fast_gw, fast_cn[3], fast_gn[3];
  int32_t wlo, whi;
  int32_t fast_qlo, fast_qhi;  // [1, kQMax] and [wlo, whi] together (q is W), not empty
  // The fast start values of every pixel the polygon covers lie inside
  // those limits (checked once at set-up over the box of its columns and
  // rows on the frame: fast_safe in render_setup.cpp; view-mapped polygons
  // only), so a span takes them without the checks.
  bool fast_safe;
};

// The bound on a span's numerators (the fast set-up's check, row_piece's
// range): their products with a reciprocal stay within int64 after the shift.
constexpr int64_t kNumLimit = (int64_t{1} << 30) + 4096;

// Rounded to nearest: r5 = round(r 31 / 255) = (r 249 + 1014) >> 11 and
// g6 = round(g 63 / 255) = (g 253 + 505) >> 10, exact for every 8-bit value.
inline uint16_t pack565(uint32_t c) {
  const uint32_t r = (c >> 16) & 255, g = (c >> 8) & 255, b = c & 255;
  return static_cast<uint16_t>((((r * 249 + 1014) >> 11) << 11) | (((g * 253 + 505) >> 10) << 5) |
                               ((b * 249 + 1014) >> 11));
}

// The per-pixel step of a plane in row units: gx / 2^16 rounded, saturated.
inline int32_t step16(int64_t gx) {
  const int64_t d = (gx + (int64_t{1} << (kPlaneFrac - 1))) >> kPlaneFrac;
  return static_cast<int32_t>(d < kI32Min ? kI32Min : (d > kI32Max ? kI32Max : d));
}

// The span loop for a material on a target (nullptr: a format compiled out).
SpanFn select_span(const PolygonTarget& target, const Mesh& m, bool repeat);
// The span loop of a face drawn in one colour (ViewMapSource::point).
SpanFn select_flat_span(const PolygonTarget& target);
// Whether point_colour samples this texture form (Y'CbCr 4:2:0).
bool point_samples(const Texture& t);
// The colour in the target's format of the sample at texel position
// (u, v) (Q24.8, a texel's centre at +0.5), as the mesh's filter draws it.
uint32_t point_colour(const PolygonTarget& target, const Mesh& m, const Texture& t, int32_t u_q8, int32_t v_q8);
// The texture as the span loops address it.
TexCtx make_tex_ctx(const Texture& t, bool repeat);
// Fraction bits of the texture coordinates: 0 for nearest sampling.
int fraction_bits(const Mesh& m, PixelFormat out);
// Fraction bits of the lattice coordinates of the mesh-colors linear filter.
constexpr int kLatticeFracBits = 8;
// Whether every sample index a face can give lies below `samples`.
bool lattice_face_valid(const LatticeFace& f, uint32_t samples);

}  // namespace vds::detail
