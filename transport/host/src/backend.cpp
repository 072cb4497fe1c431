// Opening a backend from a --link argument, and the pump that moves bytes
// between a Link and any backend.
#include "vds/link/backend.h"

#include <chrono>

#include "vds/link/fd_backends.h"
#include "vds/link/usb.h"

namespace vds::link {

const char* backend_error_kind_name(BackendError::Kind k) {
  switch (k) {
    case BackendError::Kind::bad_spec: return "bad_spec";
    case BackendError::Kind::unavailable: return "unavailable";
    case BackendError::Kind::not_found: return "not_found";
    case BackendError::Kind::access: return "access";
    case BackendError::Kind::disconnected: return "disconnected";
    case BackendError::Kind::stalled: return "stalled";
    case BackendError::Kind::io: return "io";
  }
  return "?";
}

std::unique_ptr<Backend> open_backend(const std::string& spec, uint32_t baud, bool paced) {
  const uint32_t pace = paced ? baud : 0;  // FdBackend::set_pacing(0): unpaced
  auto rest = [&](size_t n) { return spec.substr(n); };
  if (spec.rfind("pty:", 0) == 0) {
    if (rest(4).empty()) throw BackendError(BackendError::Kind::bad_spec, "pty: needs a path, as in pty:/dev/ttyACM0");
    auto b = open_serial(rest(4), baud);
    b->set_pacing(pace);
    return b;
  }
  if (spec.rfind("tcp:", 0) == 0) {
    const std::string hp = rest(4);
    const size_t c = hp.rfind(':');
    if (c == std::string::npos || c == 0 || c + 1 == hp.size() ||
        hp.find_first_not_of("0123456789", c + 1) != std::string::npos || hp.size() - c - 1 > 5)
      throw BackendError(BackendError::Kind::bad_spec, "tcp: '" + spec + "' is not tcp:HOST:PORT");
    const unsigned long port = std::stoul(hp.substr(c + 1));
    if (port == 0 || port > 65535) throw BackendError(BackendError::Kind::bad_spec, "tcp: port out of range in '" + spec + "'");
    auto b = tcp_connect(hp.substr(0, c), static_cast<uint16_t>(port));
    b->set_pacing(pace);  // an emulated UART behind a socket is not paced by anyone else
    return b;
  }
  if (spec.rfind("tcp-listen:", 0) == 0) {
    const std::string p = rest(11);
    if (p.empty() || p.size() > 5 || p.find_first_not_of("0123456789") != std::string::npos || std::stoul(p) > 65535)
      throw BackendError(BackendError::Kind::bad_spec, "tcp-listen: '" + spec + "' is not tcp-listen:PORT");
    TcpListener l(static_cast<uint16_t>(std::stoul(p)), false);
    auto b = l.accept(-1);
    if (b) b->set_pacing(pace);
    return b;
  }
  if (spec.rfind("usb:", 0) == 0) return open_usb(parse_usb_spec(rest(4)));
  throw BackendError(BackendError::Kind::bad_spec,
                     "'" + spec + "' is not loopback, pty:PATH, tcp:HOST:PORT, tcp-listen:PORT or usb:VID:PID");
}

size_t Pump::step(uint32_t now_ms, int wait_ms) {
  link_.poll(now_ms);
  for (int rounds = 0; rounds < 64; ++rounds) {
    if (out_pos_ == out_len_) {
      const size_t room = backend_.write_room();
      if (room == 0) break;
      out_len_ = link_.transmit(out_.data(), room < out_.size() ? room : out_.size(), now_ms);
      out_pos_ = 0;
      if (out_len_ == 0) break;
    }
    const size_t k = backend_.write(out_.data() + out_pos_, out_len_ - out_pos_);
    out_pos_ += k;
    if (k == 0) break;
  }
  size_t total = 0;
  size_t n = backend_.read(in_.data(), in_.size(), wait_ms);
  for (int rounds = 0; n != 0 && rounds < 64; ++rounds) {
    link_.receive(in_.data(), n, now_ms);
    total += n;
    n = backend_.read(in_.data(), in_.size(), 0);
  }
  if (n != 0) {
    link_.receive(in_.data(), n, now_ms);
    total += n;
  }
  return total;
}

uint32_t monotonic_ms() {
  using namespace std::chrono;
  return static_cast<uint32_t>(duration_cast<milliseconds>(steady_clock::now().time_since_epoch()).count());
}

}  // namespace vds::link
