// vds client library, private: delivery of decoded MCUs to an ImageTarget
// (colour conversion, clipping, rectangles and bands), shared by the vds
// image decoder and the JPEG decoder.
#pragma once
#include <cstddef>
#include <cstdint>

#include "vds/image.h"

namespace vds::detail {

// One decoded MCU of Y'CbCr samples.
struct McuSamples {
  const uint8_t* y;
  ptrdiff_t y_stride;
  const uint8_t* cb;  // null for grey
  const uint8_t* cr;
  ptrdiff_t c_stride;
  uint8_t sub_x;  // chroma subsampling as a shift: 1 = half resolution
  uint8_t sub_y;
};

// The geometry of an image as the output stage sees it.
struct OutputGeometry {
  int width, height;
  int mcu_w, mcu_h;  // MCU size in luma pixels
  int components;    // 1 or 3
  int sub_x, sub_y;  // chroma subsampling shifts
  int chroma_width() const { return (width + (1 << sub_x) - 1) >> sub_x; }
  int chroma_height() const { return (height + (1 << sub_y) - 1) >> sub_y; }
};

// invalid_argument unless the target suits an image of this geometry (see
// ImageTarget). `residual` requires a source of prediction.
Status check_target(const ImageTarget& t, const OutputGeometry& g, bool residual);

// Converts the top-left w x h pixels of an MCU to packed pixels at dst.
void mcu_to_packed(PixelFormat f, const McuSamples& s, int w, int h, uint8_t* dst, ptrdiff_t dst_stride);

// Delivers the MCU whose top-left luma pixel is (x0, y0) to a packed
// target (frame, rects or bands); `scratch` holds one MCU of packed pixels.
// `row_end` is true for the last MCU of an MCU row (a band is emitted then).
// aborted if a callback returned false.
Status deliver_packed(const ImageTarget& t, const OutputGeometry& g, const McuSamples& s, int x0, int y0,
                      bool row_end, uint8_t* scratch);

// Emits the band of the MCU row starting at y0 (bands targets), for MCU
// rows that end with an MCU that was not decoded (region images).
Status emit_band(const ImageTarget& t, const OutputGeometry& g, int y0);

}  // namespace vds::detail
