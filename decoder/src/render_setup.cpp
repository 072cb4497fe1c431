// Polygon setup and span filling of the renderer: plane equations of 1/z and
// of the perspective numerators (u/z, v/z, colour/z, or the rows of a view
// homography), exact span start values, one reciprocal per pixel
// (an interpolated table), nearest / bilinear texture
// sampling and the z-test. The rule u = (a x + b y + c) / (g x + h y + i) is
// rational linear interpolation (Heckbert, "Fundamentals of texture mapping
// and image warping", 1989); the fixed-point scaling is in docs/renderer.md.
#include <type_traits>

#include "render_internal.h"
#include "vds/config.h"
#include "vds/render_raster.h"
#include "colour.h"

namespace vds::detail {

namespace {

// ---------------------------------------------------------------------------
// Integer helpers
// ---------------------------------------------------------------------------
int bitlen64(uint64_t v) { return 64 - clz64(v); }
uint64_t abs64(int64_t v) { return v < 0 ? 0 - static_cast<uint64_t>(v) : static_cast<uint64_t>(v); }
int64_t wrap_add64(int64_t a, int64_t b) { return static_cast<int64_t>(static_cast<uint64_t>(a) + static_cast<uint64_t>(b)); }
int64_t wrap_mul64(int64_t a, int64_t b) { return static_cast<int64_t>(static_cast<uint64_t>(a) * static_cast<uint64_t>(b)); }
int32_t wrap_add32(int32_t a, int32_t b) { return static_cast<int32_t>(static_cast<uint32_t>(a) + static_cast<uint32_t>(b)); }

constexpr int64_t kSat62 = int64_t{1} << 62;

// v * 2^-s: s >= 0 a floor shift, s < 0 a left shift saturated at +-2^62.
int64_t shift_floor(int64_t v, int s) {
  if (s >= 0) return s >= 63 ? (v < 0 ? -1 : 0) : (v >> s);
  const int l = -s;
  if (l >= 62 || abs64(v) >= (uint64_t{1} << (62 - l))) return v < 0 ? -kSat62 : (v == 0 ? 0 : kSat62);
  return static_cast<int64_t>(static_cast<uint64_t>(v) << l);
}
// The same, rounded to nearest (ties up) for s > 0.
int64_t shift_round(int64_t v, int s) {
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

int64_t eval(const Plane& p, int32_t dx, int32_t dy) {
  // |gx dx| < 2^47 * 2^14 each: the sum stays below 2^62.6 (wrap-safe anyway).
  return wrap_add64(wrap_add64(p.a0, wrap_mul64(p.gx, dx)), wrap_mul64(p.gy, dy));
}

// 1/den ~= mant * 2^-shift for den > 0, 31 significant bits.
struct Inv {
  uint32_t mant;
  int shift;
};
Inv inverse(uint64_t den) {
  const int nb = bitlen64(den);
  const uint32_t m = nb > 32 ? static_cast<uint32_t>(den >> (nb - 32)) : static_cast<uint32_t>(den << (32 - nb));
  // recip_mant(m) = floor(2^63 / m) and den ~= m 2^(nb - 32).
  return {recip_mant(m), 31 + nb};
}

// num * 2^extra / den (den from inverse()), saturated to +-kGradLimit.
int64_t mul_inv(int64_t num, Inv inv, int extra) {
  if (num == 0) return 0;
  const bool neg = num < 0;
  uint64_t u = abs64(num);
  int sn = bitlen64(u) - 31;
  if (sn < 0) sn = 0;
  u >>= sn;
  const uint64_t p = u * inv.mant;  // < 2^63
  const int e = sn + extra - inv.shift;
  uint64_t r;
  if (e >= 0) {
    if (e >= 47 || p >= (static_cast<uint64_t>(kGradLimit) >> e)) {
      r = static_cast<uint64_t>(kGradLimit);
    } else {
      r = p << e;
    }
  } else {
    r = (-e >= 64) ? 0 : ((p >> (-e - 1)) + 1) >> 1;  // rounded
    if (r > static_cast<uint64_t>(kGradLimit)) r = static_cast<uint64_t>(kGradLimit);
  }
  return neg ? -static_cast<int64_t>(r) : static_cast<int64_t>(r);
}

// The plane through three vertices (Q24.8 positions) with values A (|A| <=
// 2^31): dA/dx = (dA1 dy2 - dA2 dy1) / area2, dA/dy = (dx1 dA2 - dx2 dA1) / area2
// per 1/256 pixel, times 2^8 per pixel, times 2^16 for Q.16.
Plane plane_from(const ScreenVertex& a, const ScreenVertex& b, const ScreenVertex& c, const int64_t val[3],
                 Inv inv, bool negative_area, int32_t xr, int32_t yr) {
  const int64_t da1 = val[1] - val[0], da2 = val[2] - val[0];  // < 2^32
  const int64_t dx1 = int64_t{b.x} - a.x, dy1 = int64_t{b.y} - a.y;
  const int64_t dx2 = int64_t{c.x} - a.x, dy2 = int64_t{c.y} - a.y;  // < 2^22
  const int64_t nx = da1 * dy2 - da2 * dy1;                            // < 2^55
  const int64_t ny = dx1 * da2 - dx2 * da1;
  Plane p;
  p.gx = mul_inv(nx, inv, 24);
  p.gy = mul_inv(ny, inv, 24);
  if (negative_area) {
    p.gx = -p.gx;
    p.gy = -p.gy;
  }
  // Value at the centre of pixel (xr, yr), offsets in 1/256 pixel.
  const int64_t ox = int64_t{xr} * 256 + 128 - a.x;
  const int64_t oy = int64_t{yr} * 256 + 128 - a.y;
  p.a0 = wrap_add64(val[0] * (int64_t{1} << kPlaneFrac), shift_floor(wrap_add64(wrap_mul64(p.gx, ox), wrap_mul64(p.gy, oy)), 8));
  return p;
}

// The plane of c0 x + c1 y + c2 at pixel centres (x + 1/2, y + 1/2), |c| < 2^31.
Plane plane_linear(int64_t c0, int64_t c1, int64_t c2, int32_t xr, int32_t yr) {
  Plane p;
  p.gx = c0 * (int64_t{1} << kPlaneFrac);
  p.gy = c1 * (int64_t{1} << kPlaneFrac);
  // (c0 (2 xr + 1) + c1 (2 yr + 1) + 2 c2) 2^15: below 3 * 2^31 * 2^15 * 2^15.
  p.a0 = (c0 * (2 * int64_t{xr} + 1) + c1 * (2 * int64_t{yr} + 1) + 2 * c2) * (int64_t{1} << (kPlaneFrac - 1));
  return p;
}

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

template <TexAddress A>
inline int32_t tx(int32_t u, int32_t mask, int32_t max) {
  if constexpr (A == TexAddress::repeat) {
    return u & mask;
  } else {
    return u < 0 ? 0 : (u > max ? max : u);
  }
}

// Colours: rgb565 as uint16_t, 8-bit channels as 0x00RRGGBB.
inline uint32_t expand565(uint32_t c) {
  const uint32_t r = c >> 11, g = (c >> 5) & 63, b = c & 31;
  return ((r << 3 | r >> 2) << 16) | ((g << 2 | g >> 4) << 8) | (b << 3 | b >> 2);
}
// Rounded to nearest: r5 = round(r 31 / 255) = (r 249 + 1014) >> 11 and
// g6 = round(g 63 / 255) = (g 253 + 505) >> 10, exact for every 8-bit value.
inline uint16_t pack565(uint32_t c) {
  const uint32_t r = (c >> 16) & 255, g = (c >> 8) & 255, b = c & 255;
  return static_cast<uint16_t>((((r * 249 + 1014) >> 11) << 11) | (((g * 253 + 505) >> 10) << 5) |
                               ((b * 249 + 1014) >> 11));
}

// JFIF full-range Y'CbCr -> R'G'B' (colour.h, the image output's
// constants), each channel rounded and clamped.
inline uint32_t ycbcr_to_rgb(int32_t y, int32_t cb, int32_t cr) {
  using namespace colour;
  const int32_t cbd = cb - kChromaCentre, crd = cr - kChromaCentre;
  const int32_t r = y + ((kCrToR * crd + kHalf) >> kFracBits);
  const int32_t g = y + ((-kCbToG * cbd - kCrToG * crd + kHalf) >> kFracBits);
  const int32_t b = y + ((kCbToB * cbd + kHalf) >> kFracBits);
  return (static_cast<uint32_t>(sat_u8(r)) << 16) | (static_cast<uint32_t>(sat_u8(g)) << 8) | sat_u8(b);
}

// Blend of two 0x00RR00BB (or 0x0000GG00) words with an 8-bit weight f of b:
// (a 256 + (b - a) f + 128) >> 8 per field is a (256 - f) + b f rounded; the
// fields are 16 bits apart and each sum stays below 2^16, so the packed
// arithmetic is exact (modulo 2^32 on the way, exact at the end).
inline uint32_t lerp_rb(uint32_t a, uint32_t b, uint32_t f) { return (((a << 8) + (b - a) * f + 0x00800080u) >> 8) & 0x00FF00FFu; }
inline uint32_t lerp_g(uint32_t a, uint32_t b, uint32_t f) { return (((a << 8) + (b - a) * f + 0x00008000u) >> 8) & 0x0000FF00u; }
inline uint32_t bilerp8888(uint32_t c00, uint32_t c01, uint32_t c10, uint32_t c11, uint32_t fu, uint32_t fv) {
  const uint32_t rb0 = lerp_rb(c00 & 0xFF00FFu, c01 & 0xFF00FFu, fu);
  const uint32_t rb1 = lerp_rb(c10 & 0xFF00FFu, c11 & 0xFF00FFu, fu);
  const uint32_t g0 = lerp_g(c00 & 0xFF00u, c01 & 0xFF00u, fu);
  const uint32_t g1 = lerp_g(c10 & 0xFF00u, c11 & 0xFF00u, fu);
  return lerp_rb(rb0, rb1, fv) | lerp_g(g0, g1, fv);
}
inline uint32_t lerp8(uint32_t a, uint32_t b, uint32_t f) { return ((a << 8) + (b - a) * f + 128) >> 8 & 0xFFu; }

// RGB565 spread to 0b00000GGGGGG00000RRRRR000000BBBBB: every channel gets 5
// spare bits above it, enough for a blend with a 5-bit weight (0..32).
constexpr uint32_t kSpreadMask = 0x07E0F81Fu;
constexpr uint32_t kSpreadRound = 16u | (16u << 11) | (16u << 21);
inline uint32_t spread565(uint32_t c) { return (c | (c << 16)) & kSpreadMask; }
inline uint32_t lerp_spread(uint32_t a, uint32_t b, uint32_t f5) { return (((a << 5) + (b - a) * f5 + kSpreadRound) >> 5) & kSpreadMask; }
inline uint16_t unspread565(uint32_t s) { return static_cast<uint16_t>((s | (s >> 16)) & 0xFFFFu); }

template <PixelFormat O>
using OutColor = std::conditional_t<O == PixelFormat::rgb565, uint16_t, uint32_t>;

template <PixelFormat O>
inline OutColor<O> from8888(uint32_t c) {
  if constexpr (O == PixelFormat::rgb565) {
    return pack565(c);
  } else {
    return c & 0xFFFFFFu;
  }
}
template <PixelFormat O>
inline OutColor<O> from565(uint32_t c) {
  if constexpr (O == PixelFormat::rgb565) {
    return static_cast<uint16_t>(c);
  } else {
    return expand565(c);
  }
}

// One rgb565 / xrgb8888 texel at a linear index, as 0x00RRGGBB.
template <TexFormat TF>
inline uint32_t texel8888(const TexCtx& t, uint32_t index) {
  if constexpr (TF == TexFormat::rgb565) {
    return expand565(reinterpret_cast<const uint16_t*>(t.base)[index]);
  } else {
    return reinterpret_cast<const uint32_t*>(t.base)[index];
  }
}

template <TexFormat TF, TexAddress A, PixelFormat O>
struct NearestSampler {
  static constexpr int kFracBits = 0;
  static constexpr bool kInlineStart = TF == TexFormat::rgb565 && O == PixelFormat::rgb565;
  // (u, v): the texel containing the sample point.
  static OutColor<O> sample(const TexCtx& t, int32_t u, int32_t v) {
    const int32_t col = tx<A>(u, t.wmask, t.wmax);
    const int32_t row = tx<A>(v, t.hmask, t.hmax);
    const uint32_t index = static_cast<uint32_t>(row) * t.stride + static_cast<uint32_t>(col);
    if constexpr (TF == TexFormat::rgb565) {
      return from565<O>(reinterpret_cast<const uint16_t*>(t.base)[index]);
    } else if constexpr (TF == TexFormat::xrgb8888) {
      return from8888<O>(reinterpret_cast<const uint32_t*>(t.base)[index]);
    } else {
      // The chroma sample (col/2, row/2) covers luma texels 2i and 2i + 1.
      const uint32_t ci = static_cast<uint32_t>(row >> 1) * t.cstride + static_cast<uint32_t>(col >> 1);
      return from8888<O>(ycbcr_to_rgb(t.base[index], t.cb[ci], t.cr[ci]));
    }
  }
};

// Bilinear weights: 5 bits where both texture and output are rgb565 (the
// blend runs on all three channels at once in one 32-bit word), else 8 bits.
constexpr int bilinear_frac_bits(TexFormat tf, PixelFormat o) {
  return tf == TexFormat::rgb565 && o == PixelFormat::rgb565 ? 5 : 8;
}

template <TexFormat TF, TexAddress A, PixelFormat O>
struct BilinearSampler {
  static constexpr int kFracBits = bilinear_frac_bits(TF, O);
  static constexpr bool kInlineStart = TF == TexFormat::rgb565 && O == PixelFormat::rgb565;
  static constexpr uint32_t kFracMask = (1u << kFracBits) - 1;
  // (u, v): the sample point minus half a texel, kFracBits fraction bits.
  static OutColor<O> sample(const TexCtx& t, int32_t u, int32_t v) {
    const int32_t i0 = u >> kFracBits, j0 = v >> kFracBits;
    const uint32_t fu = static_cast<uint32_t>(u) & kFracMask, fv = static_cast<uint32_t>(v) & kFracMask;
    const uint32_t c0 = static_cast<uint32_t>(tx<A>(i0, t.wmask, t.wmax));
    const uint32_t c1 = static_cast<uint32_t>(tx<A>(i0 + 1, t.wmask, t.wmax));
    const uint32_t r0 = static_cast<uint32_t>(tx<A>(j0, t.hmask, t.hmax)) * t.stride;
    const uint32_t r1 = static_cast<uint32_t>(tx<A>(j0 + 1, t.hmask, t.hmax)) * t.stride;
    if constexpr (TF == TexFormat::ycbcr420) {
      const uint8_t* y = t.base;
      const uint32_t yy = lerp8(lerp8(y[r0 + c0], y[r0 + c1], fu), lerp8(y[r1 + c0], y[r1 + c1], fu), fv);
      // In chroma texels the point is u/2, minus half a chroma texel:
      // (u_q8 + 128)/2 - 128 = u_q8/2 - 64.
      const int32_t cu = (u >> 1) - 64, cv = (v >> 1) - 64;
      const uint32_t gu = static_cast<uint32_t>(cu) & 255u, gv = static_cast<uint32_t>(cv) & 255u;
      const uint32_t k0 = static_cast<uint32_t>(tx<A>(cu >> 8, t.cwmask, t.cwmax));
      const uint32_t k1 = static_cast<uint32_t>(tx<A>((cu >> 8) + 1, t.cwmask, t.cwmax));
      const uint32_t s0 = static_cast<uint32_t>(tx<A>(cv >> 8, t.chmask, t.chmax)) * t.cstride;
      const uint32_t s1 = static_cast<uint32_t>(tx<A>((cv >> 8) + 1, t.chmask, t.chmax)) * t.cstride;
      const uint32_t cb = lerp8(lerp8(t.cb[s0 + k0], t.cb[s0 + k1], gu), lerp8(t.cb[s1 + k0], t.cb[s1 + k1], gu), gv);
      const uint32_t cr = lerp8(lerp8(t.cr[s0 + k0], t.cr[s0 + k1], gu), lerp8(t.cr[s1 + k0], t.cr[s1 + k1], gu), gv);
      return from8888<O>(ycbcr_to_rgb(static_cast<int32_t>(yy), static_cast<int32_t>(cb), static_cast<int32_t>(cr)));
    } else if constexpr (TF == TexFormat::rgb565 && O == PixelFormat::rgb565) {
      const uint16_t* p = reinterpret_cast<const uint16_t*>(t.base);
      const uint32_t top = lerp_spread(spread565(p[r0 + c0]), spread565(p[r0 + c1]), fu);
      const uint32_t bot = lerp_spread(spread565(p[r1 + c0]), spread565(p[r1 + c1]), fu);
      return unspread565(lerp_spread(top, bot, fv));
    } else {
      return from8888<O>(bilerp8888(texel8888<TF>(t, r0 + c0), texel8888<TF>(t, r0 + c1), texel8888<TF>(t, r1 + c0),
                                    texel8888<TF>(t, r1 + c1), fu, fv));
    }
  }
};

// Bilinear filtering of a texture with an apron (Texture::apron): the right
// and lower neighbours are at +1 and +stride whatever the addressing. Clamp
// addressing clamps the sample position to [0, size - 1] before splitting it,
// which gives exactly the clamp-to-edge result (the neighbour then has weight 0).
template <TexFormat TF, TexAddress A, PixelFormat O>
struct BilinearApronSampler {
  static constexpr int kFracBits = bilinear_frac_bits(TF, O);
  static constexpr bool kInlineStart = TF == TexFormat::rgb565 && O == PixelFormat::rgb565;
  static constexpr uint32_t kFracMask = (1u << kFracBits) - 1;
  static OutColor<O> sample(const TexCtx& t, int32_t u, int32_t v) {
    uint32_t index;
    uint32_t fu, fv;
    if constexpr (A == TexAddress::repeat) {
      index = static_cast<uint32_t>((v >> kFracBits) & t.hmask) * t.stride + static_cast<uint32_t>((u >> kFracBits) & t.wmask);
      fu = static_cast<uint32_t>(u) & kFracMask;
      fv = static_cast<uint32_t>(v) & kFracMask;
    } else {
      const int32_t uc = u < 0 ? 0 : (u > (t.wmax << kFracBits) ? (t.wmax << kFracBits) : u);
      const int32_t vc = v < 0 ? 0 : (v > (t.hmax << kFracBits) ? (t.hmax << kFracBits) : v);
      index = static_cast<uint32_t>(vc >> kFracBits) * t.stride + static_cast<uint32_t>(uc >> kFracBits);
      fu = static_cast<uint32_t>(uc) & kFracMask;
      fv = static_cast<uint32_t>(vc) & kFracMask;
    }
    if constexpr (TF == TexFormat::rgb565 && O == PixelFormat::rgb565) {
      // The lower row by index, not by a second pointer: one register less
      // in the span loop.
      const uint16_t* p = reinterpret_cast<const uint16_t*>(t.base);
      const uint32_t below = index + t.stride;
      const uint32_t top = lerp_spread(spread565(p[index]), spread565(p[index + 1]), fu);
      const uint32_t bot = lerp_spread(spread565(p[below]), spread565(p[below + 1]), fu);
      return unspread565(lerp_spread(top, bot, fv));
    } else {
      return from8888<O>(bilerp8888(texel8888<TF>(t, index), texel8888<TF>(t, index + 1), texel8888<TF>(t, index + t.stride),
                                    texel8888<TF>(t, index + t.stride + 1), fu, fv));
    }
  }
};

// ---------------------------------------------------------------------------
// Output and depth buffers
// ---------------------------------------------------------------------------
template <PixelFormat O>
struct Store;
template <>
struct Store<PixelFormat::rgb565> {
  static constexpr int kBytes = 2;
  static void put(uint8_t* p, uint16_t c) { *reinterpret_cast<uint16_t*>(p) = c; }
};
template <>
struct Store<PixelFormat::rgb888> {
  static constexpr int kBytes = 3;
  static void put(uint8_t* p, uint32_t c) {
    p[0] = static_cast<uint8_t>(c >> 16);
    p[1] = static_cast<uint8_t>(c >> 8);
    p[2] = static_cast<uint8_t>(c);
  }
};

template <DepthFormat D>
struct Depth;
template <>
struct Depth<DepthFormat::d16> {
  using T = uint16_t;
  static T value(int32_t q) { return static_cast<uint16_t>(q >> kDepth16Shift); }  // q < 2^30
};
template <>
struct Depth<DepthFormat::d32> {
  using T = uint32_t;
  static T value(int32_t q) { return static_cast<uint32_t>(q); }
};

// ---------------------------------------------------------------------------
// Polygon setup and span start values
// ---------------------------------------------------------------------------
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
  // Fast span set-up (fast == true): the planes' own scale serves the whole
  // polygon (chosen from the values at its vertices with a margin), so a span
  // start is (a0 + gx dx + gy dy + 2^15) >> 16 and the steps are fixed. A
  // span whose start and end values stay inside [wlo, whi] (divisor) and
  // +-kNumLimit (numerators) uses them; any other takes the per-span path.
  bool fast;
  int32_t fast_shb;
  int32_t fast_dq, fast_dw, fast_dn[3];
  int32_t wlo, whi;
  int32_t fast_qlo, fast_qhi;  // [1, kQMax] and [wlo, whi] together (q is W), not empty
};

// Integer state of one span piece: values at its first pixel and per-pixel
// steps. Every value stays inside int32 over the piece (both ends checked),
// W >= 1 throughout, and sh_base - clz(W) lies in [0, 31] for every pixel.
struct RowState {
  int32_t q, dq;
  int32_t w, dw;
  int32_t n[3], dn[3];
  int32_t sh_base;
};

constexpr int64_t kI32Max = INT32_MAX;
constexpr int64_t kI32Min = INT32_MIN;

// Start value (plane / 2^s rounded) and step of one interpolant over `len`
// pixels; the step is dropped (0) if the stepped end would leave [lo, hi].
void interpolant(int64_t start_q16, int64_t gx, int s, int32_t len, int64_t lo, int64_t hi, int32_t* v, int32_t* dv) {
  int64_t a = shift_round(start_q16, s);
  a = a < lo ? lo : (a > hi ? hi : a);
  int64_t d = shift_round(gx, s);
  d = d < kI32Min ? kI32Min : (d > kI32Max ? kI32Max : d);
  const int64_t end = a + d * (len - 1);  // |d (len - 1)| < 2^31 * 2^11
  if (end < lo || end > hi) d = 0;
  *v = static_cast<int32_t>(a);
  *dv = static_cast<int32_t>(d);
}

constexpr int64_t kNumLimit = (int64_t{1} << 30) + 4096;  // |numerator| bound of a span

// The per-pixel step of a plane in row units: gx / 2^16 rounded, saturated.
inline int32_t step16(int64_t gx) {
  const int64_t d = (gx + (int64_t{1} << (kPlaneFrac - 1))) >> kPlaneFrac;
  return static_cast<int32_t>(d < kI32Min ? kI32Min : (d > kI32Max ? kI32Max : d));
}

// Row units from a plane value: rounded, the 16 fraction bits dropped.
inline int64_t row_value(const Plane& p, int32_t dx, int32_t dy) {
  return wrap_add64(eval(p, dx, dy), int64_t{1} << (kPlaneFrac - 1)) >> kPlaneFrac;
}

// v in [lo, hi] with one unsigned compare (no overflow: unsigned arithmetic).
inline bool in_range(int64_t v, int64_t lo, int64_t hi) {
  return static_cast<uint64_t>(v) - static_cast<uint64_t>(lo) <= static_cast<uint64_t>(hi - lo);
}

// The fast span set-up (PolySetup::fast): start values from the planes, the
// polygon's fixed steps and exponent, and a check that both ends of the span
// stay inside the limits the exponent was chosen for. false sends the span
// to the general row_piece(). NN numerators, kProj a separate divisor.
template <int NN, bool kProj>
[[gnu::always_inline]] inline bool row_fast(const PolySetup& s, int32_t y, int32_t x, int32_t len, RowState& r) {
  if (!s.fast) return false;
  const int32_t dx = x - s.xr, dy = y - s.yr;
  const int64_t last = len - 1;
  const int64_t q0 = row_value(s.q, dx, dy);
  const int64_t q1 = q0 + int64_t{s.fast_dq} * last;
  // q is also the divisor unless kProj: one check against both ranges.
  const int64_t qlo = NN > 0 && !kProj ? s.fast_qlo : 1, qhi = NN > 0 && !kProj ? s.fast_qhi : kQMax;
  if (!in_range(q0, qlo, qhi) || !in_range(q1, qlo, qhi)) return false;
  r.q = static_cast<int32_t>(q0);
  r.dq = s.fast_dq;
  if constexpr (NN > 0) {
    int64_t w0 = q0, w1 = q1;
    if constexpr (kProj) {
      w0 = row_value(s.w, dx, dy);
      w1 = w0 + int64_t{s.fast_dw} * last;
      if (!in_range(w0, s.wlo, s.whi) || !in_range(w1, s.wlo, s.whi)) return false;
    }
    r.w = static_cast<int32_t>(w0);
    r.dw = s.fast_dw;
    for (int j = 0; j < NN; ++j) {
      const int64_t n0 = row_value(s.n[j], dx, dy);
      const int64_t n1 = n0 + int64_t{s.fast_dn[j]} * last;
      if (!in_range(n0, -kNumLimit, kNumLimit) || !in_range(n1, -kNumLimit, kNumLimit)) return false;
      r.n[j] = static_cast<int32_t>(n0);
      r.dn[j] = s.fast_dn[j];
    }
    r.sh_base = s.fast_shb;
  }
  return true;
}

// The same as a function of its own: most span loops call it, so that it is
// not copied into each of them (see texture_span).
template <int NN, bool kProj>
[[gnu::noinline]] bool row_fast_call(const PolySetup& s, int32_t y, int32_t x, int32_t len, RowState& r) {
  return row_fast<NN, kProj>(s, y, x, len, r);
}

// Sets up the first `len` pixels of row y from x. false when the numerators
// and the divisor cannot share one shift window over this many pixels (the
// caller halves len; a single pixel always succeeds).
bool row_piece(const PolySetup& s, int32_t y, int32_t x, int32_t len, RowState& r) {
  const int32_t dx = x - s.xr, dy = y - s.yr;
  interpolant(eval(s.q, dx, dy), s.q.gx, kPlaneFrac, len, 1, kQMax, &r.q, &r.dq);
  if (s.nn == 0) return true;

  // The divisor W over the piece and its exponent ew (true W = W_row 2^ew).
  int ew = 0;
  int64_t w0, w1;
  if (s.proj) {
    const int64_t p0 = eval(s.w, dx, dy);
    const int64_t p1 = wrap_add64(p0, wrap_mul64(s.w.gx, len - 1));
    const uint64_t mx = abs64(p0) > abs64(p1) ? abs64(p0) : abs64(p1);
    ew = bitlen64(mx) - 46;  // W_row = P >> (16 + ew) below 2^30
    interpolant(p0, s.w.gx, kPlaneFrac + ew, len, 1, kI32Max, &r.w, &r.dw);
    w0 = r.w;
    w1 = int64_t{r.w} + int64_t{r.dw} * (len - 1);
  } else {
    r.w = r.q;
    r.dw = r.dq;
    w0 = r.q;
    w1 = int64_t{r.q} + int64_t{r.dq} * (len - 1);
  }
  const int z_lo = clz32(static_cast<uint32_t>(w0 > w1 ? w0 : w1));
  const int z_hi = clz32(static_cast<uint32_t>(w0 < w1 ? w0 : w1));

  int64_t pn[3];
  uint64_t mx = 0;
  for (int j = 0; j < s.nn; ++j) {
    pn[j] = eval(s.n[j], dx, dy);
    const int64_t e = wrap_add64(pn[j], wrap_mul64(s.n[j].gx, len - 1));
    if (abs64(pn[j]) > mx) mx = abs64(pn[j]);
    if (abs64(e) > mx) mx = abs64(e);
  }
  // result = N_row y' >> (32 + sh), sh = sh_base - z, sh_base = 30 - (bw + en)
  // with y' = recip_y(W) ~ 2^62 / (W 2^z) (docs/renderer.md).
  const int bw = s.b0 - ew;
  const int en_overflow = bitlen64(mx) - 46;  // |N_row| <= 2^30
  const int en_lo = -1 - z_lo - bw;           // sh <= 31 at the largest W
  const int en_hi = 30 - z_hi - bw;           // sh >= 0 at the smallest W
  int en = en_overflow > en_lo ? en_overflow : en_lo;
  if (en > en_hi) {
    if (len > 1) return false;
    // One pixel whose result overflows 32 bits (only wild input gets here):
    // sample at 0 instead.
    for (int j = 0; j < s.nn; ++j) r.n[j] = r.dn[j] = 0;
    r.sh_base = z_lo;
    return true;
  }
  r.sh_base = 30 - (bw + en);
  for (int j = 0; j < s.nn; ++j) {
    interpolant(pn[j], s.n[j].gx, kPlaneFrac + en, len, -(int64_t{1} << 30) - 4096, (int64_t{1} << 30) + 4096,
                &r.n[j], &r.dn[j]);
  }
  return true;
}

// The per-pixel reciprocal. For m = w << clz(w) in [2^31, 2^32) (x = m / 2^32
// in [1/2, 1)) it returns y ~= 2^62 / m = 2^30 / x by linear interpolation
// between value_k = round(2^30 / x_k), x_k = 1/2 + k/512, with slope_k =
// value_k - value_(k+1): y = value_k - slope_k t / 2^32 with t = m << 9 the
// position inside the interval (Q0.32). With m = (256 + k) 2^23 + low,
// slope_k (2^9 m) / 2^32 = slope_k (256 + k) + slope_k t / 2^32 exactly (the
// first term is whole), so the table stores base_k = value_k + slope_k (256
// + k) and slope_k 2^9 (below 2^32) and y = base_k - (slope_k 2^9 m) / 2^32,
// all modulo 2^32 (y itself is below 2^31): no shift of m. 2 KiB; 8
// Cortex-M4 instructions (CLZ, LSL, UBFX, ADD, LDR, LDR, UMULL, SUB) against
// 12 for a table seed plus a Newton step (vds::recip_mant_fast). The chord
// lies above the convex 1/x, so -2^-31 <= y / (2^62 / m) - 1 < 2^-18 (h^2/8
// max|f''| with h = 1/512, plus the rounding of the entries);
// tests/unit/render_test.cpp checks the bound. Each entry is one 64-bit
// word, slope_k 2^9 in the high half and base_k in the low half, so that it
// is one load whatever the byte order.
struct RecipTable {
  uint64_t e[256];
};
constexpr int32_t recip_node(uint64_t k) {
  const uint64_t v = ((uint64_t{1} << 40) / (256 + k) + 1) / 2;  // round(2^39 / (256 + k))
  return v > static_cast<uint64_t>(INT32_MAX) ? INT32_MAX : static_cast<int32_t>(v);  // the first clipped to 2^31 - 1
}
constexpr RecipTable make_recip_table() {
  RecipTable t{};
  for (uint64_t k = 0; k < 256; ++k) {
    const uint64_t slope = static_cast<uint64_t>(recip_node(k) - recip_node(k + 1));  // < 2^23
    const uint32_t base = static_cast<uint32_t>(static_cast<uint64_t>(recip_node(k)) + slope * (256 + k));
    t.e[k] = (slope << 9) << 32 | base;
  }
  return t;
}
constexpr RecipTable kRecipTable = make_recip_table();

inline int32_t recip_y(uint32_t w, int& z) {
  z = __builtin_clz(w);  // w >= 1 (row_piece keeps every W and q positive)
  const uint32_t m = w << z;
  const uint64_t e = kRecipTable.e[(m >> 23) & 255u];
  const uint32_t base = static_cast<uint32_t>(e), slope9 = static_cast<uint32_t>(e >> 32);
  return static_cast<int32_t>(base - static_cast<uint32_t>((uint64_t{slope9} * m) >> 32));
}
// round-down of n * y / 2^(32 + sh): SMULL and an arithmetic shift.
inline int32_t scaled(int32_t n, int32_t y, int sh) { return static_cast<int32_t>((int64_t{n} * y) >> 32) >> sh; }

// ---------------------------------------------------------------------------
// Span loops
// ---------------------------------------------------------------------------
template <PixelFormat O, DepthFormat D>
void flat_span(const BandTarget& b, const PolySetup& s, int32_t y, int32_t xa, int32_t xb) {
  using DT = typename Depth<D>::T;
  RowState r;
  if (!row_fast<0, false>(s, y, xa, xb - xa, r)) row_piece(s, y, xa, xb - xa, r);
  const OutColor<O> c = static_cast<OutColor<O>>(s.flat);
  // Both buffers are indexed from their span end with i = -len .. -1.
  DT* const ze = static_cast<DT*>(b.depth) + static_cast<uint32_t>(y - b.y0) * static_cast<uint32_t>(b.width) + xb;
  uint8_t* const oe = b.color + static_cast<uint32_t>(y - b.y0) * b.color_stride + xb * Store<O>::kBytes;
  int32_t q = r.q;
  const int32_t dq = r.dq;
  int32_t i = xa - xb;
  do {
    const DT d = Depth<D>::value(q);
    if (d > ze[i]) {
      ze[i] = d;
      Store<O>::put(oe + i * Store<O>::kBytes, c);
    }
    q = wrap_add32(q, dq);
  } while (++i != 0);
}

// Colour entry i of a span whose colour and depth rows end at oe and ze
// (delta = oe - ze in bytes). When colour and depth entries have the same
// size, the colour address is the depth address plus delta: the span loop
// then steps one pointer instead of two (one instruction per pixel less).
template <PixelFormat O, class DT>
inline uint8_t* pixel_at(uint8_t* oe, DT* ze, uintptr_t delta, int32_t i) {
  if constexpr (Store<O>::kBytes == sizeof(DT)) {
    return reinterpret_cast<uint8_t*>(reinterpret_cast<uintptr_t>(ze + i) + delta);
  } else if constexpr (2 * Store<O>::kBytes == sizeof(DT)) {
    // Half the depth address (depth entries are aligned) plus delta = oe - ze / 2.
    return reinterpret_cast<uint8_t*>((reinterpret_cast<uintptr_t>(ze + i) >> 1) + delta);
  } else {
    return oe + i * Store<O>::kBytes;
  }
}

template <class Sampler, bool kProj, PixelFormat O, DepthFormat D>
void texture_span(const BandTarget& b, const PolySetup& s, int32_t y, int32_t xa, int32_t xb) {
  using DT = typename Depth<D>::T;
  DT* const zrow = static_cast<DT*>(b.depth) + static_cast<uint32_t>(y - b.y0) * static_cast<uint32_t>(b.width);
  uint8_t* const crow = b.color + static_cast<uint32_t>(y - b.y0) * b.color_stride;
  const TexCtx tex = s.tex;  // a local copy: the stores below cannot alias it
  while (xa < xb) {
    int32_t len = xb - xa;
    RowState r;
    // The start values are inlined into the loops of rgb565 textures drawn
    // to rgb565 (about 1 instruction per pixel less in the scenes of
    // bench/results/render.md), called from the others (code size).
    bool fast;
    if constexpr (Sampler::kInlineStart && !kProj) {
      fast = row_fast<2, kProj>(s, y, xa, len, r);
    } else {
      fast = row_fast_call<2, kProj>(s, y, xa, len, r);
    }
    if (!fast) {
      while (!row_piece(s, y, xa, len, r)) len = (len + 1) >> 1;
    }
    // Both buffers are indexed from the piece end with i = -len .. -1.
    DT* const ze = zrow + xa + len;
    uint8_t* const oe = crow + (xa + len) * Store<O>::kBytes;
    const uintptr_t delta = reinterpret_cast<uintptr_t>(oe) -
                            (reinterpret_cast<uintptr_t>(ze) >> (sizeof(DT) == 2 * Store<O>::kBytes ? 1 : 0));
    int32_t q = r.q, w = r.w, u = r.n[0], v = r.n[1];
    const int32_t dq = r.dq, dw = r.dw, du = r.dn[0], dv = r.dn[1];
    const int32_t shb = r.sh_base;
    int32_t i = -len;
    do {
      const DT d = Depth<D>::value(q);
      if (d > ze[i]) {
        ze[i] = d;
        int z;
        const int32_t yr = recip_y(static_cast<uint32_t>(kProj ? w : q), z);
        const int sh = shb - z;
        Store<O>::put(pixel_at<O, DT>(oe, ze, delta, i), Sampler::sample(tex, scaled(u, yr, sh), scaled(v, yr, sh)));
      }
      q = wrap_add32(q, dq);
      if constexpr (kProj) w = wrap_add32(w, dw);
      u = wrap_add32(u, du);
      v = wrap_add32(v, dv);
    } while (++i != 0);
    xa += len;
  }
}

template <PixelFormat O, DepthFormat D>
void gouraud_span(const BandTarget& b, const PolySetup& s, int32_t y, int32_t xa, int32_t xb) {
  using DT = typename Depth<D>::T;
  DT* const zrow = static_cast<DT*>(b.depth) + static_cast<uint32_t>(y - b.y0) * static_cast<uint32_t>(b.width);
  uint8_t* const crow = b.color + static_cast<uint32_t>(y - b.y0) * b.color_stride;
  while (xa < xb) {
    int32_t len = xb - xa;
    RowState r;
    if (!row_fast<3, false>(s, y, xa, len, r)) {
      while (!row_piece(s, y, xa, len, r)) len = (len + 1) >> 1;
    }
    DT* const ze = zrow + xa + len;
    uint8_t* const oe = crow + (xa + len) * Store<O>::kBytes;
    int32_t q = r.q, c0 = r.n[0], c1 = r.n[1], c2 = r.n[2];
    int32_t i = -len;
    do {
      const DT d = Depth<D>::value(q);
      if (d > ze[i]) {
        ze[i] = d;
        int z;
        const int32_t yr = recip_y(static_cast<uint32_t>(q), z);
        const int sh = r.sh_base - z;
        // Channels in Q8.8, rounded to 8 bits.
        const uint32_t rr = sat_u8((scaled(c0, yr, sh) + 128) >> 8);
        const uint32_t gg = sat_u8((scaled(c1, yr, sh) + 128) >> 8);
        const uint32_t bb = sat_u8((scaled(c2, yr, sh) + 128) >> 8);
        Store<O>::put(oe + i * Store<O>::kBytes, from8888<O>((rr << 16) | (gg << 8) | bb));
      }
      q = wrap_add32(q, r.dq);
      c0 = wrap_add32(c0, r.dn[0]);
      c1 = wrap_add32(c1, r.dn[1]);
      c2 = wrap_add32(c2, r.dn[2]);
    } while (++i != 0);
    xa += len;
  }
}

// ---------------------------------------------------------------------------
// Span function selection (the formats compiled in: vds/config.h)
// ---------------------------------------------------------------------------
template <template <TexFormat, TexAddress, PixelFormat> class S, TexFormat TF, PixelFormat O, DepthFormat D>
SpanFn pick_address(bool repeat, bool proj) {
  if (repeat) {
    return proj ? &texture_span<S<TF, TexAddress::repeat, O>, true, O, D>
                : &texture_span<S<TF, TexAddress::repeat, O>, false, O, D>;
  }
  return proj ? &texture_span<S<TF, TexAddress::clamp, O>, true, O, D>
              : &texture_span<S<TF, TexAddress::clamp, O>, false, O, D>;
}

template <TexFormat TF, PixelFormat O, DepthFormat D>
SpanFn pick_filter(Filter f, bool apron, bool repeat, bool proj) {
  if (!(VDS_CONFIG_RENDER_TEXTURE_FORMATS & (1 << static_cast<int>(TF)))) return nullptr;
  if (f == Filter::nearest) return pick_address<NearestSampler, TF, O, D>(repeat, proj);
  if constexpr (TF != TexFormat::ycbcr420) {
    if (apron) return pick_address<BilinearApronSampler, TF, O, D>(repeat, proj);
  }
  return pick_address<BilinearSampler, TF, O, D>(repeat, proj);
}

template <PixelFormat O, DepthFormat D>
SpanFn pick_span(const Mesh& m, bool repeat) {
  if (!(VDS_CONFIG_RENDER_OUTPUT_FORMATS & (1 << static_cast<int>(O)))) return nullptr;
  if (!(VDS_CONFIG_RENDER_DEPTH_FORMATS & (1 << static_cast<int>(D)))) return nullptr;
  switch (m.shading) {
    case Shading::flat: return &flat_span<O, D>;
    case Shading::gouraud: return &gouraud_span<O, D>;
    default: break;
  }
  const bool proj = m.shading == Shading::view_mapped;
  const bool apron = m.texture->apron;
  switch (m.texture->format) {
    case TexFormat::rgb565: return pick_filter<TexFormat::rgb565, O, D>(m.filter, apron, repeat, proj);
    case TexFormat::xrgb8888: return pick_filter<TexFormat::xrgb8888, O, D>(m.filter, apron, repeat, proj);
    case TexFormat::ycbcr420: return pick_filter<TexFormat::ycbcr420, O, D>(m.filter, apron, repeat, proj);
  }
  return nullptr;
}

SpanFn select_span(const PolygonTarget& b, const Mesh& m, bool repeat) {
  if (b.format == PixelFormat::rgb565) {
    return b.depth_format == DepthFormat::d16 ? pick_span<PixelFormat::rgb565, DepthFormat::d16>(m, repeat)
                                              : pick_span<PixelFormat::rgb565, DepthFormat::d32>(m, repeat);
  }
  return b.depth_format == DepthFormat::d16 ? pick_span<PixelFormat::rgb888, DepthFormat::d16>(m, repeat)
                                            : pick_span<PixelFormat::rgb888, DepthFormat::d32>(m, repeat);
}

bool is_pow2(uint32_t v) { return v != 0 && (v & (v - 1)) == 0; }

TexCtx make_tex_ctx(const Texture& t, bool repeat) {
  TexCtx c{};
  c.base = static_cast<const uint8_t*>(t.texels);
  c.stride = t.stride;
  c.wmask = t.width - 1;
  c.hmask = t.height - 1;
  c.wmax = t.width - 1;
  c.hmax = t.height - 1;
  if (t.format == TexFormat::ycbcr420) {
    const int32_t cw = (t.width + 1) / 2, ch = (t.height + 1) / 2;
    c.cb = t.cb;
    c.cr = t.cr;
    c.cstride = t.chroma_stride;
    c.cwmask = cw - 1;
    c.chmask = ch - 1;
    c.cwmax = cw - 1;
    c.chmax = ch - 1;
  }
  (void)repeat;
  return c;
}

int64_t floor_div(int64_t a, int64_t b) {  // b > 0
  int64_t q = a / b;
  if (q * b > a) --q;
  return q;
}
int32_t floor_div32(int32_t a, int32_t b) {  // b > 0; a hardware division on Cortex-M4
  int32_t q = a / b;
  if (q * b > a) --q;
  return q;
}

int fraction_bits(const Mesh& m, PixelFormat out) {
  return m.filter == Filter::nearest ? 0 : bilinear_frac_bits(m.texture->format, out);
}

}  // namespace

int32_t span_reciprocal(uint32_t w, int* z) {
  int zz = 0;
  const int32_t y = recip_y(w ? w : 1u, zz);
  *z = zz;
  return y;
}

bool texture_repeats(const Texture& t) {
  return t.address == TexAddress::repeat && is_pow2(t.width) && is_pow2(t.height);
}

// A polygon set up for rasterisation: everything draw_polygon computes that
// does not depend on the band, so that one set-up serves every band the
// polygon crosses (RenderConfig::setup_cache).
struct PreparedPolygon {
  PolySetup s;
  SpanFn fn;                        // nullptr: nothing to draw (culled, off screen, compiled out)
  int32_t row_begin, row_end;       // rows [row_begin, row_end) the polygon can cover
  int32_t n;                        // outline vertices
  bool culled;                      // facing or zero area (counted per band it touches)
  bool set_up;                      // planes computed (counted per band it touches)
  RasterVertex outline[kMaxPolyVerts];
};

size_t prepared_polygon_bytes() { return sizeof(PreparedPolygon); }
size_t prepared_polygon_align() { return alignof(PreparedPolygon); }

void prepare_polygon(const PolygonTarget& target, const MaterialCtx& mat, const ScreenVertex* v, int n, PreparedPolygon* pp) {
  pp->fn = nullptr;
  pp->culled = false;
  pp->set_up = false;
  pp->n = n;
  // Rows and columns the polygon can touch (pixel centres inside its box).
  int32_t xmin = v[0].x, xmax = v[0].x, ymin = v[0].y, ymax = v[0].y;
  for (int i = 1; i < n; ++i) {
    xmin = v[i].x < xmin ? v[i].x : xmin;
    xmax = v[i].x > xmax ? v[i].x : xmax;
    ymin = v[i].y < ymin ? v[i].y : ymin;
    ymax = v[i].y > ymax ? v[i].y : ymax;
  }
  pp->row_begin = raster_row(ymin);
  pp->row_end = raster_row(ymax);
  if (xmin < -kRasterCoordLimit || xmax > kRasterCoordLimit || ymin < -kRasterCoordLimit || ymax > kRasterCoordLimit) {
    return;  // cannot happen after guard-band clipping; kept as a hard limit
  }
  if (raster_row(xmax) <= 0 || raster_row(xmin) >= target.width) return;
  for (int i = 0; i < n; ++i) pp->outline[i] = {v[i].x, v[i].y};

  // Orientation and the best-conditioned fan triangle for the planes.
  int64_t area = 0, best = 0;
  int bi = 1;
  for (int i = 1; i + 1 < n; ++i) {
    const int64_t a = int64_t{v[i].x - v[0].x} * (v[i + 1].y - v[0].y) - int64_t{v[i + 1].x - v[0].x} * (v[i].y - v[0].y);
    area += a;
    if (abs64(a) > abs64(best)) {
      best = a;
      bi = i;
    }
  }
  const Mesh& m = *mat.mesh;
  if (area == 0 || best == 0 || (m.cull == Cull::back && area > 0) || (m.cull == Cull::front && area < 0)) {
    pp->culled = true;
    return;
  }
  pp->set_up = true;

  const ScreenVertex& a = v[0];
  const ScreenVertex& b = v[bi];
  const ScreenVertex& c = v[bi + 1];
  const Inv inv = inverse(abs64(best));
  const bool neg = best < 0;
  // Every field the span functions read is set below (no zeroing of the
  // whole struct: it is a few hundred bytes and this runs per triangle).
  PolySetup& s = pp->s;
  s.xr = a.x >> 8;
  s.yr = a.y >> 8;
  s.nn = 0;
  s.proj = false;
  s.b0 = 0;
  s.flat = 0;
  s.fast = false;
  s.wlo = 1;
  s.whi = kQMax;
  {
    const int64_t qv[3] = {a.q, b.q, c.q};
    s.q = plane_from(a, b, c, qv, inv, neg, s.xr, s.yr);
  }
  s.fast_dq = step16(s.q.gx);
  const int ref[3] = {0, bi, bi + 1};
  bool repeat = false;

  // The divisor W and the numerators N at every vertex of the polygon, in
  // their natural scale, give the exponents kw and kn of the planes: N / 2^kn
  // below 2^30, W / 2^kw below 2^30, and, when one set of exponents serves
  // the whole polygon (the fast span set-up, checked per span anyway), kn
  // raised until sh = 30 - (g + kn - kw) - clz(W) stays in [0, 31].
  // Extremes over the vertices, and N at the three vertices of the plane
  // fit (kept instead of all vertices' values: this runs on a small stack).
  int64_t wmin = INT64_MAX, wmax = INT64_MIN;
  uint64_t nmax = 0;
  int64_t nref[3][3];
  auto note = [&](int i, int64_t w, const int64_t* nvals, int count) __attribute__((always_inline)) {
    wmin = w < wmin ? w : wmin;
    wmax = w > wmax ? w : wmax;
    // Which vertex of the plane fit i is, if any (ref[] holds distinct values).
    const int k = i == ref[0] ? 0 : (i == ref[1] ? 1 : (i == ref[2] ? 2 : -1));
    for (int j = 0; j < count; ++j) {
      const uint64_t mag = abs64(nvals[j]);
      nmax = mag > nmax ? mag : nmax;
      if (k >= 0) nref[j][k] = nvals[j];
    }
  };
  int g = 0;       // result = N / W * 2^(g + kn - kw)
  int kn = 0, kw = 0;
  int kn_min = 0;  // smallest kn that keeps every |N| below 2^30
  const int32_t(&h)[3][3] = m.view_map.m;
  // The homography rows (view_mapped only; set there before any use: no
  // zeroing, which costs a memset call per polygon).
  int64_t wrow[3], nrow[2][3];
  if (m.shading == Shading::flat) {
    s.flat = target.format == PixelFormat::rgb565 ? pack565(m.color) : (m.color & 0xFFFFFFu);
  } else if (m.shading == Shading::gouraud) {
    // N = colour (Q8.8) q < 2^46; the result is the colour in Q8.8.
    s.nn = 3;
    for (int i = 0; i < n; ++i) {
      const int64_t nvals[3] = {int64_t{v[i].a[0]} * v[i].q, int64_t{v[i].a[1]} * v[i].q, int64_t{v[i].a[2]} * v[i].q};
      note(i, v[i].q, nvals, 3);
    }
  } else if (m.shading == Shading::texture) {
    const Texture& t = *m.texture;
    repeat = texture_repeats(t);
    s.tex = make_tex_ctx(t, repeat);
    s.nn = 2;
    const int f = fraction_bits(m, target.format);
    // Texture origin: a whole number of texture periods below the polygon
    // keeps the numerators small (repeat only; clamp needs true coordinates).
    int64_t org[2] = {0, 0};
    if (repeat) {
      const int32_t size[2] = {t.width, t.height};
      for (int j = 0; j < 2; ++j) {
        int32_t mn = v[0].a[j];
        for (int i = 1; i < n; ++i) mn = v[i].a[j] < mn ? v[i].a[j] : mn;
        org[j] = int64_t{floor_div32(mn >> 16, size[j])} * size[j] * 65536;
      }
    }
    const int64_t half = f ? 32768 : 0;  // bilinear blends around u - 1/2
    for (int i = 0; i < n; ++i) {
      const int64_t nvals[2] = {(int64_t{v[i].a[0]} - org[0] - half) * v[i].q,   // < 2^33 * 2^30
                                (int64_t{v[i].a[1]} - org[1] - half) * v[i].q};
      note(i, v[i].q, nvals, 2);
    }
    g = f - 16;  // u (Q16.16) = N / q, wanted in Q.f
  } else {  // view_mapped
    const Texture& t = *m.texture;
    repeat = texture_repeats(t);
    s.tex = make_tex_ctx(t, repeat);
    s.nn = 2;
    s.proj = true;
    const int f = fraction_bits(m, target.format);
    // The homography works on coordinates / 256 (vds/homography.h): per
    // pixel, 256 W = h20 x + h21 y + 256 h22 and 65536 S = 256 (h00 x + h01 y)
    // + 65536 h02, so that texel u = 65536 S / (256 W).
    wrow[0] = h[2][0];
    wrow[1] = h[2][1];
    wrow[2] = int64_t{h[2][2]} * 256;
    int64_t srow[2][3];
    for (int j = 0; j < 2; ++j) {
      srow[j][0] = int64_t{h[j][0]} * 256;
      srow[j][1] = int64_t{h[j][1]} * 256;
      srow[j][2] = int64_t{h[j][2]} * 65536;
    }
    int64_t org[2] = {0, 0};
    if (repeat) {
      // Origin from the first vertex: u = 65536 S / (256 W) there; both rows
      // evaluated in Q.8 (below 2^62).
      const int64_t W = wrow[0] * a.x + wrow[1] * a.y + wrow[2] * 256;
      const int32_t size[2] = {t.width, t.height};
      for (int j = 0; j < 2 && W > 0; ++j) {
        const int64_t X = wrap_add64(wrap_add64(wrap_mul64(srow[j][0], a.x), wrap_mul64(srow[j][1], a.y)), wrap_mul64(srow[j][2], 256));
        int64_t u = floor_div(X, W);
        u = u < -(int64_t{1} << 20) ? -(int64_t{1} << 20) : (u > (int64_t{1} << 20) ? (int64_t{1} << 20) : u);
        org[j] = floor_div(u, size[j]) * size[j];
      }
    }
    // Nearest: S - o W. Bilinear: 2 S - (2 o + 1) W, i.e. 2 (u - o - 1/2) W.
    uint64_t mx = 0;
    for (int j = 0; j < 2; ++j)
      for (int k = 0; k < 3; ++k) {
        nrow[j][k] = f ? 2 * srow[j][k] - (2 * org[j] + 1) * wrow[k] : srow[j][k] - org[j] * wrow[k];
        mx = abs64(nrow[j][k]) > mx ? abs64(nrow[j][k]) : mx;
      }
    // Rows brought below 2^30 first (plane_linear's range); then the values
    // at the vertices, (c0 X + c1 Y) / 256 + c2 with X, Y in Q24.8.
    const int r0 = bitlen64(mx) - 30 > 0 ? bitlen64(mx) - 30 : 0;
    uint64_t wmx = 0;
    for (int k = 0; k < 3; ++k) wmx = abs64(wrow[k]) > wmx ? abs64(wrow[k]) : wmx;
    const int w0 = bitlen64(wmx) - 30 > 0 ? bitlen64(wmx) - 30 : 0;
    for (int k = 0; k < 3; ++k) {
      wrow[k] = shift_round(wrow[k], w0);
      for (int j = 0; j < 2; ++j) nrow[j][k] = shift_round(nrow[j][k], r0);
    }
    for (int i = 0; i < n; ++i) {
      const int64_t nvals[2] = {((nrow[0][0] * v[i].x + nrow[0][1] * v[i].y) >> 8) + nrow[0][2],
                                ((nrow[1][0] * v[i].x + nrow[1][1] * v[i].y) >> 8) + nrow[1][2]};
      note(i, ((wrow[0] * v[i].x + wrow[1] * v[i].y) >> 8) + wrow[2], nvals, 2);
    }
    kw = w0;
    kn = r0;
    g = f ? f - 1 : f;
  }

  if (s.nn) {
    // Divisor: proj scales W below 2^30 (q already is).
    int kw_extra = 0;
    if (s.proj && wmax > 0) kw_extra = bitlen64(static_cast<uint64_t>(wmax)) - 30 > 0 ? bitlen64(static_cast<uint64_t>(wmax)) - 30 : 0;
    kn_min = bitlen64(nmax) - 30;
    if (s.proj) {
      // The rows are shifted further: below 2^30 already, never scaled up.
      kn_min = kn_min > 0 ? kn_min : 0;
    } else if (kn_min < -16) {
      kn_min = -16;
    }
    const int kn_base = kn;  // proj: shift already applied to the rows
    kn = kn_base + kn_min;
    kw += kw_extra;
    // The fast window, with the divisor range widened by 1/64 for the
    // rounding of the planes between the vertices.
    const int64_t wlo_v = shift_floor(wmin, kw_extra), whi_v = shift_floor(wmax, kw_extra);
    const int64_t wl = wlo_v - (wlo_v >> 6), wh = whi_v + (whi_v >> 6);
    if (wl >= 1 && wh <= kI32Max) {
      const int z_lo = clz32(static_cast<uint32_t>(wh));
      const int z_hi = clz32(static_cast<uint32_t>(wl));
      int bw = g + kn - kw;
      const int raise = -1 - z_lo - bw;  // sh <= 31 at the largest W
      if (raise > 0) {
        kn += raise;
        bw += raise;
      }
      if (30 - z_hi - bw >= 0) {  // sh >= 0 at the smallest W
        s.fast = true;
        s.fast_shb = 30 - bw;
        const int zmax = s.fast_shb < 31 ? s.fast_shb : 31;
        const int zmin = s.fast_shb - 31 > 0 ? s.fast_shb - 31 : 0;
        s.wlo = static_cast<int32_t>(uint32_t{1} << (31 - zmax));
        s.whi = zmin == 0 ? INT32_MAX : static_cast<int32_t>((uint32_t{1} << (32 - zmin)) - 1);
      }
    }
    // The planes at the chosen exponents.
    if (s.proj) {
      const int en = kn - kn_base, ew = kw_extra;
      for (int j = 0; j < 2; ++j) {
        s.n[j] = plane_linear(shift_round(nrow[j][0], en), shift_round(nrow[j][1], en), shift_round(nrow[j][2], en), s.xr, s.yr);
      }
      s.w = plane_linear(shift_round(wrow[0], ew), shift_round(wrow[1], ew), shift_round(wrow[2], ew), s.xr, s.yr);
      s.fast_dw = step16(s.w.gx);
    } else {
      s.fast_dw = s.fast_dq;
      for (int j = 0; j < s.nn; ++j) {
        const int64_t val[3] = {shift_round(nref[j][0], kn), shift_round(nref[j][1], kn), shift_round(nref[j][2], kn)};
        s.n[j] = plane_from(a, b, c, val, inv, neg, s.xr, s.yr);
      }
    }
    for (int j = 0; j < s.nn; ++j) s.fast_dn[j] = step16(s.n[j].gx);
    s.b0 = g + kn - kw;
  } else {
    s.fast = true;  // flat: q only
  }

  s.fast_qlo = s.wlo > 1 ? s.wlo : 1;
  s.fast_qhi = s.whi < kQMax ? s.whi : kQMax;
  // Empty: no span of a non-projective polygon passes both checks anyway.
  if (s.nn && !s.proj && s.fast_qlo > s.fast_qhi) s.fast = false;
  pp->fn = select_span(target, m, repeat);
}

int32_t prepared_row_end(const PreparedPolygon& pp) { return pp.row_end; }

void draw_prepared(const BandTarget& band, const PreparedPolygon& pp, RenderStats& stats) {
  if (pp.row_end <= band.y0 || pp.row_begin >= band.y1) return;
  if (pp.culled) ++stats.culled;
  const SpanFn fn = pp.fn;
  if (!fn) return;
  const PolySetup& s = pp.s;
  const RasterVertex* o = pp.outline;
  for (int i = 1; i + 1 < pp.n; ++i) {
    const RasterVertex rv[3] = {o[0], o[i], o[i + 1]};
    raster_triangle(rv, band.y0, band.y1, band.width, [&](int32_t y, int32_t xa, int32_t xb) {
      fn(band, s, y, xa, xb);
      ++stats.spans;
      stats.pixels += static_cast<uint32_t>(xb - xa);
    });
  }
}

void draw_polygon(const BandTarget& band, const MaterialCtx& mat, const ScreenVertex* v, int n, RenderStats& stats) {
  PreparedPolygon pp;
  prepare_polygon(PolygonTarget{band.width, band.format, band.depth_format}, mat, v, n, &pp);
  if (pp.set_up && pp.row_end > band.y0 && pp.row_begin < band.y1) ++stats.setups;
  draw_prepared(band, pp, stats);
}

}  // namespace vds::detail
