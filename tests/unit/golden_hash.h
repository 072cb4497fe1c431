// The tests' fingerprint of a golden file: 64-bit FNV-1a over its bytes.
//
// Not CRC-32C: a vds stream is chunks that each end in the CRC-32C of
// their own bytes, and the CRC-32C of bytes followed by their CRC is a
// constant, so the CRC-32C of a whole stream depends only on its chunk
// lengths and the few bytes no chunk CRC covers. A regenerated stream with
// new contents would keep it.
#pragma once
#include <cstdint>
#include <vector>

namespace vds::test {

inline uint64_t golden_hash(const std::vector<uint8_t>& bytes) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (uint8_t b : bytes) {
    h ^= b;
    h *= 0x100000001b3ull;
  }
  return h;
}

}  // namespace vds::test
