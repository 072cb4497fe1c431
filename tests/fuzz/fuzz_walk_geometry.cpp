// libFuzzer: the walkthrough's geometry chunks (vds/walk_geometry.h) as the
// client reads them, frame after frame. The first byte picks the slot
// budget and grid; the rest is a run of chunks, each a 2-byte length and
// its payload. Invariants: no crash, sanitizer report or hang; after every
// accepted chunk the hot slots are ascending, inside the budget and hold a
// triangle.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "vds/arena.h"
#include "vds/walk_geometry.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const uint32_t slots = 1u + (data[0] & 0x3F) * 7;
  const int32_t quantum = int32_t{1} << (8 + (data[0] >> 6) * 2);
  std::vector<uint8_t> work(vds::WalkGeometry::workspace_bytes(slots));
  vds::Arena arena(work.data(), work.size());
  vds::WalkGeometry g;
  if (g.init(arena, slots, quantum) != vds::Status::ok) abort();
  size_t at = 1;
  while (at + 2 <= size) {
    const size_t n = std::min<size_t>(size - at - 2, static_cast<size_t>(data[at]) | static_cast<size_t>(data[at + 1]) << 8);
    at += 2;
    if (g.consume(data + at, static_cast<uint32_t>(n)) != vds::Status::ok) break;
    at += n;
    for (uint32_t i = 0; i < g.hot_count(); ++i) {
      if (g.hot()[i] >= slots || g.triangle(g.hot()[i]) == nullptr) abort();
      if (i > 0 && g.hot()[i] <= g.hot()[i - 1]) abort();
    }
  }
  return 0;
}
