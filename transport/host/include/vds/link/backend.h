// Host side of the link: one interface for every byte pipe (loopback,
// serial/pty, TCP, USB bulk), the errors they report, and the pump that
// moves bytes between a Link and a backend.
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "vds/link/link.h"

namespace vds::link {

// A backend failure with a stable kind and a message naming the backend,
// the device and the system's own error name.
class BackendError : public std::runtime_error {
 public:
  enum class Kind {
    bad_spec,      // the --link argument cannot be parsed
    unavailable,   // the subsystem itself is missing (no USB stack, no libusb backend)
    not_found,     // no such device, path or host
    access,        // permission denied
    disconnected,  // the peer or device went away
    stalled,       // an endpoint stayed halted after clearing
    io,            // any other system error
  };
  BackendError(Kind kind, const std::string& what) : std::runtime_error(what), kind_(kind) {}
  Kind kind() const { return kind_; }

 private:
  Kind kind_;
};

const char* backend_error_kind_name(BackendError::Kind k);

class Backend {
 public:
  virtual ~Backend() = default;
  // Bytes write() can take now (pacing of a simulated line); a large
  // number for a real device, whose write() takes what the OS accepts.
  virtual size_t write_room() = 0;
  // Writes up to n bytes, never blocking long; returns how many were taken.
  virtual size_t write(const uint8_t* data, size_t n) = 0;
  // Reads what has arrived, waiting up to timeout_ms for the first byte
  // (simulated backends never wait); 0 when nothing came.
  virtual size_t read(uint8_t* buf, size_t n, int timeout_ms) = 0;
  virtual std::string describe() const = 0;
};

// Opens "pty:PATH" (any tty; raw mode at `baud`), "tcp:HOST:PORT" (client),
// "tcp-listen:PORT" (server, waits for one peer) or "usb:VID:PID[:IFACE]"
// (hex ids). "loopback" is not a device: see loopback.h. Serial and TCP
// links are paced at `baud` (10 bits a byte) by the host side unless
// `paced` is false.
std::unique_ptr<Backend> open_backend(const std::string& spec, uint32_t baud, bool paced = true);

// Moves bytes between a Link and a Backend. Bytes the Link produced but the
// backend did not take yet are kept here, so the Link never loses a frame.
class Pump {
 public:
  Pump(Link& link, Backend& backend) : link_(link), backend_(backend) {}
  // Runs the link's timers, sends what the backend can take, and feeds
  // what arrived (waiting up to wait_ms for it). Returns bytes received.
  size_t step(uint32_t now_ms, int wait_ms = 0);

 private:
  Link& link_;
  Backend& backend_;
  std::vector<uint8_t> out_ = std::vector<uint8_t>(4096);
  size_t out_len_ = 0;
  size_t out_pos_ = 0;
  std::vector<uint8_t> in_ = std::vector<uint8_t>(4096);
};

// Milliseconds of a monotonic clock, for the real-time backends.
uint32_t monotonic_ms();

}  // namespace vds::link
