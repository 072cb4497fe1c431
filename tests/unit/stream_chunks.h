// The chunks of a well-formed stream, by the container's layout (an 8-byte
// preamble, then per chunk: u32 type, u32 payload size, the payload, u32
// CRC-32C): for tests that read or alter a stream the encoder wrote.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "vds/bytes.h"
#include "vds/container.h"

namespace vds::test {

struct ChunkAt {
  uint32_t type;
  size_t at;      // the chunk's first byte (its type)
  uint32_t size;  // its payload's
  size_t payload() const { return at + kChunkHeadBytes; }
  std::vector<uint8_t> bytes(const std::vector<uint8_t>& s) const {
    return {s.begin() + static_cast<std::ptrdiff_t>(payload()), s.begin() + static_cast<std::ptrdiff_t>(payload() + size)};
  }
};

inline std::vector<ChunkAt> stream_chunks(const std::vector<uint8_t>& s) {
  std::vector<ChunkAt> out;
  for (size_t at = kPreambleBytes; at + kChunkHeadBytes <= s.size();) {
    out.push_back({load_le32(&s[at]), at, load_le32(&s[at + 4])});
    at += kChunkHeadBytes + out.back().size + kChunkTailBytes;
  }
  return out;
}

}  // namespace vds::test
