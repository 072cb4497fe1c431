// vds encoder: the context-adaptive binary range encoder matching
// vds::ArithDecoder bit for bit (same contexts, adaptation and
// binarisations), plus bin cost estimates for rate-distortion decisions.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "vds/arith.h"

namespace vds::enc {

// --- Cost estimates -----------------------------------------------------------
// Costs are in 1/256 bit (Q8): 256 = one bit.
constexpr int kCostFracBits = 8;
constexpr uint32_t kCostOneBitQ8 = 1u << kCostFracBits;

// -log2(probability of `bin`) in Q8 bits for a Q15 probability p0 that the
// bin is 0 (a 1024-entry table; probabilities are resolved to 1/1024).
uint32_t arith_cost_q8(uint32_t p0_q15, int bin);
// The cost of coding `bin` with `ctx` in its current state.
inline uint32_t arith_bin_cost_q8(const ArithContext& ctx, int bin) { return arith_cost_q8(arith_p0(ctx), bin); }

// Costs of the binarisations with the contexts in their current states
// (ignoring the adaptation within the value itself), matching the encode_*
// calls below.
uint32_t arith_cost_unary_q8(const ArithContext* ctx, int num_ctx, uint32_t value, uint32_t max);
uint32_t arith_cost_exp_golomb_q8(const ArithContext* ctx, int num_ctx, uint32_t value, int k);
uint32_t arith_cost_ueg_q8(const ArithContext* ctx, int num_ctx, uint32_t value, uint32_t cutoff, int k);
uint32_t arith_cost_signed_q8(const ArithContext& zero_ctx, const ArithContext* mag_ctx, int num_mag_ctx,
                              int32_t value, uint32_t cutoff, int k);

// --- Encoder --------------------------------------------------------------------
class ArithEncoder {
 public:
  void encode_bit(ArithContext& ctx, int bin) {
    const uint32_t bound = (range_ >> kArithProbShift) * arith_p0(ctx);
    if (bin == 0) {
      range_ = bound;
    } else {
      low_ += bound;
      range_ -= bound;
    }
    arith_update(ctx, bin);
    while (range_ < kArithRangeTop) {
      range_ <<= 8;
      shift_low();
    }
    ++bins_;
  }
  void encode_bypass(int bin);
  // The low n (0..32) bits of value as bypass bins, most significant first.
  void encode_bits_bypass(uint32_t value, int n);

  // Mirrors of the ArithDecoder binarisations; they throw
  // std::invalid_argument for values the decoder cannot return:
  // unary value > max; Exp-Golomb k outside 0..30 or value >= 2^32 - 2^k;
  // UEGk value - cutoff beyond Exp-Golomb's range; signed INT32_MIN.
  void encode_unary(ArithContext* ctx, int num_ctx, uint32_t value, uint32_t max);
  void encode_exp_golomb(ArithContext* ctx, int num_ctx, uint32_t value, int k);
  void encode_ueg(ArithContext* ctx, int num_ctx, uint32_t value, uint32_t cutoff, int k);
  void encode_signed(ArithContext& zero_ctx, ArithContext* mag_ctx, int num_mag_ctx, int32_t value,
                     uint32_t cutoff, int k);

  // Flushes and returns the stream; the encoder starts afresh after.
  std::vector<uint8_t> finish();

  // The size finish() would return now, in bytes (exact).
  size_t finished_size() const { return out_.size() + static_cast<size_t>(pending_) + (has_cache_ ? 1 : 0) + 1; }
  // Bins coded so far (context and bypass).
  uint64_t bins() const { return bins_; }

 private:
  void shift_low();

  std::vector<uint8_t> out_;
  // Low end of the interval: bits 0..31 are the current window, bit 32 a
  // carry into bytes not yet written.
  uint64_t low_ = 0;
  uint32_t range_ = 0xFFFFFFFFu;
  // The last settled byte is held back (it may still take a carry), followed
  // by pending_ 0xFF bytes that a carry would turn into 0x00.
  uint8_t cache_ = 0;
  bool has_cache_ = false;
  uint64_t pending_ = 0;
  uint64_t bins_ = 0;
};

}  // namespace vds::enc
