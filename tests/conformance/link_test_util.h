// Shared pieces of the link tests: a reproducible stream pattern, a
// checker that the device received exactly that stream, and a driver that
// runs a stream over a simulated link the way `vds serve` does.
#pragma once
#include <cstdint>
#include <functional>
#include <vector>

#include "vds/link/link.h"
#include "vds/link/sim.h"

namespace vds::link::linktest {

// Byte i of test stream `seed` (any length, never periodic on short scales).
inline uint8_t stream_byte(uint64_t seed, uint64_t i) {
  uint64_t z = (i + 1) * 0x9E3779B97F4A7C15ull ^ seed * 0xD1B54A32D192ED03ull;
  z = (z ^ (z >> 31)) * 0xBF58476D1CE4E5B9ull;
  return static_cast<uint8_t>(z >> 56);
}

// What the device application saw: bytes must arrive as the stream, in
// order, once. `first_bad` is the stream offset of the first wrong byte.
struct StreamChecker {
  uint64_t seed = 0;
  uint64_t got = 0;
  bool intact = true;
  uint64_t first_bad = UINT64_MAX;
  void feed(const uint8_t* p, size_t n) {
    for (size_t i = 0; i < n; ++i) {
      if (p[i] != stream_byte(seed, got + i) && intact) {
        intact = false;
        first_bad = got + i;
      }
    }
    got += n;
  }
  void restart() { got = 0; }  // a new session starts the stream over
};

// Host side of a transfer: writes the stream into the stream channel as
// the send buffer frees, restarting from byte 0 when a new session begins
// (the peer lost the session, so everything must be sent again).
struct StreamSource {
  uint64_t seed = 0;
  uint64_t total = 0;
  uint64_t written = 0;
  uint32_t epoch = 0;
  uint32_t restarts = 0;
  void pump(Link& host) {
    // Write only inside a session: a session's end discards the send
    // buffer, and the next one starts the stream over.
    if (!host.established()) return;
    if (host.session_epoch() != epoch) {
      if (epoch != 0) ++restarts;
      epoch = host.session_epoch();
      written = 0;
    }
    uint8_t buf[4096];
    while (written < total) {
      size_t room = host.writable(channel::kStream);
      if (room == 0) return;
      size_t n = room < sizeof buf ? room : sizeof buf;
      if (n > total - written) n = static_cast<size_t>(total - written);
      for (size_t i = 0; i < n; ++i) buf[i] = stream_byte(seed, written + i);
      size_t acc = 0;
      if (host.write(channel::kStream, buf, n, &acc) != Status::ok || acc == 0) return;
      written += acc;
    }
  }
  bool done(Link& host) const { return written == total && host.unacked(channel::kStream) == 0; }
};

// Reads everything the device has delivered into `check`, restarting the
// check when the device's session changes.
struct DeviceReader {
  StreamChecker check;
  uint32_t epoch = 0;
  uint32_t restarts = 0;
  uint64_t max_chunk = UINT64_MAX;  // read at most this much per call (a slow application)
  std::vector<uint8_t> buf = std::vector<uint8_t>(8192);
  void pump(Link& dev) {
    if (dev.session_epoch() != epoch) {
      if (epoch != 0) {
        ++restarts;
        check.restart();
      }
      epoch = dev.session_epoch();
    }
    size_t n = 0;
    const size_t want = max_chunk < buf.size() ? static_cast<size_t>(max_chunk) : buf.size();
    while (dev.read(channel::kStream, buf.data(), want, &n) == Status::ok && n != 0) {
      check.feed(buf.data(), n);
      if (max_chunk != UINT64_MAX) break;
    }
  }
};

// Steps `sim` with `src` writing and `rd` reading until the device
// application holds the whole stream (and, with `until_acked`, the host has
// it all acknowledged) or the simulated clock reaches `limit_ms`. Returns
// when the host was first seen established (where a goodput measurement
// starts), 0 if never.
inline uint64_t stream_down(LinkSim& sim, StreamSource& src, DeviceReader& rd, uint64_t limit_ms,
                            bool until_acked = false) {
  uint64_t established_ms = 0;
  while (!(rd.check.got == src.total && (!until_acked || src.done(sim.host()))) && sim.now_ms() < limit_ms) {
    if (established_ms == 0 && sim.host().established()) established_ms = sim.now_ms();
    src.pump(sim.host());
    sim.step();
    rd.pump(sim.device());
  }
  return established_ms;
}

}  // namespace vds::link::linktest
