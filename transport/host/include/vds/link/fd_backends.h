// Backends over file descriptors: a tty (serial port or pseudo-terminal)
// in raw mode at a chosen baud, a pseudo-terminal pair, and TCP.
#pragma once
#include <cstdint>
#include <memory>
#include <string>

#include "vds/link/backend.h"

namespace vds::link {

// Non-blocking reads and writes on one descriptor (closed on destruction).
class FdBackend : public Backend {
 public:
  FdBackend(int fd, std::string name);
  ~FdBackend() override;
  FdBackend(const FdBackend&) = delete;
  FdBackend& operator=(const FdBackend&) = delete;
  // With a queue limit set (serial ports), only as much as keeps the
  // driver's output queue below it, so a retransmission never waits behind
  // seconds of queued bytes; otherwise 4096.
  // With a line rate set, also no more than the bytes a UART at that rate
  // would have sent since the last write (a token bucket holding at most
  // 20 ms of bytes): a pseudo-terminal or a socket to an emulator has no
  // baud rate of its own, and without pacing the sender fills the kernel's
  // buffers, the round trip grows with them, and retransmissions pile up.
  size_t write_room() override;
  void set_queue_limit(size_t bytes) { queue_limit_ = bytes; }
  void set_pacing(uint32_t baud);
  size_t write(const uint8_t* data, size_t n) override;
  size_t read(uint8_t* buf, size_t n, int timeout_ms) override;
  std::string describe() const override { return name_; }
  int fd() const { return fd_; }

 private:
  int fd_;
  std::string name_;
  size_t queue_limit_ = 0;
  uint32_t bytes_per_s_ = 0;  // 0: not paced
  uint64_t tokens_milli_ = 0;  // thousandths of a byte the line may still take
  uint64_t last_us_ = 0;
};

// Opens a tty and puts it in raw mode (cfmakeraw: no echo, no line
// editing, no CR/LF translation, 8 data bits) at `baud`. Throws
// BackendError naming the path (not_found, access, bad_spec for a baud the
// system has no constant for, io when it is not a terminal). A
// pseudo-terminal (/dev/pts/N) takes any baud: only the pacing sets its rate.
std::unique_ptr<FdBackend> open_serial(const std::string& path, uint32_t baud);

// The termios speed constant for a baud rate; throws BackendError(bad_spec).
unsigned baud_to_speed(uint32_t baud);

// A pseudo-terminal pair: the master end as a backend, and the path of the
// slave end (open it with open_serial, which configures termios).
struct PtyPair {
  std::unique_ptr<FdBackend> master;
  std::string slave_path;
};
PtyPair open_pty_pair();

// TCP client (e.g. to QEMU's `-serial tcp::PORT,server`).
std::unique_ptr<FdBackend> tcp_connect(const std::string& host, uint16_t port);

// TCP server accepting one peer at a time.
class TcpListener {
 public:
  explicit TcpListener(uint16_t port, bool loopback_only = true);  // 0: any free port
  ~TcpListener();
  TcpListener(const TcpListener&) = delete;
  TcpListener& operator=(const TcpListener&) = delete;
  uint16_t port() const { return port_; }
  // The next peer, or nullptr if none came within timeout_ms (-1: wait).
  std::unique_ptr<FdBackend> accept(int timeout_ms);

 private:
  int fd_ = -1;
  uint16_t port_ = 0;
};

}  // namespace vds::link
