// The libusb-1.0 side of the USB seam: context, device by VID:PID,
// interface claim, endpoint discovery, synchronous bulk transfers.
#include <libusb.h>

#include <cstdio>

#include "vds/link/usb.h"

namespace vds::link {

namespace {

std::string libusb_text(int r) {
  return std::string(libusb_error_name(r)) + " (" + libusb_strerror(static_cast<libusb_error>(r)) + ")";
}

UsbResult map(int r) {
  switch (r) {
    case LIBUSB_SUCCESS: return UsbResult::ok;
    case LIBUSB_ERROR_TIMEOUT: return UsbResult::timeout;
    case LIBUSB_ERROR_PIPE: return UsbResult::stall;
    case LIBUSB_ERROR_NO_DEVICE: return UsbResult::no_device;
    case LIBUSB_ERROR_OVERFLOW: return UsbResult::overflow;
    default: return UsbResult::error;
  }
}

class LibusbTransfers : public UsbTransfers {
 public:
  LibusbTransfers(libusb_context* ctx, libusb_device_handle* h, int iface) : ctx_(ctx), h_(h), iface_(iface) {}
  ~LibusbTransfers() override {
    libusb_release_interface(h_, iface_);
    libusb_close(h_);
    libusb_exit(ctx_);
  }
  UsbResult bulk(uint8_t ep, uint8_t* data, size_t length, size_t* transferred, unsigned timeout_ms) override {
    int got = 0;
    const int r = libusb_bulk_transfer(h_, ep, data, static_cast<int>(length), &got, timeout_ms);
    *transferred = got > 0 ? static_cast<size_t>(got) : 0;
    return map(r);
  }
  UsbResult clear_halt(uint8_t ep) override { return map(libusb_clear_halt(h_, ep)); }

 private:
  libusb_context* ctx_;
  libusb_device_handle* h_;
  int iface_;
};

}  // namespace

std::unique_ptr<UsbTransfers> open_libusb(const UsbDeviceSpec& spec, UsbEndpoints* found) {
  const std::string id = "usb " + usb_id(spec);
  libusb_context* ctx = nullptr;
  int r = libusb_init(&ctx);
  if (r < 0)
    throw BackendError(BackendError::Kind::unavailable,
                       id + ": libusb_init failed: " + libusb_text(r) + "; this machine has no usable USB subsystem");
  libusb_device** list = nullptr;
  const ssize_t count = libusb_get_device_list(ctx, &list);
  if (count < 0) {
    libusb_exit(ctx);
    throw BackendError(BackendError::Kind::unavailable,
                       id + ": cannot list USB devices: " + libusb_text(static_cast<int>(count)));
  }
  libusb_device* dev = nullptr;
  for (ssize_t i = 0; i < count; ++i) {
    libusb_device_descriptor d{};
    if (libusb_get_device_descriptor(list[i], &d) == 0 && d.idVendor == spec.vid && d.idProduct == spec.pid) {
      dev = libusb_ref_device(list[i]);
      break;
    }
  }
  libusb_free_device_list(list, 1);
  if (dev == nullptr) {
    libusb_exit(ctx);
    throw BackendError(BackendError::Kind::not_found, id + ": no such device (LIBUSB_ERROR_NOT_FOUND; " +
                                                          std::to_string(count) + " USB devices present)");
  }
  UsbEndpoints ep;
  libusb_config_descriptor* cfg = nullptr;
  bool have_in = spec.ep_in >= 0, have_out = spec.ep_out >= 0;
  if (have_in) ep.in = static_cast<uint8_t>(spec.ep_in);
  if (have_out) ep.out = static_cast<uint8_t>(spec.ep_out);
  if (libusb_get_active_config_descriptor(dev, &cfg) == 0) {
    if (spec.interface < cfg->bNumInterfaces && cfg->interface[spec.interface].num_altsetting > 0) {
      const libusb_interface_descriptor& alt = cfg->interface[spec.interface].altsetting[0];
      for (int i = 0; i < alt.bNumEndpoints; ++i) {
        const libusb_endpoint_descriptor& e = alt.endpoint[i];
        if ((e.bmAttributes & LIBUSB_TRANSFER_TYPE_MASK) != LIBUSB_TRANSFER_TYPE_BULK) continue;
        const bool in = (e.bEndpointAddress & LIBUSB_ENDPOINT_IN) != 0;
        if (in && !have_in) {
          ep.in = e.bEndpointAddress;
          have_in = true;
        } else if (!in && !have_out) {
          ep.out = e.bEndpointAddress;
          have_out = true;
        }
        if (e.bEndpointAddress == ep.in || e.bEndpointAddress == ep.out) ep.max_packet = e.wMaxPacketSize & 0x7FF;
      }
    }
    libusb_free_config_descriptor(cfg);
  }
  if (!have_in || !have_out) {
    libusb_unref_device(dev);
    libusb_exit(ctx);
    throw BackendError(BackendError::Kind::not_found,
                       id + ": interface " + std::to_string(spec.interface) + " has no bulk IN/OUT endpoint pair");
  }
  libusb_device_handle* h = nullptr;
  r = libusb_open(dev, &h);
  libusb_unref_device(dev);
  if (r < 0) {
    libusb_exit(ctx);
    throw BackendError(r == LIBUSB_ERROR_ACCESS ? BackendError::Kind::access : BackendError::Kind::io,
                       id + ": cannot open: " + libusb_text(r));
  }
  libusb_set_auto_detach_kernel_driver(h, 1);
  r = libusb_claim_interface(h, spec.interface);
  if (r < 0) {
    libusb_close(h);
    libusb_exit(ctx);
    throw BackendError(r == LIBUSB_ERROR_BUSY ? BackendError::Kind::access : BackendError::Kind::io,
                       id + ": cannot claim interface " + std::to_string(spec.interface) + ": " + libusb_text(r));
  }
  *found = ep;
  return std::make_unique<LibusbTransfers>(ctx, h, spec.interface);
}

}  // namespace vds::link
