// The client's baseline JPEG decoder without the libjpeg-turbo tools: a
// fixed small JPEG (cjpeg -quality 70 -sample 2x1 -optimize of a 24x18
// picture, kept as bytes) checks the API contract: header info, workspace
// and target refusals, pieces of every size, restarts, latched errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

#include "vds/crc32c.h"
#include "vds/jpeg.h"
#include "jpeg_sample_422.h"

namespace {

using vds::JpegDecoder;
using vds::PixelFormat;
using vds::Status;

using vds::test::kJpeg422;
const std::vector<uint8_t> kFile(kJpeg422, kJpeg422 + sizeof kJpeg422);
constexpr uint32_t kPinnedCrc = 0x2789A1FAu;

struct Decoder {
  std::vector<uint8_t> ws = std::vector<uint8_t>(JpegDecoder::kWorkspaceBytes);
  vds::Arena arena{ws.data(), ws.size()};
  JpegDecoder dec;
  Decoder() { EXPECT_EQ(dec.init(arena), Status::ok); }
};

std::vector<uint8_t> rgb_whole() {
  Decoder d;
  std::vector<uint8_t> px(24 * 18 * 3);
  EXPECT_EQ(d.dec.decode(kFile.data(), kFile.size(), vds::ImageTarget::frame(PixelFormat::rgb888, px.data(), 72)),
            Status::ok);
  return px;
}

TEST(ImageJpeg, PeekInfo) {
  vds::JpegInfo info;
  ASSERT_EQ(vds::jpeg_peek_info(kFile.data(), kFile.size(), &info), Status::ok);
  EXPECT_EQ(info.width, 24);
  EXPECT_EQ(info.height, 18);
  EXPECT_EQ(info.components, 3);
  EXPECT_EQ(info.sub_x, 1);  // 4:2:2
  EXPECT_EQ(info.sub_y, 0);
  EXPECT_EQ(info.chroma_width(), 12);
  EXPECT_EQ(info.chroma_height(), 18);
  EXPECT_EQ(vds::jpeg_peek_info(kFile.data(), 100, &info), Status::truncated);
  const uint8_t png[] = {0x89, 'P', 'N', 'G'};
  EXPECT_EQ(vds::jpeg_peek_info(png, sizeof png, &info), Status::malformed);
}

TEST(ImageJpeg, PinnedOutput) {
  // The decoded pixels are pinned: any change to the decoder, the IDCT or
  // the colour conversion shows here (and in JpegConformance against
  // libjpeg-turbo when its tools are installed).
  const std::vector<uint8_t> px = rgb_whole();
  EXPECT_EQ(vds::crc32c(px.data(), px.size()), kPinnedCrc);
}

TEST(ImageJpeg, WorkspaceAndTargetsAreChecked) {
  std::vector<uint8_t> small(JpegDecoder::kWorkspaceBytes - 200);
  vds::Arena a(small.data(), small.size());
  JpegDecoder dec;
  EXPECT_EQ(dec.init(a), Status::workspace_too_small);
  Decoder d;
  std::vector<uint8_t> px(24 * 18 * 3 + 2);
  // Stride too small for a 24-pixel row: refused when the frame header arrives.
  EXPECT_EQ(d.dec.decode(kFile.data(), kFile.size(), vds::ImageTarget::frame(PixelFormat::rgb888, px.data(), 71)),
            Status::invalid_argument);
  EXPECT_NE(std::string(d.dec.error_detail()), "");
  // RGB565 needs 2-byte alignment.
  uint8_t* odd = px.data() + ((reinterpret_cast<uintptr_t>(px.data()) & 1) ? 0 : 1);
  EXPECT_EQ(d.dec.decode(kFile.data(), kFile.size(), vds::ImageTarget::frame(PixelFormat::rgb565, odd, 48)),
            Status::invalid_argument);
  // Planes need the chroma planes for a colour image.
  std::vector<uint8_t> y(24 * 18);
  EXPECT_EQ(d.dec.decode(kFile.data(), kFile.size(), vds::ImageTarget::planes(y.data(), 24, nullptr, 12, nullptr, 12)),
            Status::invalid_argument);
  // feed() before start() is misuse.
  JpegDecoder fresh;
  EXPECT_EQ(fresh.feed(kFile.data(), kFile.size()), Status::invalid_argument);
}

TEST(ImageJpeg, PiecesOfEverySizeGiveTheSamePixels) {
  const std::vector<uint8_t> want = rgb_whole();
  for (size_t piece = 1; piece <= 40; ++piece) {
    Decoder d;
    std::vector<uint8_t> px(24 * 18 * 3);
    ASSERT_EQ(d.dec.start(vds::ImageTarget::frame(PixelFormat::rgb888, px.data(), 72)), Status::ok);
    Status s = Status::more_input;
    for (size_t at = 0; at < kFile.size(); at += piece) {
      const std::vector<uint8_t> copy(kFile.begin() + static_cast<ptrdiff_t>(at),
                                      kFile.begin() + static_cast<ptrdiff_t>(std::min(at + piece, kFile.size())));
      s = d.dec.feed(copy.data(), copy.size());
      if (s != Status::more_input) break;
    }
    ASSERT_EQ(s, Status::ok) << "pieces of " << piece;
    EXPECT_EQ(px, want) << "pieces of " << piece;
  }
}

TEST(ImageJpeg, RestartsAndLatchedErrors) {
  Decoder d;
  std::vector<uint8_t> px(24 * 18 * 3);
  const auto t = vds::ImageTarget::frame(PixelFormat::rgb888, px.data(), 72);
  // Two images in a row with one decoder; bytes after EOI are ignored.
  ASSERT_EQ(d.dec.decode(kFile.data(), kFile.size(), t), Status::ok);
  EXPECT_EQ(d.dec.feed(kFile.data(), 10), Status::ok);
  ASSERT_EQ(d.dec.decode(kFile.data(), kFile.size(), t), Status::ok);
  // Truncated: the whole-file call says so; fed in pieces it wants more.
  EXPECT_EQ(d.dec.decode(kFile.data(), kFile.size() - 2, t), Status::truncated);
  ASSERT_EQ(d.dec.start(t), Status::ok);
  EXPECT_EQ(d.dec.feed(kFile.data(), kFile.size() / 2), Status::more_input);
  // A wrong byte after SOI: malformed, latched for every later call.
  std::vector<uint8_t> bad = kFile;
  bad[2] = 0x12;
  EXPECT_EQ(d.dec.decode(bad.data(), bad.size(), t), Status::malformed);
  EXPECT_EQ(d.dec.feed(kFile.data(), kFile.size()), Status::malformed);
  // The frame header says 16-bit samples: refused as unsupported.
  bad = kFile;
  for (size_t i = 0; i + 4 < bad.size(); ++i)
    if (bad[i] == 0xFF && bad[i + 1] == 0xC0) {
      bad[i + 4] = 12;  // P
      break;
    }
  EXPECT_EQ(d.dec.decode(bad.data(), bad.size(), t), Status::unsupported_feature);
}

}  // namespace
