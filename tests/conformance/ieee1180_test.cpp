// IEEE 1180-1990 accuracy procedure for vds::idct8x8 (all six runs), plus the
// put/add/DC-only entry points and the host forward DCT (vds/enc/dct.h).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <vector>

#include "vds/enc/dct.h"
#include "vds/idct.h"
#include "../unit/xorshift.h"

namespace {

// The standard's generator: randx = randx * 1103515245 + 12345 on a 32-bit
// long, keep bits 1..30, scale to [0, 1) and then to [-L, H]. Only bits below
// 31 are used, so unsigned 32-bit arithmetic gives the identical sequence.
class Ieee1180Random {
 public:
  long next(long L, long H) {
    randx_ = randx_ * 1103515245u + 12345u;
    const uint32_t i = randx_ & 0x7ffffffeu;
    double x = static_cast<double>(i) / static_cast<double>(0x7fffffff);
    x *= static_cast<double>(L + H + 1);
    const long j = static_cast<long>(x);  // truncate, as the standard does
    return j - L;
  }

 private:
  uint32_t randx_ = 1;
};

// IEEE 1180-1990 limits.
constexpr int kBlocks = 10000;
constexpr int kPeakLimit = 1;             // peak error at any pixel
constexpr double kPmseLimit = 0.06;       // mean square error of each pixel
constexpr double kOmseLimit = 0.02;       // overall mean square error
constexpr double kPmeLimit = 0.015;       // |mean error| of each pixel
constexpr double kOmeLimit = 0.0015;      // |overall mean error|

struct Figures {
  int peak = 0;
  double worst_pmse = 0;
  double omse = 0;
  double worst_pme = 0;  // largest |mean error| over the 64 pixels
  double ome = 0;
};

int clip(long v, long lo, long hi) { return static_cast<int>(std::clamp(v, lo, hi)); }

Figures run_ieee1180(long L, long H, int sign) {
  Ieee1180Random rng;
  std::array<long, 64> sum_err{}, sum_sq{};
  int peak = 0;
  for (int b = 0; b < kBlocks; ++b) {
    double pix[64], freq[64];
    for (int i = 0; i < 64; ++i) pix[i] = static_cast<double>(sign * rng.next(L, H));
    vds::enc::fdct8x8_ref(pix, freq);
    int16_t coef[64];
    double coefd[64];
    for (int i = 0; i < 64; ++i) {
      coef[i] = static_cast<int16_t>(clip(static_cast<long>(std::floor(freq[i] + 0.5)), -2048, 2047));
      coefd[i] = coef[i];
    }
    double refd[64];
    vds::enc::idct8x8_ref(coefd, refd);
    int16_t test[64];
    vds::idct8x8(coef, test);
    for (int i = 0; i < 64; ++i) {
      const int ref = clip(static_cast<long>(std::floor(refd[i] + 0.5)), -256, 255);
      const int err = clip(test[i], -256, 255) - ref;
      sum_err[i] += err;
      sum_sq[i] += err * err;
      peak = std::max(peak, std::abs(err));
    }
  }
  Figures f;
  f.peak = peak;
  long tot_err = 0, tot_sq = 0;
  for (int i = 0; i < 64; ++i) {
    f.worst_pmse = std::max(f.worst_pmse, static_cast<double>(sum_sq[i]) / kBlocks);
    f.worst_pme = std::max(f.worst_pme, std::abs(static_cast<double>(sum_err[i]) / kBlocks));
    tot_err += sum_err[i];
    tot_sq += sum_sq[i];
  }
  f.omse = static_cast<double>(tot_sq) / (64.0 * kBlocks);
  f.ome = static_cast<double>(tot_err) / (64.0 * kBlocks);
  // One machine-readable line per run (bench/run_idct.sh collects them).
  std::printf("IEEE1180 L=%ld H=%ld sign=%+d peak=%d pmse=%.6f omse=%.6f pme=%.6f ome=%.7f\n", L, H,
              sign, f.peak, f.worst_pmse, f.omse, f.worst_pme, f.ome);
  return f;
}

void expect_within_limits(const Figures& f) {
  EXPECT_LE(f.peak, kPeakLimit);
  EXPECT_LE(f.worst_pmse, kPmseLimit);
  EXPECT_LE(f.omse, kOmseLimit);
  EXPECT_LE(f.worst_pme, kPmeLimit);
  EXPECT_LE(std::abs(f.ome), kOmeLimit);
}

TEST(Ieee1180, Range256_255Positive) { expect_within_limits(run_ieee1180(256, 255, +1)); }
TEST(Ieee1180, Range256_255Negated) { expect_within_limits(run_ieee1180(256, 255, -1)); }
TEST(Ieee1180, Range5Positive) { expect_within_limits(run_ieee1180(5, 5, +1)); }
TEST(Ieee1180, Range5Negated) { expect_within_limits(run_ieee1180(5, 5, -1)); }
TEST(Ieee1180, Range300Positive) { expect_within_limits(run_ieee1180(300, 300, +1)); }
TEST(Ieee1180, Range300Negated) { expect_within_limits(run_ieee1180(300, 300, -1)); }

TEST(Ieee1180, GeneratorFirstValues) {
  // First outputs of the standard's generator, worked out independently from
  // its formula: randx_1 = 1103527590, bits 1..30 / (2^31 - 1) = 0.51387...,
  // times 512 truncates to 263, minus L = 7; and so on.
  Ieee1180Random a;
  const long expect_256[5] = {7, -167, -98, 17, 229};
  for (long e : expect_256) EXPECT_EQ(a.next(256, 255), e);
  Ieee1180Random b;
  const long expect_5[5] = {0, -4, -2, 0, 5};
  for (long e : expect_5) EXPECT_EQ(b.next(5, 5), e);
}

TEST(Ieee1180, ZeroInZeroOut) {
  double pix[64] = {}, freq[64];
  vds::enc::fdct8x8_ref(pix, freq);
  int16_t coef[64];
  for (int i = 0; i < 64; ++i) coef[i] = static_cast<int16_t>(std::floor(freq[i] + 0.5));
  int16_t out[64];
  std::memset(out, 0x55, sizeof out);
  vds::idct8x8(coef, out);
  for (int i = 0; i < 64; ++i) EXPECT_EQ(out[i], 0) << "pixel " << i;
}

// ---------------------------------------------------------------------------
// The other entry points, the domain edges and the host DCT.

// Small deterministic generator for the remaining tests.
struct Xorshift : vds::test::Xorshift32 {
  int range(int lo, int hi) { return lo + static_cast<int>(next() % static_cast<uint32_t>(hi - lo + 1)); }
};

// A coefficient block as a decoder would see it: kind 0 = DC only, 1 = a few
// low frequencies, 2 = dense, 3 = dense at the full 12-bit range.
void random_block(Xorshift& rng, int kind, int16_t coef[64]) {
  std::memset(coef, 0, 64 * sizeof(int16_t));
  coef[0] = static_cast<int16_t>(rng.range(-2048, 2047));
  if (kind == 1) {
    const int n = rng.range(1, 6);
    for (int i = 0; i < n; ++i) coef[rng.range(1, 3) * 8 + rng.range(0, 3)] = static_cast<int16_t>(rng.range(-300, 300));
  } else if (kind == 2) {
    for (int i = 1; i < 64; ++i) coef[i] = static_cast<int16_t>(rng.range(-200, 200) / (1 + i / 8 + i % 8));
  } else if (kind == 3) {
    for (int i = 1; i < 64; ++i) coef[i] = static_cast<int16_t>(rng.range(-2048, 2047));
  }
}

uint8_t clamp_u8(int v) { return static_cast<uint8_t>(std::clamp(v, 0, 255)); }

constexpr ptrdiff_t kStride = 13;  // not 8, to catch stride bugs
constexpr size_t kCanvas = 8 * kStride + 16;

// Every written byte must be inside the 8x8 block of a strided canvas.
void expect_untouched_outside_block(const std::vector<uint8_t>& canvas, const std::vector<uint8_t>& before) {
  for (size_t i = 0; i < canvas.size(); ++i) {
    const bool inside = i < 8 * kStride && static_cast<ptrdiff_t>(i) % kStride < 8;
    if (!inside) ASSERT_EQ(canvas[i], before[i]) << "byte " << i << " outside the block was written";
  }
}

TEST(Idct8x8, PutAndAddMatchStoreWithLevelShiftAndClamp) {
  Xorshift rng;
  for (int t = 0; t < 4000; ++t) {
    int16_t coef[64];
    random_block(rng, t % 4, coef);
    int16_t ref[64];
    vds::idct8x8(coef, ref);

    std::vector<uint8_t> canvas(kCanvas), before;
    for (auto& b : canvas) b = static_cast<uint8_t>(rng.next());
    before = canvas;
    vds::idct8x8_put(coef, canvas.data(), kStride);
    for (int y = 0; y < 8; ++y)
      for (int x = 0; x < 8; ++x)
        ASSERT_EQ(canvas[y * kStride + x], clamp_u8(ref[8 * y + x] + 128)) << "put, block " << t;
    expect_untouched_outside_block(canvas, before);

    for (auto& b : canvas) b = static_cast<uint8_t>(rng.next());
    before = canvas;
    vds::idct8x8_add(coef, canvas.data(), kStride);
    for (int y = 0; y < 8; ++y)
      for (int x = 0; x < 8; ++x)
        ASSERT_EQ(canvas[y * kStride + x], clamp_u8(before[y * kStride + x] + ref[8 * y + x]))
            << "add, block " << t;
    expect_untouched_outside_block(canvas, before);
  }
}

TEST(Idct8x8, DcOnlyPathsEqualFullPath) {
  for (int dc = -2048; dc <= 2047; ++dc) {
    int16_t coef[64] = {};
    coef[0] = static_cast<int16_t>(dc);
    int16_t full[64];
    vds::idct8x8(coef, full);
    const int32_t v = vds::idct8x8_dc_value(static_cast<int16_t>(dc));
    // The orthonormal DC basis is 1/8: the value is dc/8 rounded to nearest.
    ASSERT_LE(std::abs(8 * v - dc), 4) << dc;
    for (int i = 0; i < 64; ++i) ASSERT_EQ(full[i], v) << "dc " << dc << " pixel " << i;

    uint8_t a[8 * kStride], b[8 * kStride];
    std::memset(a, 0xa5, sizeof a);
    std::memset(b, 0xa5, sizeof b);
    vds::idct8x8_put(coef, a, kStride);
    vds::idct8x8_put_dc(coef[0], b, kStride);
    ASSERT_EQ(0, std::memcmp(a, b, sizeof a)) << "put_dc, dc " << dc;

    for (size_t i = 0; i < sizeof a; ++i) a[i] = b[i] = static_cast<uint8_t>(i * 37 + dc);
    vds::idct8x8_add(coef, a, kStride);
    vds::idct8x8_add_dc(coef[0], b, kStride);
    ASSERT_EQ(0, std::memcmp(a, b, sizeof a)) << "add_dc, dc " << dc;
  }
}

// The header promises overflow-free results over the whole 12-bit coefficient
// domain. The largest outputs come from blocks whose signs match a pixel's
// basis functions at full magnitude: check each of the 128 such worst cases
// against the double reference. An overflowed (wrapped) sum would be off by
// thousands; the multiplier precision allows a few units at this magnitude,
// where the IEEE 1180 data (|output| <= 300) allows one.
TEST(Idct8x8, ExtremeBlocksAtDomainEdgeMatchReference) {
  const double pi = std::acos(-1.0);
  int largest = 0;
  double worst = 0;
  for (int p = 0; p < 64; ++p) {
    for (int sign : {+1, -1}) {
      const int py = p / 8, px = p % 8;
      int16_t coef[64];
      double coefd[64], ref[64];
      for (int v = 0; v < 8; ++v)
        for (int u = 0; u < 8; ++u) {
          const double basis = std::cos((2 * px + 1) * u * pi / 16) * std::cos((2 * py + 1) * v * pi / 16);
          const bool positive = (basis >= 0) == (sign > 0);
          coef[8 * v + u] = static_cast<int16_t>(positive ? vds::kIdctCoefMax : vds::kIdctCoefMin);
          coefd[8 * v + u] = coef[8 * v + u];
        }
      vds::enc::idct8x8_ref(coefd, ref);
      int16_t out[64];
      vds::idct8x8(coef, out);
      for (int i = 0; i < 64; ++i) worst = std::max(worst, std::abs(out[i] - ref[i]));
      largest = std::max(largest, std::abs(static_cast<int>(out[p])));

      uint8_t px8[64];
      vds::idct8x8_put(coef, px8, 8);
      for (int i = 0; i < 64; ++i) ASSERT_EQ(px8[i], clamp_u8(out[i] + 128)) << p;
    }
  }
  EXPECT_LE(worst, 3.0);
  // 2048 * (sum_k C(k)/2 |cos((2x+1)k pi/16)|)^2 = 14296: the cases reach the edge.
  EXPECT_GE(largest, 14290);
}

// Outside the 12-bit domain results are unspecified but must be safe (UBSan
// judges) and deterministic; DC-only blocks stay exact for every int16.
TEST(Idct8x8, FullInt16InputIsSafeAndDeterministic) {
  Xorshift rng;
  for (int t = 0; t < 500; ++t) {
    int16_t coef[64];
    for (auto& c : coef) c = static_cast<int16_t>(rng.next());
    if (t % 5 == 0) std::fill(coef, coef + 64, t % 10 == 0 ? INT16_MIN : INT16_MAX);
    int16_t a[64], b[64];
    vds::idct8x8(coef, a);
    vds::idct8x8(coef, b);
    ASSERT_EQ(0, std::memcmp(a, b, sizeof a));
    uint8_t px[64];
    vds::idct8x8_put(coef, px, 8);
    vds::idct8x8_add(coef, px, 8);
  }
  for (int dc : {INT16_MIN, INT16_MIN + 1, -2049, 2048, INT16_MAX}) {
    int16_t coef[64] = {};
    coef[0] = static_cast<int16_t>(dc);
    int16_t out[64];
    vds::idct8x8(coef, out);
    for (int i = 0; i < 64; ++i) ASSERT_EQ(out[i], vds::idct8x8_dc_value(coef[0])) << dc;
  }
}

// Bit-exactness lock: the same pseudo-random blocks must give the same bytes
// on every host and on the Cortex-M build; a change of the fixed-point design
// must change these values deliberately. The sparse set (a few coefficients,
// often all in the low-frequency quarter) pins the zero-skipping shortcuts to
// the results of the full computation, from which the values were taken.
uint32_t fnv_block(uint32_t h, const int16_t out[64]) {
  for (int i = 0; i < 64; ++i) {
    const uint16_t u = static_cast<uint16_t>(out[i]);
    h = (h ^ (u & 0xffu)) * 16777619u;
    h = (h ^ (u >> 8)) * 16777619u;
  }
  return h;
}

TEST(Idct8x8, GoldenChecksum) {
  Xorshift rng;
  uint32_t h = 2166136261u;  // FNV-1a
  for (int t = 0; t < 2000; ++t) {
    int16_t coef[64], out[64];
    random_block(rng, t % 4, coef);
    vds::idct8x8(coef, out);
    h = fnv_block(h, out);
  }
  EXPECT_EQ(h, 0x69c099acu);
}

TEST(Idct8x8, GoldenChecksumSparse) {
  Xorshift rng;
  uint32_t h = 2166136261u;
  for (int t = 0; t < 6000; ++t) {
    int16_t coef[64] = {};
    const int n = rng.range(1, 6);
    const int span = t % 2 ? 4 : 8;  // low-frequency quarter, or anywhere
    for (int i = 0; i < n; ++i)
      coef[8 * rng.range(0, span - 1) + rng.range(0, span - 1)] = static_cast<int16_t>(rng.range(-2048, 2047));
    int16_t out[64];
    vds::idct8x8(coef, out);
    h = fnv_block(h, out);
  }
  EXPECT_EQ(h, 0x90934794u);
}

// ---------------------------------------------------------------------------
// Host forward DCT.

TEST(HostDct, ReferencePairIsOrthonormalAndInverse) {
  Xorshift rng;
  for (int t = 0; t < 200; ++t) {
    double in[64], f[64], back[64];
    double energy_in = 0, energy_f = 0;
    for (double& v : in) {
      v = rng.range(-300, 300);
      energy_in += v * v;
    }
    vds::enc::fdct8x8_ref(in, f);
    for (double v : f) energy_f += v * v;
    EXPECT_NEAR(energy_in, energy_f, 1e-6 * energy_in + 1e-9);  // Parseval
    vds::enc::idct8x8_ref(f, back);
    for (int i = 0; i < 64; ++i) ASSERT_NEAR(back[i], in[i], 1e-9);
  }
  // A flat block has only DC = 8 * value; one cosine has one coefficient.
  double flat[64], f[64];
  std::fill(flat, flat + 64, 10.0);
  vds::enc::fdct8x8_ref(flat, f);
  EXPECT_NEAR(f[0], 80.0, 1e-9);
  for (int i = 1; i < 64; ++i) EXPECT_NEAR(f[i], 0.0, 1e-9);
  const double pi = std::acos(-1.0);
  double wave[64];
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) wave[8 * y + x] = 100.0 * std::cos((2 * x + 1) * 3 * pi / 16);
  vds::enc::fdct8x8_ref(wave, f);
  // Row-major coefficient index 8*v + u: horizontal frequency u = 3, v = 0.
  // 1/4 * C(0) * C(3) * 100 * (sum_x cos^2 = 4) * (sum_y 1 = 8) = 800/sqrt2.
  EXPECT_NEAR(f[3], 800.0 / std::sqrt(2.0), 1e-9);
  for (int i = 0; i < 64; ++i)
    if (i != 3) EXPECT_NEAR(f[i], 0.0, 1e-9) << i;
}

TEST(HostDct, IntegerFdctRoundsAndSaturates) {
  int16_t in[64], out[64];
  std::fill(in, in + 64, int16_t{300});
  vds::enc::fdct8x8(in, out);
  EXPECT_EQ(out[0], 2047);  // 2400 saturates to the IDCT domain
  std::fill(in, in + 64, int16_t{-300});
  vds::enc::fdct8x8(in, out);
  EXPECT_EQ(out[0], -2048);
  std::fill(in, in + 64, int16_t{-5});
  in[0] = -4;  // DC = (-320 + 1) / 8 = -39.875 -> -40
  vds::enc::fdct8x8(in, out);
  EXPECT_EQ(out[0], -40);
}

// fdct -> (no quantisation) -> idct8x8_put reproduces 8-bit blocks within +-1.
TEST(HostDct, RoundTripPixelsWithinOne) {
  Xorshift rng;
  int max_err = 0;
  long exact = 0;
  for (int t = 0; t < 3000; ++t) {
    uint8_t src[8 * kStride], dst[8 * kStride];
    const int kind = t % 3;  // uniform noise, smooth gradient, saturated edges
    for (int y = 0; y < 8; ++y)
      for (int x = 0; x < 8; ++x) {
        int v = rng.range(0, 255);
        if (kind == 1) v = std::clamp(static_cast<int>(t % 256) + 9 * x - 7 * y + rng.range(-3, 3), 0, 255);
        if (kind == 2) v = (x + y + t) % 2 ? 255 : rng.range(0, 3);
        src[y * kStride + x] = static_cast<uint8_t>(v);
      }
    int16_t coef[64];
    vds::enc::fdct8x8(src, kStride, coef);
    vds::idct8x8_put(coef, dst, kStride);
    for (int y = 0; y < 8; ++y)
      for (int x = 0; x < 8; ++x) {
        const int e = std::abs(dst[y * kStride + x] - src[y * kStride + x]);
        max_err = std::max(max_err, e);
        exact += e == 0;
      }
  }
  EXPECT_LE(max_err, 1);
  EXPECT_GT(exact, 3000 * 64 * 9 / 10);  // the vast majority is exact
}

// Residual round trip through idct8x8_add (the inter path).
TEST(HostDct, RoundTripResidualWithinOne) {
  Xorshift rng;
  for (int t = 0; t < 2000; ++t) {
    uint8_t pred[64], target[64];
    int16_t resid[64], coef[64];
    for (int i = 0; i < 64; ++i) {
      pred[i] = static_cast<uint8_t>(rng.next());
      target[i] = static_cast<uint8_t>(std::clamp(pred[i] + rng.range(-40, 40), 0, 255));
      resid[i] = static_cast<int16_t>(target[i] - pred[i]);
    }
    vds::enc::fdct8x8(resid, coef);
    vds::idct8x8_add(coef, pred, 8);
    for (int i = 0; i < 64; ++i) ASSERT_LE(std::abs(pred[i] - target[i]), 1) << "block " << t;
  }
}

}  // namespace
