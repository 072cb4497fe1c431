// vds encoder: MSB-first bit writer and Exp-Golomb codes (ITU-T H.264 9.1),
// the mirror of the client's vds::BitReader.
#include "vds/enc/bitwriter.h"

#include <bit>
#include <stdexcept>

namespace vds::enc {

void BitWriter::put_bits(uint32_t value, int n) {
  if (n < 0 || n > 32) throw std::invalid_argument("BitWriter::put_bits: n must be 0..32");
  if (n == 0) return;
  const uint64_t mask = (uint64_t{1} << n) - 1;
  acc_ = (acc_ << n) | (value & mask);
  pending_bits_ += n;
  while (pending_bits_ >= 8) {
    pending_bits_ -= 8;
    bytes_.push_back(static_cast<uint8_t>(acc_ >> pending_bits_));
  }
  acc_ &= (uint64_t{1} << pending_bits_) - 1;
}

void BitWriter::put_ue(uint32_t value) {
  if (value == 0xFFFFFFFFu) throw std::invalid_argument("BitWriter::put_ue: value must be <= 2^32 - 2");
  const uint64_t v = uint64_t{value} + 1;
  const int bits = std::bit_width(v);  // 1..32
  put_bits(0, bits - 1);
  // v has `bits` <= 32 bits with a leading one: the one ends the zero prefix.
  put_bits(static_cast<uint32_t>(v), bits);
}

void BitWriter::put_se(int32_t value) {
  if (value == INT32_MIN) throw std::invalid_argument("BitWriter::put_se: INT32_MIN has no code");
  const uint32_t mag = static_cast<uint32_t>(value < 0 ? -value : value);
  put_ue(value > 0 ? 2 * mag - 1 : 2 * mag);
}

void BitWriter::align_to_byte() {
  if (pending_bits_ != 0) put_bits(0, 8 - pending_bits_);
}

std::vector<uint8_t> BitWriter::bytes() const {
  std::vector<uint8_t> out = bytes_;
  if (pending_bits_ != 0) out.push_back(static_cast<uint8_t>(acc_ << (8 - pending_bits_)));
  return out;
}

std::vector<uint8_t> BitWriter::finish() {
  align_to_byte();
  std::vector<uint8_t> out;
  out.swap(bytes_);
  acc_ = 0;
  pending_bits_ = 0;
  return out;
}

}  // namespace vds::enc
