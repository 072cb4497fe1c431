// vds encoder: host 8x8 forward DCT (and a double reference inverse) with the
// coefficient scaling the client's integer IDCT (vds/idct.h) expects.
#pragma once

#include <cstddef>
#include <cstdint>

namespace vds::enc {

// Orthonormal 2-D DCT-II as in JPEG, MPEG and IEEE 1180-1990, natural
// (row-major) order, index 8*v + u (v vertical frequency / row):
//   F(u,v) = 1/4 C(u) C(v) sum_x sum_y f(x,y) cos((2x+1)u pi/16) cos((2y+1)v pi/16)
//   C(0) = 1/sqrt(2), C(k) = 1 otherwise.
// Double precision, separable, cosine table computed once.
void fdct8x8_ref(const double in[64], double out[64]);
// The exact inverse of fdct8x8_ref (the IEEE 1180 reference IDCT before its
// rounding and clipping).
void idct8x8_ref(const double in[64], double out[64]);

// Forward DCT of an integer block (residuals, or level-shifted pixels): each
// coefficient rounded to nearest (halves away from zero) and saturated to the
// client IDCT's domain [vds::kIdctCoefMin, vds::kIdctCoefMax] = [-2048, 2047].
void fdct8x8(const int16_t in[64], int16_t out[64]);

// Forward DCT of an 8x8 pixel block with the -128 level shift, the inverse of
// vds::idct8x8_put: src[y*stride + x] -> coefficients as above.
void fdct8x8(const uint8_t* src, ptrdiff_t stride, int16_t out[64]);

}  // namespace vds::enc
