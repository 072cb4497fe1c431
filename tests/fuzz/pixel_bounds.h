// Shared by the image decoder fuzz harnesses: a display callback that traps
// on a rectangle outside the image and reads every pixel byte it is handed
// (so the sanitizers see a pixel pointer that strays), and stops the decode
// after a bounded number of calls.
#pragma once
#include <cstdint>

#include "vds/image.h"

namespace vds::fuzz {

struct PixelBounds {
  uint32_t width, height;
  uint32_t bytes_per_pixel;  // of the target's pixel format
  uint32_t calls;
};

inline bool check_rect(void* ctx, const PixelRect& r) {
  PixelBounds& b = *static_cast<PixelBounds*>(ctx);
  if (r.w == 0 || r.h == 0 || r.x + r.w > b.width || r.y + r.h > b.height) __builtin_trap();
  volatile uint8_t sink = 0;
  for (int y = 0; y < r.h; ++y)
    for (uint32_t x = 0; x < r.w * b.bytes_per_pixel; ++x) sink = static_cast<uint8_t>(sink + r.pixels[y * r.stride + x]);
  return ++b.calls < 100000;
}

}  // namespace vds::fuzz
