// Simulated-time host/device pair over the loopback wire.
#include "vds/link/sim.h"

#include <stdexcept>
#include <string>

namespace vds::link {

SimEndpoint::SimEndpoint(const LinkConfig& cfg, Backend& backend)
    : ws_((link_workspace_size(cfg) + 7) / 8), arena_(ws_.data(), ws_.size() * 8), pump_(link_, backend) {
  const Status s = link_.init(cfg, arena_);
  if (s != Status::ok) throw std::runtime_error(std::string("link init failed: ") + status_name(s));
}

LinkSim::LinkSim(uint32_t baud, const FaultConfig& down, const FaultConfig& up, const LinkConfig& host,
                 const LinkConfig& device, uint32_t latency_ms)
    : loop_(baud, down, up, latency_ms) {
  host_ = std::make_unique<SimEndpoint>(host, loop_.a());
  device_ = std::make_unique<SimEndpoint>(device, loop_.b());
}

void LinkSim::step() {
  const uint32_t now = static_cast<uint32_t>(loop_.now_ms());
  host_->pump().step(now);
  device_->pump().step(now);
  loop_.advance(1);
}

void LinkSim::reboot_device(const LinkConfig& cfg) { device_ = std::make_unique<SimEndpoint>(cfg, loop_.b()); }
void LinkSim::restart_host(const LinkConfig& cfg) { host_ = std::make_unique<SimEndpoint>(cfg, loop_.a()); }

}  // namespace vds::link
