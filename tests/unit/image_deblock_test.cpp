// The block-edge smoothing of decoded views (vds/image.h, image_deblock).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "vds/image.h"

namespace {

constexpr int kW = 44, kH = 36, kStride = 48;  // not whole blocks, a stride wider than the plane

double mse(const std::vector<uint8_t>& a, const std::vector<double>& truth) {
  double e = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const double d = a[static_cast<size_t>(y * kStride + x)] - truth[static_cast<size_t>(y * kW + x)];
      e += d * d;
    }
  return e / (kW * kH);
}

TEST(ImageDeblock, DcOnlyBlocksOfASmoothImageComeCloserToIt) {
  // A smooth gradient, then each 8x8 block replaced by its mean rounded to
  // a DC step of 48 (6 levels of the mean): the blocks a low quality makes.
  std::vector<double> truth(kW * kH);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) truth[static_cast<size_t>(y * kW + x)] = 60 + 1.5 * x + 1.1 * y;
  std::vector<uint8_t> plane(kStride * kH, 0xEE);
  for (int by = 0; by < kH; by += 8)
    for (int bx = 0; bx < kW; bx += 8) {
      double sum = 0;
      int n = 0;
      for (int y = by; y < by + 8 && y < kH; ++y)
        for (int x = bx; x < bx + 8 && x < kW; ++x) sum += truth[static_cast<size_t>(y * kW + x)], ++n;
      const int mean = static_cast<int>(std::lround(sum / n / 6) * 6);
      for (int y = by; y < by + 8 && y < kH; ++y)
        for (int x = bx; x < bx + 8 && x < kW; ++x) plane[static_cast<size_t>(y * kStride + x)] = static_cast<uint8_t>(mean);
    }
  const std::vector<uint8_t> blocky = plane;
  vds::image_deblock_plane(plane.data(), kW, kH, kStride, 48);
  EXPECT_LT(mse(plane, truth), 0.5 * mse(blocky, truth));
  // Nothing outside the plane is touched (the stride's padding).
  for (int y = 0; y < kH; ++y)
    for (int x = kW; x < kStride; ++x) EXPECT_EQ(plane[static_cast<size_t>(y * kStride + x)], 0xEE);
  // The steps across block edges shrink: no two neighbours differ by more than a DC level.
  for (int y = 0; y < kH; ++y)
    for (int x = 1; x < kW; ++x)
      EXPECT_LE(std::abs(plane[static_cast<size_t>(y * kStride + x)] - plane[static_cast<size_t>(y * kStride + x - 1)]), 6)
          << x << "," << y;
}

TEST(ImageDeblock, EdgesLargerThanTheQuantisationStayAndFineStepsDoNothing) {
  // A black and white boundary on a block edge is the picture's own edge.
  std::vector<uint8_t> plane(kStride * kH, 0);
  for (int y = 0; y < kH; ++y)
    for (int x = 16; x < kW; ++x) plane[static_cast<size_t>(y * kStride + x)] = 200;
  std::vector<uint8_t> before = plane;
  vds::image_deblock_plane(plane.data(), kW, kH, kStride, 48);
  EXPECT_EQ(plane, before);
  // With a fine quantiser (a DC step under 4: the mean moves in steps
  // under half a level) nothing moves.
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) plane[static_cast<size_t>(y * kStride + x)] = static_cast<uint8_t>((x / 8) * 3 + (y / 8) * 2);
  before = plane;
  vds::image_deblock_plane(plane.data(), kW, kH, kStride, 3);
  EXPECT_EQ(plane, before);
  // A textured side (samples 20 apart) is not flattened: only the two
  // samples next to each edge move.
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x)
      plane[static_cast<size_t>(y * kStride + x)] = static_cast<uint8_t>(100 + (x % 2) * 20 + (x < 8 ? 0 : 6));
  before = plane;
  vds::image_deblock_plane(plane.data(), kW, kH, kStride, 48);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x)
      if (x % 8 != 7 && (x % 8 != 0 || x == 0))
        EXPECT_EQ(plane[static_cast<size_t>(y * kStride + x)], before[static_cast<size_t>(y * kStride + x)]) << x;
  EXPECT_NE(plane[static_cast<size_t>(7)], before[7]);
}

}  // namespace
