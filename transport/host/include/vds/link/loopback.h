// In-process loopback link in simulated time: two endpoints joined by a
// wire that paces bytes at a baud rate (10 bits per byte: start, 8 data,
// stop) and injects seeded, reproducible faults.
#pragma once
#include <cstdint>
#include <deque>
#include <memory>
#include <utility>
#include <vector>

#include "vds/link/backend.h"

namespace vds::link {

// splitmix64: the seeded generator of every simulated fault and device
// schedule (small, fast, the same on every platform). Advances `state`.
inline uint64_t splitmix64(uint64_t& state) {
  uint64_t z = (state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

struct FaultConfig {
  uint64_t seed = 1;
  double bit_error_rate = 0;       // per data bit on the wire
  double byte_drop_rate = 0;       // per byte
  double frame_drop_rate = 0;      // per frame (bytes up to a 0x00)
  double frame_dup_rate = 0;       // a frame sent twice in a row
  double frame_truncate_rate = 0;  // a frame cut short (its delimiter kept or lost)
  double garbage_rate = 0;         // per frame: a burst of random bytes before it
  uint32_t garbage_max = 64;       // longest burst
  double stall_rate = 0;           // per ms: the wire stops delivering for a while
  uint32_t stall_max_ms = 100;
  // Times [from, to) in ms when the wire is cut: everything on it or sent
  // over it is lost, then it comes back.
  std::vector<std::pair<uint64_t, uint64_t>> cuts;
};

struct WireStats {
  uint64_t bytes_in = 0;  // bytes the sender put on the wire
  uint64_t bytes_out = 0;  // bytes delivered
  uint64_t bit_flips = 0;
  uint64_t bytes_dropped = 0;
  uint64_t frames = 0;
  uint64_t frames_dropped = 0;
  uint64_t frames_duplicated = 0;
  uint64_t frames_truncated = 0;
  uint64_t garbage_bursts = 0;
  uint64_t stalls = 0;
  uint64_t cut_bytes = 0;
};

// One direction of the wire.
class Wire {
 public:
  Wire(uint32_t baud, uint32_t latency_ms, const FaultConfig& faults);
  size_t room() const { return static_cast<size_t>(credit_milli_ / 1000); }
  size_t write(const uint8_t* data, size_t n);  // takes at most room()
  size_t read(uint8_t* buf, size_t n);
  void advance_to(uint64_t now_ms);
  const WireStats& stats() const { return stats_; }
  // Swaps the fault set (e.g. to stop injecting for a clean end phase).
  void set_faults(const FaultConfig& f);

 private:
  uint64_t rng();
  double uniform();
  uint64_t geometric(double p);
  void end_frame(bool delimited);
  void deliver(std::vector<uint8_t>& bytes);
  bool cut_at(uint64_t t) const;

  uint32_t baud_;
  uint32_t latency_ms_;
  FaultConfig f_;
  uint64_t state_;
  uint64_t now_ = 0;
  uint64_t credit_milli_ = 0;  // thousandths of a byte the line may still carry
  std::vector<uint8_t> frame_;
  std::deque<std::pair<uint64_t, std::vector<uint8_t>>> flight_;
  std::vector<uint8_t> arrived_;
  size_t arrived_pos_ = 0;
  uint64_t stall_until_ = 0;
  uint64_t next_flip_bit_ = 0;   // bits until the next flipped bit
  uint64_t next_drop_byte_ = 0;  // bytes until the next dropped byte
  WireStats stats_;
};

// Two endpoints, a and b, joined by one Wire each way.
class Loopback {
 public:
  Loopback(uint32_t baud, const FaultConfig& a_to_b, const FaultConfig& b_to_a, uint32_t latency_ms = 1);
  ~Loopback();
  Backend& a();
  Backend& b();
  Wire& wire_ab() { return ab_; }
  Wire& wire_ba() { return ba_; }
  uint64_t now_ms() const { return now_; }
  void advance(uint32_t ms);

 private:
  class End;
  Wire ab_, ba_;
  std::unique_ptr<End> a_, b_;
  uint64_t now_ = 0;
};

}  // namespace vds::link
