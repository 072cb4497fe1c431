// USB backend: the USB-specific logic against a scripted fake of the
// transfer calls (packetisation, zero-length and short packets, timeouts,
// stalls, disconnects), the link protocol carried over it, the real libusb
// backend failing cleanly when no device is present, and a hardware test
// that runs only with VDS_USB_DEVICE=VID:PID.
#include <gtest/gtest.h>

#include <cstdlib>
#include <deque>
#include <vector>

#include "../conformance/link_test_util.h"
#include "vds/link/usb.h"

namespace {

using namespace vds::link;
using vds::Status;

// One expected call and the device's answer.
struct Step {
  bool clear = false;  // clear_halt instead of a transfer
  uint8_t ep = 0;
  UsbResult result = UsbResult::ok;
  size_t transferred = SIZE_MAX;  // SIZE_MAX: all of it (OUT) / in_data.size() (IN)
  std::vector<uint8_t> in_data;
};

struct Seen {
  bool clear;
  uint8_t ep;
  size_t length;
  std::vector<uint8_t> out_data;
};

class ScriptedUsb : public UsbTransfers {
 public:
  std::deque<Step>* script;
  std::vector<Seen>* seen;
  ScriptedUsb(std::deque<Step>* s, std::vector<Seen>* v) : script(s), seen(v) {}
  UsbResult bulk(uint8_t ep, uint8_t* data, size_t length, size_t* transferred, unsigned) override {
    if (script->empty()) {
      ADD_FAILURE() << "unexpected transfer on endpoint " << int(ep);
      *transferred = 0;
      return UsbResult::error;
    }
    const Step s = script->front();
    script->pop_front();
    EXPECT_FALSE(s.clear);
    EXPECT_EQ(s.ep, ep);
    Seen v{false, ep, length, {}};
    if ((ep & 0x80) == 0 && length != 0) v.out_data.assign(data, data + length);
    seen->push_back(v);
    if (ep & 0x80) {
      const size_t n = std::min(s.in_data.size(), length);
      if (n != 0) std::copy_n(s.in_data.begin(), n, data);
      *transferred = s.transferred == SIZE_MAX ? n : s.transferred;
    } else {
      *transferred = s.transferred == SIZE_MAX ? length : s.transferred;
    }
    return s.result;
  }
  UsbResult clear_halt(uint8_t ep) override {
    seen->push_back({true, ep, 0, {}});
    if (script->empty() || !script->front().clear) {
      ADD_FAILURE() << "unexpected clear_halt";
      return UsbResult::error;
    }
    const Step s = script->front();
    script->pop_front();
    EXPECT_EQ(s.ep, ep);
    return s.result;
  }
};

struct Rig {
  std::deque<Step> script;
  std::vector<Seen> seen;
  std::unique_ptr<UsbBackend> usb;
  explicit Rig(uint16_t mps = 64) {
    UsbEndpoints ep;
    ep.in = 0x81;
    ep.out = 0x02;
    ep.max_packet = mps;
    usb = std::make_unique<UsbBackend>(std::make_unique<ScriptedUsb>(&script, &seen), ep, "usb test", 5);
  }
};

Step out(UsbResult r = UsbResult::ok, size_t n = SIZE_MAX) { return Step{false, 0x02, r, n, {}}; }
Step in(std::vector<uint8_t> d, UsbResult r = UsbResult::ok) { return Step{false, 0x81, r, SIZE_MAX, std::move(d)}; }
Step clear(uint8_t ep, UsbResult r = UsbResult::ok) { return Step{true, ep, r, 0, {}}; }

TEST(LinkUsb, WritesInWholeTransfersWithZeroLengthPacketOnBoundary) {
  Rig r(64);
  std::vector<uint8_t> data(64 * 64 + 10);
  for (size_t i = 0; i < data.size(); ++i) data[i] = static_cast<uint8_t>(i);
  r.script = {out(), out(), out()};  // 4096 bytes, its ZLP, then 10 bytes
  EXPECT_EQ(r.usb->write(data.data(), data.size()), data.size());
  ASSERT_EQ(r.seen.size(), 3u);
  EXPECT_EQ(r.seen[0].length, 4096u);
  EXPECT_EQ(r.seen[1].length, 0u) << "a transfer ending on a packet boundary is closed by a ZLP";
  EXPECT_EQ(r.seen[2].length, 10u);
  std::vector<uint8_t> sent = r.seen[0].out_data;
  sent.insert(sent.end(), r.seen[2].out_data.begin(), r.seen[2].out_data.end());
  EXPECT_EQ(sent, data);
  EXPECT_EQ(r.usb->stats().zlps_sent, 1u);
  // A short transfer needs no ZLP.
  r.seen.clear();
  r.script = {out()};
  EXPECT_EQ(r.usb->write(data.data(), 100), 100u);
  EXPECT_EQ(r.seen.size(), 1u);
  // Exactly one packet: ZLP.
  r.seen.clear();
  r.script = {out(), out()};
  EXPECT_EQ(r.usb->write(data.data(), 64), 64u);
  ASSERT_EQ(r.seen.size(), 2u);
  EXPECT_EQ(r.seen[1].length, 0u);
}

TEST(LinkUsb, TimeoutReturnsWhatWentThrough) {
  Rig r(64);
  std::vector<uint8_t> data(200, 7);
  r.script = {out(UsbResult::timeout, 128)};
  EXPECT_EQ(r.usb->write(data.data(), data.size()), 128u) << "the pump offers the other 72 bytes again";
  EXPECT_EQ(r.usb->stats().timeouts, 1u);
  r.script = {in({}, UsbResult::timeout)};
  uint8_t buf[16];
  EXPECT_EQ(r.usb->read(buf, sizeof buf, 5), 0u);
}

TEST(LinkUsb, ReadsWholePacketsShortAndZeroLength) {
  Rig r(64);
  uint8_t buf[8];
  r.script = {in({1, 2, 3, 4, 5, 6, 7, 8, 9, 10})};
  EXPECT_EQ(r.usb->read(buf, 4, 5), 4u);
  ASSERT_EQ(r.seen.size(), 1u);
  EXPECT_EQ(r.seen[0].length % 64, 0u) << "requests are whole packets, so the device cannot overflow them";
  EXPECT_EQ(r.usb->read(buf, 8, 5), 6u) << "the rest of the short packet, without a new transfer";
  EXPECT_EQ(buf[0], 5);
  EXPECT_EQ(r.seen.size(), 1u);
  EXPECT_EQ(r.usb->stats().short_packets, 1u);
  r.script = {in({})};
  EXPECT_EQ(r.usb->read(buf, 8, 5), 0u);
  EXPECT_EQ(r.usb->stats().zlps_received, 1u);
}

TEST(LinkUsb, StallIsClearedOnceThenAnError) {
  Rig r(64);
  std::vector<uint8_t> data(10, 1);
  r.script = {out(UsbResult::stall, 0), clear(0x02), out()};
  EXPECT_EQ(r.usb->write(data.data(), data.size()), 10u);
  EXPECT_EQ(r.usb->stats().stalls_cleared, 1u);
  r.script = {in({}, UsbResult::stall), clear(0x81)};
  uint8_t buf[8];
  EXPECT_EQ(r.usb->read(buf, sizeof buf, 5), 0u);
  r.script = {in({}, UsbResult::stall)};
  try {
    r.usb->read(buf, sizeof buf, 5);
    FAIL() << "a second stall in a row must fail";
  } catch (const BackendError& e) {
    EXPECT_EQ(e.kind(), BackendError::Kind::stalled);
    EXPECT_NE(std::string(e.what()).find("stall"), std::string::npos);
  }
}

TEST(LinkUsb, DisconnectAndOverflowAreNamedErrors) {
  Rig r(64);
  std::vector<uint8_t> data(10, 1);
  r.script = {out(UsbResult::no_device, 0)};
  try {
    r.usb->write(data.data(), data.size());
    FAIL();
  } catch (const BackendError& e) {
    EXPECT_EQ(e.kind(), BackendError::Kind::disconnected);
    EXPECT_NE(std::string(e.what()).find("usb test: device disconnected"), std::string::npos);
  }
  r.script = {in({}, UsbResult::overflow)};
  uint8_t buf[8];
  try {
    r.usb->read(buf, sizeof buf, 5);
    FAIL();
  } catch (const BackendError& e) {
    EXPECT_EQ(e.kind(), BackendError::Kind::io);
    EXPECT_NE(std::string(e.what()).find("overflow"), std::string::npos);
  }
}

// A device on the far side of the seam: bulk OUT feeds its Link, bulk IN
// takes what its Link sends, in whole packets, with a ZLP when idle; every
// 7th IN transfer times out and every 11th OUT stalls once.
class LinkDevice : public UsbTransfers {
 public:
  explicit LinkDevice(uint32_t* clock) : clock_(clock), ws_((link_workspace_size(device_config(9)) + 7) / 8) {
    vds::Arena a(ws_.data(), ws_.size() * 8);
    EXPECT_EQ(link.init(device_config(9), a), Status::ok);
  }
  UsbResult bulk(uint8_t ep, uint8_t* data, size_t length, size_t* transferred, unsigned) override {
    *transferred = 0;
    if (ep & 0x80) {
      if (++ins_ % 7 == 0) return UsbResult::timeout;
      *transferred = link.transmit(data, length, *clock_);
      return UsbResult::ok;
    }
    if (++outs_ % 11 == 0 && !halted_) {
      halted_ = true;
      return UsbResult::stall;
    }
    if (halted_) return UsbResult::stall;
    link.receive(data, length, *clock_);
    *transferred = length;
    return UsbResult::ok;
  }
  UsbResult clear_halt(uint8_t) override {
    halted_ = false;
    ++clears;
    return UsbResult::ok;
  }
  Link link;
  int clears = 0;

 private:
  uint32_t* clock_;
  std::vector<uint64_t> ws_;
  uint32_t ins_ = 0, outs_ = 0;
  bool halted_ = false;
};

TEST(LinkUsb, CarriesTheLinkProtocolOverTheSeam) {
  uint32_t clock = 0;
  auto dev_owned = std::make_unique<LinkDevice>(&clock);
  LinkDevice* dev = dev_owned.get();
  UsbEndpoints ep;
  UsbBackend usb(std::move(dev_owned), ep, "usb fake", 5);
  const LinkConfig hc = host_config(8);
  std::vector<uint64_t> hw((link_workspace_size(hc) + 7) / 8);
  vds::Arena ha(hw.data(), hw.size() * 8);
  Link host;
  ASSERT_EQ(host.init(hc, ha), Status::ok);
  Pump pump(host, usb);
  linktest::StreamSource src;
  linktest::DeviceReader rd;
  src.seed = rd.check.seed = 5;
  src.total = 256 << 10;
  for (; clock < 100000 && !(rd.check.got == src.total && src.done(host)); ++clock) {
    src.pump(host);
    pump.step(clock, 0);
    rd.pump(dev->link);
  }
  EXPECT_EQ(rd.check.got, src.total);
  EXPECT_TRUE(rd.check.intact);
  EXPECT_GT(dev->clears, 0);
  EXPECT_GT(usb.stats().timeouts, 0u);
  EXPECT_GT(usb.stats().zlps_received, 0u);
}

TEST(LinkUsb, ParsesDeviceSpecs) {
  UsbDeviceSpec s = parse_usb_spec("1209:7764");
  EXPECT_EQ(s.vid, 0x1209);
  EXPECT_EQ(s.pid, 0x7764);
  EXPECT_EQ(s.interface, 0);
  s = parse_usb_spec("cafe:BABE:1:82:02");
  EXPECT_EQ(s.vid, 0xCAFE);
  EXPECT_EQ(s.interface, 1);
  EXPECT_EQ(s.ep_in, 0x82);
  EXPECT_EQ(s.ep_out, 0x02);
  for (const char* bad : {"", "1209", "12345:1", "xyz:1", "1209:7764:1:02:82", "1:2:3:4"}) {
    EXPECT_THROW(parse_usb_spec(bad), BackendError) << bad;
  }
}

// This machine has no USB subsystem: the real backend must start libusb
// and fail with a named error, not crash or hang.
TEST(LinkUsb, RealBackendFailsCleanlyWhenNoDeviceIsPresent) {
  const UsbDeviceSpec spec = parse_usb_spec("1209:0ffe");
  try {
    auto b = open_usb(spec);
    GTEST_SKIP() << "a device 1209:0ffe is attached; nothing to check";
  } catch (const BackendError& e) {
    const std::string m = e.what();
    EXPECT_TRUE(e.kind() == BackendError::Kind::not_found || e.kind() == BackendError::Kind::unavailable)
        << backend_error_kind_name(e.kind());
    EXPECT_NE(m.find("usb 1209:0ffe"), std::string::npos) << m;
    EXPECT_NE(m.find("LIBUSB_ERROR_"), std::string::npos) << "libusb's error name: " << m;
  }
  EXPECT_THROW(open_backend("usb:1209:0ffe", 115200), BackendError);
}

// Hardware: a vds client on a real board (docs/usb.md). Runs only with
// VDS_USB_DEVICE=VID:PID[:IFACE[:EPIN:EPOUT]].
TEST(LinkUsb, HardwareDevice) {
  const char* env = std::getenv("VDS_USB_DEVICE");
  if (env == nullptr || *env == 0)
    GTEST_SKIP() << "SKIPPED: no USB hardware test without a device; set VDS_USB_DEVICE=VID:PID with a vds client "
                    "attached (docs/usb.md)";
  std::unique_ptr<Backend> usb = open_usb(parse_usb_spec(env));
  const LinkConfig hc = host_config(monotonic_ms());
  std::vector<uint64_t> hw((link_workspace_size(hc) + 7) / 8);
  vds::Arena ha(hw.data(), hw.size() * 8);
  Link host;
  ASSERT_EQ(host.init(hc, ha), Status::ok);
  Pump pump(host, *usb);
  linktest::StreamSource src;
  src.seed = 1;
  src.total = 64 << 10;
  const uint32_t start = monotonic_ms();
  while (monotonic_ms() - start < 20000 && !src.done(host)) {
    src.pump(host);
    pump.step(monotonic_ms(), 2);
  }
  EXPECT_TRUE(host.established()) << "no session with the device within 20 s";
  EXPECT_TRUE(src.done(host)) << "the device did not acknowledge 64 KiB within 20 s";
}

}  // namespace
