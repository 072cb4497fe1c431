// Fuzzes the link frame decoder and an established Link's handling of
// frames: raw wire bytes, and well-formed frames (valid COBS and CRC, the
// session's tag) with arbitrary headers and payloads, so acks, data
// offsets, datagrams and hellos are all reached. Also round-trips
// encode -> decode. Invariants: no crash, nothing beyond the window held,
// a decoded frame equals what was encoded.
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "vds/link/frame.h"
#include "vds/link/link.h"

using namespace vds::link;

namespace {

struct Pair {
  std::vector<uint64_t> hw, dw;
  vds::Arena ha, da;
  Link host, dev;
  uint32_t now = 0;
  Pair()
      : hw((link_workspace_size(host_config(1)) + 7) / 8),
        dw((link_workspace_size(device_config(2)) + 7) / 8),
        ha(hw.data(), hw.size() * 8),
        da(dw.data(), dw.size() * 8) {
    if (host.init(host_config(1), ha) != vds::Status::ok || dev.init(device_config(2), da) != vds::Status::ok) abort();
    uint8_t buf[512];
    for (int i = 0; i < 50 && !(host.established() && dev.established()); ++i) {
      ++now;
      size_t n;
      while ((n = host.transmit(buf, sizeof buf, now)) != 0) dev.receive(buf, n, now);
      while ((n = dev.transmit(buf, sizeof buf, now)) != 0) host.receive(buf, n, now);
    }
    if (!host.established() || !dev.established()) abort();
  }
};

void check(const Link& l) {
  for (uint8_t c = 0; c < kChannels; ++c) {
    if (l.readable(c) > l.rx_window(c) || l.rx_peak(c) > l.rx_window(c)) abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const uint8_t mode = data[0];
  ++data;
  --size;

  // Raw bytes into a bare receiver with a small buffer.
  {
    uint8_t buf[frame_rx_buffer_size(64)];
    FrameReceiver r;
    r.init(buf, sizeof buf);
    size_t at = 0;
    while (at < size) {
      RxEvent ev;
      RxFrame f;
      const size_t k = r.push(data + at, size - at, &ev, &f);
      if (k == 0) abort();
      if (ev == RxEvent::frame && (f.size + kFrameOverhead > sizeof buf || f.payload < buf)) abort();
      at += k;
    }
  }

  // Round trip of a frame built from the input.
  if (size >= 4) {
    FrameHeader h;
    h.type = static_cast<FrameType>(data[0] % kFrameTypeCount);
    h.channel = data[1] & 0x0F;
    h.tag = data[2];
    h.seq = static_cast<uint16_t>(data[3] | data[2] << 8);
    const size_t n = size - 4 > 2000 ? 2000 : size - 4;
    std::vector<uint8_t> enc(frame_wire_bound(n));
    size_t len = 0;
    if (frame_encode(h, data + 4, n, enc.data(), enc.size(), &len) != vds::Status::ok) abort();
    std::vector<uint8_t> buf(frame_rx_buffer_size(2000));
    FrameReceiver r;
    r.init(buf.data(), buf.size());
    RxEvent ev;
    RxFrame f;
    if (r.push(enc.data(), len, &ev, &f) != len || ev != RxEvent::frame) abort();
    if (f.size != n || (n != 0 && memcmp(f.payload, data + 4, n) != 0) || f.header.seq != h.seq ||
        f.header.channel != h.channel || f.header.type != h.type || f.header.tag != h.tag)
      abort();
  }

  // Into an established pair: raw bytes (mode odd) or a series of valid
  // frames described by the input (mode even), to either side.
  Pair pair;
  Link& dev = pair.dev;
  Link& host = pair.host;
  uint32_t now = pair.now;
  if (mode & 1) {
    ((mode & 2) ? host : dev).receive(data, size, now);
  } else {
    size_t at = 0;
    std::vector<uint8_t> enc(frame_wire_bound(1100));
    while (at + 5 <= size) {
      FrameHeader h;
      h.type = static_cast<FrameType>(data[at] >> 4 & 3);
      h.channel = data[at] & 0x0F;
      const bool to_host = (data[at] & 0x40) != 0;
      Link& target = to_host ? host : dev;
      h.tag = (data[at + 1] == 0xFF) ? static_cast<uint8_t>(target.session_tag() + 1) : target.session_tag();
      h.seq = static_cast<uint16_t>(data[at + 2] | data[at + 3] << 8);
      size_t n = data[at + 4];
      if (n == 255) n = 1024;
      at += 5;
      std::vector<uint8_t> payload(n);
      for (size_t i = 0; i < n; ++i) payload[i] = at + i < size ? data[at + i] : static_cast<uint8_t>(i);
      at += n < size - at ? n : size - at;
      size_t len = 0;
      if (frame_encode(h, payload.data(), n, enc.data(), enc.size(), &len) != vds::Status::ok) abort();
      target.receive(enc.data(), len, ++now);
      check(target);
    }
  }
  // Let both sides run a little: whatever state they reached must hold.
  uint8_t buf[512];
  for (int i = 0; i < 20; ++i) {
    ++now;
    size_t n;
    while ((n = host.transmit(buf, sizeof buf, now)) != 0) dev.receive(buf, n, now);
    while ((n = dev.transmit(buf, sizeof buf, now)) != 0) host.receive(buf, n, now);
    size_t got = 0;
    dev.read(channel::kStream, buf, sizeof buf, &got);
  }
  check(host);
  check(dev);
  return 0;
}
