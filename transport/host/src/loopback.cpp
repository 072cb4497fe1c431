// Loopback link in simulated time: a wire per direction that paces bytes at
// baud/10 bytes per second (a UART byte is 10 bits) and injects seeded
// faults frame by frame (a frame is the bytes up to a 0x00 delimiter).
#include "vds/link/loopback.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace vds::link {

Wire::Wire(uint32_t baud, uint32_t latency_ms, const FaultConfig& faults)
    : baud_(baud), latency_ms_(latency_ms), state_(0) {
  set_faults(faults);
}

void Wire::set_faults(const FaultConfig& f) {
  f_ = f;
  state_ = f.seed * 0x9E3779B97F4A7C15ull + 0x632BE59BD9B4E019ull;
  next_flip_bit_ = geometric(f_.bit_error_rate);
  next_drop_byte_ = geometric(f_.byte_drop_rate);
}

uint64_t Wire::rng() { return splitmix64(state_); }

double Wire::uniform() { return static_cast<double>(rng() >> 11) * (1.0 / 9007199254740992.0); }

// Trials before the next event of probability p (skip sampling, so a rate
// of 1e-5 costs one draw per event, not one per bit).
uint64_t Wire::geometric(double p) {
  if (p <= 0) return UINT64_MAX;
  if (p >= 1) return 0;
  const double u = 1.0 - uniform();  // (0, 1]
  const double g = std::floor(std::log(u) / std::log1p(-p));
  return g > 1e18 ? UINT64_MAX : static_cast<uint64_t>(g);
}

bool Wire::cut_at(uint64_t t) const {
  for (const auto& c : f_.cuts)
    if (t >= c.first && t < c.second) return true;
  return false;
}

size_t Wire::write(const uint8_t* data, size_t n) {
  n = std::min(n, room());
  credit_milli_ -= static_cast<uint64_t>(n) * 1000;
  stats_.bytes_in += n;
  if (cut_at(now_)) {
    stats_.cut_bytes += n;
    return n;
  }
  size_t i = 0;
  while (i < n) {
    const void* z = std::memchr(data + i, 0, n - i);
    const size_t end = z ? static_cast<size_t>(static_cast<const uint8_t*>(z) - data) + 1 : n;
    frame_.insert(frame_.end(), data + i, data + end);
    i = end;
    if (z) end_frame(true);
  }
  return n;
}

void Wire::end_frame(bool delimited) {
  std::vector<uint8_t> fr;
  fr.swap(frame_);
  if (fr.size() <= 1) {  // a lone delimiter
    deliver(fr);
    return;
  }
  ++stats_.frames;
  std::vector<uint8_t> out;
  if (f_.garbage_rate > 0 && uniform() < f_.garbage_rate) {
    ++stats_.garbage_bursts;
    const uint32_t len = 1 + static_cast<uint32_t>(rng() % std::max<uint32_t>(f_.garbage_max, 1));
    for (uint32_t i = 0; i < len; ++i) out.push_back(static_cast<uint8_t>(rng()));
  }
  if (f_.frame_drop_rate > 0 && uniform() < f_.frame_drop_rate) {
    ++stats_.frames_dropped;
    deliver(out);
    return;
  }
  if (f_.frame_truncate_rate > 0 && uniform() < f_.frame_truncate_rate) {
    ++stats_.frames_truncated;
    const size_t keep = rng() % (fr.size() - 1);
    const bool delim = (rng() & 1) != 0 && delimited;
    fr.resize(keep);
    if (delim) fr.push_back(0);
  }
  const bool dup = f_.frame_dup_rate > 0 && uniform() < f_.frame_dup_rate;
  out.insert(out.end(), fr.begin(), fr.end());
  if (dup) {
    ++stats_.frames_duplicated;
    out.insert(out.end(), fr.begin(), fr.end());
  }
  deliver(out);
}

// Byte drops, then bit flips, at positions drawn by skip sampling: the
// next event is a geometric number of bytes (bits) ahead.
void Wire::deliver(std::vector<uint8_t>& bytes) {
  std::vector<uint8_t> out;
  if (next_drop_byte_ >= bytes.size()) {
    out.swap(bytes);
    if (next_drop_byte_ != UINT64_MAX) next_drop_byte_ -= out.size();
  } else {
    out.reserve(bytes.size());
    size_t at = 0;
    while (at < bytes.size()) {
      if (next_drop_byte_ >= bytes.size() - at) {
        out.insert(out.end(), bytes.begin() + static_cast<std::ptrdiff_t>(at), bytes.end());
        if (next_drop_byte_ != UINT64_MAX) next_drop_byte_ -= bytes.size() - at;
        break;
      }
      const size_t keep = static_cast<size_t>(next_drop_byte_);
      out.insert(out.end(), bytes.begin() + static_cast<std::ptrdiff_t>(at),
                 bytes.begin() + static_cast<std::ptrdiff_t>(at + keep));
      at += keep + 1;
      ++stats_.bytes_dropped;
      next_drop_byte_ = geometric(f_.byte_drop_rate);
    }
  }
  const uint64_t bits = static_cast<uint64_t>(out.size()) * 8;
  while (next_flip_bit_ < bits) {
    out[next_flip_bit_ / 8] = static_cast<uint8_t>(out[next_flip_bit_ / 8] ^ (1u << (next_flip_bit_ % 8)));
    ++stats_.bit_flips;
    const uint64_t g = geometric(f_.bit_error_rate);
    next_flip_bit_ = g == UINT64_MAX ? UINT64_MAX : next_flip_bit_ + 1 + g;
  }
  if (next_flip_bit_ != UINT64_MAX) next_flip_bit_ -= bits;
  if (!out.empty()) flight_.emplace_back(now_ + latency_ms_, std::move(out));
}

void Wire::advance_to(uint64_t t) {
  const uint64_t per_ms = baud_ / 10;  // thousandths of a byte per ms: baud/10 bytes per second
  const uint64_t cap = std::max<uint64_t>(per_ms * 2, 1000);
  while (now_ < t) {
    ++now_;
    credit_milli_ = std::min(credit_milli_ + per_ms, cap);
    if (cut_at(now_) && !flight_.empty()) {
      for (const auto& e : flight_) stats_.cut_bytes += e.second.size();
      flight_.clear();
    }
    if (f_.stall_rate > 0 && now_ >= stall_until_ && uniform() < f_.stall_rate) {
      ++stats_.stalls;
      stall_until_ = now_ + 1 + rng() % std::max<uint32_t>(f_.stall_max_ms, 1);
    }
    if (now_ < stall_until_) continue;
    while (!flight_.empty() && flight_.front().first <= now_) {
      auto& v = flight_.front().second;
      if (arrived_pos_ == arrived_.size()) {
        arrived_.clear();
        arrived_pos_ = 0;
      }
      arrived_.insert(arrived_.end(), v.begin(), v.end());
      stats_.bytes_out += v.size();
      flight_.pop_front();
    }
  }
}

size_t Wire::read(uint8_t* buf, size_t n) {
  const size_t k = std::min(n, arrived_.size() - arrived_pos_);
  std::copy_n(arrived_.begin() + static_cast<std::ptrdiff_t>(arrived_pos_), k, buf);
  arrived_pos_ += k;
  return k;
}

class Loopback::End : public Backend {
 public:
  End(Wire& out, Wire& in, const char* name) : out_(out), in_(in), name_(name) {}
  size_t write_room() override { return out_.room(); }
  size_t write(const uint8_t* data, size_t n) override { return out_.write(data, n); }
  size_t read(uint8_t* buf, size_t n, int) override { return in_.read(buf, n); }
  std::string describe() const override { return name_; }

 private:
  Wire& out_;
  Wire& in_;
  const char* name_;
};

Loopback::Loopback(uint32_t baud, const FaultConfig& a_to_b, const FaultConfig& b_to_a, uint32_t latency_ms)
    : ab_(baud, latency_ms, a_to_b), ba_(baud, latency_ms, b_to_a) {
  a_ = std::make_unique<End>(ab_, ba_, "loopback (a)");
  b_ = std::make_unique<End>(ba_, ab_, "loopback (b)");
}

Loopback::~Loopback() = default;
Backend& Loopback::a() { return *a_; }
Backend& Loopback::b() { return *b_; }

void Loopback::advance(uint32_t ms) {
  now_ += ms;
  ab_.advance_to(now_);
  ba_.advance_to(now_);
}

}  // namespace vds::link
