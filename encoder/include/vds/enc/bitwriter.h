// vds encoder: MSB-first bit writer, the mirror of vds::BitReader.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

namespace vds::enc {

class BitWriter {
 public:
  // Appends the low n bits of value (0 <= n <= 32), most significant first.
  void put_bits(uint32_t value, int n);
  void put_bit(int bit) { put_bits(bit ? 1u : 0u, 1); }
  // Exp-Golomb order 0 (value <= 2^32 - 2) and its signed mapping
  // 0, 1, -1, 2, -2, ... (value != INT32_MIN), as vds::BitReader reads them.
  void put_ue(uint32_t value);
  void put_se(int32_t value);
  // Pads with zero bits to the next byte boundary.
  void align_to_byte();

  size_t bit_count() const { return bytes_.size() * 8 + static_cast<size_t>(pending_bits_); }
  // The bytes so far with any partial byte padded with zero bits.
  std::vector<uint8_t> bytes() const;
  // Pads to a byte boundary and hands over the buffer (the writer is empty after).
  std::vector<uint8_t> finish();

 private:
  std::vector<uint8_t> bytes_;
  uint64_t acc_ = 0;      // the low pending_bits_ bits are not yet in bytes_
  int pending_bits_ = 0;  // 0..7 between calls
};

}  // namespace vds::enc
