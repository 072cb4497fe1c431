// Integer 8x8 inverse DCT: separable 1-D Loeffler-Ligtenberg-Moschytz (ICASSP
// 1989) factorisation, 12 multiplies per 1-D transform; accuracy per IEEE 1180-1990.
#include "vds/idct.h"

#if defined(__ARM_FEATURE_SIMD32) && defined(__ARM_FEATURE_DSP) && defined(__ARM_FEATURE_QBIT) && \
    defined(__ARM_FEATURE_SAT)
#include <arm_acle.h>  // dual 16-bit multiply-accumulate, saturation, the Q flag (Cortex-M4 DSP extension)
#define VDS_IDCT_DUAL16 1
#elif defined(__ARM_FEATURE_SIMD32)
#include <arm_acle.h>  // __uqadd8 / __uqsub8
#endif

namespace vds {
namespace {

// Design (docs/idct.md):
// - Each 1-D pass computes the "unscaled" IDCT
//     x[n] = sum_k a(k) X[k] cos((2n+1)k pi/16),  a(0) = 1, a(k) = sqrt(2),
//   i.e. sqrt(8) times the orthonormal 1-D IDCT, so two passes carry a gain of
//   8 that the final shift removes (kGainShift). The DC and the X0 +/- X4
//   butterfly need no multiply, which makes DC-only rows and columns exact
//   shortcuts of the full computation.
// - Column pass: multipliers in Q13. Its sum is the column result in Q13 and
//   stays below 2^31 for every int16 input (|result| <= 7.47 * 32768), so
//   this pass is exact for any input. Results are kept with kPass1FracBits = 3
//   fraction bits (Q3) in a 32-bit workspace: fewer fraction bits measurably
//   worsen the IEEE 1180 error figures.
// - Row pass: multipliers in Q11. Its sum is the output in Q17 (11 + 3 + 3).
//   For coefficients in [-2048, 2047] the output is at most 14296 in
//   magnitude (2048 * (sum_k C(k)/2 |cos|)^2), and (14296 + 128) * 2^17 < 2^31
//   even with idct8x8_put's level shift folded in, so every result is exact.
//   Q12 multipliers would need Q18 and could overflow; the split Q13 / Q3 /
//   Q11 was chosen from the measured candidates in docs/idct.md.
// - Arithmetic is modulo 2^32 (uint32_t): intermediate LLM terms may exceed the
//   final sum, and modular arithmetic makes that both defined and harmless,
//   because a final sum that fits in int32 is recovered exactly from its
//   residue. Out-of-domain input thus stays free of undefined behaviour. The
//   only signed operations are the arithmetic shifts that end each pass.
using u32 = uint32_t;

constexpr int kConstBits1 = 13;     // column-pass multipliers: Q13
constexpr int kPass1FracBits = 3;   // workspace between passes: Q3
constexpr int kConstBits2 = 11;     // row-pass multipliers: Q11
constexpr int kGainShift = 3;       // log2(8): gain of two unscaled passes
constexpr int kPass1Shift = kConstBits1 - kPass1FracBits;               // Q13 -> Q3
constexpr int kPass2Shift = kConstBits2 + kPass1FracBits + kGainShift;  // Q17 -> integer
static_assert(kPass2Shift == 17, "row-pass sum is the output in Q17 (exactness bound above)");
static_assert(kPass2Shift - kConstBits2 - kPass1FracBits == kIdctDcShift,
              "idct8x8_dc_value() must equal the DC shortcut of the full path");

// Round to nearest (ties toward +infinity) by adding half an output step
// before the arithmetic shift.
constexpr u32 kPass1Round = u32{1} << (kPass1Shift - 1);
constexpr u32 kPass2Round = u32{1} << (kPass2Shift - 1);
// idct8x8_put's +128 level shift, folded into the row-pass rounding term.
constexpr u32 kPutLevel = u32{128} << kPass2Shift;

// LLM multipliers as exact-to-1e-8 Q28 literals (value in the comment); ck is
// cos(k pi/16). Reduced to a pass's precision by rounding in integer constexpr
// code, so no float ever reaches the target.
constexpr int kQ28 = 28;
constexpr int32_t kQ28S6 = 145276222;     // sqrt2*c6             0.541196100
constexpr int32_t kQ28S2mS6 = 205451603;  // sqrt2*(c2-c6)        0.765366865
constexpr int32_t kQ28S2pS6 = 496004047;  // sqrt2*(c2+c6)        1.847759065
constexpr int32_t kQ28B5 = 315646704;     // sqrt2*c3             1.175875602
constexpr int32_t kQ28B1 = -241585528;    // sqrt2*(c7-c3)       -0.899976223
constexpr int32_t kQ28B2 = -687977377;    // -sqrt2*(c1+c3)      -2.562915448
constexpr int32_t kQ28B3 = -526555088;    // -sqrt2*(c3+c5)      -1.961570561
constexpr int32_t kQ28B4 = -104738319;    // sqrt2*(c5-c3)       -0.390180644
constexpr int32_t kQ28A7 = 80163239;      // sqrt2*(-c1+c3+c5-c7) 0.298631336
constexpr int32_t kQ28A5 = 551130168;     // sqrt2*(c1+c3-c5+c7)  2.053119869
constexpr int32_t kQ28A3 = 824824586;     // sqrt2*(c1+c3+c5-c7)  3.072711027
constexpr int32_t kQ28A1 = 403007817;     // sqrt2*(c1+c3-c5-c7)  1.501321110

// Q28 -> Q(bits), round to nearest; returned as its 32-bit residue.
constexpr u32 q_from_q28(int32_t q28, int bits) {
  return static_cast<u32>((q28 + (int32_t{1} << (kQ28 - bits - 1))) >> (kQ28 - bits));
}

template <int kBits>
struct Llm {
  static constexpr u32 s6 = q_from_q28(kQ28S6, kBits);
  static constexpr u32 s2m6 = q_from_q28(kQ28S2mS6, kBits);
  static constexpr u32 s2p6 = q_from_q28(kQ28S2pS6, kBits);
  static constexpr u32 b1 = q_from_q28(kQ28B1, kBits);
  static constexpr u32 b2 = q_from_q28(kQ28B2, kBits);
  static constexpr u32 b3 = q_from_q28(kQ28B3, kBits);
  static constexpr u32 b4 = q_from_q28(kQ28B4, kBits);
  static constexpr u32 b5 = q_from_q28(kQ28B5, kBits);
  static constexpr u32 a1 = q_from_q28(kQ28A1, kBits);
  static constexpr u32 a3 = q_from_q28(kQ28A3, kBits);
  static constexpr u32 a5 = q_from_q28(kQ28A5, kBits);
  static constexpr u32 a7 = q_from_q28(kQ28A7, kBits);
  // Sums of the rounded multipliers above, for idct1d_low. Modular
  // arithmetic distributes exactly, so x*(p+q) == x*p + x*q bit for bit.
  static constexpr u32 c2 = s6 + s2m6;        // sqrt2*c2
  static constexpr u32 o0x1 = a1 + b1 + b4 + b5;  // sqrt2*c1
  static constexpr u32 o1x3 = a3 + b2 + b3 + b5;  // -sqrt2*c7
  static constexpr u32 o2x1 = b4 + b5;            // sqrt2*c5
  static constexpr u32 o2x3 = b2 + b5;            // -sqrt2*c1
  static constexpr u32 o3x1 = b1 + b5;            // sqrt2*c7
  static constexpr u32 o3x3 = b3 + b5;            // -sqrt2*c5
};
static_assert(Llm<13>::a3 == 25172 && Llm<13>::s6 == 4433 && Llm<11>::a3 == 6293,
              "multiplier derivation");

// One unscaled 1-D IDCT in Q(kBits). x[0] is unused: the caller passes the DC
// already shifted to Q(kBits) with its rounding term added (dc_term), so one
// add rounds all eight outputs. y[n] is x[n] in Q(kBits).
template <int kBits>
constexpr inline __attribute__((always_inline)) void idct1d(u32 dc_term, const u32 x[8], u32 y[8]) {
  using K = Llm<kBits>;
  // Even part: X0 +/- X4, then the X2/X6 rotation by 3 multiplies.
  const u32 t0 = dc_term + (x[4] << kBits);
  const u32 t1 = dc_term - (x[4] << kBits);
  const u32 zr = (x[2] + x[6]) * K::s6;
  const u32 r0 = zr + x[2] * K::s2m6;  // sqrt2*(c2*X2 + c6*X6)
  const u32 r1 = zr - x[6] * K::s2p6;  // sqrt2*(c6*X2 - c2*X6)
  const u32 e0 = t0 + r0, e3 = t0 - r0;
  const u32 e1 = t1 + r1, e2 = t1 - r1;

  // Odd part: the 4x4 matrix sqrt2*[c1 c3 c5 c7; c3 -c7 -c1 -c5;
  // c5 -c1 c7 c3; c7 -c5 c3 -c1] by 9 multiplies.
  const u32 z1 = (x[7] + x[1]) * K::b1;
  const u32 z2 = (x[5] + x[3]) * K::b2;
  const u32 z5 = (x[7] + x[3] + x[5] + x[1]) * K::b5;
  const u32 z3 = (x[7] + x[3]) * K::b3 + z5;
  const u32 z4 = (x[5] + x[1]) * K::b4 + z5;
  const u32 o0 = x[1] * K::a1 + z1 + z4;
  const u32 o1 = x[3] * K::a3 + z2 + z3;
  const u32 o2 = x[5] * K::a5 + z2 + z4;
  const u32 o3 = x[7] * K::a7 + z1 + z3;

  y[0] = e0 + o0;
  y[7] = e0 - o0;
  y[1] = e1 + o1;
  y[6] = e1 - o1;
  y[2] = e2 + o2;
  y[5] = e2 - o2;
  y[3] = e3 + o3;
  y[4] = e3 - o3;
}

// idct1d for x[4..7] == 0, the common case of sparse blocks (energy in the
// low frequencies): 10 multiplies and 16 adds instead of 12 and 34. It is the
// same linear map with the terms of the zero inputs dropped and the remaining
// products of each input merged, so results are bit-identical to idct1d.
template <int kBits>
inline __attribute__((always_inline)) void idct1d_low(u32 dc_term, const u32 x[8], u32 y[8]) {
  using K = Llm<kBits>;
  const u32 r0 = x[2] * K::c2;
  const u32 r1 = x[2] * K::s6;
  const u32 e0 = dc_term + r0, e3 = dc_term - r0;
  const u32 e1 = dc_term + r1, e2 = dc_term - r1;
  const u32 o0 = x[1] * K::o0x1 + x[3] * K::b5;
  const u32 o1 = x[3] * K::o1x3 + x[1] * K::b5;
  const u32 o2 = x[1] * K::o2x1 + x[3] * K::o2x3;
  const u32 o3 = x[1] * K::o3x1 + x[3] * K::o3x3;
  y[0] = e0 + o0;
  y[7] = e0 - o0;
  y[1] = e1 + o1;
  y[6] = e1 - o1;
  y[2] = e2 + o2;
  y[5] = e2 - o2;
  y[3] = e3 + o3;
  y[4] = e3 - o3;
}

inline u32 wrap(int32_t v) { return static_cast<u32>(v); }
inline int32_t unwrap(u32 v) { return static_cast<int32_t>(v); }  // modular (C++20)

// Written as one conditional expression so that compilers emit a single
// saturate instruction (USAT on Cortex-M4).
inline uint8_t clamp_u8(int32_t v) { return static_cast<uint8_t>(v > 255 ? 255 : (v < 0 ? 0 : v)); }

// Column pass: coef (natural order) -> ws in Q3. A column whose AC terms are
// all zero is flat, DC << kPass1FracBits, bit-identical to the full path
// because the DC takes no multiply.
inline void columns(const int16_t* coef, int32_t* ws) {
  for (int c = 0; c < 8; ++c) {
    const int16_t* in = coef + c;
    int32_t* w = ws + c;
    const int32_t high = in[32] | in[40] | in[48] | in[56];
    if ((in[8] | in[16] | in[24] | high) == 0) {
      const int32_t flat = static_cast<int32_t>(in[0]) * (int32_t{1} << kPass1FracBits);
#pragma GCC unroll 8
      for (int r = 0; r < 8; ++r) w[8 * r] = flat;
      continue;
    }
    // Named loads (not a loop) so the block stays in registers.
    const u32 x[8] = {wrap(in[0]),  wrap(in[8]),  wrap(in[16]), wrap(in[24]),
                      wrap(in[32]), wrap(in[40]), wrap(in[48]), wrap(in[56])};
    u32 y[8];
    if (high == 0)
      idct1d_low<kConstBits1>((x[0] << kConstBits1) + kPass1Round, x, y);
    else
      idct1d<kConstBits1>((x[0] << kConstBits1) + kPass1Round, x, y);
#pragma GCC unroll 8
    for (int r = 0; r < 8; ++r) w[8 * r] = unwrap(y[r]) >> kPass1Shift;
  }
}

enum class Emit { store, put, add };

// Row pass: ws (Q3) -> output, rounded with `bias` (rounding plus any level
// shift, in Q17). Rows with all AC zero take the flat shortcut, bit-identical
// to the full path for the same reason as in the column pass.
template <Emit kEmit>
inline void rows(const int32_t* ws, u32 bias, int16_t* out16, uint8_t* dst, ptrdiff_t stride) {
  for (int r = 0; r < 8; ++r) {
    const int32_t* w = ws + 8 * r;
    int32_t v[8];
    const int32_t high = w[4] | w[5] | w[6] | w[7];
    if ((w[1] | w[2] | w[3] | high) == 0) {
      const int32_t flat = unwrap((wrap(w[0]) << kConstBits2) + bias) >> kPass2Shift;
      if constexpr (kEmit == Emit::put) {  // one clamp for the whole row
        const uint8_t p = clamp_u8(flat);
        uint8_t* d = dst + r * stride;
#pragma GCC unroll 8
        for (int n = 0; n < 8; ++n) d[n] = p;
        continue;
      }
#pragma GCC unroll 8
      for (int n = 0; n < 8; ++n) v[n] = flat;
    } else {
      const u32 x[8] = {wrap(w[0]), wrap(w[1]), wrap(w[2]), wrap(w[3]),
                        wrap(w[4]), wrap(w[5]), wrap(w[6]), wrap(w[7])};
      u32 y[8];
      if (high == 0)
        idct1d_low<kConstBits2>((x[0] << kConstBits2) + bias, x, y);
      else
        idct1d<kConstBits2>((x[0] << kConstBits2) + bias, x, y);
#pragma GCC unroll 8
      for (int n = 0; n < 8; ++n) v[n] = unwrap(y[n]) >> kPass2Shift;
    }
    if constexpr (kEmit == Emit::store) {
      int16_t* o = out16 + 8 * r;
      // An int32 shifted right by 17 always fits int16.
#pragma GCC unroll 8
      for (int n = 0; n < 8; ++n) o[n] = static_cast<int16_t>(v[n]);
    } else if constexpr (kEmit == Emit::put) {
      uint8_t* d = dst + r * stride;
#pragma GCC unroll 8
      for (int n = 0; n < 8; ++n) d[n] = clamp_u8(v[n]);
    } else {
      uint8_t* d = dst + r * stride;
#pragma GCC unroll 8
      for (int n = 0; n < 8; ++n) d[n] = clamp_u8(d[n] + v[n]);
    }
  }
}

#if defined(VDS_IDCT_DUAL16)
// ---- Cortex-M4: both passes on 16-bit lanes ---------------------------------
// Each 1-D pass above is a linear map modulo 2^32, so it equals the plain
// matrix product y[n] = dc_term +/- (x4 << kBits) + sum_v M[n][v] x[v] whose
// entries M are the LLM multipliers summed along each input's paths (the
// same identity idct1d_low relies on). Every entry fits a signed halfword,
// so with the inputs packed in pairs the M4's SMUAD/SMLAD do two of the
// products and the sum in one instruction, and the results are those of
// the 32-bit path bit for bit: a lane product is exact, and the sums are
// the same residues modulo 2^32.
// The column pass reads int16 coefficients, so it always fits the lanes; its
// Q3 results fit a halfword only when the block is not extreme (in-domain
// blocks can reach 17 bits). They are saturated to int16 (SSAT), which
// raises the sticky Q flag when a value did not fit (SMLAD raises it too on
// any accumulator overflow); then the block is transformed again by the
// 32-bit path. Otherwise the row pass takes halfword pairs as well.
namespace dual {

// M[n][v] of a pass: idct1d applied to the unit vector e_v (dc_term 0).
template <int kBits>
constexpr int32_t entry(int n, int v) {
  u32 x[8] = {};
  x[v] = 1;
  u32 y[8] = {};
  idct1d<kBits>(0, x, y);
  return static_cast<int32_t>(y[n]);
}
constexpr bool fits16(int32_t v) { return v >= -32768 && v <= 32767; }
constexpr uint32_t pair(int32_t lo, int32_t hi) {
  return (static_cast<uint32_t>(lo) & 0xFFFFu) | static_cast<uint32_t>(hi) << 16;
}

// The halfword pairs of one pass: the even rotation r0 (outputs 0, 7, 3,
// 4) and r1 (1, 6, 2, 5) on (x2, x6); the odd sums o_n (output n and 7 - n)
// on (x1, x3) and (x5, x7).
struct Pairs {
  uint32_t r[2];
  uint32_t o13[4];
  uint32_t o57[4];
  bool ok;  // every entry fits a halfword, and the structure assumed holds
};
template <int kBits>
constexpr Pairs make_pairs() {
  Pairs p{};
  p.ok = true;
  for (int i = 0; i < 2; ++i) {
    p.r[i] = pair(entry<kBits>(i, 2), entry<kBits>(i, 6));
    p.ok = p.ok && fits16(entry<kBits>(i, 2)) && fits16(entry<kBits>(i, 6));
  }
  for (int n = 0; n < 4; ++n) {
    p.o13[n] = pair(entry<kBits>(n, 1), entry<kBits>(n, 3));
    p.o57[n] = pair(entry<kBits>(n, 5), entry<kBits>(n, 7));
    for (int v = 1; v < 8; v += 2) p.ok = p.ok && fits16(entry<kBits>(n, v)) && entry<kBits>(7 - n, v) == -entry<kBits>(n, v);
  }
  // Even inputs: outputs 0/3 and 1/2 mirror the rotation, 7 - n repeats n.
  for (int v = 2; v < 8; v += 4) {
    p.ok = p.ok && entry<kBits>(3, v) == -entry<kBits>(0, v) && entry<kBits>(2, v) == -entry<kBits>(1, v);
    for (int n = 0; n < 4; ++n) p.ok = p.ok && entry<kBits>(7 - n, v) == entry<kBits>(n, v);
  }
  return p;
}
constexpr Pairs kColPairs = make_pairs<kConstBits1>();
constexpr Pairs kRowPairs = make_pairs<kConstBits2>();
static_assert(kColPairs.ok && kRowPairs.ok, "LLM matrix entries fit halfwords with the expected symmetry");

// GCC does not pick PKHBT / PKHTB for these merges.
inline __attribute__((always_inline)) uint32_t low_halves(uint32_t a, uint32_t b) {  // a.lo, b.lo
  uint32_t r;
  __asm__("pkhbt %0, %1, %2, lsl #16" : "=r"(r) : "r"(a), "r"(b));
  return r;
}
inline __attribute__((always_inline)) uint32_t high_halves(uint32_t a, uint32_t b) {  // a.hi, b.hi
  uint32_t r;
  __asm__("pkhtb %0, %2, %1, asr #16" : "=r"(r) : "r"(a), "r"(b));
  return r;
}
inline int32_t s32(uint32_t v) { return static_cast<int32_t>(v); }

// One 1-D transform from packed inputs: dc = x0 * 2^kBits + rounding (and
// level shift), x4 in either half of w4 (kHigh4), p13 = (x1, x3), p57 =
// (x5, x7), p26 = (x2, x6). y[n] as 32-bit residues, as idct1d.
template <const Pairs& k, int kBits, bool kHigh4>
inline __attribute__((always_inline)) void idct1d_pairs(u32 dc, uint32_t w4, uint32_t p13, uint32_t p57,
                                                        uint32_t p26, u32 y[8]) {
  constexpr int32_t kUnit = int32_t{1} << kBits;
  const u32 t0 = static_cast<u32>(kHigh4 ? __smlatb(s32(w4), kUnit, s32(dc)) : __smlabb(s32(w4), kUnit, s32(dc)));
  const u32 t1 = (dc << 1) - t0;  // dc - x4 * 2^kBits
  const u32 r0 = static_cast<u32>(__smuad(s32(p26), s32(k.r[0])));
  const u32 r1 = static_cast<u32>(__smuad(s32(p26), s32(k.r[1])));
  const u32 e0 = t0 + r0, e3 = t0 - r0, e1 = t1 + r1, e2 = t1 - r1;
  const u32 o0 = static_cast<u32>(__smlad(s32(p57), s32(k.o57[0]), __smuad(s32(p13), s32(k.o13[0]))));
  const u32 o1 = static_cast<u32>(__smlad(s32(p57), s32(k.o57[1]), __smuad(s32(p13), s32(k.o13[1]))));
  const u32 o2 = static_cast<u32>(__smlad(s32(p57), s32(k.o57[2]), __smuad(s32(p13), s32(k.o13[2]))));
  const u32 o3 = static_cast<u32>(__smlad(s32(p57), s32(k.o57[3]), __smuad(s32(p13), s32(k.o13[3]))));
  y[0] = e0 + o0;
  y[7] = e0 - o0;
  y[1] = e1 + o1;
  y[6] = e1 - o1;
  y[2] = e2 + o2;
  y[5] = e2 - o2;
  y[3] = e3 + o3;
  y[4] = e3 - o3;
}

inline __attribute__((always_inline)) uint32_t load32(const void* p) {
  uint32_t v;
  __builtin_memcpy(&v, p, sizeof v);  // unaligned-capable word load
  return v;
}
inline __attribute__((always_inline)) void store32(void* p, uint32_t v) { __builtin_memcpy(p, &v, sizeof v); }

// One column of a pair (kHigh: the odd column, the high halves of the
// words at coef). It loads its own words: see columns().
template <bool kHigh>
inline __attribute__((always_inline)) void column(const int16_t* coef, int16_t* out) {
  uint32_t w[8];
#pragma GCC unroll 8
  for (int v = 0; v < 8; ++v) w[v] = load32(coef + 8 * v);
  constexpr u32 kRound = kPass1Round;
  const u32 dc = static_cast<u32>(kHigh ? __smlatb(s32(w[0]), int32_t{1} << kConstBits1, s32(kRound))
                                        : __smlabb(s32(w[0]), int32_t{1} << kConstBits1, s32(kRound)));
  const uint32_t p13 = kHigh ? high_halves(w[1], w[3]) : low_halves(w[1], w[3]);
  const uint32_t p57 = kHigh ? high_halves(w[5], w[7]) : low_halves(w[5], w[7]);
  const uint32_t p26 = kHigh ? high_halves(w[2], w[6]) : low_halves(w[2], w[6]);
  u32 y[8];
  idct1d_pairs<kColPairs, kConstBits1, kHigh>(dc, w[4], p13, p57, p26, y);
#pragma GCC unroll 8
  for (int r = 0; r < 8; ++r) out[8 * r] = static_cast<int16_t>(__ssat(s32(y[r]) >> kPass1Shift, 16));
}

// Column pass into ws (Q3 halfwords, natural order). Returns false when a
// value did not fit a halfword (or an accumulator overflowed): ws is then
// unusable.
inline __attribute__((always_inline)) bool columns(const int16_t* coef, int16_t* ws) {
  __set_saturation_occurred(0);
  for (int c = 0; c < 8; c += 2) {
    uint32_t w[8];
#pragma GCC unroll 8
    for (int v = 0; v < 8; ++v) w[v] = load32(coef + 8 * v + c);
    if ((w[1] | w[2] | w[3] | w[4] | w[5] | w[6] | w[7]) == 0) {
      // Both columns flat: DC << kPass1FracBits down each.
      const int32_t lo = __ssat(static_cast<int16_t>(w[0]) * (int32_t{1} << kPass1FracBits), 16);
      const int32_t hi = __ssat((s32(w[0]) >> 16) * (int32_t{1} << kPass1FracBits), 16);
      const uint32_t both = low_halves(static_cast<uint32_t>(lo), static_cast<uint32_t>(hi));
#pragma GCC unroll 8
      for (int r = 0; r < 8; ++r) store32(ws + 8 * r + c, both);
      continue;
    }
    // One column at a time: the barrier keeps the compiler from
    // interleaving the two, which would need more registers than there are.
    column<false>(coef + c, ws + c);
    __asm__ volatile("" ::: "memory");
    column<true>(coef + c, ws + c + 1);
  }
  return __saturation_occurred() == 0;
}

// Row pass from halfword pairs, emitting as rows() does.
template <Emit kEmit>
inline __attribute__((always_inline)) void rows(const int16_t* ws, u32 bias, int16_t* out16, uint8_t* dst,
                                                ptrdiff_t stride) {
  for (int r = 0; r < 8; ++r) {
    const uint32_t r01 = load32(ws + 8 * r), r23 = load32(ws + 8 * r + 2);
    const uint32_t r45 = load32(ws + 8 * r + 4), r67 = load32(ws + 8 * r + 6);
    const u32 dc = static_cast<u32>(__smlabb(s32(r01), int32_t{1} << kConstBits2, s32(bias)));
    int32_t v[8];
    if (((r01 >> 16) | r23 | r45 | r67) == 0) {
      const int32_t flat = s32(dc) >> kPass2Shift;
      if constexpr (kEmit == Emit::put) {  // one clamp for the whole row
        constexpr uint32_t kSplat = 0x01010101u;
        const uint32_t p = clamp_u8(flat) * kSplat;
        store32(dst + r * stride, p);
        store32(dst + r * stride + 4, p);
        continue;
      }
#pragma GCC unroll 8
      for (int n = 0; n < 8; ++n) v[n] = flat;
    } else {
      u32 y[8];
      idct1d_pairs<kRowPairs, kConstBits2, false>(dc, r45, high_halves(r01, r23), high_halves(r45, r67),
                                                  low_halves(r23, r67), y);
#pragma GCC unroll 8
      for (int n = 0; n < 8; ++n) v[n] = s32(y[n]) >> kPass2Shift;
    }
    if constexpr (kEmit == Emit::store) {
      int16_t* o = out16 + 8 * r;
#pragma GCC unroll 8
      for (int n = 0; n < 8; ++n) o[n] = static_cast<int16_t>(v[n]);
    } else if constexpr (kEmit == Emit::put) {
      uint32_t b[8];
#pragma GCC unroll 8
      for (int n = 0; n < 8; ++n) b[n] = clamp_u8(v[n]);
      store32(dst + r * stride, b[0] | b[1] << 8 | b[2] << 16 | b[3] << 24);
      store32(dst + r * stride + 4, b[4] | b[5] << 8 | b[6] << 16 | b[7] << 24);
    } else {
      uint8_t* d = dst + r * stride;
#pragma GCC unroll 8
      for (int n = 0; n < 8; ++n) d[n] = clamp_u8(d[n] + v[n]);
    }
  }
}

// The whole block; false (nothing written) when the 32-bit path must do it.
template <Emit kEmit>
inline __attribute__((always_inline)) bool transform(const int16_t* coef, u32 bias, int16_t* out16, uint8_t* dst,
                                                     ptrdiff_t stride) {
  alignas(4) int16_t ws[64];
  if (!columns(coef, ws)) return false;
  rows<kEmit>(ws, bias, out16, dst, stride);
  return true;
}

}  // namespace dual
#endif  // VDS_IDCT_DUAL16

}  // namespace

void idct8x8(const int16_t coef[64], int16_t out[64]) {
#if defined(VDS_IDCT_DUAL16)
  if (dual::transform<Emit::store>(coef, kPass2Round, out, nullptr, 0)) return;
#endif
  int32_t ws[64];
  columns(coef, ws);
  rows<Emit::store>(ws, kPass2Round, out, nullptr, 0);
}

void idct8x8_put(const int16_t coef[64], uint8_t* dst, ptrdiff_t stride) {
#if defined(VDS_IDCT_DUAL16)
  if (dual::transform<Emit::put>(coef, kPass2Round + kPutLevel, nullptr, dst, stride)) return;
#endif
  int32_t ws[64];
  columns(coef, ws);
  rows<Emit::put>(ws, kPass2Round + kPutLevel, nullptr, dst, stride);
}

void idct8x8_add(const int16_t coef[64], uint8_t* dst, ptrdiff_t stride) {
#if defined(VDS_IDCT_DUAL16)
  if (dual::transform<Emit::add>(coef, kPass2Round, nullptr, dst, stride)) return;
#endif
  int32_t ws[64];
  columns(coef, ws);
  rows<Emit::add>(ws, kPass2Round, nullptr, dst, stride);
}

void idct8x8_put_dc(int16_t dc, uint8_t* dst, ptrdiff_t stride) {
  constexpr uint32_t kSplat = 0x01010101u;  // byte -> all four lanes of a word
  const uint32_t w = clamp_u8(idct8x8_dc_value(dc) + 128) * kSplat;
  // __builtin_memcpy: -ffreestanding makes memcpy a real call; the builtin
  // with a constant size is one (unaligned-capable) word store.
  for (int r = 0; r < 8; ++r) {
    __builtin_memcpy(dst + r * stride, &w, 4);
    __builtin_memcpy(dst + r * stride + 4, &w, 4);
  }
}

void idct8x8_add_dc(int16_t dc, uint8_t* dst, ptrdiff_t stride) {
  const int32_t v = idct8x8_dc_value(dc);
#if defined(__ARM_FEATURE_SIMD32)
  // Four pixels per instruction: clamp(d + v) is a saturating unsigned byte
  // add of min(v, 255) (v >= 0) or subtract of min(-v, 255) (v < 0), so the
  // result is the same as the portable loop below, bit for bit.
  constexpr uint32_t kSplat = 0x01010101u;
  const uint32_t mag = static_cast<uint32_t>(v < 0 ? (v < -255 ? 255 : -v) : (v > 255 ? 255 : v)) * kSplat;
  for (int r = 0; r < 8; ++r) {
    uint8_t* d = dst + r * stride;
    uint32_t lo, hi;  // scalars, not an array, to stay in registers
    __builtin_memcpy(&lo, d, 4);  // unaligned word loads (see idct8x8_put_dc)
    __builtin_memcpy(&hi, d + 4, 4);
    lo = v < 0 ? __uqsub8(lo, mag) : __uqadd8(lo, mag);
    hi = v < 0 ? __uqsub8(hi, mag) : __uqadd8(hi, mag);
    __builtin_memcpy(d, &lo, 4);
    __builtin_memcpy(d + 4, &hi, 4);
  }
#else
  for (int r = 0; r < 8; ++r) {
    uint8_t* d = dst + r * stride;
#pragma GCC unroll 8
    for (int n = 0; n < 8; ++n) d[n] = clamp_u8(d[n] + v);
  }
#endif
}

}  // namespace vds
