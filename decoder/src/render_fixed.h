// The renderer's fixed-point arithmetic shared by polygon set-up
// (render_setup.cpp) and the span loops (render_span.cpp): 64-bit helpers
// that wrap or saturate as stated, and the plane equations every
// interpolant is evaluated from (docs/renderer.md has the scaling).
#pragma once
#include <cstdint>

#include "vds/fixed.h"

namespace vds::detail {

// ---------------------------------------------------------------------------
// Integer helpers
// ---------------------------------------------------------------------------
inline int64_t wrap_add64(int64_t a, int64_t b) { return static_cast<int64_t>(static_cast<uint64_t>(a) + static_cast<uint64_t>(b)); }
inline int64_t wrap_mul64(int64_t a, int64_t b) { return static_cast<int64_t>(static_cast<uint64_t>(a) * static_cast<uint64_t>(b)); }
inline int32_t wrap_add32(int32_t a, int32_t b) { return static_cast<int32_t>(static_cast<uint32_t>(a) + static_cast<uint32_t>(b)); }
// a + d k modulo 2^32: exact whenever the true value fits int32.
inline int32_t wrap_mad32(int32_t a, int32_t d, int32_t k) {
  return static_cast<int32_t>(static_cast<uint32_t>(a) + static_cast<uint32_t>(d) * static_cast<uint32_t>(k));
}

constexpr int64_t kSat62 = int64_t{1} << 62;

// v * 2^-s: s >= 0 a floor shift, s < 0 a left shift saturated at +-2^62.
inline int64_t shift_floor(int64_t v, int s) {
  if (s >= 0) return s >= 63 ? (v < 0 ? -1 : 0) : (v >> s);
  const int l = -s;
  if (l >= 62 || abs64(v) >= (uint64_t{1} << (62 - l))) return v < 0 ? -kSat62 : (v == 0 ? 0 : kSat62);
  return static_cast<int64_t>(static_cast<uint64_t>(v) << l);
}
// The same, rounded to nearest (ties up) for s > 0.
inline int64_t shift_round(int64_t v, int s) {
  if (s <= 0) return shift_floor(v, s);
  if (s >= 63) return 0;
  return shr_round(v, s);
}

// ---------------------------------------------------------------------------
// Plane equations
// ---------------------------------------------------------------------------
// value(x, y) = (a0 + gx (x - xr) + gy (y - yr)) / 2^16 at the centre of pixel
// (x, y); (xr, yr) is the polygon's reference pixel. Gradients are Q.16 per
// pixel and saturate at 2^47 (2^31 per pixel: more than any attribute's whole
// range within one pixel, which only a sub-pixel sliver produces).
constexpr int kPlaneFrac = 16;
constexpr int64_t kGradLimit = int64_t{1} << 47;

struct Plane {
  int64_t a0, gx, gy;
};

inline int64_t eval(const Plane& p, int32_t dx, int32_t dy) {
  // |gx dx| < 2^47 * 2^14 each: the sum stays below 2^62.6 (wrap-safe anyway).
  return wrap_add64(wrap_add64(p.a0, wrap_mul64(p.gx, dx)), wrap_mul64(p.gy, dy));
}

constexpr int64_t kI32Max = INT32_MAX;
constexpr int64_t kI32Min = INT32_MIN;

}  // namespace vds::detail
