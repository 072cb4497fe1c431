// libFuzzer: raw bytes into the client's stream parser, fed in pieces whose
// sizes come from the input itself; the parser must never crash, and
// feeding after an error must keep returning that error.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "vds/container.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const uint32_t capacity = 256u + data[0] * 16u;
  static std::vector<uint8_t> ws(1 << 16);
  vds::Arena arena(ws.data(), ws.size());
  vds::StreamParser p;
  vds::ChunkSink sink;
  sink.on_chunk = [](void*, uint32_t type, const uint8_t* payload, uint32_t n) {
    volatile uint8_t sum = 0;
    for (uint32_t i = 0; i < n; ++i) sum = static_cast<uint8_t>(sum + payload[i]);
    return (type & 1) ? vds::ChunkResult::consumed : vds::ChunkResult::unknown;
  };
  if (p.init(arena, capacity, sink) != vds::Status::ok) return 0;
  size_t at = 1;
  size_t piece = 1;
  vds::Status s = vds::Status::more_input;
  while (at < size) {
    const size_t n = piece < size - at ? piece : size - at;
    std::vector<uint8_t> copy(data + at, data + at + n);  // exact size: overreads are caught
    s = p.feed(copy.data(), copy.size());
    at += n;
    piece = piece * 3 % 97 + 1;
    if (vds::is_error(s)) {
      if (p.feed(data, 1) != s) __builtin_trap();
      break;
    }
  }
  if (!vds::is_error(s)) {
    const vds::Status f = p.finish();
    if (f == vds::Status::ok && !p.done()) __builtin_trap();
  }
  return 0;
}
