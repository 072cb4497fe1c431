// A renderer band sink (vds::BandSink) that folds every row of a frame's
// bands into a CRC-32C: what the firmware prints to compare boards.
#pragma once
#include <cstdint>

#include "vds/crc32c.h"
#include "vds/render.h"

namespace vds::fw {

// ctx: the uint32_t CRC, 0 before the frame.
inline bool crc_band(void* ctx, const Band& b) {
  auto* crc = static_cast<uint32_t*>(ctx);
  const uint32_t row_bytes = uint32_t{b.width} * static_cast<uint32_t>(bytes_per_pixel(b.format));
  for (uint32_t y = 0; y < b.height; ++y) *crc = crc32c_update(*crc, b.pixels + y * b.stride, row_bytes);
  return true;
}

}  // namespace vds::fw
