// vds client library: MSB-first bit reader refill and Exp-Golomb codes
// (Exp-Golomb as in ITU-T H.264 clause 9.1). Rules in vds/bitreader.h.
#include "vds/bitreader.h"

namespace vds {

namespace {
// A refill tops the cache up while it holds at most this many bits, so each
// refill adds whole bytes without overflowing the 32-bit word.
constexpr int kRefillBelow = 32 - 8;
// Padding is counted up to here only, so a caller that keeps reading after
// the truncated latch cannot overflow the counter; consuming this much
// padding has long since latched the error.
constexpr int kPadBitsCap = 1 << 28;
}  // namespace

void BitReader::init(const uint8_t* data, size_t size) {
  status_ = Status::ok;
  if (data == nullptr && size != 0) {
    size = 0;
    status_ = Status::invalid_argument;
  }
  data_ = data;
  ptr_ = data;
  end_ = data + size;
  size_ = size;
  cache_ = 0;
  count_ = 0;
  pad_bits_ = 0;
}

void BitReader::refill() {
  if (end_ - ptr_ >= 4) {
    // Word-wide load: OR in 32 - count_ bits but count only whole bytes. The
    // bits of the partial byte left below count_ are that byte's own leading
    // bits, so the next refill ORs identical values over them.
    const uint32_t w = (static_cast<uint32_t>(ptr_[0]) << 24) | (static_cast<uint32_t>(ptr_[1]) << 16) |
                       (static_cast<uint32_t>(ptr_[2]) << 8) | static_cast<uint32_t>(ptr_[3]);
    cache_ |= w >> count_;  // count_ <= 24 here or the caller would not refill
    const int bytes = (32 - count_) >> 3;
    ptr_ += bytes;
    count_ += bytes * 8;
    return;
  }
  while (count_ <= kRefillBelow) {
    if (ptr_ < end_) {
      cache_ |= static_cast<uint32_t>(*ptr_++) << (kRefillBelow - count_);
    } else if (pad_bits_ < kPadBitsCap) {
      // Past the end: the bits below count_ are zero here (a word-wide load
      // only happens with 4 real bytes left), so this byte is zero padding.
      pad_bits_ += 8;
    }
    count_ += 8;
  }
}

void BitReader::note_overrun() { fail(Status::truncated); }

uint32_t BitReader::read_long(int n) {
  // 26..32 bits: two reads of at most 16 bits each.
  const uint32_t hi = read(16);
  const uint32_t lo = read(n - 16);
  return (hi << (n - 16)) | lo;
}

uint32_t BitReader::read_ue() {
  int zeros = 0;
  while (read(1) == 0) {
    if (++zeros > kMaxExpGolombZeros) {
      fail(Status::malformed);
      return 0;
    }
  }
  // zeros <= 31: 2^zeros - 1 + (zeros bits) <= 2^32 - 2.
  const uint32_t base = (zeros == 0) ? 0u : ((1u << zeros) - 1u);
  return base + read(zeros);
}

int32_t BitReader::read_se() {
  const uint32_t k = read_ue();
  // Odd codes are positive: k = 2v - 1; even codes are -v: k = 2v.
  const uint32_t mag = (k >> 1) + (k & 1u);  // <= 2^31 - 1 since k <= 2^32 - 2
  return (k & 1u) ? static_cast<int32_t>(mag) : -static_cast<int32_t>(mag);
}

}  // namespace vds
