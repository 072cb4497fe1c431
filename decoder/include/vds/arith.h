// vds client library: context-adaptive binary range decoder (a 32-bit
// multiplicative range coder in the style of G. N. N. Martin, "Range
// encoding", 1979, with byte-wise renormalisation and a dual-rate
// probability estimate as in ITU-T H.266 clause 9.3.4.3.2.2).
//
// The exact rules (state, adaptation, renormalisation, encoder flush, the
// end-of-data rule) are in docs/entropy.md; the host encoder in
// vds/enc/arith_encoder.h follows them bit for bit.
#pragma once
#include <cstddef>
#include <cstdint>

#include "vds/status.h"

namespace vds {

// --- Probability model ------------------------------------------------------

// Probabilities are Q15: 32768 stands for 1.0.
using ProbQ15 = uint16_t;
constexpr uint32_t kProbOneQ15 = 1u << 15;

// Default adaptation shifts: a fast estimate (window ~32 bins) and a slow
// one (window ~128 bins), averaged. Chosen on synthetic sources (see
// docs/entropy.md): within ~2 % of the entropy on stationary skewed bins and
// within ~5 % on sources that switch probability every 2000 bins. Codecs may
// pick others per context.
constexpr int kArithDefaultFastShift = 5;
constexpr int kArithDefaultSlowShift = 7;
constexpr int kArithMaxShift = 15;

// One adaptive binary context: 6 bytes. Both estimates are the probability
// that the next bin is 0, in Q15, and stay within [1, 32767] under the update
// rule so neither sub-interval can become empty.
struct ArithContext {
  ProbQ15 p0_fast;
  ProbQ15 p0_slow;
  // Bins coded so far, saturating at kArithWarmupDone. While below it the
  // adaptation shifts are capped at bit_length(count + 1), so a fresh context
  // learns as fast as a running average would.
  uint8_t count;
  // Adaptation shifts: fast in the low nibble, slow in the high nibble (1..15).
  uint8_t shifts;
};
static_assert(sizeof(ArithContext) == 6, "ArithContext is documented as 6 bytes");

constexpr uint8_t kArithWarmupDone = 255;

// A context with probability p0 (Q15, clamped to [1, 32767]) and the given
// adaptation shifts (clamped to [1, 15]).
constexpr ArithContext arith_context(int fast_shift = kArithDefaultFastShift,
                                     int slow_shift = kArithDefaultSlowShift,
                                     uint32_t p0_q15 = kProbOneQ15 / 2) {
  const uint32_t p = p0_q15 < 1 ? 1 : (p0_q15 > kProbOneQ15 - 1 ? kProbOneQ15 - 1 : p0_q15);
  const int f = fast_shift < 1 ? 1 : (fast_shift > kArithMaxShift ? kArithMaxShift : fast_shift);
  const int s = slow_shift < 1 ? 1 : (slow_shift > kArithMaxShift ? kArithMaxShift : slow_shift);
  return ArithContext{static_cast<ProbQ15>(p), static_cast<ProbQ15>(p), 0,
                      static_cast<uint8_t>(f | (s << 4))};
}

// Sets `n` contexts to arith_context(fast_shift, slow_shift, p0_q15).
void arith_init_contexts(ArithContext* ctx, size_t n, int fast_shift = kArithDefaultFastShift,
                         int slow_shift = kArithDefaultSlowShift, uint32_t p0_q15 = kProbOneQ15 / 2);

// Probability (Q15) that the next bin coded with `ctx` is 0: the mean of the
// two estimates, in [1, 32767].
inline uint32_t arith_p0(const ArithContext& ctx) {
  return (static_cast<uint32_t>(ctx.p0_fast) + ctx.p0_slow) >> 1;
}

// The adaptation rule, shared by decoder and encoder.
inline void arith_update(ArithContext& ctx, int bin) {
  int fast = ctx.shifts & 0xF;
  int slow = ctx.shifts >> 4;
  if (ctx.count < kArithWarmupDone) {
    ++ctx.count;
    // bit_length(count) after the increment: 1, 2, 2, 3, 3, 3, 3, 4, ...
    const int warm = 32 - __builtin_clz(static_cast<uint32_t>(ctx.count));
    if (fast > warm) fast = warm;
    if (slow > warm) slow = warm;
  }
  // p += (1 - p) >> s moves toward 1.0 without reaching it (the shifted gap
  // is smaller than the gap); p -= p >> s never reaches 0 for the same reason.
  if (bin == 0) {
    ctx.p0_fast = static_cast<ProbQ15>(ctx.p0_fast + ((kProbOneQ15 - ctx.p0_fast) >> fast));
    ctx.p0_slow = static_cast<ProbQ15>(ctx.p0_slow + ((kProbOneQ15 - ctx.p0_slow) >> slow));
  } else {
    ctx.p0_fast = static_cast<ProbQ15>(ctx.p0_fast - (ctx.p0_fast >> fast));
    ctx.p0_slow = static_cast<ProbQ15>(ctx.p0_slow - (ctx.p0_slow >> slow));
  }
}

// --- Coder constants (shared with the encoder) -----------------------------

// The range is renormalised (shifted up a byte at a time) whenever it falls
// below 2^24, so between bins it lies in [2^24, 2^32).
constexpr uint32_t kArithRangeTop = 1u << 24;
// The range is split as (range >> 15) * p0: a 17-bit by 15-bit product that
// fits 32 bits, and no division.
constexpr int kArithProbShift = 15;
// After the last real byte the decoder may legitimately take this many zero
// bytes: the decoder's 4-byte window reaches 3 bytes past the encoder's last
// byte when every bin has been decoded (docs/entropy.md, "End of data").
constexpr size_t kArithEndPaddingBytes = 3;

// --- Decoder ------------------------------------------------------------------

class ArithDecoder {
 public:
  ArithDecoder() = default;

  // Starts decoding `size` bytes at `data` (read as 4 bytes of code window
  // plus one byte per renormalisation). invalid_argument if data is null with
  // size > 0; malformed if the first 4 bytes are FF FF FF FF (no encoder
  // output starts so). The status is also latched.
  Status init(const uint8_t* data, size_t size);

  // One bin with an adaptive context (updates the context).
  int decode_bit(ArithContext& ctx) {
    const uint32_t bound = (range_ >> kArithProbShift) * arith_p0(ctx);
    int bin;
    if (code_ < bound) {
      range_ = bound;
      bin = 0;
    } else {
      code_ -= bound;
      range_ -= bound;
      bin = 1;
    }
    arith_update(ctx, bin);
    if (range_ < kArithRangeTop) renormalise();
    return bin;
  }

  // One equiprobable bin (no context).
  int decode_bypass() {
    const uint32_t bound = range_ >> 1;
    int bin;
    if (code_ < bound) {
      range_ = bound;
      bin = 0;
    } else {
      code_ -= bound;
      range_ -= bound;
      bin = 1;
    }
    if (range_ < kArithRangeTop) renormalise();
    return bin;
  }

  // n (0..32) bypass bins, first bin in the most significant position.
  uint32_t decode_bits_bypass(int n);

  // --- Binarisations (the encoder has the mirror of each) -----------------
  // Bin i of a prefix uses ctx[min(i, num_ctx - 1)]; num_ctx == 0 codes the
  // prefix in bypass bins. A 1 bin continues a prefix, a 0 bin ends it, so
  // zero padding past the end of the data ends every prefix quickly.

  // Truncated unary: `value` ones then a zero, the zero omitted when
  // value == max. Returns 0..max.
  uint32_t decode_unary(ArithContext* ctx, int num_ctx, uint32_t max);

  // Exp-Golomb of order k (0..30): a unary prefix of p ones and a zero
  // (contexts as above), then p + k bypass bits; value = (2^p - 1) 2^k +
  // suffix. A prefix longer than 31 - k cannot give a 32-bit value and
  // latches malformed (returns 0).
  uint32_t decode_exp_golomb(ArithContext* ctx, int num_ctx, int k);

  // Unary with escape (H.264 UEGk): a truncated-unary prefix up to `cutoff`
  // with contexts; a value >= cutoff continues with (value - cutoff) as
  // bypass Exp-Golomb of order k. Values past 2^32 - 1 latch malformed.
  uint32_t decode_ueg(ArithContext* ctx, int num_ctx, uint32_t cutoff, int k);

  // A signed value: a "nonzero" bin in *zero_ctx, then |v| - 1 with
  // decode_ueg(mag_ctx, num_mag_ctx, cutoff, k), then a bypass sign bin
  // (1 = negative). |v| above 2^31 - 1 latches malformed (returns 0).
  int32_t decode_signed(ArithContext& zero_ctx, ArithContext* mag_ctx, int num_mag_ctx,
                        uint32_t cutoff, int k);

  // --- Status ----------------------------------------------------------------
  // Latched: the first error stays. truncated once the decoder has taken
  // more than kArithEndPaddingBytes zero bytes past the end of the data.
  Status status() const { return status_; }
  bool ok() const { return status_ == Status::ok; }

  // Call after the last bin of a stream whose byte size is exact: ok only if
  // the decoder took exactly the stream plus the end padding, as it does
  // when it has decoded exactly the bins the encoder coded. Fewer bytes
  // taken means trailing bytes no bin used: malformed.
  Status finish() const;

  // Bytes taken into the code window so far, zero padding included.
  size_t bytes_taken() const { return taken_; }

 private:
  void renormalise() {
    // At most two steps: a split leaves at least 2^9 of a range >= 2^24.
    do {
      range_ <<= 8;
      code_ = (code_ << 8) | next_byte();
    } while (range_ < kArithRangeTop);
  }
  uint32_t next_byte() {
    ++taken_;
    if (ptr_ < end_) return *ptr_++;
    return past_end();
  }
  uint32_t past_end();

  const uint8_t* ptr_ = nullptr;
  const uint8_t* end_ = nullptr;
  size_t size_ = 0;
  size_t taken_ = 0;
  // A decoder used before init() decodes zeros safely (range never empty)
  // and reports invalid_argument.
  uint32_t range_ = 0xFFFFFFFFu;
  uint32_t code_ = 0;  // offset of the code point from the range's low end; < range_
  Status status_ = Status::invalid_argument;
};

}  // namespace vds
