// Host image files: PNG write/read round trip, PSNR against a hand-computed
// value, and named errors for bad files.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <string>

#include "jpeg_sample_422.h"
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

// --- Files a user did not make ----------------------------------------------------

namespace {

std::string refusal(const std::vector<uint8_t>& file) {
  try {
    vds::io::decode_image(file.data(), file.size(), "f");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

std::vector<uint8_t> tga(int type, int w, int h, int bits, const std::vector<uint8_t>& pixels, int desc = 0x20) {
  std::vector<uint8_t> f = {0, 0, static_cast<uint8_t>(type), 0, 0, 0, 0, 0, 0, 0, 0, 0,
                            static_cast<uint8_t>(w), static_cast<uint8_t>(w >> 8), static_cast<uint8_t>(h),
                            static_cast<uint8_t>(h >> 8), static_cast<uint8_t>(bits), static_cast<uint8_t>(desc)};
  f.insert(f.end(), pixels.begin(), pixels.end());
  return f;
}

}  // namespace

TEST(ImageIoHostile, SizesBeyondTheLimitAreRefusedBeforeDecoding) {
  EXPECT_EQ(refusal(tga(2, 16384, 16384, 24, std::vector<uint8_t>(100))),
            "f: the TGA declares a 16384x16384 image; the most read is 16384 on a side and 64 Mpixels");
  EXPECT_NE(refusal(tga(2, 4096, 4096, 24, std::vector<uint8_t>(100))).find("but 100 follow its header"), std::string::npos);
  const std::string ppm = "P6\n4096 4096\n255\n";
  EXPECT_NE(refusal(std::vector<uint8_t>(ppm.begin(), ppm.end())).find("follow its header"), std::string::npos);
  EXPECT_NE(refusal({'B', 'M', 0, 0}).find("BMP"), std::string::npos);
  EXPECT_NE(refusal({0xFF, 0xD8, 0xFF, 0xE0, 0, 0}).find("not a readable JPEG"), std::string::npos);
}

TEST(ImageIoHostile, TgaKindsReadAsWritten) {
  // 2x2 true colour, stored bottom row first (descriptor bit 5 clear), BGR.
  const vds::io::Image raw = vds::io::decode_image(
      tga(2, 2, 2, 24, {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12}, 0).data(), 18 + 12, "t");
  EXPECT_EQ(raw.pixels, (std::vector<uint8_t>{9, 8, 7, 12, 11, 10, 3, 2, 1, 6, 5, 4}));
  // The same pixels run-length coded (a run of 2, then 2 raw), top row first.
  const std::vector<uint8_t> rle = tga(10, 2, 2, 24, {0x81, 1, 2, 3, 0x01, 4, 5, 6, 7, 8, 9});
  const vds::io::Image r = vds::io::decode_image(rle.data(), rle.size(), "t");
  EXPECT_EQ(r.pixels, (std::vector<uint8_t>{3, 2, 1, 3, 2, 1, 6, 5, 4, 9, 8, 7}));
  // A run past the last pixel and a file ending inside a run are refused.
  EXPECT_NE(refusal(tga(10, 2, 2, 24, {0x84, 1, 2, 3})).find("run passes the last pixel"), std::string::npos);
  EXPECT_NE(refusal(tga(10, 2, 2, 24, {0x01, 1, 2, 3, 4, 5})).find("ends inside its pixels"), std::string::npos);
}

namespace {

// A Windows BMP: a 54-byte header, then the rows bottom first, each padded
// to 4 bytes (24 bits: B, G, R).
std::vector<uint8_t> bmp(int w, int h, int bits, uint32_t compression, const std::vector<uint8_t>& rows) {
  auto le = [](std::vector<uint8_t>& f, uint32_t v, int n) {
    for (int i = 0; i < n; ++i) f.push_back(static_cast<uint8_t>(v >> (8 * i)));
  };
  std::vector<uint8_t> f = {'B', 'M'};
  le(f, 54 + static_cast<uint32_t>(rows.size()), 4);
  le(f, 0, 4);
  le(f, 54, 4);
  le(f, 40, 4);
  le(f, static_cast<uint32_t>(w), 4);
  le(f, static_cast<uint32_t>(h), 4);
  le(f, 1, 2);
  le(f, static_cast<uint32_t>(bits), 2);
  le(f, compression, 4);
  le(f, static_cast<uint32_t>(rows.size()), 4);
  le(f, 2835, 4);
  le(f, 2835, 4);
  le(f, 0, 4);
  le(f, 0, 4);
  f.insert(f.end(), rows.begin(), rows.end());
  return f;
}

}  // namespace

TEST(ImageIoHostile, BmpReadAsWrittenAndRefusedWhereItLies) {
  // 2x2, 24 bits: the bottom row (1,2,3 4,5,6) first, then the top row.
  const std::vector<uint8_t> rows = {1, 2, 3, 4, 5, 6, 0, 0, 7, 8, 9, 10, 11, 12, 0, 0};
  const std::vector<uint8_t> f = bmp(2, 2, 24, 0, rows);
  const vds::io::Image img = vds::io::decode_image(f.data(), f.size(), "b", 3);
  ASSERT_EQ(img.width, 2);
  ASSERT_EQ(img.height, 2);
  EXPECT_EQ(img.pixels, (std::vector<uint8_t>{9, 8, 7, 12, 11, 10, 3, 2, 1, 6, 5, 4}));
  // Rows missing from the end, a size beyond the limit, run-length coding.
  std::vector<uint8_t> cut = f;
  cut.resize(cut.size() - 3);
  EXPECT_NE(refusal(cut).find("end at byte 70, past the file's 67"), std::string::npos) << refusal(cut);
  EXPECT_NE(refusal(bmp(20000, 20000, 24, 0, rows)).find("the BMP declares a 20000x20000 image"), std::string::npos)
      << refusal(bmp(20000, 20000, 24, 0, rows));
  EXPECT_NE(refusal(bmp(2, 2, 8, 1, rows)).find("BMP"), std::string::npos);
  EXPECT_NE(refusal({'B', 'M', 0, 0}).find("f: a BMP file of 4 bytes"), std::string::npos);
  // Every shorter prefix of the valid file is refused, naming it.
  for (size_t n = 2; n < f.size(); ++n)
    EXPECT_EQ(refusal(std::vector<uint8_t>(f.begin(), f.begin() + static_cast<long>(n))).rfind("f: ", 0), 0u) << "prefix " << n;
}

TEST(ImageIoHostile, DeclaredSizesMustFitTheFile) {
  // A PNG of a few dozen bytes declaring 16384 x 4096 RGBA: 256 MiB of rows.
  std::vector<uint8_t> png = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
  auto chunk = [&](const char* type, std::vector<uint8_t> data) {
    const uint32_t n = static_cast<uint32_t>(data.size());
    for (int k = 3; k >= 0; --k) png.push_back(static_cast<uint8_t>(n >> (8 * k)));
    std::vector<uint8_t> td(type, type + 4);
    td.insert(td.end(), data.begin(), data.end());
    png.insert(png.end(), td.begin(), td.end());
    uint32_t crc = 0xFFFFFFFFu;  // the PNG CRC (ISO 3309)
    for (uint8_t b : td) {
      crc ^= b;
      for (int i = 0; i < 8; ++i) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
    }
    crc ^= 0xFFFFFFFFu;
    for (int k = 3; k >= 0; --k) png.push_back(static_cast<uint8_t>(crc >> (8 * k)));
  };
  chunk("IHDR", {0, 0, 0x40, 0, 0, 0, 0x10, 0, 8, 6, 0, 0, 0});
  chunk("IDAT", {0x78, 0x9C, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01});  // zlib of nothing
  chunk("IEND", {});
  EXPECT_NE(refusal(png).find("f: the PNG declares 16384x4096 pixels, more than its"), std::string::npos) << refusal(png);
  // PNM: a size of more than 9 digits, and a magic not followed by whitespace.
  const std::string long_field = "P5 0000000016 16 255\n";
  EXPECT_NE(refusal(std::vector<uint8_t>(long_field.begin(), long_field.end())).find("more than 9 digits"), std::string::npos);
  const std::string glued = "P516 16 255\n";
  EXPECT_NE(refusal(std::vector<uint8_t>(glued.begin(), glued.end())).find("not a binary PNM"), std::string::npos);
}

TEST(ImageIoHostile, EveryPrefixOfAPictureIsRefused) {
  std::vector<std::vector<uint8_t>> files;
  files.push_back(tga(2, 2, 2, 24, {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12}));
  files.push_back(tga(10, 2, 2, 24, {0x81, 1, 2, 3, 0x01, 4, 5, 6, 7, 8, 9}));
  const std::string pnm = "P6\n2 2\n255\n" + std::string(12, '\x40');
  files.emplace_back(pnm.begin(), pnm.end());
  {
    vds::io::Image img(5, 3, 3);
    for (size_t i = 0; i < img.pixels.size(); ++i) img.pixels[i] = static_cast<uint8_t>(i * 17);
    const std::string path = ::testing::TempDir() + "prefix.png";
    vds::io::save_png(path, img);
    std::ifstream f(path, std::ios::binary);
    files.emplace_back((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  }
  files.emplace_back(vds::test::kJpeg422, vds::test::kJpeg422 + sizeof vds::test::kJpeg422);
  for (size_t k = 0; k < files.size(); ++k) {
    const std::vector<uint8_t>& f = files[k];
    EXPECT_EQ(refusal(f), "") << "file " << k;
    for (size_t n = 0; n < f.size(); ++n)
      EXPECT_NE(refusal(std::vector<uint8_t>(f.begin(), f.begin() + static_cast<std::ptrdiff_t>(n))), "")
          << "file " << k << " prefix " << n;
  }
}
