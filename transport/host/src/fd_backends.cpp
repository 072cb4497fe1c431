// Backends over POSIX descriptors: ttys through termios in raw mode
// (POSIX.1 general terminal interface), pseudo-terminal pairs
// (posix_openpt), and TCP sockets.
#include "vds/link/fd_backends.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>

namespace vds::link {

namespace {

std::string errno_text(int e) { return std::string(strerrorname_np(e) ? strerrorname_np(e) : "errno") + " (" + std::strerror(e) + ")"; }

BackendError::Kind kind_of(int e) {
  switch (e) {
    case ENOENT:
    case ENODEV:
    case ENXIO:
    case ECONNREFUSED:
    case EHOSTUNREACH:
    case ENETUNREACH: return BackendError::Kind::not_found;
    case EACCES:
    case EPERM: return BackendError::Kind::access;
    case EIO:
    case EPIPE:
    case ECONNRESET: return BackendError::Kind::disconnected;
    default: return BackendError::Kind::io;
  }
}

void set_nonblocking(int fd) {
  const int fl = fcntl(fd, F_GETFL, 0);
  if (fl >= 0) fcntl(fd, F_SETFL, fl | O_NONBLOCK);
}

}  // namespace

FdBackend::FdBackend(int fd, std::string name) : fd_(fd), name_(std::move(name)) { set_nonblocking(fd_); }

FdBackend::~FdBackend() {
  if (fd_ >= 0) ::close(fd_);
}

void FdBackend::set_pacing(uint32_t baud) {
  bytes_per_s_ = baud / 10;  // a UART byte is 10 bits on the wire
  tokens_milli_ = 0;
  last_us_ = 0;
}

size_t FdBackend::write_room() {
  size_t room = 4096;
  if (queue_limit_ != 0) {
    int queued = 0;
    if (ioctl(fd_, TIOCOUTQ, &queued) != 0 || queued < 0) {
      room = queue_limit_;
    } else {
      room = static_cast<size_t>(queued) >= queue_limit_ ? 0 : queue_limit_ - static_cast<size_t>(queued);
    }
  }
  if (bytes_per_s_ != 0) {
    const uint64_t now_us = static_cast<uint64_t>(
        std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now().time_since_epoch()).count());
    // Bytes/s times microseconds over 1000 is thousandths of a byte.
    if (last_us_ != 0) tokens_milli_ += (now_us - last_us_) * bytes_per_s_ / 1000;
    last_us_ = now_us;
    const uint64_t burst_milli = std::max<uint64_t>(64, bytes_per_s_ / 50) * 1000;
    tokens_milli_ = std::min(tokens_milli_, burst_milli);
    room = std::min<size_t>(room, static_cast<size_t>(tokens_milli_ / 1000));
  }
  return room;
}

size_t FdBackend::write(const uint8_t* data, size_t n) {
  if (n == 0) return 0;
  const ssize_t w = ::write(fd_, data, n);
  if (w >= 0) {
    const uint64_t spent = static_cast<uint64_t>(w) * 1000;
    tokens_milli_ = tokens_milli_ > spent ? tokens_milli_ - spent : 0;
    return static_cast<size_t>(w);
  }
  if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) return 0;
  const int e = errno;
  throw BackendError(kind_of(e), name_ + ": write failed: " + errno_text(e));
}

size_t FdBackend::read(uint8_t* buf, size_t n, int timeout_ms) {
  pollfd p{fd_, POLLIN, 0};
  const int r = ::poll(&p, 1, timeout_ms);
  if (r <= 0) return 0;
  const ssize_t got = ::read(fd_, buf, n);
  if (got > 0) return static_cast<size_t>(got);
  if (got == 0) throw BackendError(BackendError::Kind::disconnected, name_ + ": the peer closed the connection");
  if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) return 0;
  const int e = errno;
  throw BackendError(kind_of(e), name_ + ": read failed: " + errno_text(e));
}

unsigned baud_to_speed(uint32_t baud) {
  switch (baud) {
    case 1200: return B1200;
    case 2400: return B2400;
    case 4800: return B4800;
    case 9600: return B9600;
    case 19200: return B19200;
    case 38400: return B38400;
    case 57600: return B57600;
    case 115200: return B115200;
    case 230400: return B230400;
    case 460800: return B460800;
    case 500000: return B500000;
    case 921600: return B921600;
    case 1000000: return B1000000;
    case 1500000: return B1500000;
    case 2000000: return B2000000;
    case 3000000: return B3000000;
    case 4000000: return B4000000;
    default:
      throw BackendError(BackendError::Kind::bad_spec,
                         "serial: " + std::to_string(baud) + " baud has no termios speed (use 9600..4000000)");
  }
}

std::unique_ptr<FdBackend> open_serial(const std::string& path, uint32_t baud) {
  // A pseudo-terminal has no line rate (the host's pacing is the rate), so
  // it takes any baud, 14,400 for the modem of the VDS paper included; a
  // real port needs one the driver knows.
  speed_t speed = B38400;
  try {
    speed = baud_to_speed(baud);
  } catch (const BackendError&) {
    if (path.rfind("/dev/pts/", 0) != 0) throw;
  }
  const int fd = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    const int e = errno;
    throw BackendError(kind_of(e), "serial " + path + ": cannot open: " + errno_text(e));
  }
  auto b = std::make_unique<FdBackend>(fd, "serial " + path);
  termios t{};
  if (tcgetattr(fd, &t) != 0) {
    const int e = errno;
    throw BackendError(BackendError::Kind::io, "serial " + path + ": not a terminal: " + errno_text(e));
  }
  cfmakeraw(&t);
  t.c_cflag |= CLOCAL | CREAD;
  t.c_cflag &= ~static_cast<tcflag_t>(CRTSCTS | CSTOPB | PARENB);
  t.c_cc[VMIN] = 0;
  t.c_cc[VTIME] = 0;
  if (cfsetispeed(&t, speed) != 0 || cfsetospeed(&t, speed) != 0 || tcsetattr(fd, TCSANOW, &t) != 0) {
    const int e = errno;
    throw BackendError(BackendError::Kind::io, "serial " + path + ": cannot set raw mode at " +
                                                   std::to_string(baud) + " baud: " + errno_text(e));
  }
  tcflush(fd, TCIOFLUSH);
  // Keep about 20 ms of bytes queued in the driver (at least 256).
  b->set_queue_limit(std::max<size_t>(256, baud / 10 / 50));
  return b;
}

PtyPair open_pty_pair() {
  const int m = posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
  if (m < 0) {
    const int e = errno;
    throw BackendError(BackendError::Kind::unavailable, "pty: posix_openpt failed: " + errno_text(e));
  }
  PtyPair p;
  p.master = std::make_unique<FdBackend>(m, "pty master");
  char name[128] = {};
  if (grantpt(m) != 0 || unlockpt(m) != 0 || ptsname_r(m, name, sizeof name) != 0) {
    const int e = errno;
    throw BackendError(BackendError::Kind::io, "pty: cannot unlock the slave: " + errno_text(e));
  }
  p.slave_path = name;
  return p;
}

std::unique_ptr<FdBackend> tcp_connect(const std::string& host, uint16_t port) {
  const std::string where = "tcp " + host + ":" + std::to_string(port);
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* res = nullptr;
  const int g = getaddrinfo(host.c_str(), std::to_string(port).c_str(), &hints, &res);
  if (g != 0) throw BackendError(BackendError::Kind::not_found, where + ": cannot resolve: " + gai_strerror(g));
  int last = ECONNREFUSED;
  for (addrinfo* a = res; a != nullptr; a = a->ai_next) {
    const int fd = ::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC, a->ai_protocol);
    if (fd < 0) {
      last = errno;
      continue;
    }
    if (::connect(fd, a->ai_addr, a->ai_addrlen) == 0) {
      freeaddrinfo(res);
      const int one = 1;
      setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
      return std::make_unique<FdBackend>(fd, where);
    }
    last = errno;
    ::close(fd);
  }
  freeaddrinfo(res);
  throw BackendError(kind_of(last), where + ": cannot connect: " + errno_text(last));
}

TcpListener::TcpListener(uint16_t port, bool loopback_only) {
  fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) {
    const int e = errno;
    throw BackendError(BackendError::Kind::io, "tcp: socket failed: " + errno_text(e));
  }
  const int one = 1;
  setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(loopback_only ? INADDR_LOOPBACK : INADDR_ANY);
  if (::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 || ::listen(fd_, 1) != 0) {
    const int e = errno;
    ::close(fd_);
    fd_ = -1;
    throw BackendError(kind_of(e), "tcp: cannot listen on port " + std::to_string(port) + ": " + errno_text(e));
  }
  socklen_t len = sizeof a;
  getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len);
  port_ = ntohs(a.sin_port);
}

TcpListener::~TcpListener() {
  if (fd_ >= 0) ::close(fd_);
}

std::unique_ptr<FdBackend> TcpListener::accept(int timeout_ms) {
  pollfd p{fd_, POLLIN, 0};
  if (::poll(&p, 1, timeout_ms) <= 0) return nullptr;
  const int c = ::accept4(fd_, nullptr, nullptr, SOCK_CLOEXEC);
  if (c < 0) return nullptr;
  const int one = 1;
  setsockopt(c, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  return std::make_unique<FdBackend>(c, "tcp peer on port " + std::to_string(port_));
}

}  // namespace vds::link
