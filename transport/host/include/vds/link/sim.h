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
          const LinkConfig& device, uint32_t latency_ms = 1);
  Link& host() { return host_->link(); }
  Link& device() { return device_->link(); }
  Loopback& wire() { return loop_; }
  uint64_t now_ms() const { return loop_.now_ms(); }
  // One millisecond: both endpoints send what the line takes and receive
  // what arrived, then the wire moves on.
  void step();
  // A fresh device (power cycle) or host process, with new state.
  void reboot_device(const LinkConfig& cfg);
  void restart_host(const LinkConfig& cfg);

 private:
  Loopback loop_;
  std::unique_ptr<SimEndpoint> host_, device_;
};

}  // namespace vds::link
