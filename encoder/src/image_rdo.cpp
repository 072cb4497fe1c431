// vds encoder: rate-distortion optimised quantisation of one block — a
// trellis (dynamic programme) over the scan positions whose state is the
// number of levels still to code, with bit costs from the range coder's
// contexts in their current states (the approach of trellis quantisation in
// H.264/HEVC encoders, fitted to the vds block syntax).
#include <algorithm>
#include <cmath>
#include <limits>

#include "image_coder.h"

namespace vds::enc::detail {

namespace m = image_model;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kBitsPerQ8 = 1.0 / kCostOneBitQ8;

double bits(const ArithContext& c, int bin) { return arith_bin_cost_q8(c, bin) * kBitsPerQ8; }

// Bits of an order-0 Exp-Golomb value (bypass).
double eg0_bits(uint32_t v) {
  int p = 0;
  while (((static_cast<uint64_t>(v) + 1) >> (p + 1)) != 0) ++p;
  return 2.0 * p + 1.0;
}

// Bits of an order-k Exp-Golomb value (bypass).
double egk_bits(uint32_t v, int k) { return eg0_bits(v >> k) + k; }

double dc_bits(const m::ClassContexts& cc, const BlockEnv& env, int32_t res) {
  if (res == 0) return bits(cc.dc_zero[env.dz_ctx], 0);
  const uint32_t mag = static_cast<uint32_t>(res < 0 ? -res : res);
  double b = bits(cc.dc_zero[env.dz_ctx], 1) + bits(cc.dc_gt1[env.dz_ctx], mag > 1) + 1.0;
  if (mag > 1) b += bits(cc.dc_gt2, mag > 2);
  if (mag > 2) b += egk_bits(mag - 3, m::kDcRestOrder);
  return b;
}

double nz_bits(const m::ClassContexts& cc, const BlockEnv& env, uint32_t nz, bool implied) {
  const ArithContext* pre = cc.nz_prefix[m::kNzBucketOf[env.pred_nz]];
  const int len = m::nz_length(nz);
  double b = 0;
  if (!implied) b += bits(pre[0], len > 0);
  if (len > 0)
    for (int i = 1; i < m::kNzPrefixBins && i <= len; ++i) b += bits(pre[i], len > i);
  if (len >= 2) b += bits(cc.nz_suffix[len], static_cast<int>((nz >> (len - 2)) & 1u)) + (len - 2);
  return b;
}

int32_t round_level(double a) { return static_cast<int32_t>(std::floor(a + 0.5)); }

}  // namespace

void choose_levels(const CoderState& s, const BlockEnv& env, const double c[64], const uint16_t q[64],
                   const RdoParams& p, int32_t levels[64]) {
  // DC range keeps the dequantised value inside the IDCT domain.
  const auto clamp_dc = [](int32_t v) { return std::clamp(v, m::kDcLevelMin, m::kDcLevelMax); };
  if (!p.rdo) {
    levels[0] = clamp_dc(round_level(c[0] / q[0]));
    for (int k = 1; k < 64; ++k) {
      const int32_t l = round_level(std::fabs(c[k]) / q[k]);
      const int32_t mag = std::min<int32_t>(l, static_cast<int32_t>(m::kMaxLevel));
      levels[k] = c[k] < 0 ? -mag : mag;
    }
    return;
  }

  const m::ClassContexts& cc = s.ctx.cls[env.cls];
  const double lam = p.lambda, w = p.weight;

  // Bit costs of this block's contexts in their current states.
  double sig_bits[m::kSigPos][m::kSigLeft][2];
  for (int i = 0; i < m::kSigPos; ++i)
    for (int j = 0; j < m::kSigLeft; ++j)
      for (int b = 0; b < 2; ++b) sig_bits[i][j][b] = bits(cc.sig[j][i], b);
  double gt1_bits[m::kLevelPos][m::kLevelLeft][2], gt2_bits[m::kLevelPos][m::kLevelLeft][2];
  for (int i = 0; i < m::kLevelPos; ++i)
    for (int j = 0; j < m::kLevelLeft; ++j)
      for (int b = 0; b < 2; ++b) {
        gt1_bits[i][j][b] = bits(cc.gt1[i][j], b);
        gt2_bits[i][j][b] = bits(cc.gt2[i][j], b);
      }
  // rest_bits[u]: bits of |v| - 3 = u (bypass Exp-Golomb at order 0: the
  // order within a block depends on earlier levels, which the backward
  // trellis does not know).
  double rest_bits[64];
  for (uint32_t u = 0; u < 64; ++u) rest_bits[u] = eg0_bits(u);
  const auto level_cost = [&](int lp, int lb, uint32_t mag) {
    double b = 1.0 + gt1_bits[lp][lb][mag > 1];
    if (mag > 1) {
      b += gt2_bits[lp][lb][mag > 2];
      if (mag > 2) {
        const uint32_t u = mag - 3;
        b += u < 64 ? rest_bits[u] : eg0_bits(u);
      }
    }
    return b;
  };

  // Candidate magnitudes per position: 0, and floor/ceil of |c|/q when useful.
  int cand[64][2];
  int ncand[64];
  double d0[64];
  int last = 0;
  for (int k = 1; k < 64; ++k) {
    const double a = std::fabs(c[k]) / q[k];
    d0[k] = w * c[k] * c[k];
    ncand[k] = 0;
    const int lf = static_cast<int>(std::floor(a));
    if (lf >= 1) cand[k][ncand[k]++] = std::min(lf, static_cast<int>(m::kMaxLevel));
    if (a - lf >= 0.25 || lf == 0) {
      if (lf + 1 <= static_cast<int>(m::kMaxLevel) && (lf >= 1 || a >= 0.3)) cand[k][ncand[k]++] = lf + 1;
    }
    if (ncand[k] > 0) last = k;
  }
  // Distortion of a nonzero level (with the decoder's saturation).
  const auto dist = [&](int k, int mag) {
    const double v = std::fabs(static_cast<double>(dequantise_ac(mag, q[k])));
    const double e = std::fabs(c[k]) - v;
    return w * e * e;
  };

  // cnt[k]: positions in [k, last] with a nonzero candidate.
  int cnt[65];
  cnt[last + 1 <= 64 ? last + 1 : 64] = 0;
  for (int k = 64; k > last; --k) cnt[k] = 0;
  for (int k = last; k >= 1; --k) cnt[k] = cnt[k + 1] + (ncand[k] > 0 ? 1 : 0);

  // f[k][n]: least cost of positions k..last holding exactly n levels.
  static thread_local double f[65][64];
  static thread_local int16_t choice[65][64];
  const int nmax = cnt[1];
  f[last + 1][0] = 0;
  for (int k = last; k >= 1; --k) {
    const int rem = 64 - k;
    f[k][0] = d0[k] + f[k + 1][0];
    choice[k][0] = 0;
    const int sp = m::kSigPosOf[k], lp = m::kLevelPosOf[k];
    for (int n = 1; n <= cnt[k]; ++n) {
      double best = kInf;
      int best_l = 0;
      const bool coded_sig = rem > n;
      if (coded_sig && n <= cnt[k + 1]) {
        const double j = d0[k] + lam * sig_bits[sp][m::kSigLeftOf[n]][0] + f[k + 1][n];
        if (j < best) {
          best = j;
          best_l = 0;
        }
      }
      if (ncand[k] > 0 && n - 1 <= cnt[k + 1]) {
        const double sig1 = coded_sig ? sig_bits[sp][m::kSigLeftOf[n]][1] : 0.0;
        const int lb = m::kLevelLeftOf[n];
        for (int i = 0; i < ncand[k]; ++i) {
          const int mag = cand[k][i];
          const double j = dist(k, mag) + lam * (sig1 + level_cost(lp, lb, static_cast<uint32_t>(mag))) + f[k + 1][n - 1];
          if (j < best) {
            best = j;
            best_l = mag;
          }
        }
      }
      f[k][n] = best;
      choice[k][n] = static_cast<int16_t>(best_l);
    }
  }
  double tail = 0;
  for (int k = last + 1; k < 64; ++k) tail += d0[k];

  // DC candidates: floor and ceil of c0/q0, and the prediction when close.
  const double a0 = c[0] / q[0];
  int32_t dcs[3];
  int ndc = 0;
  dcs[ndc++] = clamp_dc(static_cast<int32_t>(std::floor(a0)));
  dcs[ndc++] = clamp_dc(static_cast<int32_t>(std::floor(a0)) + 1);
  if (std::fabs(env.pred_dc - a0) < 2.0 && env.pred_dc != dcs[0] && env.pred_dc != dcs[1]) dcs[ndc++] = env.pred_dc;
  const auto dc_dist = [&](int32_t dc) {
    const double e = c[0] - dequantise_dc(dc, q[0]);
    return w * e * e;
  };

  // Not coded: DC = prediction, no AC.
  double best = dc_dist(env.pred_dc) + f[1][0] + tail + lam * bits(cc.cbf[env.cbf_ctx], 0);
  int32_t best_dc = env.pred_dc;
  int best_n = 0;
  const double cbf1 = lam * bits(cc.cbf[env.cbf_ctx], 1);
  for (int i = 0; i < ndc; ++i) {
    const int32_t dc = dcs[i];
    const int32_t res = dc - env.pred_dc;
    if (res > m::kDcLevelMax - m::kDcLevelMin || res < m::kDcLevelMin - m::kDcLevelMax) continue;
    const double base = dc_dist(dc) + cbf1 + lam * dc_bits(cc, env, res) + tail;
    for (int n = (res == 0 ? 1 : 0); n <= nmax; ++n) {
      const double j = base + lam * nz_bits(cc, env, static_cast<uint32_t>(n), res == 0) + f[1][n];
      if (j < best) {
        best = j;
        best_dc = dc;
        best_n = n;
      }
    }
  }

  levels[0] = best_dc;
  for (int k = 1; k < 64; ++k) levels[k] = 0;
  int n = best_n;
  for (int k = 1; k <= last && n > 0; ++k) {
    const int mag = choice[k][n];
    if (mag != 0) {
      levels[k] = c[k] < 0 ? -mag : mag;
      --n;
    }
  }
}

}  // namespace vds::enc::detail
