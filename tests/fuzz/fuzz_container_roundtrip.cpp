// libFuzzer: the input describes a stream (header fields and chunks); the
// host writer writes it, the client parser must return exactly those chunks
// whatever the piece sizes, and must refuse every strict prefix.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "vds/container.h"
#include "vds/enc/stream_writer.h"

namespace {

struct Seen {
  std::vector<std::pair<uint32_t, std::vector<uint8_t>>> chunks;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 4) return 0;
  vds::StreamHeader h = vds::enc::default_header(static_cast<vds::StreamMode>(data[0] % 4), 1 + data[1], 1 + data[2]);
  h.max_chunk_payload = 64;
  std::vector<std::pair<uint32_t, std::vector<uint8_t>>> want;
  for (size_t at = 4; at < size;) {
    const size_t n = data[at] % 65;
    const uint32_t type = vds::fourcc('C', 'H', static_cast<char>('A' + data[at] % 26), 'K');
    ++at;
    const size_t take = n < size - at ? n : size - at;
    want.emplace_back(type, std::vector<uint8_t>(data + at, data + at + take));
    at += take;
  }
  vds::enc::StreamWriter w(h);
  for (const auto& c : want) w.add_chunk(c.first, c.second);
  const std::vector<uint8_t> stream = w.finish();

  std::vector<uint8_t> ws(4096);
  for (int pass = 0; pass < 2; ++pass) {
    vds::Arena arena(ws.data(), ws.size());
    vds::StreamParser p;
    Seen seen;
    vds::ChunkSink sink;
    sink.ctx = &seen;
    sink.on_chunk = [](void* ctx, uint32_t type, const uint8_t* payload, uint32_t n) {
      static_cast<Seen*>(ctx)->chunks.emplace_back(type, std::vector<uint8_t>(payload, payload + n));
      return vds::ChunkResult::consumed;
    };
    if (p.init(arena, 256, sink) != vds::Status::ok) __builtin_trap();
    // Pass 0: the whole stream at once; pass 1: pieces of data[3] % 17 + 1 bytes.
    const size_t piece = pass == 0 ? stream.size() : data[3] % 17 + 1;
    vds::Status s = vds::Status::more_input;
    for (size_t at = 0; at < stream.size(); at += piece) {
      const size_t n = piece < stream.size() - at ? piece : stream.size() - at;
      s = p.feed(stream.data() + at, n);
      if (vds::is_error(s)) __builtin_trap();
    }
    if (s != vds::Status::ok || seen.chunks != want) __builtin_trap();
  }
  // A strict prefix never passes as a whole stream.
  vds::Arena arena(ws.data(), ws.size());
  vds::StreamParser p;
  if (p.init(arena, 256, {}) != vds::Status::ok) __builtin_trap();
  const size_t cut = (static_cast<size_t>(data[1]) * 7919u) % stream.size();
  if (p.feed(stream.data(), cut) != vds::Status::more_input || p.finish() != vds::Status::truncated) __builtin_trap();
  return 0;
}
