// libFuzzer: the link's application messages (vds/link/messages.h), which
// the host decodes from whatever a client sends up and the client from what
// the host sends down. The first byte picks the message type; the rest is
// the message. Invariants: no crash or sanitizer report; decode reads only
// the bytes it is given; a message that decodes ok encodes back to the same
// bytes (every field is carried, nothing is invented); a short message or
// a wrong type byte is refused.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "vds/link/messages.h"

namespace {

template <class M, size_t N>
void round_trip(const uint8_t* data, size_t size) {
  // A copy of exactly `size` bytes: ASan sees any read past them.
  const std::vector<uint8_t> in(data, data + size);
  M m{};
  const vds::Status s = vds::link::decode(in.data(), in.size(), &m);
  if (s != vds::Status::ok) {
    if (s != vds::Status::malformed) abort();
    return;
  }
  if (in.size() < N) abort();  // a short message must not decode
  uint8_t out[N];
  if (vds::link::encode(m, out) != N) abort();
  if (std::memcmp(out, in.data(), N) != 0) abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const uint8_t pick = data[0] % 4;
  ++data;
  --size;
  switch (pick) {
    case 0: round_trip<vds::link::FrameRecord, vds::link::kFrameRecordBytes>(data, size); break;
    case 1: round_trip<vds::link::ClientStats, vds::link::kClientStatsBytes>(data, size); break;
    case 2: round_trip<vds::link::DoneReport, vds::link::kDoneReportBytes>(data, size); break;
    default: round_trip<vds::link::Goodbye, vds::link::kGoodbyeBytes>(data, size); break;
  }
  return 0;
}
