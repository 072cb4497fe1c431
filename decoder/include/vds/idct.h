// vds client: integer-only 8x8 inverse DCT, accurate to IEEE 1180-1990.
// Separable Loeffler-Ligtenberg-Moschytz factorisation, 32-bit arithmetic.
#pragma once

#include <cstddef>
#include <cstdint>

namespace vds {

// Coefficients are those of the orthonormal 2-D DCT-II used by JPEG, MPEG and
// IEEE 1180:
//   F(u,v) = 1/4 C(u) C(v) sum_x sum_y f(x,y) cos((2x+1)u pi/16) cos((2y+1)v pi/16)
//   C(0) = 1/sqrt(2), C(k) = 1 otherwise,
// stored in natural (row-major) order: coef[8*v + u], v vertical frequency.
// No scale factor is folded into the dequantisation tables: the LLM form is
// unscaled, so a plain dequantised coefficient goes straight in.
//
// Domain: results are exact to the documented fixed-point design (and meet
// IEEE 1180) for coefficients in [kIdctCoefMin, kIdctCoefMax], the 12-bit range
// a dequantiser must saturate to. Any other int16 input is still safe (no
// undefined behaviour, deterministic on every target) but its result is
// unspecified.
inline constexpr int kIdctCoefMin = -2048;
inline constexpr int kIdctCoefMax = 2047;

// Inverse DCT of one block. Output is the spatial block in natural order,
// rounded to nearest; it always fits int16 and is not clamped further.
void idct8x8(const int16_t coef[64], int16_t out[64]);

// Intra block: dst[y*stride + x] = clamp(idct(coef)(x,y) + 128, 0, 255).
void idct8x8_put(const int16_t coef[64], uint8_t* dst, ptrdiff_t stride);

// Residual block: dst[y*stride + x] = clamp(dst[y*stride + x] + idct(coef)(x,y), 0, 255).
void idct8x8_add(const int16_t coef[64], uint8_t* dst, ptrdiff_t stride);

// DC-only blocks (all 63 AC coefficients zero, which the entropy decoder knows
// from the end-of-block position): about 10x cheaper than the full entry
// points, with the same result. The full transform of such a block is flat
// with this value, bit-exactly: the unscaled LLM passes carry the DC through
// without a multiply, so only the final rounding shift remains. kIdctDcShift
// is log2(8): the 2-D orthonormal DC basis is 1/8.
inline constexpr int kIdctDcShift = 3;
constexpr int32_t idct8x8_dc_value(int16_t dc) {
  return (static_cast<int32_t>(dc) + (1 << (kIdctDcShift - 1))) >> kIdctDcShift;
}
void idct8x8_put_dc(int16_t dc, uint8_t* dst, ptrdiff_t stride);
void idct8x8_add_dc(int16_t dc, uint8_t* dst, ptrdiff_t stride);

}  // namespace vds
