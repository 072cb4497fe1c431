// USB bulk pipe logic over the UsbTransfers seam (USB 2.0 spec 5.8: bulk
// transfers end with a short or zero-length packet).
#include <algorithm>

#include "vds/link/usb.h"

namespace vds::link {

namespace {
constexpr size_t kPacketsPerTransfer = 64;
}

const char* usb_result_name(UsbResult r) {
  switch (r) {
    case UsbResult::ok: return "ok";
    case UsbResult::timeout: return "timeout";
    case UsbResult::stall: return "stall";
    case UsbResult::no_device: return "no_device";
    case UsbResult::overflow: return "overflow";
    case UsbResult::error: return "error";
  }
  return "?";
}

UsbBackend::UsbBackend(std::unique_ptr<UsbTransfers> t, UsbEndpoints ep, std::string name, unsigned timeout_ms)
    : t_(std::move(t)), ep_(ep), name_(std::move(name)), timeout_ms_(timeout_ms) {
  if (ep_.max_packet == 0) ep_.max_packet = 64;
  max_transfer_ = static_cast<size_t>(ep_.max_packet) * kPacketsPerTransfer;
  in_buf_.resize(max_transfer_);
}

void UsbBackend::fail(UsbResult r, const char* what) {
  const std::string msg = name_ + ": " + what + ": " + usb_result_name(r);
  if (r == UsbResult::no_device) throw BackendError(BackendError::Kind::disconnected, name_ + ": device disconnected");
  if (r == UsbResult::stall) throw BackendError(BackendError::Kind::stalled, msg + " (endpoint still halted after clearing)");
  throw BackendError(BackendError::Kind::io, msg);
}

// A halted endpoint is cleared once; a second stall in a row is an error.
bool UsbBackend::recover_stall(uint8_t ep) {
  if (++stall_run_ > 1) return false;
  const UsbResult r = t_->clear_halt(ep);
  if (r == UsbResult::no_device) fail(r, "clear halt");
  if (r != UsbResult::ok) return false;
  ++stats_.stalls_cleared;
  return true;
}

size_t UsbBackend::write(const uint8_t* data, size_t n) {
  size_t done = 0;
  while (done < n) {
    const size_t chunk = std::min(n - done, max_transfer_);
    size_t got = 0;
    ++stats_.out_transfers;
    const UsbResult r = t_->bulk(ep_.out, const_cast<uint8_t*>(data + done), chunk, &got, timeout_ms_);
    done += std::min(got, chunk);
    if (r == UsbResult::ok) {
      stall_run_ = 0;
      // A transfer ending exactly on a packet boundary is followed by a
      // zero-length packet so the device knows it has ended.
      if (got == chunk && chunk % ep_.max_packet == 0) {
        size_t z = 0;
        ++stats_.zlps_sent;
        const UsbResult zr = t_->bulk(ep_.out, nullptr, 0, &z, timeout_ms_);
        if (zr == UsbResult::stall) {
          if (!recover_stall(ep_.out)) fail(zr, "bulk OUT");
        } else if (zr == UsbResult::no_device || zr == UsbResult::error || zr == UsbResult::overflow) {
          fail(zr, "bulk OUT");
        }
      }
      continue;
    }
    if (r == UsbResult::timeout) {
      ++stats_.timeouts;
      break;  // the pump keeps the rest and offers it again
    }
    if (r == UsbResult::stall) {
      if (!recover_stall(ep_.out)) fail(r, "bulk OUT");
      continue;
    }
    fail(r, "bulk OUT");
  }
  return done;
}

size_t UsbBackend::read(uint8_t* buf, size_t n, int timeout_ms) {
  if (stage_pos_ == stage_.size()) {
    stage_.clear();
    stage_pos_ = 0;
    // Always ask for whole packets: a device may send up to the request,
    // and a request that is not a multiple of the packet size can overflow.
    size_t got = 0;
    ++stats_.in_transfers;
    const unsigned wait = timeout_ms < 0 ? 0u : static_cast<unsigned>(timeout_ms);
    const UsbResult r = t_->bulk(ep_.in, in_buf_.data(), in_buf_.size(), &got, wait == 0 ? 1 : wait);
    got = std::min(got, in_buf_.size());
    if (r == UsbResult::ok) {
      stall_run_ = 0;
      if (got == 0) ++stats_.zlps_received;
      else if (got % ep_.max_packet != 0) ++stats_.short_packets;
    } else if (r == UsbResult::timeout) {
      ++stats_.timeouts;
    } else if (r == UsbResult::stall) {
      if (!recover_stall(ep_.in)) fail(r, "bulk IN");
      return 0;
    } else if (r == UsbResult::overflow) {
      fail(r, "bulk IN (device sent more than requested)");
    } else {
      fail(r, "bulk IN");
    }
    stage_.assign(in_buf_.begin(), in_buf_.begin() + static_cast<std::ptrdiff_t>(got));
  }
  const size_t k = std::min(n, stage_.size() - stage_pos_);
  std::copy_n(stage_.begin() + static_cast<std::ptrdiff_t>(stage_pos_), k, buf);
  stage_pos_ += k;
  return k;
}

UsbDeviceSpec parse_usb_spec(const std::string& s) {
  UsbDeviceSpec d;
  std::vector<std::string> parts;
  size_t at = 0;
  for (;;) {
    const size_t c = s.find(':', at);
    parts.push_back(s.substr(at, c == std::string::npos ? std::string::npos : c - at));
    if (c == std::string::npos) break;
    at = c + 1;
  }
  auto hex = [&](const std::string& p, unsigned long max) -> unsigned long {
    if (p.empty() || p.size() > 4 || p.find_first_not_of("0123456789abcdefABCDEF") != std::string::npos)
      throw BackendError(BackendError::Kind::bad_spec, "usb: '" + s + "' is not VID:PID[:IFACE[:EPIN:EPOUT]] in hex");
    const unsigned long v = std::stoul(p, nullptr, 16);
    if (v > max) throw BackendError(BackendError::Kind::bad_spec, "usb: '" + p + "' out of range in '" + s + "'");
    return v;
  };
  if (parts.size() != 2 && parts.size() != 3 && parts.size() != 5)
    throw BackendError(BackendError::Kind::bad_spec, "usb: '" + s + "' is not VID:PID[:IFACE[:EPIN:EPOUT]] in hex");
  d.vid = static_cast<uint16_t>(hex(parts[0], 0xFFFF));
  d.pid = static_cast<uint16_t>(hex(parts[1], 0xFFFF));
  if (parts.size() >= 3) d.interface = static_cast<int>(hex(parts[2], 0xFF));
  if (parts.size() == 5) {
    d.ep_in = static_cast<int>(hex(parts[3], 0xFF));
    d.ep_out = static_cast<int>(hex(parts[4], 0xFF));
    if ((d.ep_in & 0x80) == 0 || (d.ep_out & 0x80) != 0)
      throw BackendError(BackendError::Kind::bad_spec, "usb: IN endpoint must have bit 7 set, OUT clear, in '" + s + "'");
  }
  return d;
}

std::string usb_id(const UsbDeviceSpec& s) {
  char b[16];
  std::snprintf(b, sizeof b, "%04x:%04x", s.vid, s.pid);
  return b;
}

std::unique_ptr<Backend> open_usb(const UsbDeviceSpec& spec, unsigned timeout_ms) {
  UsbEndpoints ep;
  auto t = open_libusb(spec, &ep);
  return std::make_unique<UsbBackend>(std::move(t), ep, "usb " + usb_id(spec), timeout_ms);
}

}  // namespace vds::link
