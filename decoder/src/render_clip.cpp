// Polygon clipping of the renderer in camera space (Sutherland-Hodgman)
// against the near and far planes and the guard band. Every intersection is
// computed from the inside end of the edge toward the outside end, so two
// triangles sharing an edge get bit-identical new vertices (no cracks).
#include "render_internal.h"

namespace vds::detail {

namespace {

// Signed distance of v from clip plane `bit` (>= 0 inside), in the plane's
// own units (only signs and ratios are used).
//   near:  z - near            far: far - z
//   left:  G z + fx x          right: G z - fx x      (|fx x / z| <= G)
//   top:   G z + fy y          bottom: G z - fy y
// fx x is Q16.16 x Q16.16 >> 16; every value is below 2^47.
int64_t plane_distance(const FrameCamera& fc, uint8_t bit, const ClipVertex& v) {
  const int64_t gz = fc.guard * v.z;
  switch (bit) {
    case kOutNear: return int64_t{v.z} - fc.near_raw;
    case kOutFar: return int64_t{fc.far_raw} - v.z;
    case kOutLeft: return gz + (mul32x32_64(fc.cam->fx.raw(), v.x) >> 16);
    case kOutRight: return gz - (mul32x32_64(fc.cam->fx.raw(), v.x) >> 16);
    case kOutTop: return gz + (mul32x32_64(fc.cam->fy.raw(), v.y) >> 16);
    default: return gz - (mul32x32_64(fc.cam->fy.raw(), v.y) >> 16);
  }
}

// The clip parameter t is Q2.30.
constexpr int kQ30 = Q2_30::kFracBits;

int32_t lerp_q30(int32_t a, int32_t b, int64_t t30) {
  // a + (b - a) t with t in [0, 1] (Q2.30); |b - a| < 2^32, product < 2^62.
  const int64_t d = int64_t{b} - a;
  return sat_s32(int64_t{a} + shr_round(d * t30, kQ30));
}

// The point where edge (in -> out) crosses the plane: din >= 0 > dout.
ClipVertex intersect(const ClipVertex& in, const ClipVertex& out, int64_t din, int64_t dout, uint8_t bit,
                     const FrameCamera& fc, int num_attribs) {
  // t = din / (din - dout) in Q2.30, with both distances first scaled below
  // 2^32 so that din << 30 fits 64 bits.
  int64_t den = din - dout;  // > 0, < 2^48
  int64_t num = din;
  const int len = 64 - clz64(static_cast<uint64_t>(den));
  if (len > 32) {
    num >>= (len - 32);
    den >>= (len - 32);
  }
  int64_t t30 = den > 0 ? (num << kQ30) / den : 0;
  if (t30 > (int64_t{1} << kQ30)) t30 = int64_t{1} << kQ30;
  ClipVertex r;
  r.x = lerp_q30(in.x, out.x, t30);
  r.y = lerp_q30(in.y, out.y, t30);
  r.z = lerp_q30(in.z, out.z, t30);
  // On the depth planes the new vertex lies exactly on the plane.
  if (bit == kOutNear) r.z = fc.near_raw;
  if (bit == kOutFar) r.z = fc.far_raw;
  for (int k = 0; k < kMaxAttribs; ++k) r.a[k] = k < num_attribs ? lerp_q30(in.a[k], out.a[k], t30) : 0;
  return r;
}

}  // namespace

uint8_t outcode(const FrameCamera& fc, const ClipVertex& v) {
  uint8_t oc = 0;
  for (uint8_t bit = kOutNear; bit <= kOutBottom; bit = static_cast<uint8_t>(bit << 1)) {
    if (plane_distance(fc, bit, v) < 0) oc |= bit;
  }
  return oc;  // the clip planes only; callers add kNoProjection
}

int32_t depth_q(const FrameCamera& fc, int32_t z) {
  if (z < fc.near_raw) z = fc.near_raw;
  const int32_t q = div_shl_round_sat(fc.near_raw, z, kQFracBits);  // <= 2^30
  return q - (q >> 15);
}

int clip_polygon(const FrameCamera& fc, uint8_t planes, const ClipVertex* in, int n, ClipVertex* out,
                 ClipVertex* tmp, int num_attribs) {
  // Ping-pong between out and tmp so the result ends in out.
  int count = 0;
  for (uint8_t bit = kOutNear; bit <= kOutBottom; bit = static_cast<uint8_t>(bit << 1))
    if (planes & bit) ++count;
  if (count == 0) {
    for (int i = 0; i < n && i < kMaxPolyVerts; ++i) out[i] = in[i];
    return n < kMaxPolyVerts ? n : kMaxPolyVerts;
  }
  const ClipVertex* src = in;
  ClipVertex* dst = (count & 1) ? out : tmp;
  for (uint8_t bit = kOutNear; bit <= kOutBottom; bit = static_cast<uint8_t>(bit << 1)) {
    if (!(planes & bit)) continue;
    int m = 0;
    for (int i = 0; i < n; ++i) {
      const ClipVertex& a = src[i];
      const ClipVertex& b = src[i + 1 < n ? i + 1 : 0];
      const int64_t da = plane_distance(fc, bit, a);
      const int64_t db = plane_distance(fc, bit, b);
      if (da >= 0) {
        if (m < kMaxPolyVerts) dst[m++] = a;
        if (db < 0 && m < kMaxPolyVerts) dst[m++] = intersect(a, b, da, db, bit, fc, num_attribs);
      } else if (db >= 0 && m < kMaxPolyVerts) {
        dst[m++] = intersect(b, a, db, da, bit, fc, num_attribs);
      }
    }
    n = m;
    src = dst;
    dst = (dst == out) ? tmp : out;
    if (n < 3) return 0;
  }
  return n;
}

}  // namespace vds::detail
