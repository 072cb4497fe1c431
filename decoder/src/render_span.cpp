// The span stage of the renderer: exact span start values from a polygon's
// planes, one reciprocal per pixel (an interpolated table), nearest and
// bilinear texture sampling in every texture and output format, and the
// z-test; the loops selected per material and target. The rule u = (a x +
// b y + c) / (g x + h y + i) is rational linear interpolation (Heckbert,
// "Fundamentals of texture mapping and image warping", 1989); the
// fixed-point scaling is in docs/renderer.md.
#include <cstddef>
#include <type_traits>

#include "colour.h"
#include "render_span.h"
#include "vds/config.h"

namespace vds::detail {

namespace {

// How a sampler addresses texels: wrapping (power-of-two sizes), clamped to
// the edge, or as they come — only for the pixels of a span piece that
// piece_inside() has shown to lie where clamping changes nothing.
enum class Addr { repeat, clamp, inside };

template <Addr A>
inline int32_t tx(int32_t u, int32_t mask, int32_t max) {
  if constexpr (A == Addr::repeat) {
    return u & mask;
  } else if constexpr (A == Addr::clamp) {
    return u < 0 ? 0 : (u > max ? max : u);
  } else {
    return u;
  }
}

// The sample coordinates, lo <= u < uhi and vlo <= v < vhi, for which a
// clamping sampler reads only texels clamping would not move.
struct UvBox {
  int32_t ulo, uhi, vlo, vhi;
};

// Colours: rgb565 as uint16_t, 8-bit channels as 0x00RRGGBB.
inline uint32_t expand565(uint32_t c) {
  const uint32_t r = c >> 11, g = (c >> 5) & 63, b = c & 31;
  return ((r << 3 | r >> 2) << 16) | ((g << 2 | g >> 4) << 8) | (b << 3 | b >> 2);
}

// JFIF full-range Y'CbCr -> R'G'B' (colour.h, the image output's
// constants), each channel rounded and clamped. Channels: each channel's
// value before clamping, plus 256: 0..767 for any Y', Cb, Cr. Each chroma value's part of the sums is looked up rather than
// multiplied (3 KiB; the same values: R = Y + r[Cr], G = Y + ((g_cb[Cb] +
// g_cr[Cr]) >> 16), B = Y + b[Cb], with the rounding half and the 256 in
// the tables).
struct Channels {
  int32_t r, g, b;
};
struct ChromaTables {
  int16_t r[256], b[256];
  int32_t g_cb[256], g_cr[256];
};
constexpr int32_t kChannelBias = 256;
constexpr ChromaTables make_chroma_tables() {
  using namespace colour;
  ChromaTables t{};
  for (int c = 0; c < 256; ++c) {
    const int32_t d = c - kChromaCentre;
    t.r[c] = static_cast<int16_t>(((kCrToR * d + kHalf) >> kFracBits) + kChannelBias);
    t.b[c] = static_cast<int16_t>(((kCbToB * d + kHalf) >> kFracBits) + kChannelBias);
    t.g_cb[c] = -kCbToG * d;
    t.g_cr[c] = -kCrToG * d + kHalf + (kChannelBias << kFracBits);
  }
  return t;
}
constexpr ChromaTables kChroma = make_chroma_tables();
// The chroma terms of a chroma sample: each channel is Y' plus its term.
inline Channels chroma_terms(uint32_t cb, uint32_t cr) {
  return {kChroma.r[cr], (kChroma.g_cb[cb] + kChroma.g_cr[cr]) >> colour::kFracBits, kChroma.b[cb]};
}
inline Channels ycbcr_channels(int32_t y, uint32_t cb, uint32_t cr) {
  const Channels t = chroma_terms(cb, cr);
  return {y + t.r, y + t.g, y + t.b};
}
// Y' and the chroma terms as 0x00RRGGBB.
inline uint32_t terms_to_8888(int32_t y, const Channels& t) {
  return (static_cast<uint32_t>(sat_u8(y + t.r - kChannelBias)) << 16) | (static_cast<uint32_t>(sat_u8(y + t.g - kChannelBias)) << 8) |
         sat_u8(y + t.b - kChannelBias);
}
inline uint32_t ycbcr_to_rgb(int32_t y, uint32_t cb, uint32_t cr) { return terms_to_8888(y, chroma_terms(cb, cr)); }

// The same straight to RGB565: each channel's biased value indexes a table
// holding it clamped, rounded to 5 or 6 bits (pack565's rounding) and in
// place. Exactly pack565(ycbcr_to_rgb(...)), in about 20 instructions less
// on a Cortex-M4.
// Entry c is red's, kPack565Channel + c green's, 2 kPack565Channel + c blue's.
constexpr int kPack565Channel = 768;
struct Pack565Table {
  uint16_t v[3 * kPack565Channel];
};
constexpr Pack565Table make_pack565_table() {
  Pack565Table t{};
  for (int i = 0; i < kPack565Channel; ++i) {
    const uint32_t v = static_cast<uint32_t>(i < kChannelBias ? 0 : (i > kChannelBias + 255 ? 255 : i - kChannelBias));
    t.v[i] = static_cast<uint16_t>(((v * 249 + 1014) >> 11) << 11);
    t.v[kPack565Channel + i] = static_cast<uint16_t>(((v * 253 + 505) >> 10) << 5);
    t.v[2 * kPack565Channel + i] = static_cast<uint16_t>((v * 249 + 1014) >> 11);
  }
  return t;
}
constexpr Pack565Table kPack565 = make_pack565_table();
inline uint16_t ycbcr_to_565(int32_t y, uint32_t cb, uint32_t cr) {
  const Channels c = ycbcr_channels(y, cb, cr);
  return static_cast<uint16_t>(kPack565.v[c.r] | kPack565.v[kPack565Channel + c.g] | kPack565.v[2 * kPack565Channel + c.b]);
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
// Bilinear blend of four 8-bit samples (a b above, c d below) with 8-bit
// weights, rounded once: the rows' blends are kept in Q8 (below 2^16), the
// column's in Q16. Every term stays within int32; the result is 0..255.
inline uint32_t bilerp8(int32_t a, int32_t b, int32_t c, int32_t d, int32_t fu, int32_t fv) {
  const int32_t top = a * 256 + (b - a) * fu;
  const int32_t bot = c * 256 + (d - c) * fu;
  return static_cast<uint32_t>(top * 256 + (bot - top) * fv + 32768) >> 16;
}

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

// Y'CbCr to the output format.
template <PixelFormat O>
inline OutColor<O> from_ycbcr(int32_t y, uint32_t cb, uint32_t cr) {
  if constexpr (O == PixelFormat::rgb565) {
    return ycbcr_to_565(y, cb, cr);
  } else {
    return from8888<O>(ycbcr_to_rgb(y, cb, cr));
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

// What a texture sampler reads of a polygon's set-up.
struct TexSampler {
  using Ctx = TexCtx;
  static const TexCtx& ctx(const PolySetup& s) { return s.tex; }
};

template <TexFormat TF, Addr A, PixelFormat O>
struct NearestSampler : TexSampler {
  static constexpr int kFracBits = 0;
  static constexpr bool kInlineStart = TF == TexFormat::rgb565 && O == PixelFormat::rgb565;
  static constexpr bool kHasInside = A == Addr::clamp && TF == TexFormat::ycbcr420;  // texture_span: the views (flash)
  using Inside = NearestSampler<TF, Addr::inside, O>;
  // Every texel of the texture (a 4:2:0 chroma texel (col/2, row/2) is then
  // inside too: col <= wmax gives col/2 <= cwmax).
  static UvBox inside_box(const TexCtx& t) { return {0, t.wmax + 1, 0, t.hmax + 1}; }
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
      return from_ycbcr<O>(t.base[index], t.cb[ci], t.cr[ci]);
    }
  }
};

// Bilinear weights: 5 bits where both texture and output are rgb565 (the
// blend runs on all three channels at once in one 32-bit word), else 8 bits.
constexpr int bilinear_frac_bits(TexFormat tf, PixelFormat o) {
  return tf == TexFormat::rgb565 && o == PixelFormat::rgb565 ? 5 : 8;
}

// kNearestChroma (Y'CbCr 4:2:0, Filter::bilinear_luma): chroma from the
// chroma texel the sample point lies in instead of blended.
template <TexFormat TF, Addr A, PixelFormat O, bool kNearestChroma>
struct BilinearBlend : TexSampler {
  static constexpr int kFracBits = bilinear_frac_bits(TF, O);
  static constexpr bool kInlineStart = TF == TexFormat::rgb565 && O == PixelFormat::rgb565;
  static constexpr uint32_t kFracMask = (1u << kFracBits) - 1;
  static constexpr bool kHasInside = A == Addr::clamp && TF == TexFormat::ycbcr420;
  using Inside = BilinearBlend<TF, Addr::inside, O, kNearestChroma>;
  // Texel pairs i0, i0 + 1 both inside: 0 <= u < wmax 2^F. The 4:2:0
  // chroma texel of the nearest rule, (u + 128) >> 9, is then inside too
  // (u + 128 < 256 w <= 512 cw); the bilinear chroma pair needs
  // 0 <= cu = u/2 - 64 < cwmax 256 as well.
  static UvBox inside_box(const TexCtx& t) {
    UvBox b{0, t.wmax << kFracBits, 0, t.hmax << kFracBits};
    if constexpr (TF == TexFormat::ycbcr420 && !kNearestChroma) {
      b.ulo = b.vlo = 128;
      b.uhi = b.uhi < (t.cwmax << 9) + 128 ? b.uhi : (t.cwmax << 9) + 128;
      b.vhi = b.vhi < (t.chmax << 9) + 128 ? b.vhi : (t.chmax << 9) + 128;
    }
    return b;
  }
  // Nearest chroma read once for a run of samples in the same chroma
  // texel (a magnified view's chroma texel covers several pixels): the
  // texel's index and its chroma terms, each with its place in kPack565
  // (rgb565 output). The sample point (u, v) comes with 8 more fraction
  // bits (Q16: the affine runs' steps); the same texels and weights as
  // sample(t, u >> 8, v >> 8).
  static constexpr bool kChromaMemo = TF == TexFormat::ycbcr420 && kNearestChroma && A == Addr::inside;
  // rgb565: each channel's part of kPack565 moved by its term, indexed by
  // Y' alone (one load a channel: no addition, no table base register).
  struct ChromaMemo {
    uint32_t ci = ~0u;
    Channels terms{};
    const uint16_t* r565 = nullptr;
    const uint16_t* g565 = nullptr;
    const uint16_t* b565 = nullptr;
  };
  [[gnu::always_inline]] static OutColor<O> sample_q16(const TexCtx& t, ChromaMemo& m, int32_t u, int32_t v)
    requires kChromaMemo
  {
    const int32_t i0 = u >> 16, j0 = v >> 16;
    const int32_t fu = (u >> 8) & 255, fv = (v >> 8) & 255;
    const uint8_t* y = t.base + static_cast<uint32_t>(j0) * t.stride + static_cast<uint32_t>(i0);
    const int32_t yy = static_cast<int32_t>(bilerp8(y[0], y[1], y[t.stride], y[t.stride + 1], fu, fv));
    // The point in chroma texels: (u_q8 + 128) / 512 = (u_q16 + 2^15) / 2^17.
    const uint32_t ci = static_cast<uint32_t>((v + 32768) >> 17) * t.cstride + static_cast<uint32_t>((u + 32768) >> 17);
    if (ci != m.ci) {
      m.ci = ci;
      const Channels terms = chroma_terms(t.cb[ci], t.cr[ci]);
      if constexpr (O == PixelFormat::rgb565) {
        m.r565 = kPack565.v + terms.r;
        m.g565 = kPack565.v + kPack565Channel + terms.g;
        m.b565 = kPack565.v + 2 * kPack565Channel + terms.b;
      } else {
        m.terms = terms;
      }
    }
    if constexpr (O == PixelFormat::rgb565) {
      return static_cast<uint16_t>(m.r565[yy] | m.g565[yy] | m.b565[yy]);
    } else {
      return from8888<O>(terms_to_8888(yy, m.terms));
    }
  }
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
      const uint32_t yy = bilerp8(y[r0 + c0], y[r0 + c1], y[r1 + c0], y[r1 + c1], static_cast<int32_t>(fu), static_cast<int32_t>(fv));
      if constexpr (kNearestChroma) {
        // The point in chroma texels: (u_q8 + 128) / 512.
        const uint32_t k = static_cast<uint32_t>(tx<A>((u + 128) >> 9, t.cwmask, t.cwmax));
        const uint32_t ci = static_cast<uint32_t>(tx<A>((v + 128) >> 9, t.chmask, t.chmax)) * t.cstride + k;
        return from_ycbcr<O>(static_cast<int32_t>(yy), t.cb[ci], t.cr[ci]);
      } else {
        // In chroma texels the point is u/2, minus half a chroma texel:
        // (u_q8 + 128)/2 - 128 = u_q8/2 - 64.
        const int32_t cu = (u >> 1) - 64, cv = (v >> 1) - 64;
        const uint32_t gu = static_cast<uint32_t>(cu) & 255u, gv = static_cast<uint32_t>(cv) & 255u;
        const uint32_t k0 = static_cast<uint32_t>(tx<A>(cu >> 8, t.cwmask, t.cwmax));
        const uint32_t k1 = static_cast<uint32_t>(tx<A>((cu >> 8) + 1, t.cwmask, t.cwmax));
        const uint32_t s0 = static_cast<uint32_t>(tx<A>(cv >> 8, t.chmask, t.chmax)) * t.cstride;
        const uint32_t s1 = static_cast<uint32_t>(tx<A>((cv >> 8) + 1, t.chmask, t.chmax)) * t.cstride;
        const int32_t su = static_cast<int32_t>(gu), sv = static_cast<int32_t>(gv);
        const uint32_t cb = bilerp8(t.cb[s0 + k0], t.cb[s0 + k1], t.cb[s1 + k0], t.cb[s1 + k1], su, sv);
        const uint32_t cr = bilerp8(t.cr[s0 + k0], t.cr[s0 + k1], t.cr[s1 + k0], t.cr[s1 + k1], su, sv);
        return from_ycbcr<O>(static_cast<int32_t>(yy), cb, cr);
      }
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

template <TexFormat TF, Addr A, PixelFormat O>
using BilinearSampler = BilinearBlend<TF, A, O, false>;
template <TexFormat TF, Addr A, PixelFormat O>
using LumaBilinearSampler = BilinearBlend<TF, A, O, true>;

// Bilinear filtering of a texture with an apron (Texture::apron): the right
// and lower neighbours are at +1 and +stride whatever the addressing. Clamp
// addressing clamps the sample position to [0, size - 1] before splitting it,
// which gives exactly the clamp-to-edge result (the neighbour then has weight 0).
template <TexFormat TF, Addr A, PixelFormat O>
struct BilinearApronSampler : TexSampler {
  static constexpr int kFracBits = bilinear_frac_bits(TF, O);
  static constexpr bool kInlineStart = TF == TexFormat::rgb565 && O == PixelFormat::rgb565;
  static constexpr bool kHasInside = false;  // its clamp is two compares a coordinate
  using Inside = void;
  static constexpr uint32_t kFracMask = (1u << kFracBits) - 1;
  static OutColor<O> sample(const TexCtx& t, int32_t u, int32_t v) {
    uint32_t index;
    uint32_t fu, fv;
    if constexpr (A == Addr::repeat) {
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
// Mesh colors (Shading::mesh_colors): samples on a face's lattice
// ---------------------------------------------------------------------------
// The index of lattice point (i, j) of a face of resolution R (render.h's
// LatticeFace); 0 <= i, j and i + j <= R.
inline uint32_t lattice_index(const LatticeFace& f, int32_t R, int32_t i, int32_t j) {
  if (j == 0) {
    if (i == 0) return f.vertex[0];
    if (i == R) return f.vertex[1];
    return f.edge_base[0] + static_cast<uint32_t>(i * f.edge_step[0]);
  }
  if (i == 0) {
    if (j == R) return f.vertex[2];
    return f.edge_base[2] + static_cast<uint32_t>((R - j) * f.edge_step[2]);
  }
  if (i + j == R) return f.edge_base[1] + static_cast<uint32_t>(j * f.edge_step[1]);
  const int32_t r = j - 1;  // rows 1 .. j - 1 hold R - 2, R - 3, ... samples
  return f.face_base + static_cast<uint32_t>(r * (R - 1) - ((r * (r + 1)) >> 1) + i - 1);
}

struct LatticeSampler {
  using Ctx = LatticeCtx;
  static constexpr bool kHasInside = false;
  using Inside = void;
  static const LatticeCtx& ctx(const PolySetup& s) { return s.lat; }
};

// The nearest lattice point: (u, v) arrive rounded (the set-up adds a
// half); points just outside the triangle (rounding at its edges) are
// brought back to its border.
template <PixelFormat O>
struct LatticeNearestSampler : LatticeSampler {
  static constexpr bool kInlineStart = false;
  static OutColor<O> sample(const LatticeCtx& t, int32_t u, int32_t v) {
    const int32_t R = t.res;
    u = u < 0 ? 0 : (u > R ? R : u);
    v = v < 0 ? 0 : (v > R ? R : v);
    if (u + v > R) {
      const int32_t e = u + v - R;
      u -= e >> 1;
      v -= e - (e >> 1);
    }
    const uint32_t k = lattice_index(t.face, R, u, v);
    return from_ycbcr<O>(t.y[k], t.cb[k], t.cr[k]);
  }
};

// The linear filter: (u, v) in Q.8 lattice units.
template <PixelFormat O>
struct LatticeLinearSampler : LatticeSampler {
  static constexpr bool kInlineStart = false;
  static constexpr int kF = kLatticeFracBits;
  static constexpr int32_t kOne = 1 << kF;
  static OutColor<O> sample(const LatticeCtx& t, int32_t u, int32_t v) {
    const int32_t R = t.res;
    const int32_t lim = R << kF;
    u = u < 0 ? 0 : u;
    v = v < 0 ? 0 : v;
    if (u + v > lim) {  // beyond the edge opposite corner a: onto it
      const int32_t e = u + v - lim;
      u -= e >> 1;
      v -= e - (e >> 1);
      if (u < 0) {
        u = 0;
        v = lim;
      } else if (v < 0) {
        v = 0;
        u = lim;
      }
    }
    int32_t i0 = u >> kF, j0 = v >> kF;
    int32_t fu = u & (kOne - 1), fv = v & (kOne - 1);
    if (i0 + j0 >= R) {  // a lattice point on that edge: the cell beside it
      if (i0 > 0) {
        --i0;
        fu = kOne;
      } else {
        --j0;
        fv = kOne;
      }
    }
    uint32_t k0, k1, k2;
    int32_t w0, w1, w2;
    const bool lower = fu + fv <= kOne;
    if (i0 >= 1 && j0 >= 1 && i0 + j0 + 2 < R) {
      // Every point of the cell is the face's own: rows j0 and j0 + 1 of
      // its samples (row j holds i = 1 .. R - 1 - j, lattice_index's layout).
      const int32_t r = j0 - 1;
      const uint32_t row = t.face.face_base + static_cast<uint32_t>(r * (R - 1) - ((r * (r + 1)) >> 1) - 1);
      const uint32_t next = row + static_cast<uint32_t>(R - 1 - j0);
      const uint32_t a = row + static_cast<uint32_t>(i0), b = next + static_cast<uint32_t>(i0);
      if (lower) {  // (i0, j0), (i0 + 1, j0), (i0, j0 + 1)
        k0 = a;
        k1 = a + 1;
        k2 = b;
      } else {  // (i0 + 1, j0 + 1), (i0, j0 + 1), (i0 + 1, j0)
        k0 = b + 1;
        k1 = b;
        k2 = a + 1;
      }
    } else if (lower) {
      k0 = lattice_index(t.face, R, i0, j0);
      k1 = lattice_index(t.face, R, i0 + 1, j0);
      k2 = lattice_index(t.face, R, i0, j0 + 1);
    } else {
      k0 = lattice_index(t.face, R, i0 + 1, j0 + 1);
      k1 = lattice_index(t.face, R, i0, j0 + 1);
      k2 = lattice_index(t.face, R, i0 + 1, j0);
    }
    if (lower) {
      w0 = kOne - fu - fv;
      w1 = fu;
      w2 = fv;
    } else {
      w0 = fu + fv - kOne;
      w1 = kOne - fu;
      w2 = kOne - fv;
    }
    constexpr int32_t kHalf = kOne / 2;
    const int32_t y = (w0 * t.y[k0] + w1 * t.y[k1] + w2 * t.y[k2] + kHalf) >> kF;
    const int32_t cb = (w0 * t.cb[k0] + w1 * t.cb[k1] + w2 * t.cb[k2] + kHalf) >> kF;
    const int32_t cr = (w0 * t.cr[k0] + w1 * t.cr[k1] + w2 * t.cr[k2] + kHalf) >> kF;
    return from_ycbcr<O>(y, static_cast<uint32_t>(cb), static_cast<uint32_t>(cr));
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
// Span start values
// ---------------------------------------------------------------------------
// Integer state of one span piece: values at its first pixel and per-pixel
// steps. Every value stays inside int32 over the piece (both ends checked),
// W >= 1 throughout, and sh_base - clz(W) lies in [0, 31] for every pixel.
struct RowState {
  int32_t q, dq;
  int32_t w, dw;
  int32_t n[3], dn[3];
  int32_t sh_base;
};


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

// A fast start value (PolySetup::fast_c*): c + step dx + g dy, exact in 64
// bits (each product below 2^31 2^12).
inline int64_t row_start(int32_t c, int32_t step, int32_t g, int32_t dx, int32_t dy) {
  return int64_t{c} + int64_t{step} * dx + int64_t{g} * dy;
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
[[gnu::always_inline]] inline bool row_fast(const PolySetup& s, int32_t y, int32_t x, int32_t len, RowState& r);
template <int NN, bool kProj>
[[gnu::noinline]] bool row_fast_call(const PolySetup& s, int32_t y, int32_t x, int32_t len, RowState& r);

// The fast start values of a polygon whose values all lie inside their
// limits (PolySetup::fast_safe): each fits int32, so it is exact modulo 2^32.
// (Built with VDS_CHECK_FAST_SAFE it traps where the checks row_fast skips
// for such a polygon would fail.)
template <int NN, bool kProj>
[[gnu::always_inline]] inline void row_safe(const PolySetup& s, int32_t y, int32_t x, [[maybe_unused]] int32_t len,
                                            RowState& r) {
#ifdef VDS_CHECK_FAST_SAFE
  PolySetup t = s;
  t.fast_safe = false;
  RowState checked;
  if (!row_fast_call<NN, kProj>(t, y, x, len, checked)) __builtin_trap();
#endif
  const int32_t dx = x - s.fast_xr, dy = y - s.fast_yr;
  const auto start = [dx, dy](int32_t c, int32_t step, int32_t g) { return wrap_mad32(wrap_mad32(c, step, dx), g, dy); };
  r.q = start(s.fast_cq, s.fast_dq, s.fast_gq);
  r.dq = s.fast_dq;
  if constexpr (NN > 0) {
    if constexpr (kProj) {
      r.w = start(s.fast_cw, s.fast_dw, s.fast_gw);
      r.dw = s.fast_dw;
    } else {
      r.w = r.q;
      r.dw = r.dq;
    }
    for (int j = 0; j < NN; ++j) {
      r.n[j] = start(s.fast_cn[j], s.fast_dn[j], s.fast_gn[j]);
      r.dn[j] = s.fast_dn[j];
    }
    r.sh_base = s.fast_shb;
  }
}

template <int NN, bool kProj>
[[gnu::always_inline]] inline bool row_fast(const PolySetup& s, int32_t y, int32_t x, int32_t len, RowState& r) {
  if (!s.fast) return false;
  if (kProj && s.fast_safe) {
    row_safe<NN, kProj>(s, y, x, len, r);
    return true;
  }
  const int32_t dx = x - s.fast_xr, dy = y - s.fast_yr;
  const int64_t last = len - 1;
  const int64_t q0 = row_start(s.fast_cq, s.fast_dq, s.fast_gq, dx, dy);
  const int64_t q1 = q0 + int64_t{s.fast_dq} * last;
  // q is also the divisor unless kProj: one check against both ranges.
  const int64_t qlo = NN > 0 && !kProj ? s.fast_qlo : 1, qhi = NN > 0 && !kProj ? s.fast_qhi : kQMax;
  if (!in_range(q0, qlo, qhi) || !in_range(q1, qlo, qhi)) return false;
  r.q = static_cast<int32_t>(q0);
  r.dq = s.fast_dq;
  if constexpr (NN > 0) {
    int64_t w0 = q0, w1 = q1;
    if constexpr (kProj) {
      w0 = row_start(s.fast_cw, s.fast_dw, s.fast_gw, dx, dy);
      w1 = w0 + int64_t{s.fast_dw} * last;
      if (!in_range(w0, s.wlo, s.whi) || !in_range(w1, s.wlo, s.whi)) return false;
    }
    r.w = static_cast<int32_t>(w0);
    r.dw = s.fast_dw;
    for (int j = 0; j < NN; ++j) {
      const int64_t n0 = row_start(s.fast_cn[j], s.fast_dn[j], s.fast_gn[j], dx, dy);
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

// The sample coordinates of a pixel from its numerators and divisor.
[[gnu::always_inline]] inline void sample_uv(int32_t nu, int32_t nv, int32_t div, int32_t shb, int32_t* u, int32_t* v) {
  int z;
  const int32_t yr = recip_y(static_cast<uint32_t>(div), z);
  const int sh = shb - z;
  *u = scaled(nu, yr, sh);
  *v = scaled(nv, yr, sh);
}

// The pixels of one span piece whose divisor is the depth plane (the
// texture mappings; view-mapped pieces: affine_pixels below): i = -len ..
// -1 from the piece end (ze, oe).
template <class Sampler, PixelFormat O, DepthFormat D>
[[gnu::always_inline]] inline void span_pixels(typename Depth<D>::T* ze, uint8_t* oe, int32_t len, const RowState& r,
                                               const typename Sampler::Ctx& tex) {
  using DT = typename Depth<D>::T;
  const uintptr_t delta = reinterpret_cast<uintptr_t>(oe) -
                          (reinterpret_cast<uintptr_t>(ze) >> (sizeof(DT) == 2 * Store<O>::kBytes ? 1 : 0));
  int32_t q = r.q, u = r.n[0], v = r.n[1];
  const int32_t dq = r.dq, du = r.dn[0], dv = r.dn[1];
  const int32_t shb = r.sh_base;
  int32_t i = -len;
  do {
    const DT d = Depth<D>::value(q);
    if (d > ze[i]) {
      ze[i] = d;
      int32_t su, sv;
      sample_uv(u, v, q, shb, &su, &sv);
      Store<O>::put(pixel_at<O, DT>(oe, ze, delta, i), Sampler::sample(tex, su, sv));
    }
    q = wrap_add32(q, dq);
    u = wrap_add32(u, du);
    v = wrap_add32(v, dv);
  } while (++i != 0);
}

// The sample coordinates of pixel k of a piece, as span_pixels computes them.
template <bool kProj>
inline void piece_uv(const RowState& r, int32_t k, int32_t* u, int32_t* v) {
  // Inside the piece every value fits int32 (row_fast and row_piece check
  // both ends, or fast_safe all of the polygon's), so 32-bit arithmetic
  // modulo 2^32 gives it exactly.
  sample_uv(wrap_mad32(r.n[0], r.dn[0], k), wrap_mad32(r.n[1], r.dn[1], k),
            kProj ? wrap_mad32(r.w, r.dw, k) : wrap_mad32(r.q, r.dq, k), r.sh_base, u, v);
}

// Whether every pixel of the piece samples inside the box. Over a piece the
// numerators and the divisor W > 0 are linear in the pixel, so N / W is
// monotonic and lies between its values at the two ends; the loop's value
// is N / W times (1 + e) rounded down, |e| < 2^-18 (recip_y), so it lies
// within |N / W| 2^-18 + 1 of it. Both ends at least a margin m > 2 (that
// + 1) inside the box therefore keep every pixel between them inside.
// The piece's exact sample points at its first and last pixels serve the
// check (piece_ends, ends_inside) and, on a view-mapped piece, its runs.
struct PieceEnds {
  int32_t u0, v0, u1, v1;
};
template <bool kProj>
[[gnu::always_inline]] inline PieceEnds piece_ends_inline(const RowState& r, int32_t len) {
  PieceEnds p;
  piece_uv<kProj>(r, 0, &p.u0, &p.v0);
  piece_uv<kProj>(r, len - 1, &p.u1, &p.v1);
  return p;
}
// (A call of its own, but in the walkthrough's loop: code size.)
template <bool kProj>
[[gnu::noinline]] PieceEnds piece_ends(const RowState& r, int32_t len) {
  return piece_ends_inline<kProj>(r, len);
}
inline bool ends_inside(const PieceEnds& p, const UvBox& b) {
  const int32_t far = (b.uhi > b.vhi ? b.uhi : b.vhi);
  const int32_t m = (far >> 16) + 8;
  const auto in = [m](int32_t x, int32_t lo, int32_t hi) { return x >= lo + m && x < hi - m; };
  return in(p.u0, b.ulo, b.uhi) && in(p.u1, b.ulo, b.uhi) && in(p.v0, b.vlo, b.vhi) && in(p.v1, b.vlo, b.vhi);
}
template <bool kProj>
inline bool piece_inside(const RowState& r, int32_t len, const UvBox& b) {
  return ends_inside(piece_ends<kProj>(r, len), b);
}

// Whether a sampler keeps its last chroma texel between the pixels of a run.
template <class S>
constexpr bool chroma_memo() {
  if constexpr (requires { S::kChromaMemo; }) {
    return S::kChromaMemo;
  } else {
    return false;
  }
}
// Whether a sampler's variant for pieces inside the texture keeps its
// chroma texel (the walkthrough's views).
template <class S>
constexpr bool memo_inside() {
  if constexpr (S::kHasInside) {
    return chroma_memo<typename S::Inside>();
  } else {
    return false;
  }
}
template <class S, bool kMemo>
struct MemoOf {
  struct T {};
};
template <class S>
struct MemoOf<S, true> {
  using T = typename S::ChromaMemo;
};

// The pixels of one piece of a view-mapped span (the screen -> view
// homography): the sample coordinates exact every kAffineRun pixels and at
// the piece's last pixel, and linear between (the pixels between two exact
// points step by their difference over the distance, carried with 8 more
// fraction bits). A reciprocal per run instead of per pixel. Between two
// points 16 pixels apart the homography's curvature moves a sample by a
// small part of a texel except on surfaces seen nearly edge-on. The steps
// need both points within +-kAffineLimit (the differences times 2^8 then
// stay within int32): so is every point inside a texture (below
// kTextureMaxSize 2^8 = 2^20 with 8 fraction bits); a point beyond it (far
// outside the texture, where its clamps give the edge's texels; a
// repeating texture's 8,192nd copy) is held at the limit.
constexpr int32_t kAffineRun = 16;
constexpr int32_t kAffineLimit = 1 << 21;
// The homography's numerators and divisor where a run starts, and the
// exact point there.
struct AffineRun {
  int32_t nu, nv, w;
  int32_t u, v;
};
inline int32_t hold_affine(int32_t x) { return x < -kAffineLimit ? -kAffineLimit : (x > kAffineLimit ? kAffineLimit : x); }
// The run of n >= 1 pixels from a's point to (u1, v1): the first pixel's
// coordinates (su, sv) and their steps (du, dv) in Q16; a's point moves on.
[[gnu::always_inline]] inline void run_to(AffineRun* a, int32_t n, int32_t u1, int32_t v1, int32_t* su, int32_t* sv,
                                          int32_t* du, int32_t* dv) {
  *su = a->u * 256;
  *sv = a->v * 256;
  if (n == kAffineRun) {
    *du = (u1 - a->u) * (256 / kAffineRun);
    *dv = (v1 - a->v) * (256 / kAffineRun);
  } else {
    *du = (u1 - a->u) * 256 / n;
    *dv = (v1 - a->v) * 256 / n;
  }
  a->u = u1;
  a->v = v1;
}
// The same to the exact point n pixels on, and a's numerators and divisor
// moved there.
[[gnu::always_inline]] inline void run_steps(const RowState& r, int32_t n, AffineRun* a, int32_t* su, int32_t* sv,
                                             int32_t* du, int32_t* dv) {
  a->nu = wrap_mad32(a->nu, r.dn[0], n);
  a->nv = wrap_mad32(a->nv, r.dn[1], n);
  a->w = wrap_mad32(a->w, r.dw, n);
  int32_t u1, v1;
  sample_uv(a->nu, a->nv, a->w, r.sh_base, &u1, &v1);
  run_to(a, n, hold_affine(u1), hold_affine(v1), su, sv, du, dv);
}
// The same two, called (once a run): inlined only into the walkthrough's
// loop (Y'CbCr views, bilinear luma, inside the view), the rest stay small.
[[gnu::noinline]] void next_run(const RowState& r, int32_t n, AffineRun* a, int32_t* su, int32_t* sv, int32_t* du,
                                int32_t* dv) {
  run_steps(r, n, a, su, sv, du, dv);
}
[[gnu::noinline]] void last_run(AffineRun* a, int32_t n, int32_t u1, int32_t v1, int32_t* su, int32_t* sv, int32_t* du,
                                int32_t* dv) {
  run_to(a, n, u1, v1, su, sv, du, dv);
}

// The walkthrough's pixels on Thumb-2 (Cortex-M3/M4/M7): the loop of
// affine_pixels for Y'CbCr 4:2:0 views sampled inside (bilinear luma, the
// chroma texel memo) into rgb565 with 16-bit depth, written out because the
// compiler, allocating the loop's 17 values to 14 registers, reloads about
// 11 of them from the stack each pixel. The same pixels as the C++ loop
// (the boards' frame CRCs equal the host's replay: the end-to-end tests).
#if defined(__arm__) && defined(__thumb2__)
#define VDS_VIEW_RUN_ASM 1
// A run's state: the cold words are copied to the stack, the hot ones held
// in r0-r9 (in this order) and written back at the end.
struct ViewRun {
  // cold
  int32_t du, dv, dq;
  uint16_t* zlast;  // the run's last depth entry
  uintptr_t delta;  // colour address less depth address
  uint32_t cstride;
  const uint8_t* cb;
  const uint8_t* cr;
  const ChromaTables* chroma;
  const uint16_t* pack;
  // hot
  int32_t su, sv;
  uint16_t* z;  // the depth entry before the run's next pixel
  int32_t q;
  const uint8_t* y;
  uint32_t stride;
  uint32_t key;  // the chroma texel of r565..b565: row << 16 | column (~0: none)
  const uint16_t* r565;
  const uint16_t* g565;
  const uint16_t* b565;
};
static_assert(offsetof(ViewRun, du) == 0 && offsetof(ViewRun, zlast) == 12 && offsetof(ViewRun, delta) == 16 &&
              offsetof(ViewRun, cstride) == 20 && offsetof(ViewRun, cb) == 24 && offsetof(ViewRun, cr) == 28 &&
              offsetof(ViewRun, chroma) == 32 && offsetof(ViewRun, pack) == 36 && offsetof(ViewRun, su) == 40 &&
              offsetof(ViewRun, b565) == 76);
static_assert(offsetof(ChromaTables, r) == 0 && offsetof(ChromaTables, b) == 512 && offsetof(ChromaTables, g_cb) == 1024 &&
              offsetof(ChromaTables, g_cr) == 2048 && colour::kFracBits == 16 && kPack565Channel == 768 &&
              kDepth16Shift == 14);
[[gnu::naked, gnu::noinline]] void view_run(ViewRun*) {
  __asm__ volatile(
      ".syntax unified\n\t"
      "push   {r4-r11, lr}\n\t"
      "sub    sp, sp, #44\n\t"  // with the 36 bytes pushed: sp stays 8-byte aligned
      "str    r0, [sp, #40]\n\t"
      "ldmia  r0!, {r1-r10}\n\t"  // the cold words to [sp, #0..36]
      "stmia  sp, {r1-r10}\n\t"
      "ldmia  r0, {r0-r9}\n\t"  // su sv z q y stride key r565 g565 b565
      // A pixel: the depth test
      "1:\n\t"
      "ldrh   r11, [r2, #2]!\n\t"
      "ubfx   r12, r3, #14, #16\n\t"
      "ldr    r10, [sp, #8]\n\t"
      "add    r3, r3, r10\n\t"
      "cmp    r11, r12\n\t"
      "bcs    3f\n\t"
      "strh   r12, [r2]\n\t"
      // Y': bilinear in the texels (su >> 16, sv >> 16) and their
      // neighbours right and below, weights (su >> 8) & 255, (sv >> 8) & 255
      "asr    r10, r1, #16\n\t"
      "add    r11, r4, r0, asr #16\n\t"
      "mla    r10, r10, r5, r11\n\t"
      "ldrb   r11, [r10]\n\t"
      "ldrb   r12, [r10, #1]\n\t"
      "sub    r12, r12, r11\n\t"
      "ubfx   lr, r0, #8, #8\n\t"
      "mul    r12, r12, lr\n\t"
      "add    r11, r12, r11, lsl #8\n\t"  // the upper row's blend, Q8
      "add    r10, r10, r5\n\t"
      "ldrb   r12, [r10]\n\t"
      "ldrb   r10, [r10, #1]\n\t"
      "sub    r10, r10, r12\n\t"
      "mul    r10, r10, lr\n\t"
      "add    r10, r10, r12, lsl #8\n\t"  // the lower row's
      "sub    r10, r10, r11\n\t"
      "ubfx   lr, r1, #8, #8\n\t"
      "mul    r10, r10, lr\n\t"
      "add    r10, r10, r11, lsl #8\n\t"
      "add    r10, r10, #32768\n\t"
      "lsr    r10, r10, #16\n\t"  // Y'
      // The chroma texel ((sv + 2^15) >> 17, (su + 2^15) >> 17)
      "add    r11, r0, #32768\n\t"
      "asr    r11, r11, #17\n\t"
      "add    r12, r1, #32768\n\t"
      "asr    r12, r12, #17\n\t"
      "orr    r11, r11, r12, lsl #16\n\t"
      "cmp    r11, r6\n\t"
      "bne    4f\n\t"
      // Each channel's table entry at Y', ORed, stored
      "2:\n\t"
      "ldrh   r11, [r7, r10, lsl #1]\n\t"
      "ldrh   r12, [r8, r10, lsl #1]\n\t"
      "orr    r11, r11, r12\n\t"
      "ldrh   r12, [r9, r10, lsl #1]\n\t"
      "orr    r11, r11, r12\n\t"
      "ldr    r12, [sp, #16]\n\t"
      "strh   r11, [r2, r12]\n\t"
      // The next pixel
      "3:\n\t"
      "ldrd   r10, r11, [sp, #0]\n\t"
      "add    r0, r0, r10\n\t"
      "add    r1, r1, r11\n\t"
      "ldr    r12, [sp, #12]\n\t"
      "cmp    r2, r12\n\t"
      "bne    1b\n\t"
      "ldr    r10, [sp, #40]\n\t"
      "add    r10, r10, #40\n\t"
      "stmia  r10, {r0-r9}\n\t"
      "add    sp, sp, #44\n\t"
      "pop    {r4-r11, pc}\n\t"
      // A new chroma texel: its terms (chroma_terms) and table entries
      "4:\n\t"
      "mov    r6, r11\n\t"
      "lsr    r12, r11, #16\n\t"
      "uxth   r11, r11\n\t"
      "ldr    lr, [sp, #20]\n\t"
      "mla    r11, r12, lr, r11\n\t"
      "ldr    r12, [sp, #24]\n\t"
      "ldrb   r12, [r12, r11]\n\t"  // Cb
      "ldr    lr, [sp, #28]\n\t"
      "ldrb   lr, [lr, r11]\n\t"  // Cr
      "ldr    r11, [sp, #32]\n\t"
      "ldrsh  r7, [r11, lr, lsl #1]\n\t"  // r[Cr]
      "add    r9, r11, #512\n\t"
      "ldrsh  r9, [r9, r12, lsl #1]\n\t"  // b[Cb]
      "add    r8, r11, #1024\n\t"
      "ldr    r8, [r8, r12, lsl #2]\n\t"  // g_cb[Cb]
      "add    r11, r11, #2048\n\t"
      "ldr    r11, [r11, lr, lsl #2]\n\t"  // g_cr[Cr]
      "add    r8, r8, r11\n\t"
      "asr    r8, r8, #16\n\t"
      "ldr    r11, [sp, #36]\n\t"
      "add    r7, r11, r7, lsl #1\n\t"
      "add    r8, r8, #768\n\t"
      "add    r8, r11, r8, lsl #1\n\t"
      "add    r9, r9, #1536\n\t"
      "add    r9, r11, r9, lsl #1\n\t"
      "b      2b\n\t");
}
#endif

template <class Sampler, PixelFormat O, DepthFormat D>
[[gnu::always_inline]] inline void affine_pixels(typename Depth<D>::T* ze, uint8_t* oe, int32_t len, const RowState& r,
                                                 const typename Sampler::Ctx& tex, const PieceEnds& ends) {
  using DT = typename Depth<D>::T;
  constexpr bool kMemo = chroma_memo<Sampler>();
  const uintptr_t delta = reinterpret_cast<uintptr_t>(oe) -
                          (reinterpret_cast<uintptr_t>(ze) >> (sizeof(DT) == 2 * Store<O>::kBytes ? 1 : 0));
  int32_t q = r.q;
  const int32_t dq = r.dq;
  [[maybe_unused]] typename MemoOf<Sampler, kMemo>::T memo{};
#if VDS_VIEW_RUN_ASM
  constexpr bool kAsm = kMemo && O == PixelFormat::rgb565 && D == DepthFormat::d16;
  [[maybe_unused]] ViewRun vr;
  if constexpr (kAsm) {
    vr.dq = dq;
    vr.delta = delta;
    vr.cstride = tex.cstride;
    vr.cb = tex.cb;
    vr.cr = tex.cr;
    vr.chroma = &kChroma;
    vr.pack = kPack565.v;
    vr.y = tex.base;
    vr.stride = tex.stride;
    vr.key = ~0u;
    vr.r565 = vr.g565 = vr.b565 = kPack565.v;  // never read before a texel sets them; valid anyway
  }
#endif
  // The piece's end points (exact, as piece_ends computed them).
  AffineRun a{r.n[0], r.n[1], r.w, hold_affine(ends.u0), hold_affine(ends.v0)};
  const int32_t ue = hold_affine(ends.u1), ve = hold_affine(ends.v1);
  int32_t i = -len;  // pixel len + i of the piece
  for (;;) {
    // The run: pixels i .. stop - 1 from the exact point at i. A full run
    // steps toward the exact point kAffineRun pixels on; the last run (2 to
    // kAffineRun + 1 pixels, or the piece's one pixel) reaches the exact
    // point of the piece's last pixel.
    const int32_t left = -i;  // the pixels left, the last one included
    int32_t stop = 0, su = a.u * 256, sv = a.v * 256, du = 0, dv = 0;
    if (left > kAffineRun + 1) {
      stop = i + kAffineRun;
      if constexpr (kMemo) {
        run_steps(r, kAffineRun, &a, &su, &sv, &du, &dv);
      } else {
        next_run(r, kAffineRun, &a, &su, &sv, &du, &dv);
      }
    } else if (left > 1) {
      if constexpr (kMemo) {
        run_to(&a, left - 1, ue, ve, &su, &sv, &du, &dv);
      } else {
        last_run(&a, left - 1, ue, ve, &su, &sv, &du, &dv);
      }
    }
#if VDS_VIEW_RUN_ASM
    if constexpr (kAsm) {
      vr.du = du;
      vr.dv = dv;
      vr.su = su;
      vr.sv = sv;
      vr.q = q;
      vr.z = ze + i - 1;
      vr.zlast = ze + stop - 1;
      view_run(&vr);
      q = vr.q;
      i = stop;
      if (i == 0) break;
      continue;
    }
#endif
    do {
      const DT d = Depth<D>::value(q);
      if (d > ze[i]) {
        ze[i] = d;
        OutColor<O> c;
        if constexpr (kMemo) {
          c = Sampler::sample_q16(tex, memo, su, sv);
        } else {
          c = Sampler::sample(tex, su >> 8, sv >> 8);
        }
        Store<O>::put(pixel_at<O, DT>(oe, ze, delta, i), c);
      }
      q = wrap_add32(q, dq);
      su += du;
      sv += dv;
    } while (++i != stop);
    if (i == 0) break;
  }
}

template <class Sampler, bool kProj, PixelFormat O, DepthFormat D>
void texture_span(const BandTarget& b, const PolySetup& s, int32_t y, int32_t xa, int32_t xb) {
  using DT = typename Depth<D>::T;
  DT* const zrow = static_cast<DT*>(b.depth) + static_cast<uint32_t>(y - b.y0) * static_cast<uint32_t>(b.width);
  uint8_t* const crow = b.color + static_cast<uint32_t>(y - b.y0) * b.color_stride;
  const typename Sampler::Ctx tex = Sampler::ctx(s);  // a local copy: the stores below cannot alias it
  // The length the general set-up last took in this span: the next piece
  // of a projective span tries twice that first, not the whole rest
  // (where the values need short pieces, halving from the rest cost every
  // piece about 7 tries).
  [[maybe_unused]] int32_t fit = 0;
  while (xa < xb) {
    int32_t len = xb - xa;
    RowState r;
    // The start values are inlined into the loops of rgb565 textures drawn
    // to rgb565 (about 1 instruction per pixel less in the scenes of
    // bench/results/render.md), called from the others (code size).
    // A polygon whose start values need no checks takes them inline in the
    // walkthrough's loop (view-mapped Y'CbCr sampled with the chroma memo);
    // in the others row_fast takes them without the checks.
    constexpr bool kInlineSafe = kProj && memo_inside<Sampler>();
    bool fast = true;
    if (kInlineSafe && s.fast_safe) {
      row_safe<2, kProj>(s, y, xa, len, r);
    } else if constexpr (Sampler::kInlineStart && !kProj) {
      fast = row_fast<2, kProj>(s, y, xa, len, r);
    } else {
      fast = row_fast_call<2, kProj>(s, y, xa, len, r);
    }
    if (!fast) {
      if constexpr (kProj) {
        if (fit > 0 && len > 2 * fit) len = 2 * fit;
      }
      while (!row_piece(s, y, xa, len, r)) len = (len + 1) >> 1;
      if constexpr (kProj) fit = len;
    }
    // Both buffers are indexed from the piece end with i = -len .. -1.
    DT* const ze = zrow + xa + len;
    uint8_t* const oe = crow + (xa + len) * Store<O>::kBytes;
    // A clamping sampler whose piece lies inside the texture samples it
    // without the clamps (the same texels: about 20 Cortex-M4 instructions
    // a pixel less for bilinear 4:2:0).
    if constexpr (kProj) {
      const PieceEnds ends = kInlineSafe ? piece_ends_inline<true>(r, len) : piece_ends<true>(r, len);
      if constexpr (Sampler::kHasInside) {
        if (ends_inside(ends, Sampler::inside_box(tex))) {
          affine_pixels<typename Sampler::Inside, O, D>(ze, oe, len, r, tex, ends);
          xa += len;
          continue;
        }
      }
      affine_pixels<Sampler, O, D>(ze, oe, len, r, tex, ends);
    } else {
      if constexpr (Sampler::kHasInside) {
        if (piece_inside<false>(r, len, Sampler::inside_box(tex))) {
          span_pixels<typename Sampler::Inside, O, D>(ze, oe, len, r, tex);
          xa += len;
          continue;
        }
      }
      span_pixels<Sampler, O, D>(ze, oe, len, r, tex);
    }
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
template <template <TexFormat, Addr, PixelFormat> class S, TexFormat TF, PixelFormat O, DepthFormat D>
SpanFn pick_address(bool repeat, bool proj) {
  if (repeat) {
    return proj ? &texture_span<S<TF, Addr::repeat, O>, true, O, D> : &texture_span<S<TF, Addr::repeat, O>, false, O, D>;
  }
  return proj ? &texture_span<S<TF, Addr::clamp, O>, true, O, D> : &texture_span<S<TF, Addr::clamp, O>, false, O, D>;
}

template <TexFormat TF, PixelFormat O, DepthFormat D>
SpanFn pick_filter(Filter f, bool apron, bool repeat, bool proj) {
  if (!(VDS_CONFIG_RENDER_TEXTURE_FORMATS & (1 << static_cast<int>(TF)))) return nullptr;
  if (f == Filter::nearest) return pick_address<NearestSampler, TF, O, D>(repeat, proj);
  if constexpr (TF != TexFormat::ycbcr420) {
    if (apron) return pick_address<BilinearApronSampler, TF, O, D>(repeat, proj);
  } else {
    if (f == Filter::bilinear_luma) return pick_address<LumaBilinearSampler, TF, O, D>(repeat, proj);
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
    case Shading::mesh_colors:
      return m.filter == Filter::nearest ? &texture_span<LatticeNearestSampler<O>, false, O, D>
                                         : &texture_span<LatticeLinearSampler<O>, false, O, D>;
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

bool is_pow2(uint32_t v) { return v != 0 && (v & (v - 1)) == 0; }

}  // namespace

SpanFn select_span(const PolygonTarget& b, const Mesh& m, bool repeat) {
  if (b.format == PixelFormat::rgb565) {
    return b.depth_format == DepthFormat::d16 ? pick_span<PixelFormat::rgb565, DepthFormat::d16>(m, repeat)
                                              : pick_span<PixelFormat::rgb565, DepthFormat::d32>(m, repeat);
  }
  return b.depth_format == DepthFormat::d16 ? pick_span<PixelFormat::rgb888, DepthFormat::d16>(m, repeat)
                                            : pick_span<PixelFormat::rgb888, DepthFormat::d32>(m, repeat);
}

SpanFn select_flat_span(const PolygonTarget& b) {
  Mesh flat;
  flat.shading = Shading::flat;
  return select_span(b, flat, false);
}

bool point_samples(const Texture& t) {
  return (VDS_CONFIG_RENDER_TEXTURE_FORMATS & (1 << static_cast<int>(TexFormat::ycbcr420))) != 0 &&
         t.format == TexFormat::ycbcr420;
}

namespace {
template <PixelFormat O, Addr A>
OutColor<O> point_sample(const Mesh& m, const TexCtx& c, int32_t u_q8, int32_t v_q8) {
  constexpr TexFormat TF = TexFormat::ycbcr420;
  // The texel containing the point (nearest), or the point less half a
  // texel with 8 fraction bits (the bilinear samplers' coordinates).
  if (m.filter == Filter::nearest) return NearestSampler<TF, A, O>::sample(c, u_q8 >> 8, v_q8 >> 8);
  if (m.filter == Filter::bilinear_luma) return LumaBilinearSampler<TF, A, O>::sample(c, u_q8 - 128, v_q8 - 128);
  return BilinearSampler<TF, A, O>::sample(c, u_q8 - 128, v_q8 - 128);
}
}  // namespace

uint32_t point_colour(const PolygonTarget& b, const Mesh& m, const Texture& t, int32_t u_q8, int32_t v_q8) {
  // Far outside the texture the clamps give its edge; keep the arithmetic in range.
  const auto hold = [](int32_t x) { return x < -(int32_t{1} << 28) ? -(int32_t{1} << 28) : (x > (int32_t{1} << 28) ? int32_t{1} << 28 : x); };
  u_q8 = hold(u_q8);
  v_q8 = hold(v_q8);
  const bool repeat = texture_repeats(t);
  const TexCtx c = make_tex_ctx(t, repeat);
  if (b.format == PixelFormat::rgb565) {
    return repeat ? point_sample<PixelFormat::rgb565, Addr::repeat>(m, c, u_q8, v_q8)
                  : point_sample<PixelFormat::rgb565, Addr::clamp>(m, c, u_q8, v_q8);
  }
  return repeat ? point_sample<PixelFormat::rgb888, Addr::repeat>(m, c, u_q8, v_q8)
                : point_sample<PixelFormat::rgb888, Addr::clamp>(m, c, u_q8, v_q8);
}

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

bool lattice_face_valid(const LatticeFace& f, uint32_t samples) {
  if (f.res_log2 > 10) return false;
  const int64_t R = int64_t{1} << f.res_log2;
  for (int k = 0; k < 3; ++k) {
    if (f.vertex[k] >= samples) return false;
    if (R >= 2) {  // steps 1 and R - 1: the ends of a straight run
      const int64_t first = int64_t{f.edge_base[k]} + f.edge_step[k];
      const int64_t last = int64_t{f.edge_base[k]} + (R - 1) * f.edge_step[k];
      if (first < 0 || last < 0 || first >= samples || last >= samples) return false;
    }
  }
  const int64_t face = (R - 1) * (R - 2) / 2;
  return face == 0 || int64_t{f.face_base} + face <= samples;
}

int fraction_bits(const Mesh& m, PixelFormat out) {
  return m.filter == Filter::nearest ? 0 : bilinear_frac_bits(m.texture->format, out);
}


int32_t span_reciprocal(uint32_t w, int* z) {
  int zz = 0;
  const int32_t y = recip_y(w ? w : 1u, zz);
  *z = zz;
  return y;
}

bool texture_repeats(const Texture& t) {
  return t.address == TexAddress::repeat && is_pow2(t.width) && is_pow2(t.height);
}

}  // namespace vds::detail
