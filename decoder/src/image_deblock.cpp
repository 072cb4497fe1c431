// vds client library: smoothing the block edges of a decoded image
// (vds/image.h, image_deblock).
#include <cstdint>

#include "vds/image.h"

namespace vds {

namespace {

// d * k / 16, rounded half away from zero.
inline int32_t sixteenths(int32_t d, int32_t k) { return (d * k + (d >= 0 ? 8 : -8)) / 16; }

inline uint8_t clamp8(int32_t v) { return static_cast<uint8_t>(v < 0 ? 0 : (v > 255 ? 255 : v)); }

// One edge: p[-4 .. -1] on one side, p[0 .. 3] on the other, `step`
// bytes apart. A step across the edge smaller than `limit`, with the
// samples next to it on each side within `limit` of each other, is taken
// for quantisation: where both sides are flat (within limit / 2) the
// eight samples become a ramp between the two sides, else the two next to
// the edge move a quarter of the step towards each other.
inline void edge(uint8_t* p, ptrdiff_t step, int32_t limit) {
  const int32_t p3 = p[-4 * step], p2 = p[-3 * step], p1 = p[-2 * step], p0 = p[-step];
  const int32_t q0 = p[0], q1 = p[step], q2 = p[2 * step], q3 = p[3 * step];
  const int32_t d = q0 - p0;
  if (d == 0 || d >= limit || -d >= limit) return;
  const auto near = [](int32_t a, int32_t b, int32_t t) { return a - b < t && b - a < t; };
  if (!near(p1, p0, limit + 1) || !near(q1, q0, limit + 1)) return;
  const int32_t flat = limit / 2 + 1;
  if (near(p3, p0, flat) && near(p2, p0, flat) && near(q3, q0, flat) && near(q2, q0, flat)) {
    p[-4 * step] = clamp8(p3 + sixteenths(d, 1));
    p[-3 * step] = clamp8(p2 + sixteenths(d, 3));
    p[-2 * step] = clamp8(p1 + sixteenths(d, 5));
    p[-step] = clamp8(p0 + sixteenths(d, 7));
    p[0] = clamp8(q0 - sixteenths(d, 7));
    p[step] = clamp8(q1 - sixteenths(d, 5));
    p[2 * step] = clamp8(q2 - sixteenths(d, 3));
    p[3 * step] = clamp8(q3 - sixteenths(d, 1));
  } else {
    p[-step] = clamp8(p0 + sixteenths(d, 4));
    p[0] = clamp8(q0 - sixteenths(d, 4));
  }
}

}  // namespace

void image_deblock_plane(uint8_t* plane, int width, int height, ptrdiff_t stride, int dc_step) {
  // The mean of a block moves in steps of dc_step / 8 (the DC basis is
  // 1/8): a step across an edge of up to four of those is taken for
  // quantisation (two and three smoothed less: 0.1 dB less on the
  // walkthroughs of docs/walkthrough.md).
  const int32_t limit = 4 * ((dc_step + 4) / 8);
  if (plane == nullptr || limit < 2) return;
  // Edges between 8x8 blocks, the columns first, then the rows.
  for (int x = 8; x + 4 <= width; x += 8)
    for (int y = 0; y < height; ++y) edge(plane + y * stride + x, 1, limit);
  for (int y = 8; y + 4 <= height; y += 8)
    for (int x = 0; x < width; ++x) edge(plane + y * stride + x, stride, limit);
}

void image_deblock(const ImageHeader& h, const ImageTarget& planes) {
  if (!planes.planar) return;
  uint16_t zz[64];
  for (int c = 0; c < h.components(); ++c) {
    image_quant_table(c == 0 ? h.quant_luma : h.quant_chroma, h.slope, c > 0, zz);
    image_deblock_plane(planes.data[c], c == 0 ? h.width : h.chroma_width(), c == 0 ? h.height : h.chroma_height(),
                        planes.stride[c], zz[0]);
  }
}

}  // namespace vds
