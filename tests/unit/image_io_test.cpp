// Host image files: PNG write/read round trip, PSNR against a hand-computed
// value, and named errors for bad files.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "vds/enc/image_io.h"
#include "vds/enc/stream_writer.h"

namespace {

using vds::enc::Image;

TEST(ImageIo, PngRoundTripIsLossless) {
  for (int c : {1, 3, 4}) {
    Image img(37, 21, c);
    for (size_t i = 0; i < img.pixels.size(); ++i) img.pixels[i] = static_cast<uint8_t>(i * 31 + c);
    const std::string path = std::string(VDS_TEST_TMP) + "/rt" + std::to_string(c) + ".png";
    vds::enc::save_png(path, img);
    const Image back = vds::enc::load_image(path);
    EXPECT_EQ(back.width, 37);
    EXPECT_EQ(back.height, 21);
    EXPECT_EQ(back.channels, c);
    EXPECT_EQ(back.pixels, img.pixels);
  }
}

TEST(ImageIo, PsnrOfAKnownError) {
  Image a(4, 4, 1), b(4, 4, 1);
  EXPECT_TRUE(std::isinf(vds::enc::psnr(a, b)));
  b.pixels[0] = 16;  // MSE = 256 / 16 = 16
  EXPECT_DOUBLE_EQ(vds::enc::mse(a, b), 16.0);
  EXPECT_NEAR(vds::enc::psnr(a, b), 10.0 * std::log10(255.0 * 255.0 / 16.0), 1e-12);
  Image c(4, 3, 1);
  EXPECT_THROW(vds::enc::psnr(a, c), std::invalid_argument);
}

TEST(ImageIo, ErrorsNameTheFile) {
  const std::string missing = std::string(VDS_TEST_TMP) + "/no-such.png";
  try {
    vds::enc::load_image(missing);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos);
  }
  const std::string junk = std::string(VDS_TEST_TMP) + "/junk.png";
  const uint8_t bytes[] = {'n', 'o', 't', ' ', 'p', 'n', 'g'};
  vds::enc::write_file(junk, bytes);
  EXPECT_THROW(vds::enc::load_image(junk), std::runtime_error);
}

TEST(ImageIo, SideBySide) {
  Image a(2, 2, 3), b(3, 1, 3);
  std::fill(a.pixels.begin(), a.pixels.end(), 10);
  std::fill(b.pixels.begin(), b.pixels.end(), 200);
  const Image s = vds::enc::side_by_side({&a, &b}, 1);
  EXPECT_EQ(s.width, 6);
  EXPECT_EQ(s.height, 2);
  EXPECT_EQ(s.at(0, 1, 0), 10);
  EXPECT_EQ(s.at(2, 0, 0), 128);
  EXPECT_EQ(s.at(3, 0, 2), 200);
  EXPECT_EQ(s.at(3, 1, 2), 128);
}

}  // namespace
