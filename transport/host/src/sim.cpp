// Simulated-time host/device pair over the loopback wire, and a device that
// drains its line slowly.
#include "vds/link/sim.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace vds::link {

SlowDevice::SlowDevice(Backend& line, uint32_t baud, const DrainProfile& p)
    : line_(line), p_(p), per_ms_milli_(static_cast<uint64_t>(baud) / 10 * p.rate_permille / 1000),
      state_(p.seed * 0x9E3779B97F4A7C15ull + 0x2545F4914F6CDD1Dull), ring_(std::max<uint32_t>(p.ring_bytes, 1)) {
  if (p_.burst_ms == 0) p_.burst_ms = 1;
}

uint64_t SlowDevice::rng() { return splitmix64(state_); }

void SlowDevice::advance(uint64_t now_ms) {
  now_ = now_ms;
  // The UART keeps receiving whatever the firmware does.
  uint8_t buf[512];
  size_t n = 0;
  while ((n = line_.read(buf, sizeof buf, 0)) != 0) {
    for (size_t i = 0; i < n; ++i) {
      if (count_ == ring_.size()) {
        ++stats_.overflow;
        continue;
      }
      ring_[(head_ + count_) % ring_.size()] = buf[i];
      ++count_;
    }
    stats_.peak = std::max<uint32_t>(stats_.peak, static_cast<uint32_t>(count_));
  }
  if (paused()) {
    ++stats_.paused_ms;
    return;
  }
  if (p_.pause_every_ms != 0 && p_.pause_max_ms != 0 && now_ != 0 && now_ % p_.pause_every_ms == 0) {
    ++stats_.pauses;
    pause_until_ = now_ + 1 + rng() % p_.pause_max_ms;
    return;
  }
  // While the ring is empty the allowance does not pile up: a firmware
  // that has nothing to read cannot read faster later.
  credit_milli_ = count_ == 0 ? 0 : credit_milli_ + per_ms_milli_;
}

size_t SlowDevice::read(uint8_t* buf, size_t n, int) {
  if (paused() || now_ % p_.burst_ms != 0) return 0;
  size_t k = std::min<size_t>({n, count_, static_cast<size_t>(credit_milli_ / 1000)});
  for (size_t i = 0; i < k; ++i) buf[i] = ring_[(head_ + i) % ring_.size()];
  head_ = (head_ + k) % ring_.size();
  count_ -= k;
  credit_milli_ -= static_cast<uint64_t>(k) * 1000;
  stats_.taken += k;
  return k;
}

SimEndpoint::SimEndpoint(const LinkConfig& cfg, Backend& backend)
    : ws_((link_workspace_size(cfg) + 7) / 8), arena_(ws_.data(), ws_.size() * 8), pump_(link_, backend) {
  const Status s = link_.init(cfg, arena_);
  if (s != Status::ok) throw std::runtime_error(std::string("link init failed: ") + status_name(s));
}

LinkSim::LinkSim(uint32_t baud, const FaultConfig& down, const FaultConfig& up, const LinkConfig& host,
                 const LinkConfig& device, uint32_t latency_ms, const DrainProfile& drain)
    : loop_(baud, down, up, latency_ms) {
  if (drain.ring_bytes != 0) slow_ = std::make_unique<SlowDevice>(loop_.b(), baud, drain);
  host_ = std::make_unique<SimEndpoint>(host, loop_.a());
  device_ = std::make_unique<SimEndpoint>(device, device_line());
}

Backend& LinkSim::device_line() { return slow_ ? static_cast<Backend&>(*slow_) : loop_.b(); }

void LinkSim::step() {
  const uint32_t now = static_cast<uint32_t>(loop_.now_ms());
  host_->pump().step(now);
  if (slow_) slow_->advance(now);
  if (!slow_ || !slow_->paused()) device_->pump().step(now);
  loop_.advance(1);
}

void LinkSim::reboot_device(const LinkConfig& cfg) { device_ = std::make_unique<SimEndpoint>(cfg, device_line()); }
void LinkSim::restart_host(const LinkConfig& cfg) { host_ = std::make_unique<SimEndpoint>(cfg, loop_.a()); }

}  // namespace vds::link
