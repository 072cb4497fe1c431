// A small valid vds stream for the link tests that serve one: `chunks`
// chunks of `chunk_bytes` patterned bytes in an image-mode container.
#pragma once
#include <cstdint>
#include <vector>

#include "vds/enc/stream_writer.h"

namespace vds::link::linktest {

inline std::vector<uint8_t> make_stream(size_t chunks, size_t chunk_bytes) {
  vds::StreamHeader h = vds::enc::default_header(vds::StreamMode::images, 64, 48);
  h.max_chunk_payload = static_cast<uint32_t>(chunk_bytes);
  vds::enc::StreamWriter w(h);
  std::vector<uint8_t> p(chunk_bytes);
  for (size_t c = 0; c < chunks; ++c) {
    for (size_t i = 0; i < p.size(); ++i) p[i] = static_cast<uint8_t>(i * 31 + c * 7);
    w.add_chunk(vds::fourcc('D', 'A', 'T', 'A'), p);
  }
  return w.finish();
}

}  // namespace vds::link::linktest
