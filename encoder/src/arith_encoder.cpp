// vds encoder: binary range encoder with carry propagation by a held-back
// byte and a run of pending 0xFF bytes (G. N. N. Martin, "Range encoding",
// 1979); the exact mirror of the client's vds::ArithDecoder (docs/entropy.md).
#include "vds/enc/arith_encoder.h"

#include <array>
#include <cmath>
#include <stdexcept>

namespace vds::enc {

namespace {

constexpr uint64_t kLowWindow = uint64_t{1} << 32;
// A top byte below 0xFF is settled: no carry can reach past it.
constexpr uint64_t kLowPendingFrom = 0xFF000000u;
constexpr uint64_t kFlushGranule = uint64_t{1} << 24;
constexpr int kMaxExpGolombOrder = 30;

// Cost table: probability resolved to 1/1024, entry = -log2 of the interval's
// centre in Q8 bits.
constexpr int kCostTableBits = 10;
constexpr int kCostIndexShift = kArithProbShift - kCostTableBits;

const std::array<uint16_t, 1u << kCostTableBits>& cost_table() {
  static const std::array<uint16_t, 1u << kCostTableBits> table = [] {
    std::array<uint16_t, 1u << kCostTableBits> t{};
    for (size_t i = 0; i < t.size(); ++i) {
      const double p = (static_cast<double>(i) + 0.5) / static_cast<double>(t.size());
      t[i] = static_cast<uint16_t>(std::lround(-std::log2(p) * kCostOneBitQ8));
    }
    return t;
  }();
  return table;
}

// Exp-Golomb-k prefix length for value (p ones then a zero).
int exp_golomb_prefix(uint32_t value, int k) {
  if (k < 0 || k > kMaxExpGolombOrder) throw std::invalid_argument("Exp-Golomb order must be 0..30");
  const uint64_t v = (uint64_t{value} >> k) + 1;  // the prefix is bit_width(v) - 1
  int p = 0;
  while ((v >> (p + 1)) != 0) ++p;
  if (p + k > 31) throw std::invalid_argument("Exp-Golomb value beyond 32 bits");
  return p;
}

}  // namespace

uint32_t arith_cost_q8(uint32_t p0_q15, int bin) {
  if (p0_q15 >= kProbOneQ15) p0_q15 = kProbOneQ15 - 1;
  const uint32_t p = bin ? kProbOneQ15 - p0_q15 : p0_q15;
  return cost_table()[p >> kCostIndexShift];
}

uint32_t arith_cost_unary_q8(const ArithContext* ctx, int num_ctx, uint32_t value, uint32_t max) {
  uint32_t cost = 0;
  const uint32_t last = num_ctx > 0 ? static_cast<uint32_t>(num_ctx - 1) : 0;
  const uint32_t bins = value < max ? value + 1 : max;
  for (uint32_t i = 0; i < bins; ++i) {
    const int bin = i < value ? 1 : 0;
    cost += num_ctx > 0 ? arith_bin_cost_q8(ctx[i < last ? i : last], bin) : kCostOneBitQ8;
  }
  return cost;
}

uint32_t arith_cost_exp_golomb_q8(const ArithContext* ctx, int num_ctx, uint32_t value, int k) {
  const int p = exp_golomb_prefix(value, k);
  return arith_cost_unary_q8(ctx, num_ctx, static_cast<uint32_t>(p), UINT32_MAX) +
         static_cast<uint32_t>(p + k) * kCostOneBitQ8;
}

uint32_t arith_cost_ueg_q8(const ArithContext* ctx, int num_ctx, uint32_t value, uint32_t cutoff, int k) {
  if (value < cutoff) return arith_cost_unary_q8(ctx, num_ctx, value, cutoff);
  return arith_cost_unary_q8(ctx, num_ctx, cutoff, cutoff) + arith_cost_exp_golomb_q8(nullptr, 0, value - cutoff, k);
}

uint32_t arith_cost_signed_q8(const ArithContext& zero_ctx, const ArithContext* mag_ctx, int num_mag_ctx,
                              int32_t value, uint32_t cutoff, int k) {
  if (value == 0) return arith_bin_cost_q8(zero_ctx, 0);
  if (value == INT32_MIN) throw std::invalid_argument("arith_cost_signed_q8: INT32_MIN has no code");
  const uint32_t mag = static_cast<uint32_t>(value < 0 ? -value : value);
  return arith_bin_cost_q8(zero_ctx, 1) + arith_cost_ueg_q8(mag_ctx, num_mag_ctx, mag - 1, cutoff, k) +
         kCostOneBitQ8;
}

void ArithEncoder::shift_low() {
  if (low_ < kLowPendingFrom || low_ >= kLowWindow) {
    const uint8_t carry = static_cast<uint8_t>(low_ >> 32);
    // Without a held-back byte no carry can arise: the whole stream lies
    // below the initial range's top, 2^32 - 1.
    if (has_cache_) out_.push_back(static_cast<uint8_t>(cache_ + carry));
    for (; pending_ != 0; --pending_) out_.push_back(static_cast<uint8_t>(0xFFu + carry));
    cache_ = static_cast<uint8_t>(low_ >> 24);
    has_cache_ = true;
  } else {
    // Top byte 0xFF: a later carry would ripple through it.
    ++pending_;
  }
  low_ = (low_ & 0x00FFFFFFu) << 8;
}

void ArithEncoder::encode_bypass(int bin) {
  const uint32_t bound = range_ >> 1;
  if (bin == 0) {
    range_ = bound;
  } else {
    low_ += bound;
    range_ -= bound;
  }
  while (range_ < kArithRangeTop) {
    range_ <<= 8;
    shift_low();
  }
  ++bins_;
}

void ArithEncoder::encode_bits_bypass(uint32_t value, int n) {
  if (n < 0 || n > 32) throw std::invalid_argument("encode_bits_bypass: n must be 0..32");
  for (int i = n - 1; i >= 0; --i) encode_bypass(static_cast<int>((value >> i) & 1u));
}

void ArithEncoder::encode_unary(ArithContext* ctx, int num_ctx, uint32_t value, uint32_t max) {
  if (value > max) throw std::invalid_argument("encode_unary: value > max");
  const uint32_t last = num_ctx > 0 ? static_cast<uint32_t>(num_ctx - 1) : 0;
  const uint32_t bins = value < max ? value + 1 : max;
  for (uint32_t i = 0; i < bins; ++i) {
    const int bin = i < value ? 1 : 0;
    if (num_ctx > 0)
      encode_bit(ctx[i < last ? i : last], bin);
    else
      encode_bypass(bin);
  }
}

void ArithEncoder::encode_exp_golomb(ArithContext* ctx, int num_ctx, uint32_t value, int k) {
  const int p = exp_golomb_prefix(value, k);
  encode_unary(ctx, num_ctx, static_cast<uint32_t>(p), UINT32_MAX);
  const uint32_t base = static_cast<uint32_t>(((uint64_t{1} << p) - 1) << k);
  encode_bits_bypass(value - base, p + k);
}

void ArithEncoder::encode_ueg(ArithContext* ctx, int num_ctx, uint32_t value, uint32_t cutoff, int k) {
  if (value < cutoff) {
    encode_unary(ctx, num_ctx, value, cutoff);
    return;
  }
  exp_golomb_prefix(value - cutoff, k);  // validate before coding anything
  encode_unary(ctx, num_ctx, cutoff, cutoff);
  encode_exp_golomb(nullptr, 0, value - cutoff, k);
}

void ArithEncoder::encode_signed(ArithContext& zero_ctx, ArithContext* mag_ctx, int num_mag_ctx, int32_t value,
                                 uint32_t cutoff, int k) {
  if (value == INT32_MIN) throw std::invalid_argument("encode_signed: INT32_MIN has no code");
  if (value == 0) {
    encode_bit(zero_ctx, 0);
    return;
  }
  const uint32_t mag = static_cast<uint32_t>(value < 0 ? -value : value);
  if (mag - 1 >= cutoff) exp_golomb_prefix(mag - 1 - cutoff, k);  // validate first
  encode_bit(zero_ctx, 1);
  encode_ueg(mag_ctx, num_mag_ctx, mag - 1, cutoff, k);
  encode_bypass(value < 0 ? 1 : 0);
}

std::vector<uint8_t> ArithEncoder::finish() {
  // Any code point in [low, low + range) decodes the same bins. With range
  // >= 2^24 one of them is a multiple of 2^24: its last three window bytes
  // are zero, which is what the decoder reads past the end, so only its top
  // byte need be written.
  low_ = (low_ + kFlushGranule - 1) & ~(kFlushGranule - 1);
  shift_low();
  shift_low();
  std::vector<uint8_t> out;
  out.swap(out_);
  low_ = 0;
  range_ = 0xFFFFFFFFu;
  cache_ = 0;
  has_cache_ = false;
  pending_ = 0;
  bins_ = 0;
  return out;
}

}  // namespace vds::enc
