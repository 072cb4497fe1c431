// A host and a device Link joined by a Loopback, stepped in simulated
// milliseconds: what the conformance tests, the benchmark and
// `vds serve --link loopback` run. Each endpoint owns its workspace, as a
// firmware would own a static array.
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include "vds/arena.h"
#include "vds/link/backend.h"
#include "vds/link/link.h"
#include "vds/link/loopback.h"

namespace vds::link {

// How a simulated device takes bytes off its line, as a busy client does: a
// UART receive ring of `ring_bytes` (bytes arriving while it is full are
// lost, as on a real UART, and counted) that the firmware drains at
// `rate_permille` of the line rate, every `burst_ms` at once (between the
// bands of a frame), stopping now and then for up to `pause_max_ms` (a long
// decode) during which it neither reads, sends nor runs its timers.
struct DrainProfile {
  uint32_t ring_bytes = 0;        // 0: the device reads the line directly, at once
  uint32_t rate_permille = 1000;  // drain speed, thousandths of the line rate
  uint32_t burst_ms = 1;          // drains this often
  uint32_t pause_every_ms = 0;    // a pause starts every this many ms (0: none)
  uint32_t pause_max_ms = 0;      // pauses last 1..pause_max_ms
  uint64_t seed = 1;
};

struct DrainStats {
  uint64_t overflow = 0;    // bytes lost because the ring was full
  uint32_t peak = 0;        // most bytes the ring ever held
  uint64_t taken = 0;       // bytes the firmware read
  uint32_t pauses = 0;
  uint64_t paused_ms = 0;
};

// The device's side of the line under a DrainProfile: a Backend whose
// read() hands out what the firmware would read this millisecond.
class SlowDevice : public Backend {
 public:
  SlowDevice(Backend& line, uint32_t baud, const DrainProfile& p);
  // One simulated millisecond: bytes arrive into the ring; the drain
  // allowance and the pause schedule move on.
  void advance(uint64_t now_ms);
  bool paused() const { return now_ < pause_until_; }
  const DrainStats& stats() const { return stats_; }
  size_t write_room() override { return line_.write_room(); }
  size_t write(const uint8_t* data, size_t n) override { return line_.write(data, n); }
  size_t read(uint8_t* buf, size_t n, int timeout_ms) override;
  std::string describe() const override { return "slow device on " + line_.describe(); }

 private:
  uint64_t rng();
  Backend& line_;
  DrainProfile p_;
  uint64_t per_ms_milli_;  // thousandths of a byte the firmware may read per ms
  uint64_t credit_milli_ = 0;
  uint64_t now_ = 0;
  uint64_t pause_until_ = 0;
  uint64_t state_;
  std::vector<uint8_t> ring_;
  size_t head_ = 0, count_ = 0;
  DrainStats stats_;
};

class SimEndpoint {
 public:
  SimEndpoint(const LinkConfig& cfg, Backend& backend);  // throws std::runtime_error if init fails
  Link& link() { return link_; }
  Pump& pump() { return pump_; }
  size_t workspace_used() const { return arena_.used(); }

 private:
  std::vector<uint64_t> ws_;
  Arena arena_;
  Link link_;
  Pump pump_;
};

class LinkSim {
 public:
  LinkSim(uint32_t baud, const FaultConfig& down, const FaultConfig& up, const LinkConfig& host,
          const LinkConfig& device, uint32_t latency_ms = 1, const DrainProfile& drain = {});
  Link& host() { return host_->link(); }
  Link& device() { return device_->link(); }
  Loopback& wire() { return loop_; }
  uint64_t now_ms() const { return loop_.now_ms(); }
  // One millisecond: both endpoints send what the line takes and receive
  // what arrived, then the wire moves on.
  void step();
  // The device's line under its DrainProfile (nullptr when it reads directly).
  const SlowDevice* slow_device() const { return slow_.get(); }
  // A fresh device (power cycle) or host process, with new state.
  void reboot_device(const LinkConfig& cfg);
  void restart_host(const LinkConfig& cfg);

 private:
  Backend& device_line();
  Loopback loop_;
  std::unique_ptr<SlowDevice> slow_;
  std::unique_ptr<SimEndpoint> host_, device_;
};

}  // namespace vds::link
