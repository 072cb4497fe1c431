// vds client library: decoded MCUs to pixels. Y'CbCr -> R'G'B' by the JFIF
// equations (ITU-T T.871 clause 7) in Q16; chroma upsampled by replication.
#include <cstring>

#include "image_output.h"
#include "colour.h"

#if defined(__ARM_FEATURE_SIMD32)
#include <arm_acle.h>  // __uqadd8, __uqsub8, __uxtb16 (Cortex-M4 DSP extension)
#endif

namespace vds {

namespace {

// T.871 / JFIF coefficients in Q16 (colour.h).
using colour::kCbToB;
using colour::kCbToG;
using colour::kChromaCentre;
using colour::kCrToG;
using colour::kCrToR;
constexpr int kColourFracBits = colour::kFracBits;
constexpr int32_t kColourHalf = colour::kHalf;

// The three chroma terms of a chroma sample, rounded to integers (T.871
// in Q16, round to nearest).
struct ChromaTerms {
  int32_t r, g, b;
};

inline ChromaTerms chroma_terms(int cb, int cr) {
  cb -= kChromaCentre;
  cr -= kChromaCentre;
  // Round to nearest by adding half before the arithmetic shift (floor).
  return {(kCrToR * cr + kColourHalf) >> kColourFracBits,
          (-kCbToG * cb - kCrToG * cr + kColourHalf) >> kColourFracBits,
          (kCbToB * cb + kColourHalf) >> kColourFracBits};
}

// One conditional expression: a single USAT on Cortex-M4.
inline uint32_t sat8(int32_t v) { return static_cast<uint32_t>(v > 255 ? 255 : (v < 0 ? 0 : v)); }
// RGB565 fields straight from the unsaturated sum: sat8(v) >> 3 equals
// sat5(v >> 3) (and >> 2 for the 6-bit field), and on a Cortex-M4 the
// shift folds into the USAT instruction.
inline uint32_t sat5(int32_t v) { return static_cast<uint32_t>(v > 31 ? 31 : (v < 0 ? 0 : v)); }
inline uint32_t sat6(int32_t v) { return static_cast<uint32_t>(v > 63 ? 63 : (v < 0 ? 0 : v)); }
constexpr int kRed5Shift = 3, kGreen6Shift = 2, kBlue5Shift = 3;

template <PixelFormat F>
inline void put(uint8_t* d, int y, const ChromaTerms& t) {
  if constexpr (F == PixelFormat::rgb565) {
    const uint32_t r = sat5((y + t.r) >> kRed5Shift), g = sat6((y + t.g) >> kGreen6Shift),
                   b = sat5((y + t.b) >> kBlue5Shift);
    const uint16_t v = static_cast<uint16_t>(r << 11 | g << 5 | b);
    // The builtin, not memcpy: the library is built freestanding (no
    // builtins), and a 2-byte store must not become a call.
    __builtin_memcpy(d, &v, sizeof v);
  } else {
    d[0] = static_cast<uint8_t>(sat8(y + t.r));
    d[1] = static_cast<uint8_t>(sat8(y + t.g));
    d[2] = static_cast<uint8_t>(sat8(y + t.b));
  }
}

template <PixelFormat F>
inline void put_grey(uint8_t* d, int y) {
  if constexpr (F == PixelFormat::rgb565) {
    const uint32_t v8 = static_cast<uint32_t>(y);
    const uint16_t v = static_cast<uint16_t>(((v8 & 0xF8u) << 8) | ((v8 & 0xFCu) << 3) | (v8 >> 3));
    __builtin_memcpy(d, &v, sizeof v);
  } else {
    d[0] = d[1] = d[2] = static_cast<uint8_t>(y);
  }
}

constexpr int bytes_of(PixelFormat f) { return bytes_per_pixel(f); }

#if defined(__ARM_FEATURE_SIMD32)
// ---- Whole 4:2:0 MCUs to RGB565, four pixels per step ------------------------
// The per-pixel path above costs about 18 Cortex-M4 instructions a pixel;
// this one about 9, with the same results: the chroma terms come from
// tables (each term split into its positive and negative part, so that
// sat8(y + t) is a saturating byte add then a saturating byte subtract, four
// pixels at once), and the 5/6/5 fields of four pixels are cut and
// interleaved with word operations. The word layout assumes little-endian
// memory. Only where the DSP extension exists (Cortex-M4/M7): elsewhere the
// per-pixel path is the faster one, and it is the reference the benchmark's
// cross-target CRC check compares this path with.
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "the packed colour path assumes little-endian words");

namespace lanes {
inline uint32_t add_sat(uint32_t a, uint32_t b) { return __uqadd8(a, b); }  // per byte: min(a + b, 255)
inline uint32_t sub_sat(uint32_t a, uint32_t b) { return __uqsub8(a, b); }  // per byte: max(a - b, 0)
inline uint32_t bytes02(uint32_t a) { return __uxtb16(a); }  // bytes 0 and 2 into the halfwords
// GCC does not fold the rotation into UXTB16, nor pick PKHBT / PKHTB for
// the halfword merges: one instruction each here instead of two.
inline uint32_t bytes13(uint32_t a) {  // bytes 1 and 3 into the halfwords
  uint32_t r;
  __asm__("uxtb16 %0, %1, ror #8" : "=r"(r) : "r"(a));
  return r;
}
inline uint32_t low_halves(uint32_t a, uint32_t b) {  // a's low half, then b's
  uint32_t r;
  __asm__("pkhbt %0, %1, %2, lsl #16" : "=r"(r) : "r"(a), "r"(b));
  return r;
}
inline uint32_t high_halves(uint32_t a, uint32_t b) {  // a's high half, then b's
  uint32_t r;
  __asm__("pkhtb %0, %2, %1, asr #16" : "=r"(r) : "r"(a), "r"(b));
  return r;
}
}  // namespace lanes

// A chroma term t as two byte pairs: low halfword max(t, 0) in both bytes,
// high halfword max(-t, 0) in both bytes.
constexpr uint32_t term_pair(int32_t t) {
  const uint32_t pos = static_cast<uint32_t>(t > 0 ? t : 0), neg = static_cast<uint32_t>(t < 0 ? -t : 0);
  return pos * 0x0101u | (neg * 0x0101u) << 16;
}

// The chroma tables. Per sample value v, in one 16-byte row (one address
// computation, two double-word loads per chroma sample pair):
//   c[v][0] B term of Cb = v as a term pair, c[v][1] G part of Cb in Q16
//   plus the rounding half, c[v][2] R term of Cr = v as a term pair,
//   c[v][3] G part of Cr in Q16
// (R and B rounded as chroma_terms() rounds them; the G term depends on both
// samples and is rounded once, from the sum of the two parts), and
//   g[t + kGBias] = the G term t as a term pair.
constexpr int32_t g_term(int cb, int cr) {
  return (-kCbToG * (cb - kChromaCentre) - kCrToG * (cr - kChromaCentre) + kColourHalf) >> kColourFracBits;
}
constexpr int32_t kGMin = g_term(255, 255), kGMax = g_term(0, 0);
constexpr int32_t kGBias = -kGMin;
static_assert(kGMin == -134 && kGMax == 135, "G term range over all 8-bit chroma samples");

struct ChromaTables {
  uint32_t c[256][4];
  uint32_t g[kGMax - kGMin + 1];
};
constexpr ChromaTables make_chroma_tables() {
  ChromaTables t{};
  for (int v = 0; v < 256; ++v) {
    const int32_t c = v - kChromaCentre;
    t.c[v][0] = term_pair((kCbToB * c + kColourHalf) >> kColourFracBits);
    t.c[v][1] = static_cast<uint32_t>(-kCbToG * c + kColourHalf);
    t.c[v][2] = term_pair((kCrToR * c + kColourHalf) >> kColourFracBits);
    t.c[v][3] = static_cast<uint32_t>(-kCrToG * c);
  }
  for (int32_t g = kGMin; g <= kGMax; ++g) t.g[g + kGBias] = term_pair(g);
  return t;
}
alignas(8) constexpr ChromaTables kChroma = make_chroma_tables();

// The three term-pair words of one chroma sample pair.
struct Terms {
  uint32_t r, g, b;
};
inline __attribute__((always_inline)) Terms terms_of(const ChromaTables& t, const uint32_t* g_mid, uint32_t cb,
                                                     uint32_t cr) {
  const uint32_t* e = t.c[cb];
  const uint32_t* f = t.c[cr];
  // Modular sum (the parts are two's complement), then the arithmetic shift.
  const int32_t g = static_cast<int32_t>(e[1] + f[3]) >> kColourFracBits;
  return {f[2], g_mid[g], e[0]};
}

inline __attribute__((always_inline)) uint32_t load32(const uint8_t* p) {
  uint32_t v;
  __builtin_memcpy(&v, p, sizeof v);  // unaligned word load on a Cortex-M4
  return v;
}
inline __attribute__((always_inline)) void store32(uint8_t* p, uint32_t v) { __builtin_memcpy(p, &v, sizeof v); }

// Four luma samples (a word) with the chroma pair words to four RGB565
// pixels at d.
inline __attribute__((always_inline)) void put4_rgb565(uint8_t* d, uint32_t y4, uint32_t rp, uint32_t rn, uint32_t gp,
                                                        uint32_t gn, uint32_t bp, uint32_t bn) {
  const uint32_t r = lanes::sub_sat(lanes::add_sat(y4, rp), rn);
  const uint32_t g = lanes::sub_sat(lanes::add_sat(y4, gp), gn);
  const uint32_t b = lanes::sub_sat(lanes::add_sat(y4, bp), bn);
  // Per pixel: high byte R[7:3] G[7:5], low byte G[4:2] B[7:3].
  const uint32_t hi = (r & 0xF8F8F8F8u) | ((g & 0xE0E0E0E0u) >> 5);
  const uint32_t lo = ((g & 0x1C1C1C1Cu) << 3) | ((b & 0xF8F8F8F8u) >> 3);
  const uint32_t p02 = lanes::bytes02(lo) | lanes::bytes02(hi) << 8;  // pixels 0 and 2
  const uint32_t p13 = lanes::bytes13(lo) | lanes::bytes13(hi) << 8;  // pixels 1 and 3
  store32(d, lanes::low_halves(p02, p13));
  store32(d + 4, lanes::high_halves(p02, p13));
}

// The MCU buffer layout both decoders use (Y 16x16 with stride 16, Cb and
// Cr 8x8 with stride 8, Cr right after Cb): every offset an immediate, which
// keeps the loop's state in registers.
constexpr ptrdiff_t kFixedYStride = 16, kFixedCStride = 8, kFixedCrOffset = 64;

template <bool kFixed>
inline __attribute__((always_inline)) void mcu420_rows(const detail::McuSamples& s, uint8_t* dst, ptrdiff_t ds) {
  const ChromaTables& t = kChroma;
  const uint32_t* const g_mid = t.g + kGBias;
  const uint8_t* cb = s.cb;
  const uint8_t* y = s.y;
  const ptrdiff_t cr_off = kFixed ? kFixedCrOffset : s.cr - s.cb;
  const ptrdiff_t ys = kFixed ? kFixedYStride : s.y_stride;
  const ptrdiff_t cstride = kFixed ? kFixedCStride : s.c_stride;
  for (int cy = 0; cy < 8; ++cy) {
    const uint8_t* const row_end = cb + 8;
    const uint8_t* yr = y;
    uint8_t* d = dst;
    for (const uint8_t* c = cb; c != row_end; c += 2) {
      // Two chroma samples cover four luma columns of two rows.
      const Terms t0 = terms_of(t, g_mid, c[0], c[cr_off]), t1 = terms_of(t, g_mid, c[1], c[cr_off + 1]);
      const uint32_t rp = lanes::low_halves(t0.r, t1.r), rn = lanes::high_halves(t0.r, t1.r);
      const uint32_t gp = lanes::low_halves(t0.g, t1.g), gn = lanes::high_halves(t0.g, t1.g);
      const uint32_t bp = lanes::low_halves(t0.b, t1.b), bn = lanes::high_halves(t0.b, t1.b);
      put4_rgb565(d, load32(yr), rp, rn, gp, gn, bp, bn);
      put4_rgb565(d + ds, load32(yr + ys), rp, rn, gp, gn, bp, bn);
      yr += 4;
      d += 8;
    }
    cb += cstride;
    y += 2 * ys;
    dst += 2 * ds;
  }
}

void mcu420_to_rgb565(const detail::McuSamples& s, uint8_t* dst, ptrdiff_t ds) {
  if (s.y_stride == kFixedYStride && s.c_stride == kFixedCStride && s.cr == s.cb + kFixedCrOffset)
    mcu420_rows<true>(s, dst, ds);
  else
    mcu420_rows<false>(s, dst, ds);
}
#endif  // __ARM_FEATURE_SIMD32

template <PixelFormat F, int SX, int SY>
void convert(const detail::McuSamples& s, int w, int h, uint8_t* dst, ptrdiff_t ds) {
  constexpr int kBpp = bytes_of(F);
  constexpr int kSpanX = 1 << SX, kSpanY = 1 << SY;
#if defined(__ARM_FEATURE_SIMD32)
  if constexpr (F == PixelFormat::rgb565 && SX == 1 && SY == 1) {
    if (w == 16 && h == 16) {
      mcu420_to_rgb565(s, dst, ds);
      return;
    }
  }
#endif
  if (w == 8 * kSpanX && h == 8 * kSpanY) {
    // A whole MCU: fixed trip counts.
    for (int cy = 0; cy < 8; ++cy) {
      const uint8_t* cbr = s.cb + cy * s.c_stride;
      const uint8_t* crr = s.cr + cy * s.c_stride;
      const uint8_t* yr = s.y + (cy << SY) * s.y_stride;
      uint8_t* d = dst + (cy << SY) * ds;
      for (int cx = 0; cx < 8; ++cx) {
        const ChromaTerms t = chroma_terms(cbr[cx], crr[cx]);
#pragma GCC unroll 2
        for (int dy = 0; dy < kSpanY; ++dy)
#pragma GCC unroll 2
          for (int dx = 0; dx < kSpanX; ++dx)
            put<F>(d + dy * ds + ((cx << SX) + dx) * kBpp, yr[dy * s.y_stride + (cx << SX) + dx], t);
      }
    }
    return;
  }
  const int cw = (w + kSpanX - 1) >> SX;
  const int ch = (h + kSpanY - 1) >> SY;
  for (int cy = 0; cy < ch; ++cy) {
    const uint8_t* cbr = s.cb + cy * s.c_stride;
    const uint8_t* crr = s.cr + cy * s.c_stride;
    const int y_first = cy << SY;
    const int rows = (h - y_first) < kSpanY ? (h - y_first) : kSpanY;
    for (int cx = 0; cx < cw; ++cx) {
      const ChromaTerms t = chroma_terms(cbr[cx], crr[cx]);
      const int x_first = cx << SX;
      const int cols = (w - x_first) < kSpanX ? (w - x_first) : kSpanX;
      for (int dy = 0; dy < rows; ++dy) {
        const uint8_t* yr = s.y + (y_first + dy) * s.y_stride + x_first;
        uint8_t* d = dst + (y_first + dy) * ds + x_first * kBpp;
        for (int dx = 0; dx < cols; ++dx) put<F>(d + dx * kBpp, yr[dx], t);
      }
    }
  }
}

template <PixelFormat F>
void convert_grey(const detail::McuSamples& s, int w, int h, uint8_t* dst, ptrdiff_t ds) {
  constexpr int kBpp = bytes_of(F);
  for (int r = 0; r < h; ++r) {
    const uint8_t* yr = s.y + r * s.y_stride;
    uint8_t* d = dst + r * ds;
    for (int x = 0; x < w; ++x) put_grey<F>(d + x * kBpp, yr[x]);
  }
}

template <PixelFormat F>
void convert_any(const detail::McuSamples& s, int w, int h, uint8_t* dst, ptrdiff_t ds) {
  if (s.cb == nullptr) {
    convert_grey<F>(s, w, h, dst, ds);
  } else if (s.sub_x && s.sub_y) {
    convert<F, 1, 1>(s, w, h, dst, ds);
  } else if (s.sub_x) {
    convert<F, 1, 0>(s, w, h, dst, ds);
  } else if (s.sub_y) {
    convert<F, 0, 1>(s, w, h, dst, ds);
  } else {
    convert<F, 0, 0>(s, w, h, dst, ds);
  }
}

}  // namespace

void ycbcr_to_rgb(int y, int cb, int cr, uint8_t rgb[3]) {
  const ChromaTerms t = chroma_terms(cb, cr);
  rgb[0] = static_cast<uint8_t>(sat8(y + t.r));
  rgb[1] = static_cast<uint8_t>(sat8(y + t.g));
  rgb[2] = static_cast<uint8_t>(sat8(y + t.b));
}

namespace detail {

Status check_target(const ImageTarget& t, const OutputGeometry& g, bool residual) {
  if (t.planar) {
    if (t.emit != nullptr) return Status::invalid_argument;  // planes go to memory only
    const int n = g.components;
    for (int c = 0; c < n; ++c) {
      const int w = c == 0 ? g.width : g.chroma_width();
      if (t.data[c] == nullptr || t.stride[c] < w) return Status::invalid_argument;
    }
    return Status::ok;
  }
  if (t.format != PixelFormat::rgb565 && t.format != PixelFormat::rgb888) return Status::invalid_argument;
  if (residual && t.predict == nullptr) return Status::invalid_argument;
  const ptrdiff_t row_bytes = static_cast<ptrdiff_t>(g.width) * bytes_per_pixel(t.format);
  if (t.emit != nullptr && t.data[0] == nullptr) return Status::ok;  // rects
  if (t.data[0] == nullptr || t.stride[0] < row_bytes) return Status::invalid_argument;
  if (t.format == PixelFormat::rgb565 &&
      ((reinterpret_cast<uintptr_t>(t.data[0]) & 1u) != 0 || (t.stride[0] & 1) != 0))
    return Status::invalid_argument;  // 16-bit pixels must be aligned
  return Status::ok;
}

void mcu_to_packed(PixelFormat f, const McuSamples& s, int w, int h, uint8_t* dst, ptrdiff_t ds) {
  if (f == PixelFormat::rgb565)
    convert_any<PixelFormat::rgb565>(s, w, h, dst, ds);
  else
    convert_any<PixelFormat::rgb888>(s, w, h, dst, ds);
}

Status deliver_packed(const ImageTarget& t, const OutputGeometry& g, const McuSamples& s, int x0, int y0,
                      bool row_end, uint8_t* scratch) {
  const int w = (g.width - x0) < g.mcu_w ? (g.width - x0) : g.mcu_w;
  const int h = (g.height - y0) < g.mcu_h ? (g.height - y0) : g.mcu_h;
  const int bpp = bytes_per_pixel(t.format);
  if (t.emit == nullptr) {  // frame
    mcu_to_packed(t.format, s, w, h, t.data[0] + y0 * t.stride[0] + x0 * bpp, t.stride[0]);
    return Status::ok;
  }
  if (t.data[0] == nullptr) {  // rects
    const ptrdiff_t stride = static_cast<ptrdiff_t>(g.mcu_w) * bpp;
    mcu_to_packed(t.format, s, w, h, scratch, stride);
    const PixelRect r{static_cast<uint16_t>(x0), static_cast<uint16_t>(y0), static_cast<uint16_t>(w),
                      static_cast<uint16_t>(h), scratch, stride};
    return t.emit(t.emit_ctx, r) ? Status::ok : Status::aborted;
  }
  // bands: the band buffer holds one MCU row from its top line.
  mcu_to_packed(t.format, s, w, h, t.data[0] + x0 * bpp, t.stride[0]);
  return row_end ? emit_band(t, g, y0) : Status::ok;
}

Status emit_band(const ImageTarget& t, const OutputGeometry& g, int y0) {
  if (t.emit == nullptr || t.data[0] == nullptr || t.planar) return Status::ok;
  const int h = (g.height - y0) < g.mcu_h ? (g.height - y0) : g.mcu_h;
  const PixelRect r{0, static_cast<uint16_t>(y0), static_cast<uint16_t>(g.width), static_cast<uint16_t>(h),
                    t.data[0], t.stride[0]};
  return t.emit(t.emit_ctx, r) ? Status::ok : Status::aborted;
}

}  // namespace detail
}  // namespace vds
