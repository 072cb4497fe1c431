// The chunks of a stream the encoder wrote (docs/stream-format.md), for
// the host code that rebuilds a stream or feeds a client chunk by chunk.
// Not a parser for streams from elsewhere: those go through the client's
// StreamParser (the CRCs are not checked here).
#pragma once
#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <vector>

#include "vds/bytes.h"
#include "vds/container.h"

namespace vds::enc {

struct StreamChunk {
  uint32_t type;
  std::span<const uint8_t> payload;
  size_t end;  // stream offset just after it
};

// Every chunk after the preamble, HEAD and END included; std::logic_error
// if the framing does not reach the stream's end exactly.
inline std::vector<StreamChunk> stream_chunks(std::span<const uint8_t> s) {
  std::vector<StreamChunk> out;
  size_t at = kPreambleBytes;
  while (at + kChunkHeadBytes + kChunkTailBytes <= s.size()) {
    const uint32_t type = load_le32(s.data() + at), n = load_le32(s.data() + at + 4);
    if (n > s.size() - at - kChunkHeadBytes - kChunkTailBytes) break;
    const size_t end = at + kChunkHeadBytes + n + kChunkTailBytes;
    out.push_back({type, s.subspan(at + kChunkHeadBytes, n), end});
    at = end;
  }
  if (at != s.size()) throw std::logic_error("stream_chunks: the stream's framing does not parse");
  return out;
}

}  // namespace vds::enc
