// vds client library: range decoder start-up, end-of-data rule and the
// binarisations (unary, Exp-Golomb, UEGk as in ITU-T H.264 clause 9.3.2.3).
#include "vds/arith.h"

namespace vds {

namespace {
// Exp-Golomb prefixes above this many ones overflow 32 bits (with k = 0).
constexpr int kMaxExpGolombPrefix = 31;
constexpr int kMaxExpGolombOrder = 30;
constexpr uint32_t kMaxSignedMagnitude = 0x7FFFFFFFu;
}  // namespace

void arith_init_contexts(ArithContext* ctx, size_t n, int fast_shift, int slow_shift, uint32_t p0_q15) {
  const ArithContext c = arith_context(fast_shift, slow_shift, p0_q15);
  for (size_t i = 0; i < n; ++i) ctx[i] = c;
}

Status ArithDecoder::init(const uint8_t* data, size_t size) {
  status_ = Status::ok;
  if (data == nullptr && size != 0) {
    size = 0;
    status_ = Status::invalid_argument;
  }
  ptr_ = data;
  end_ = data + size;
  size_ = size;
  taken_ = 0;
  range_ = 0xFFFFFFFFu;
  code_ = 0;
  for (int i = 0; i < 4; ++i) code_ = (code_ << 8) | next_byte();
  if (code_ >= range_) {
    // The code point lies below the initial range's top (2^32 - 1), so the
    // encoder never starts with four FF bytes.
    code_ = range_ - 1;
    if (status_ == Status::ok) status_ = Status::malformed;
  }
  return status_;
}

uint32_t ArithDecoder::past_end() {
  if (taken_ > size_ + kArithEndPaddingBytes && status_ == Status::ok) status_ = Status::truncated;
  return 0;
}

Status ArithDecoder::finish() const {
  if (status_ != Status::ok) return status_;
  if (taken_ < size_ + kArithEndPaddingBytes) return Status::malformed;
  return Status::ok;  // more is impossible here: it latches truncated
}

uint32_t ArithDecoder::decode_bits_bypass(int n) {
  uint32_t v = 0;
  for (int i = 0; i < n; ++i) v = (v << 1) | static_cast<uint32_t>(decode_bypass());
  return v;
}

uint32_t ArithDecoder::decode_unary(ArithContext* ctx, int num_ctx, uint32_t max) {
  uint32_t v = 0;
  const int last = num_ctx - 1;
  while (v < max) {
    const int bin = (num_ctx > 0) ? decode_bit(ctx[v < static_cast<uint32_t>(last) ? v : last]) : decode_bypass();
    if (bin == 0) break;
    ++v;
  }
  return v;
}

uint32_t ArithDecoder::decode_exp_golomb(ArithContext* ctx, int num_ctx, int k) {
  if (k < 0 || k > kMaxExpGolombOrder) {
    if (status_ == Status::ok) status_ = Status::invalid_argument;
    return 0;
  }
  const int max_prefix = kMaxExpGolombPrefix - k;
  int p = 0;
  const int last = num_ctx - 1;
  for (;;) {
    const int bin = (num_ctx > 0) ? decode_bit(ctx[p < last ? p : last]) : decode_bypass();
    if (bin == 0) break;
    if (++p > max_prefix) {
      if (status_ == Status::ok) status_ = Status::malformed;
      return 0;
    }
  }
  // p + k <= 31: (2^p - 1) 2^k + suffix < 2^(p + k + 1) <= 2^32.
  const uint32_t base = ((1u << p) - 1u) << k;
  return base + decode_bits_bypass(p + k);
}

uint32_t ArithDecoder::decode_ueg(ArithContext* ctx, int num_ctx, uint32_t cutoff, int k) {
  const uint32_t prefix = decode_unary(ctx, num_ctx, cutoff);
  if (prefix < cutoff) return prefix;
  const uint32_t escape = decode_exp_golomb(nullptr, 0, k);
  if (escape > 0xFFFFFFFFu - cutoff) {
    if (status_ == Status::ok) status_ = Status::malformed;
    return 0;
  }
  return cutoff + escape;
}

int32_t ArithDecoder::decode_signed(ArithContext& zero_ctx, ArithContext* mag_ctx, int num_mag_ctx,
                                    uint32_t cutoff, int k) {
  if (decode_bit(zero_ctx) == 0) return 0;
  const uint32_t mag_minus_1 = decode_ueg(mag_ctx, num_mag_ctx, cutoff, k);
  if (mag_minus_1 >= kMaxSignedMagnitude) {
    if (status_ == Status::ok) status_ = Status::malformed;
    return 0;
  }
  const int32_t mag = static_cast<int32_t>(mag_minus_1 + 1);
  return decode_bypass() ? -mag : mag;
}

}  // namespace vds
