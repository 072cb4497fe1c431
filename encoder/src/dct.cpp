// Host 8x8 forward/inverse DCT in double precision: the orthonormal DCT-II of
// JPEG / IEEE 1180-1990, the yardstick and coefficient source for vds::idct8x8.
#include "vds/enc/dct.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "vds/idct.h"

namespace vds::enc {
namespace {

// basis[k][n] = C(k)/2 * cos((2n+1) k pi/16): the orthonormal 1-D DCT matrix.
struct Basis {
  std::array<std::array<double, 8>, 8> m{};
  Basis() {
    for (int k = 0; k < 8; ++k) {
      const double ck = k == 0 ? 1.0 / std::numbers::sqrt2 : 1.0;
      for (int n = 0; n < 8; ++n)
        m[k][n] = 0.5 * ck * std::cos((2 * n + 1) * k * std::numbers::pi / 16.0);
    }
  }
};

const Basis& basis() {
  static const Basis b;
  return b;
}

// out = M * in * M^T (forward) or M^T * in * M (inverse), row-major 8x8.
void separable(const double in[64], double out[64], bool inverse) {
  const auto& m = basis().m;
  auto coef = [&](int i, int j) { return inverse ? m[j][i] : m[i][j]; };
  double tmp[64];
  for (int r = 0; r < 8; ++r)  // along rows (horizontal index)
    for (int k = 0; k < 8; ++k) {
      double s = 0.0;
      for (int n = 0; n < 8; ++n) s += coef(k, n) * in[8 * r + n];
      tmp[8 * r + k] = s;
    }
  for (int c = 0; c < 8; ++c)  // along columns (vertical index)
    for (int k = 0; k < 8; ++k) {
      double s = 0.0;
      for (int n = 0; n < 8; ++n) s += coef(k, n) * tmp[8 * n + c];
      out[8 * k + c] = s;
    }
}

int16_t round_saturate(double v) {
  const double r = std::round(v);
  return static_cast<int16_t>(std::clamp(r, double{kIdctCoefMin}, double{kIdctCoefMax}));
}

}  // namespace

void fdct8x8_ref(const double in[64], double out[64]) { separable(in, out, false); }

void idct8x8_ref(const double in[64], double out[64]) { separable(in, out, true); }

void fdct8x8(const int16_t in[64], int16_t out[64]) {
  double d[64], f[64];
  for (int i = 0; i < 64; ++i) d[i] = in[i];
  fdct8x8_ref(d, f);
  for (int i = 0; i < 64; ++i) out[i] = round_saturate(f[i]);
}

void fdct8x8(const uint8_t* src, ptrdiff_t stride, int16_t out[64]) {
  double d[64], f[64];
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) d[8 * y + x] = src[y * stride + x] - 128.0;
  fdct8x8_ref(d, f);
  for (int i = 0; i < 64; ++i) out[i] = round_saturate(f[i]);
}

}  // namespace vds::enc
