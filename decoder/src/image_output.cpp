// vds client library: decoded MCUs to pixels. Y'CbCr -> R'G'B' by the JFIF
// equations (ITU-T T.871 clause 7) in Q16; chroma upsampled by replication.
#include <cstring>

#include "image_output.h"

namespace vds {

namespace {

// T.871 / JFIF coefficients in Q16, each round(c * 2^16):
// R = Y + 1.402 Cr', G = Y - 0.34414 Cb' - 0.71414 Cr', B = Y + 1.772 Cb'
// with Cb' = Cb - 128, Cr' = Cr - 128.
constexpr int kColourFracBits = 16;
constexpr int32_t kCrToR = 91881;
constexpr int32_t kCbToG = 22554;
constexpr int32_t kCrToG = 46802;
constexpr int32_t kCbToB = 116130;
constexpr int32_t kColourHalf = int32_t{1} << (kColourFracBits - 1);
constexpr int kChromaCentre = 128;

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

// Colour MCU, chroma subsampled by (1 << SX) x (1 << SY): each chroma
// sample's terms are computed once and applied to the luma samples it covers.
template <PixelFormat F, int SX, int SY>
void convert(const detail::McuSamples& s, int w, int h, uint8_t* dst, ptrdiff_t ds) {
  constexpr int kBpp = bytes_of(F);
  constexpr int kSpanX = 1 << SX, kSpanY = 1 << SY;
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
