// Fuzzes the link session state machine: the input is a script of line
// events between a host and a device (time passing, bit flips, lost and
// replayed byte runs, client reboots, host restarts, slow reads) while the
// host streams a known pattern. Invariants: no crash; within each device
// session the delivered bytes are exactly a prefix of the stream; the
// receive window is never exceeded.
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <vector>

#include "vds/link/link.h"

using namespace vds::link;

namespace {

uint8_t pattern(uint64_t i) { return static_cast<uint8_t>((i * 0x9E3779B1u) >> 11); }

struct Endpoint {
  std::vector<uint64_t> ws;
  vds::Arena arena;
  Link link;
  explicit Endpoint(const LinkConfig& c) : ws((link_workspace_size(c) + 7) / 8), arena(ws.data(), ws.size() * 8) {
    if (link.init(c, arena) != vds::Status::ok) abort();
  }
};

struct Script {
  const uint8_t* d;
  size_t n;
  size_t at = 0;
  uint8_t next() { return at < n ? d[at++] : 0; }
  bool more() const { return at < n; }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  Script s{data, size};
  auto host = std::make_unique<Endpoint>(host_config(1));
  auto dev = std::make_unique<Endpoint>(device_config(2));
  uint32_t now = 0;
  uint64_t written = 0, got = 0;
  uint32_t host_epoch = 0, dev_epoch = 0;
  std::vector<uint8_t> buf(2048);

  auto source = [&] {
    Link& h = host->link;
    if (!h.established()) return;
    if (h.session_epoch() != host_epoch) {
      host_epoch = h.session_epoch();
      written = 0;
    }
    uint8_t w[256];
    for (size_t i = 0; i < sizeof w; ++i) w[i] = pattern(written + i);
    size_t acc = 0;
    h.write(channel::kStream, w, sizeof w, &acc);
    written += acc;
  };
  auto sink = [&](size_t max) {
    Link& d = dev->link;
    if (d.session_epoch() != dev_epoch) {
      dev_epoch = d.session_epoch();
      got = 0;
    }
    if (d.readable(channel::kStream) > d.rx_window(channel::kStream)) abort();
    if (d.rx_peak(channel::kStream) > d.rx_window(channel::kStream)) abort();
    size_t n = 0;
    d.read(channel::kStream, buf.data(), max < buf.size() ? max : buf.size(), &n);
    for (size_t i = 0; i < n; ++i)
      if (buf[i] != pattern(got + i)) abort();  // corrupted, reordered or duplicated delivery
    got += n;
  };
  auto carry = [&](Link& from, Link& to, size_t max, int flip_bit, bool drop, bool twice) {
    const size_t n = from.transmit(buf.data(), max < buf.size() ? max : buf.size(), now);
    if (flip_bit >= 0 && static_cast<size_t>(flip_bit / 8) < n) buf[flip_bit / 8] ^= static_cast<uint8_t>(1u << (flip_bit % 8));
    if (drop) return;
    to.receive(buf.data(), n, now);
    if (twice) to.receive(buf.data(), n, now);
  };

  while (s.more()) {
    const uint8_t op = s.next();
    const uint8_t arg = s.next();
    switch (op % 9) {
      case 0:  // time passes on a clean line
        for (int i = 0; i <= arg % 64; ++i) {
          ++now;
          source();
          carry(host->link, dev->link, 300, -1, false, false);
          carry(dev->link, host->link, 100, -1, false, false);
          sink(SIZE_MAX);
        }
        break;
      case 1:  // one bit flipped going down
        carry(host->link, dev->link, 1 + arg * 4, (s.next() | s.next() << 8) % 8192, false, false);
        break;
      case 2:  // one bit flipped going up
        carry(dev->link, host->link, 1 + arg, (s.next() | s.next() << 8) % 2048, false, false);
        break;
      case 3:  // a run of bytes lost
        carry((arg & 1) ? dev->link : host->link, (arg & 1) ? host->link : dev->link, 1 + arg * 3, -1, true, false);
        break;
      case 4:  // a run of bytes delivered twice
        carry((arg & 1) ? dev->link : host->link, (arg & 1) ? host->link : dev->link, 1 + arg * 3, -1, false, true);
        break;
      case 5:  // a slow application read
        sink(arg);
        break;
      case 6:  // client reboot (same or new nonce seed)
        dev = std::make_unique<Endpoint>(device_config(arg & 1 ? 2 : 2 + arg));
        dev_epoch = 0;
        got = 0;
        break;
      case 7:  // host restart
        host = std::make_unique<Endpoint>(host_config(3 + arg));
        host_epoch = 0;
        written = 0;
        break;
      case 8:  // time jumps (timers fire)
        now += 1 + arg * 16u;
        source();
        break;
    }
  }
  return 0;
}
