// vds client library: the context model of the vds image codec, shared bit
// for bit by the client decoder (image_decoder.cpp) and the host encoder
// (encoder/src/image_blocks.cpp), and the decoder's inlined range decoder.
// Not an application interface.
//
// Block syntax (docs/texture-codec.md has the full description):
//   cbf                      coded-block flag; 0 = DC equals its prediction, no AC
//   dc residual              zero flag, |r| > 1, |r| > 2 (contexts), |r| - 3 as a
//                            bypass Exp-Golomb code of order 1, sign (bypass)
//   nz                       number of nonzero AC coefficients, 0..63 (the "> 0"
//                            bin is implied when the DC residual is 0)
//   for k = 1.. while nz_left > 0 (zig-zag order):
//     sig(k)                 omitted when every remaining position must be nonzero
//     level                  |v| > 1, |v| > 2 (contexts), |v| - 3 as a bypass
//                            Exp-Golomb code of an order that adapts within
//                            the block, sign (bypass)
// The run of zeros before each level is thus coded in unary by the sig bins,
// whose contexts know the position and how many levels are still to come.
#pragma once
#include <cstddef>
#include <cstdint>

#include "vds/arith.h"
#include "vds/status.h"

namespace vds::image_model {

// Zig-zag scan (ITU-T T.81 figure A.6): scan index -> natural index 8*v + u.
inline constexpr uint8_t kZigzag[64] = {
    0,  1,  8,  16, 9,  2,  3,  10, 17, 24, 32, 25, 18, 11, 4,  5,  12, 19, 26, 33, 40, 48,
    41, 34, 27, 20, 13, 6,  7,  14, 21, 28, 35, 42, 49, 56, 57, 50, 43, 36, 29, 22, 15, 23,
    30, 37, 44, 51, 58, 59, 52, 45, 38, 31, 39, 46, 53, 60, 61, 54, 47, 55, 62, 63};

// ITU-T T.81 Annex K tables K.1 (luminance) and K.2 (chrominance), natural
// order: the image codec's quantiser shapes and the mesh colors codec's steps.
inline constexpr uint8_t kAnnexKLuma[64] = {
    16, 11, 10, 16, 24,  40,  51,  61,  12, 12, 14, 19, 26,  58,  60,  55,
    14, 13, 16, 24, 40,  57,  69,  56,  14, 17, 22, 29, 51,  87,  80,  62,
    18, 22, 37, 56, 68,  109, 103, 77,  24, 35, 55, 64, 81,  104, 113, 92,
    49, 64, 78, 87, 103, 121, 120, 101, 72, 92, 95, 98, 112, 100, 103, 99};
inline constexpr uint8_t kAnnexKChroma[64] = {
    17, 18, 24, 47, 99, 99, 99, 99, 18, 21, 26, 66, 99, 99, 99, 99, 24, 26, 56, 99, 99, 99,
    99, 99, 47, 66, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99,
    99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99};

// Context classes: 0 = luma, 1 = chroma.
constexpr int kClasses = 2;

// Significance contexts: position class (by scan index) x levels-left bucket.
constexpr int kSigPos = 22;
constexpr int kSigLeft = 9;
inline constexpr uint8_t kSigPosOf[64] = {
    0,  0,  1,  2,  3,  4,  5,  6,  7,  8,  9,  10, 11, 12, 13, 14,  // 1..15 one each
    15, 15, 15, 15, 16, 16, 16, 16, 17, 17, 17, 17, 18, 18, 18, 18,  // 16..31 by four
    19, 19, 19, 19, 19, 19, 19, 19, 20, 20, 20, 20, 20, 20, 20, 20,  // 32..47 by eight
    21, 21, 21, 21, 21, 21, 21, 21, 21, 21, 21, 21, 21, 21, 21, 21};
// Levels still to code (1..63) -> 0..8: 1, 2, 3, 4, 5-6, 7-9, 10-14, 15-23, 24+.
inline constexpr uint8_t kSigLeftOf[64] = {
    0, 0, 1, 2, 3, 4, 4, 5, 5, 5, 6, 6, 6, 6, 6, 7, 7, 7, 7, 7, 7, 7,
    7, 7, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8,
    8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8};

// Level contexts: position class x levels-left bucket.
constexpr int kLevelPos = 5;
constexpr int kLevelLeft = 5;
// Scan index -> 0: 1-2, 1: 3-5, 2: 6-9, 3: 10-20, 4: 21-63.
inline constexpr uint8_t kLevelPosOf[64] = {
    0, 0, 0, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 4,
    4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4,
    4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4};
// Levels left (1..63) -> 0: 1, 1: 2, 2: 3-4, 3: 5-8, 4: 9+.
inline constexpr uint8_t kLevelLeftOf[64] = {
    0, 0, 1, 2, 2, 3, 3, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4,
    4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4,
    4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4};
// |v| - 3 of a level is coded with a bypass Exp-Golomb code of order k; k
// starts at 0 in each block and grows by one (up to kRestMaxOrder) after a
// remainder above kRestRaise << k, so blocks with large levels spend fewer bins.
constexpr int kRestMaxOrder = 4;
constexpr uint32_t kRestRaise = 3;
// |v| of an AC level never exceeds the largest coefficient.
constexpr uint32_t kMaxLevel = 2048;

// nz (0..63): a unary prefix of its bit length (0..6) over contexts chosen by
// the neighbours' nz, then the bits below the leading one (the top one with a
// context per length, the rest bypass).
constexpr int kNzBuckets = 9;
constexpr int kNzPrefixBins = 6;
// Predicted nz (0..63) -> bucket: 0, 1, 2, 3-4, 5-7, 8-11, 12-17, 18-27, 28+.
inline constexpr uint8_t kNzBucketOf[64] = {
    0, 1, 2, 3, 3, 4, 4, 4, 5, 5, 5, 5, 6, 6, 6, 6, 6, 6, 7, 7, 7, 7,
    7, 7, 7, 7, 7, 7, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8,
    8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8, 8};

// Coded-block flag and DC residual contexts, by the neighbours (0..2).
constexpr int kCbfCtx = 3;
constexpr int kDcZeroCtx = 3;
// |r| - 3 of a DC residual: bypass Exp-Golomb of this order.
constexpr int kDcRestOrder = 1;
// A DC level always lies in the coefficient range.
constexpr int kDcLevelMin = -2048;
constexpr int kDcLevelMax = 2047;

// The contexts of one class, in any representation of a context: the
// encoder and the training tools use vds::ArithContext, the client decoder
// PackedContext (below). The layout is the same up to the element size.
template <typename Ctx>
struct ClassContextsOf {
  Ctx cbf[kCbfCtx];
  Ctx dc_zero[kDcZeroCtx];
  Ctx dc_gt1[kDcZeroCtx];
  Ctx dc_gt2;
  Ctx nz_prefix[kNzBuckets][kNzPrefixBins];
  Ctx nz_suffix[kNzPrefixBins + 1];  // [len], len 2..6; [0] and [1] are never coded
                                     // (the client decoder keeps [0] as its always-one context)
  Ctx sig[kSigLeft][kSigPos];  // by levels left, then position
  Ctx gt1[kLevelPos][kLevelLeft];
  Ctx gt2[kLevelPos][kLevelLeft];
};

template <typename Ctx>
struct ContextsOf {
  ClassContextsOf<Ctx> cls[kClasses];
  Ctx region[2];  // MCU coded flag, by the previous MCU's flag
};

using ClassContexts = ClassContextsOf<ArithContext>;
using Contexts = ContextsOf<ArithContext>;

// The client decoder's context: both probability estimates of an
// ArithContext in one word, p0_fast in bits 0..15 and p0_slow in bits
// 16..31. The codec's contexts are all past their warm-up with the default
// shifts (init_contexts), so the count and the shifts carry no information;
// one load and one store per bin instead of two of each, and 4 bytes
// instead of 6.
using PackedContext = uint32_t;
using PackedClassContexts = ClassContextsOf<PackedContext>;
using PackedContexts = ContextsOf<PackedContext>;
constexpr int kPackedSlowShift = 16;  // bit position of p0_slow
constexpr uint32_t kPackedLowMask = 0xFFFFu;
constexpr PackedContext pack_context(const ArithContext& c) {
  return static_cast<uint32_t>(c.p0_fast) | static_cast<uint32_t>(c.p0_slow) << kPackedSlowShift;
}

constexpr size_t kContextCount = sizeof(Contexts) / sizeof(ArithContext);

// Every context at its starting state: a trained probability for the
// quantiser index (luma index for luma and region contexts, chroma index
// for chroma contexts), adaptation already past its warm-up.
void init_contexts(Contexts& c, int quant_luma, int quant_chroma);
// The same starting state for the client decoder.
void init_contexts(PackedContexts& c, int quant_luma, int quant_chroma);

// The i-th context of a Contexts in declaration order (for training tools).
ArithContext& context_at(Contexts& c, size_t i);

// Bit length of nz (0 for 0, 6 for 32..63).
inline int nz_length(uint32_t nz) { return nz == 0 ? 0 : 32 - __builtin_clz(nz); }

// The decoder's range decoder: vds::ArithDecoder's decoding, end-of-data
// rule and finish() bit for bit (vds/arith.h; tests/unit/image_arith_test.cpp
// compares them on random and hostile streams), as a small value type whose
// operations are all inline so that a decode loop keeps range, code and the
// read pointer in registers.
//
// bit() is decode_bit() for contexts past their warm-up with the default
// adaptation shifts, which init_contexts() makes every context of this codec
// (the count saturates at kArithWarmupDone and the shifts never change, so
// arith_update() reduces to two fixed shifts).
struct RangeDecoder {
  uint32_t range = 0;
  uint32_t code = 0;
  const uint8_t* ptr = nullptr;  // next byte; never past end
  const uint8_t* end = nullptr;
  uint32_t past = 0;  // zero bytes taken past the end of the data
  Status status = Status::invalid_argument;

  Status init(const uint8_t* d, uint32_t n) {
    status = Status::ok;
    if (d == nullptr && n != 0) {
      n = 0;
      status = Status::invalid_argument;
    }
    ptr = d;
    end = d + n;
    past = 0;
    range = 0xFFFFFFFFu;
    code = 0;
    for (int i = 0; i < 4; ++i) code = (code << 8) | next_byte();
    check_end();
    if (code >= range) {
      code = range - 1;
      if (status == Status::ok) status = Status::malformed;
    }
    return status;
  }

  // Past the end of the data the decoder takes zero bytes. Whether it has
  // taken more than the end padding (ArithDecoder latches truncated as that
  // byte is taken) is checked by check_end(), which the decode loop calls
  // after every block and before anything else can latch an error.
  inline __attribute__((always_inline)) uint32_t next_byte() {
    if (ptr != end) return *ptr++;
    ++past;
    return 0;
  }
  void check_end() {
    if (past > kArithEndPaddingBytes && status == Status::ok) status = Status::truncated;
  }

  inline __attribute__((always_inline)) void renormalise() {
    do {
      range <<= 8;
      code = (code << 8) | next_byte();
    } while (range < kArithRangeTop);
  }

  inline __attribute__((always_inline)) int bit(ArithContext& ctx) {
    const uint32_t pf = ctx.p0_fast, ps = ctx.p0_slow;
    const uint32_t bound = (range >> kArithProbShift) * ((pf + ps) >> 1);
    int bin;
    if (code < bound) {
      range = bound;
      ctx.p0_fast = static_cast<ProbQ15>(pf + ((kProbOneQ15 - pf) >> kArithDefaultFastShift));
      ctx.p0_slow = static_cast<ProbQ15>(ps + ((kProbOneQ15 - ps) >> kArithDefaultSlowShift));
      bin = 0;
    } else {
      code -= bound;
      range -= bound;
      ctx.p0_fast = static_cast<ProbQ15>(pf - (pf >> kArithDefaultFastShift));
      ctx.p0_slow = static_cast<ProbQ15>(ps - (ps >> kArithDefaultSlowShift));
      bin = 1;
    }
    if (range < kArithRangeTop) renormalise();
    return bin;
  }

  // bit() on a PackedContext: the same arithmetic on both halves of the
  // word. The halves never carry into each other: both estimates stay in
  // [1, 32767], so their sum fits 16 bits, kProbOneQ15 - p does not borrow,
  // and each update keeps its half below 2^15.
  inline __attribute__((always_inline)) int bit(PackedContext& ctx) {
    constexpr uint32_t kOneBoth = kProbOneQ15 | kProbOneQ15 << kPackedSlowShift;
    constexpr int kSlowDown = kPackedSlowShift + kArithDefaultSlowShift;
    const uint32_t p = ctx;
    const uint32_t p0 = ((p + (p >> kPackedSlowShift)) & kPackedLowMask) >> 1;  // (fast + slow) / 2
    const uint32_t bound = (range >> kArithProbShift) * p0;
    int bin;
    if (code < bound) {
      range = bound;
      const uint32_t d = kOneBoth - p;  // kProbOneQ15 - p in each half
      ctx = p + ((d & kPackedLowMask) >> kArithDefaultFastShift) + ((d >> kSlowDown) << kPackedSlowShift);
      bin = 0;
    } else {
      code -= bound;
      range -= bound;
      ctx = p - ((p & kPackedLowMask) >> kArithDefaultFastShift) - ((p >> kSlowDown) << kPackedSlowShift);
      bin = 1;
    }
    if (range < kArithRangeTop) renormalise();
    return bin;
  }

  inline __attribute__((always_inline)) int bypass() {
    const uint32_t bound = range >> 1;
    int bin;
    if (code < bound) {
      range = bound;
      bin = 0;
    } else {
      code -= bound;
      range -= bound;
      bin = 1;
    }
    if (range < kArithRangeTop) renormalise();
    return bin;
  }

  // Bypass Exp-Golomb of order k (ArithDecoder::decode_exp_golomb without
  // contexts): a prefix longer than 31 - k latches malformed (unless the
  // data had already run out) and returns 0.
  inline __attribute__((always_inline)) uint32_t exp_golomb(int k) {
    int p = 0;
    while (bypass()) {
      if (++p > 31 - k) {
        check_end();
        if (status == Status::ok) status = Status::malformed;
        return 0;
      }
    }
    uint32_t v = 0;
    for (int i = 0; i < p + k; ++i) v = (v << 1) | static_cast<uint32_t>(bypass());
    return (((1u << p) - 1u) << k) + v;
  }

  // After the last bin: ok only if exactly the data plus the end padding
  // were taken (ArithDecoder::finish): every byte read and then exactly
  // kArithEndPaddingBytes zeros (more latches truncated).
  Status finish() {
    check_end();
    if (status != Status::ok) return status;
    if (ptr != end || past < kArithEndPaddingBytes) return Status::malformed;
    return Status::ok;
  }
};

}  // namespace vds::image_model
