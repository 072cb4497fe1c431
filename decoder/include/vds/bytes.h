// Little-endian loads and stores. Every multi-byte field vds reads or
// writes (stream container, chunks, link frames and messages) is
// little-endian; these are the only helpers for it.
#pragma once
#include <cstdint>

namespace vds {

constexpr uint16_t load_le16(const uint8_t* p) { return static_cast<uint16_t>(p[0] | p[1] << 8); }
constexpr uint32_t load_le32(const uint8_t* p) {
  return uint32_t{p[0]} | uint32_t{p[1]} << 8 | uint32_t{p[2]} << 16 | uint32_t{p[3]} << 24;
}
constexpr int32_t load_le32s(const uint8_t* p) { return static_cast<int32_t>(load_le32(p)); }  // two's complement
constexpr void store_le16(uint8_t* p, uint32_t v) {
  p[0] = static_cast<uint8_t>(v);
  p[1] = static_cast<uint8_t>(v >> 8);
}
constexpr void store_le32(uint8_t* p, uint32_t v) {
  store_le16(p, v);
  store_le16(p + 2, v >> 16);
}

}  // namespace vds
