// USB bulk backend. The USB-specific logic (transfers in multiples of the
// endpoint's max packet size, a zero-length packet after a transfer that
// ends on a packet boundary, short and zero-length packets in, timeouts,
// stalls cleared once, disconnects) lives in UsbBackend and talks to the
// device only through UsbTransfers, a seam with one libusb-1.0
// implementation and a scripted fake in the tests.
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "vds/link/backend.h"

namespace vds::link {

// Outcome of one transfer call (libusb's codes, reduced to what the
// backend acts on).
enum class UsbResult { ok, timeout, stall, no_device, overflow, error };
const char* usb_result_name(UsbResult r);

// The seam: the calls UsbBackend makes.
class UsbTransfers {
 public:
  virtual ~UsbTransfers() = default;
  // A synchronous bulk transfer; `*transferred` is set even on timeout.
  virtual UsbResult bulk(uint8_t endpoint, uint8_t* data, size_t length, size_t* transferred,
                         unsigned timeout_ms) = 0;
  virtual UsbResult clear_halt(uint8_t endpoint) = 0;
};

struct UsbEndpoints {
  uint8_t in = 0x81;
  uint8_t out = 0x01;
  uint16_t max_packet = 64;  // wMaxPacketSize of the bulk endpoints (64 full speed, 512 high speed)
};

struct UsbStats {
  uint64_t out_transfers = 0;
  uint64_t in_transfers = 0;
  uint64_t zlps_sent = 0;
  uint64_t zlps_received = 0;
  uint64_t short_packets = 0;
  uint64_t timeouts = 0;
  uint64_t stalls_cleared = 0;
};

class UsbBackend : public Backend {
 public:
  // Transfers of up to 64 packets; each call waits at most timeout_ms.
  UsbBackend(std::unique_ptr<UsbTransfers> t, UsbEndpoints ep, std::string name, unsigned timeout_ms = 20);
  size_t write_room() override { return max_transfer_; }
  size_t write(const uint8_t* data, size_t n) override;
  size_t read(uint8_t* buf, size_t n, int timeout_ms) override;
  std::string describe() const override { return name_; }
  const UsbStats& stats() const { return stats_; }

 private:
  [[noreturn]] void fail(UsbResult r, const char* what);
  bool recover_stall(uint8_t ep);

  std::unique_ptr<UsbTransfers> t_;
  UsbEndpoints ep_;
  std::string name_;
  unsigned timeout_ms_;
  size_t max_transfer_;
  std::vector<uint8_t> stage_;  // bytes read from the device, not yet handed out
  size_t stage_pos_ = 0;
  std::vector<uint8_t> in_buf_;
  uint32_t stall_run_ = 0;
  UsbStats stats_;
};

struct UsbDeviceSpec {
  uint16_t vid = 0;
  uint16_t pid = 0;
  int interface = 0;
  int ep_in = -1;  // -1: the first bulk IN endpoint of the interface
  int ep_out = -1;
};
// "VID:PID[:IFACE[:EPIN:EPOUT]]", numbers in hex (e.g. "1209:7764",
// "1209:7764:1:82:02"). Throws BackendError(bad_spec).
UsbDeviceSpec parse_usb_spec(const std::string& s);
std::string usb_id(const UsbDeviceSpec& s);  // "1209:7764"

// Initialises libusb, opens the device, claims the interface and finds the
// bulk endpoints. Throws BackendError: unavailable when libusb cannot
// start (no USB subsystem), not_found when no such device is attached,
// access when it may not be opened; the message names the VID:PID and
// libusb's error name.
std::unique_ptr<UsbTransfers> open_libusb(const UsbDeviceSpec& spec, UsbEndpoints* found);
std::unique_ptr<Backend> open_usb(const UsbDeviceSpec& spec, unsigned timeout_ms = 20);

}  // namespace vds::link
