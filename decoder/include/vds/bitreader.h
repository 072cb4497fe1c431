// vds client library: bounds-checked MSB-first bit reader over a caller
// buffer, with a latched error (the nanopb/meshoptimizer habit: check once).
//
// Rules (docs/entropy.md, "Bit reader"):
// - Bits are read most significant first from each byte, bytes in order.
// - The cache is one 32-bit word. After a refill at least kMaxPeekBits (25)
//   bits are available, so peek()/skip() take 1..25 bits; read() takes 0..32
//   (reads over 25 bits are split in two).
// - Bytes past the end of the buffer are never touched; the reader feeds zero
//   bits instead. Peeking into those zeros is legal (a Huffman decoder peeks 16
//   bits near the end); *consuming* one latches Status::truncated. The first
//   error latched stays; status() reports it.
#pragma once
#include <cstddef>
#include <cstdint>

#include "vds/status.h"

namespace vds {

class BitReader {
 public:
  // Bits guaranteed in the cache after a refill (32-bit cache refilled a
  // whole byte at a time while it holds 24 bits or fewer).
  static constexpr int kMaxPeekBits = 25;
  // Longest unsigned Exp-Golomb prefix that still yields a 32-bit value.
  static constexpr int kMaxExpGolombZeros = 31;

  BitReader() = default;
  BitReader(const uint8_t* data, size_t size) { init(data, size); }

  // A null `data` with a non-zero size is treated as an empty buffer and
  // latches Status::invalid_argument.
  void init(const uint8_t* data, size_t size);

  // The next n bits (1 <= n <= 25) as an unsigned value, without consuming.
  uint32_t peek(int n) {
    if (count_ < n) refill();
    return cache_ >> (32 - n);
  }

  // Consumes n bits (0 <= n <= 25).
  void skip(int n) {
    if (count_ < n) refill();
    // n <= 25 keeps the shift below the word width.
    cache_ <<= n;
    count_ -= n;
    // Zero padding sits at the bottom of the valid bits: eating into it means
    // the caller consumed bits the buffer does not have.
    if (count_ < pad_bits_) note_overrun();
  }

  // Reads n bits (0 <= n <= 32), first bit in the most significant position.
  uint32_t read(int n) {
    if (n <= kMaxPeekBits) {
      if (n == 0) return 0;
      const uint32_t v = peek(n);
      skip(n);
      return v;
    }
    return read_long(n);
  }

  uint32_t read_bit() { return read(1); }
  bool read_flag() { return read(1) != 0; }

  // Unsigned Exp-Golomb (order 0): k zeros, a one, k bits. More than 31
  // leading zeros cannot encode a 32-bit value and latches malformed.
  uint32_t read_ue();
  // Signed Exp-Golomb: 0, 1, -1, 2, -2, ... mapped from read_ue().
  int32_t read_se();

  // Drops bits up to the next byte boundary.
  void align_to_byte() { skip(count_ & 7); }
  bool byte_aligned() const { return (count_ & 7) == 0; }

  // Bits consumed so far (may exceed size_bits() once truncated).
  size_t bit_position() const {
    return static_cast<size_t>(ptr_ - data_) * 8 + static_cast<size_t>(pad_bits_) -
           static_cast<size_t>(count_);
  }
  size_t size_bits() const { return size_ * 8; }
  // Bits left in the buffer (0 once the end has been reached or passed).
  size_t bits_left() const {
    const size_t pos = bit_position();
    return pos < size_bits() ? size_bits() - pos : 0;
  }

  Status status() const { return status_; }
  bool ok() const { return status_ == Status::ok; }
  // Latches `s` unless an error is already latched (decoders built on the
  // reader report their own failures through the same latch).
  void fail(Status s) {
    if (status_ == Status::ok) status_ = s;
  }

 private:
  void refill();
  void note_overrun();
  uint32_t read_long(int n);

  const uint8_t* data_ = nullptr;
  const uint8_t* ptr_ = nullptr;  // next byte to load, never past end_
  const uint8_t* end_ = nullptr;
  size_t size_ = 0;
  // Left-aligned: the next bit to read is bit 31. Bits below the top count_
  // are either zero or a copy of the leading bits of *ptr_ (the word-wide
  // refill loads more than it counts); peek never exposes them.
  uint32_t cache_ = 0;
  int count_ = 0;     // valid bits in cache_
  int pad_bits_ = 0;  // how many of the valid bits are zero padding past the end
  Status status_ = Status::ok;
};

}  // namespace vds
