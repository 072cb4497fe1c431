// The vds image codec: every mode, chroma format, size and target round-trips
// bit-exactly between the encoder's reconstruction and the client decoder;
// rate control meets its targets; hostile and truncated input fails cleanly.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "vds/bytes.h"
#include "vds/crc32c.h"
#include "vds/enc/image_codec.h"
#include "vds/enc/stream_writer.h"
#include "vds/image.h"
#include "golden_hash.h"
#include "stream_chunks.h"
#include "xorshift.h"

namespace {

using vds::ChromaFormat;
using vds::ImageDecoder;
using vds::ImageTarget;
using vds::PixelFormat;
using vds::Status;
using vds::enc::EncodedImage;
using vds::enc::Image;
using vds::enc::ImageEncodeOptions;
using vds::enc::Planes;

using Rng = vds::test::Xorshift32;

// A test picture with what textures have: smooth shading, periodic detail,
// noise and hard edges (a few dark "letters").
Image synth(int w, int h, uint32_t seed) {
  Image img(w, h, 3);
  Rng r{seed};
  const double fx = 0.05 + (seed % 7) * 0.03, fy = 0.04 + (seed % 5) * 0.02;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double base = 90 + 60 * std::sin(x * fx) * std::cos(y * fy) + 0.3 * x - 0.2 * y;
      const bool ink = ((x / 6 + y / 9) % 5 == 0) && ((x % 6) < 2 || (y % 9) < 2);
      for (int c = 0; c < 3; ++c) {
        double v = base + (c == 0 ? 30 : c == 1 ? 0 : -25) * std::sin((x + 2 * y) * 0.01 * (c + 1));
        v += static_cast<int>(r.next() % 21) - 10;
        if (ink) v = 20 + c * 10;
        img.at(x, y, c) = static_cast<uint8_t>(std::clamp(static_cast<int>(v), 0, 255));
      }
    }
  return img;
}

std::vector<uint8_t> stream_of(const EncodedImage& e) { return vds::enc::image_stream(e); }

// Decodes an image through the client decoder into planes; checks that the
// player shows exactly those planes (its RGB888 bands) too.
Planes client_planes(const EncodedImage& e, const Planes* prediction = nullptr) {
  const Planes planes = vds::enc::decode_image_planes(e, prediction);
  const vds::enc::DecodedImage d = vds::enc::decode_stream_image(stream_of(e), prediction);
  EXPECT_EQ(d.kind, "vds");
  EXPECT_EQ(d.rgb.pixels, vds::enc::planes_to_rgb(planes).pixels) << "the player's RGB888 bands differ from the planes";
  return planes;
}

// The IMGH and IMGD payloads of a well-formed images stream, in order (the
// container's framing: an 8-byte preamble, then type, size, payload, CRC).
EncodedImage image_chunks_of(const std::vector<uint8_t>& s) {
  EncodedImage e;
  for (const vds::test::ChunkAt& c : vds::test::stream_chunks(s)) {
    const std::vector<uint8_t> payload = c.bytes(s);
    if (c.type == vds::chunk::kImageHeader) {
      e.imgh = payload;
      EXPECT_EQ(vds::image_header_from_bytes(payload.data(), c.size, &e.header), Status::ok);
    }
    if (c.type == vds::chunk::kImageData) e.imgd.push_back(payload);
  }
  return e;
}

TEST(ImageCodec, HeaderBytesRoundTripAndValidation) {
  vds::ImageHeader h;
  h.chroma = ChromaFormat::yuv444;
  h.flags = vds::kImageFlagResidual | vds::kImageFlagRegion;
  h.quant_luma = 200;
  h.quant_chroma = 17;
  h.slope = 16;
  h.width = 16384;
  h.height = 3;
  uint8_t b[vds::kImageHeaderBytes];
  vds::image_header_to_bytes(h, b);
  vds::ImageHeader back;
  ASSERT_EQ(vds::image_header_from_bytes(b, sizeof b, &back), Status::ok);
  EXPECT_EQ(back.chroma, h.chroma);
  EXPECT_EQ(back.flags, h.flags);
  EXPECT_EQ(back.quant_luma, 200);
  EXPECT_EQ(back.quant_chroma, 17);
  EXPECT_EQ(back.width, 16384);
  EXPECT_EQ(back.height, 3);
  EXPECT_EQ(vds::image_header_from_bytes(b, sizeof b - 1, &back), Status::truncated);
  const auto with = [&](int i, uint8_t v) {
    uint8_t c[vds::kImageHeaderBytes];
    std::memcpy(c, b, sizeof c);
    c[i] = v;
    return vds::image_header_from_bytes(c, sizeof c, &back);
  };
  EXPECT_EQ(with(0, 2), Status::unsupported_version);
  EXPECT_EQ(with(0, 0), Status::malformed);
  EXPECT_EQ(with(1, 3), Status::unsupported_feature);
  EXPECT_EQ(with(2, 0x08), Status::unsupported_feature);
  EXPECT_EQ(with(5, 17), Status::malformed);
  EXPECT_EQ(with(6, 0x01), Status::malformed);  // width 16385
  EXPECT_EQ(with(8, 0), Status::malformed);      // height 0
  EXPECT_EQ(with(10, 1), Status::malformed);     // reserved
}

TEST(ImageCodec, QuantTables) {
  uint16_t q[64];
  vds::image_quant_table(0, 0, false, q);
  for (int k = 0; k < 64; ++k) EXPECT_EQ(q[k], 1);
  // Every 32 index steps double the step: index 128 is 16, 160 is 32.
  vds::image_quant_table(128, 0, false, q);
  EXPECT_EQ(q[0], 16);
  EXPECT_EQ(q[63], 16);
  vds::image_quant_table(160, 0, true, q);
  EXPECT_EQ(q[0], 32);
  // Full slope: the Annex K luma shape (K.1: 16 .. 99 at the last position).
  vds::image_quant_table(128, 16, false, q);
  EXPECT_EQ(q[0], 16);
  EXPECT_EQ(q[1], 11);
  EXPECT_EQ(q[63], 99);
  vds::image_quant_table(255, 16, false, q);
  for (int k = 0; k < 64; ++k) EXPECT_TRUE(q[k] >= 1 && q[k] <= 2047);
  // Coarser with the index, position by position.
  uint16_t a[64], b[64];
  for (int i = 0; i < 255; i += 7) {
    vds::image_quant_table(i, 8, true, a);
    vds::image_quant_table(i + 1, 8, true, b);
    for (int k = 0; k < 64; ++k) EXPECT_LE(a[k], b[k]);
  }
}

struct Case {
  int w, h;
  ChromaFormat chroma;
  int quality;
  bool rdo;
};

TEST(ImageCodec, IntraRoundTripsBitExactly) {
  const Case cases[] = {
      {1, 1, ChromaFormat::yuv420, 75, true},     {7, 5, ChromaFormat::yuv420, 90, true},
      {16, 16, ChromaFormat::yuv444, 50, true},   {17, 33, ChromaFormat::yuv420, 30, false},
      {33, 17, ChromaFormat::grey, 80, true},     {240, 180, ChromaFormat::yuv420, 85, true},
      {64, 48, ChromaFormat::yuv444, 100, true},  {40, 40, ChromaFormat::yuv420, 1, true},
      {100, 30, ChromaFormat::yuv420, 100, false}};
  uint32_t seed = 1;
  for (const Case& c : cases) {
    const Image img = synth(c.w, c.h, seed++);
    ImageEncodeOptions o;
    o.quality = c.quality;
    o.chroma = c.chroma;
    o.rdo = c.rdo;
    const EncodedImage e = vds::enc::encode_image(img, o);
    SCOPED_TRACE(std::to_string(c.w) + "x" + std::to_string(c.h) + " q" + std::to_string(c.quality));
    EXPECT_EQ(client_planes(e), e.recon);
    // The reconstruction is the source planes up to quantisation.
    const double p = vds::enc::planes_psnr(vds::enc::rgb_to_planes(img, c.chroma), e.recon);
    if (c.quality >= 75) EXPECT_GT(p, 30.0);
    if (c.quality == 100) EXPECT_GT(p, 45.0);
  }
}

TEST(ImageCodec, QualityOrdersSizeAndPsnr) {
  const Image img = synth(96, 64, 11);
  ImageEncodeOptions o;
  size_t last_bytes = 0;
  double last_psnr = 0;
  for (int q : {10, 30, 50, 70, 90}) {
    o.quality = q;
    const EncodedImage e = vds::enc::encode_image(img, o);
    EXPECT_GT(e.coded_bytes(), last_bytes) << "quality " << q;
    EXPECT_GT(e.psnr, last_psnr) << "quality " << q;
    last_bytes = e.coded_bytes();
    last_psnr = e.psnr;
  }
}

TEST(ImageCodec, RdoBeatsRoundingAtEqualQuantisers) {
  // The trellis trades distortion for rate at the quantiser's own slope: it
  // must never cost more in D + lambda R terms; in practice it saves bits at
  // a small PSNR cost. Check it saves at least 5 % of the bytes.
  const Image img = synth(128, 96, 5);
  const Planes src = vds::enc::rgb_to_planes(img, ChromaFormat::yuv420);
  ImageEncodeOptions o;
  o.rdo = false;
  const EncodedImage plain = vds::enc::encode_planes_at(src, 100, 84, o);
  o.rdo = true;
  const EncodedImage rdo = vds::enc::encode_planes_at(src, 100, 84, o);
  EXPECT_LT(rdo.coded_bytes(), plain.coded_bytes() * 0.95);
  EXPECT_GT(rdo.psnr, plain.psnr - 1.0);
}

// An image with a smooth prediction: the previous "view" shifted and dimmed.
Planes shifted_prediction(const Planes& src, int dx, int dy, int dimming) {
  Planes p = src;
  for (int c = 0; c < src.components(); ++c)
    for (int y = 0; y < src.plane_height(c); ++y)
      for (int x = 0; x < src.plane_width(c); ++x) {
        const int sx = std::clamp(x + dx, 0, src.plane_width(c) - 1), sy = std::clamp(y + dy, 0, src.plane_height(c) - 1);
        const int v = src.row(c, sy)[sx] - (c == 0 ? dimming : 0);
        p.row(c, y)[x] = static_cast<uint8_t>(std::clamp(v, 0, 255));
      }
  return p;
}

TEST(ImageCodec, ResidualModeAddsToThePrediction) {
  for (ChromaFormat cf : {ChromaFormat::yuv420, ChromaFormat::yuv444}) {
    const Planes src = vds::enc::rgb_to_planes(synth(75, 45, 21), cf);
    const Planes pred = shifted_prediction(src, 1, 0, 12);
    ImageEncodeOptions o;
    o.chroma = cf;
    o.mode = vds::enc::ImageMode::residual;
    o.prediction = &pred;
    o.quality = 80;
    const EncodedImage e = vds::enc::encode_planes(src, o);
    EXPECT_TRUE(e.header.residual());
    EXPECT_EQ(client_planes(e, &pred), e.recon);
    EXPECT_GT(vds::enc::planes_psnr(src, e.recon), vds::enc::planes_psnr(src, pred) + 3.0);
    // Without a prediction the host wrapper adds to black, in both passes;
    // a prediction of the wrong size is refused before decoding.
    EXPECT_NO_THROW(client_planes(e, nullptr));
    const Planes wrong(74, 45, cf);
    EXPECT_THROW(vds::enc::decode_stream_image(stream_of(e), &wrong), std::runtime_error);
    // The residual of an exact prediction costs next to nothing.
    o.prediction = &src;
    const EncodedImage same = vds::enc::encode_planes(src, o);
    EXPECT_EQ(same.recon, src);
    EXPECT_LT(same.coded_bytes(), 80u);
  }
}

TEST(ImageCodec, RegionModeTouchesOnlyItsMcus) {
  const Planes src = vds::enc::rgb_to_planes(synth(70, 50, 31), ChromaFormat::yuv420);
  Planes dest(70, 50, ChromaFormat::yuv420);  // what the client holds: a flat grey
  for (auto& v : dest.plane[0]) v = 77;
  for (int mode = 0; mode < 2; ++mode) {
    ImageEncodeOptions o;
    o.quality = 85;
    o.prediction = &dest;
    o.mode = mode == 0 ? vds::enc::ImageMode::intra : vds::enc::ImageMode::residual;
    const int mx = (70 + 15) / 16, my = (50 + 15) / 16;
    o.region.assign(static_cast<size_t>(mx * my), 0);
    o.region[0] = o.region[5] = o.region[6] = o.region[static_cast<size_t>(mx * my - 1)] = 1;
    const EncodedImage e = vds::enc::encode_planes(src, o);
    EXPECT_TRUE(e.header.region());
    const Planes out = client_planes(e, &dest);
    EXPECT_EQ(out, e.recon);
    for (int y = 0; y < 50; ++y)
      for (int x = 0; x < 70; ++x) {
        const size_t m = static_cast<size_t>((y / 16) * mx + x / 16);
        if (o.region[m] == 0) {
          ASSERT_EQ(out.row(0, y)[x], 77) << "pixel outside the region changed";
        } else {
          ASSERT_LE(std::abs(out.row(0, y)[x] - src.row(0, y)[x]), 40);
        }
      }
  }
}

TEST(ImageCodec, ChunksHoldWholeMcusWithinTheLimit) {
  const Image img = synth(160, 96, 41);
  ImageEncodeOptions o;
  o.quality = 95;
  o.max_chunk_payload = 300;
  const EncodedImage e = vds::enc::encode_image(img, o);
  EXPECT_GT(e.imgd.size(), 5u);
  for (const auto& d : e.imgd) EXPECT_LE(d.size(), 300u);
  EXPECT_EQ(client_planes(e), e.recon);
  // The same image in one chunk decodes to the same pixels.
  o.max_chunk_payload = 1 << 20;
  const EncodedImage one = vds::enc::encode_image(img, o);
  EXPECT_EQ(one.imgd.size(), 1u);
  EXPECT_EQ(one.recon, e.recon);
  // One MCU cannot be split: a limit below it is refused with a message.
  o.max_chunk_payload = 40;
  o.quality = 100;
  EXPECT_THROW(vds::enc::encode_image(img, o), std::invalid_argument);
}

TEST(ImageCodec, RateControlMeetsItsTargets) {
  const Image img = synth(120, 90, 51);
  ImageEncodeOptions o;
  o.target_bytes = 1500;
  const EncodedImage e = vds::enc::encode_image(img, o);
  EXPECT_TRUE(e.target_met);
  EXPECT_LE(e.coded_bytes(), 1500u);
  EXPECT_GT(e.coded_bytes(), 1500u * 85 / 100) << "the finest quantiser that fits should come close";
  EXPECT_EQ(client_planes(e), e.recon);
  o.target_bytes = 0;
  o.target_psnr = 33.0;
  const EncodedImage p = vds::enc::encode_image(img, o);
  EXPECT_TRUE(p.target_met);
  EXPECT_GE(p.psnr, 33.0);
  EXPECT_LT(p.psnr, 35.0);
  o.target_psnr = 99.0;  // unreachable: best effort, flagged
  EXPECT_FALSE(vds::enc::encode_image(img, o).target_met);
  o.target_bytes = 10;
  EXPECT_THROW(vds::enc::encode_image(img, o), std::invalid_argument);  // both targets
}

// --- client targets -----------------------------------------------------------------

struct Collected {
  int w = 0, h = 0, bpp = 0;
  std::vector<uint8_t> px;
  std::vector<int> covered;
  int calls = 0;
  int abort_after = -1;
};

bool collect(void* ctx, const vds::PixelRect& r) {
  Collected& c = *static_cast<Collected*>(ctx);
  ++c.calls;
  for (int y = 0; y < r.h; ++y)
    for (int x = 0; x < r.w; ++x) {
      const size_t i = static_cast<size_t>(r.y + y) * c.w + r.x + x;
      std::memcpy(&c.px[i * c.bpp], r.pixels + y * r.stride + x * c.bpp, c.bpp);
      ++c.covered[i];
    }
  return c.abort_after < 0 || c.calls < c.abort_after;
}

// Feeds a stream's IMGH/IMGD payloads straight to an ImageDecoder.
Status decode_with(const EncodedImage& e, const ImageTarget& t) {
  static std::vector<uint8_t> ws(ImageDecoder::kWorkspaceBytes);
  vds::Arena arena(ws.data(), ws.size());
  ImageDecoder d;
  Status s = d.init(arena);
  if (s != Status::ok) return s;
  s = d.start(e.imgh.data(), static_cast<uint32_t>(e.imgh.size()), t);
  if (s != Status::ok) return s;
  for (const auto& c : e.imgd) {
    s = d.feed(c.data(), static_cast<uint32_t>(c.size()));
    if (vds::is_error(s)) return s;
  }
  return d.done() ? Status::ok : s;
}

TEST(ImageCodec, PackedTargetsAgreeWithEachOther) {
  for (ChromaFormat cf : {ChromaFormat::yuv420, ChromaFormat::yuv444, ChromaFormat::grey}) {
    const Image img = synth(45, 37, 61);
    ImageEncodeOptions o;
    o.chroma = cf;
    o.quality = 70;
    const EncodedImage e = vds::enc::encode_image(img, o);
    const Image rgb = vds::enc::planes_to_rgb(e.recon);
    // Frame RGB565 with a padded stride.
    const int stride = 45 * 2 + 6;
    std::vector<uint8_t> frame(static_cast<size_t>(stride) * 37 + 8, 0xAB);
    std::vector<uint8_t> aligned(frame.size() + 2);
    uint8_t* base = aligned.data() + (reinterpret_cast<uintptr_t>(aligned.data()) & 1);
    std::fill(base, base + frame.size(), 0xAB);
    ASSERT_EQ(decode_with(e, ImageTarget::frame(PixelFormat::rgb565, base, stride)), Status::ok);
    for (int y = 0; y < 37; ++y)
      for (int x = 0; x < 45; ++x) {
        uint16_t v;
        std::memcpy(&v, base + y * stride + 2 * x, 2);
        ASSERT_EQ(v, vds::pack_rgb565(rgb.at(x, y, 0), rgb.at(x, y, 1), rgb.at(x, y, 2)));
      }
    for (int y = 0; y < 37; ++y)  // the stride padding is never written
      for (int i = 90; i < stride; ++i) ASSERT_EQ(base[y * stride + i], 0xAB);
    // Rects: each pixel exactly once, same colours as the frame.
    Collected c;
    c.w = 45;
    c.h = 37;
    c.bpp = 3;
    c.px.assign(45 * 37 * 3, 0);
    c.covered.assign(45 * 37, 0);
    ASSERT_EQ(decode_with(e, ImageTarget::rects(PixelFormat::rgb888, collect, &c)), Status::ok);
    EXPECT_EQ(c.px, rgb.pixels);
    for (int n : c.covered) ASSERT_EQ(n, 1);
    // Bands: one call per MCU row, full width.
    Collected b = c;
    b.calls = 0;
    std::fill(b.covered.begin(), b.covered.end(), 0);
    std::vector<uint8_t> band(45 * 3 * 16);
    ASSERT_EQ(decode_with(e, ImageTarget::bands(PixelFormat::rgb888, band.data(), 45 * 3, collect, &b)), Status::ok);
    EXPECT_EQ(b.px, rgb.pixels);
    EXPECT_EQ(b.calls, (37 + e.header.mcu_size() - 1) / e.header.mcu_size());
    for (int n : b.covered) ASSERT_EQ(n, 1);
    // A callback that says stop.
    Collected a = c;
    a.calls = 0;
    a.abort_after = 2;
    EXPECT_EQ(decode_with(e, ImageTarget::rects(PixelFormat::rgb888, collect, &a)), Status::aborted);
    EXPECT_EQ(a.calls, 2);
  }
}

// A stage clock sees every block's entropy decoding and transform and every
// MCU's colour output, and changes nothing in the pixels.
TEST(ImageCodec, StageClockAccountsEveryStageAndChangesNothing) {
  const Image img = synth(64, 48, 7);
  ImageEncodeOptions o;
  o.quality = 80;
  const EncodedImage e = vds::enc::encode_image(img, o);
  std::vector<uint8_t> ws(ImageDecoder::kWorkspaceBytes);
  auto decode = [&](vds::StageClock* clock, std::vector<uint8_t>* frame) {
    vds::Arena arena(ws.data(), ws.size());
    ImageDecoder d;
    ASSERT_EQ(d.init(arena), Status::ok);
    d.set_stage_clock(clock);
    ASSERT_EQ(d.start(e.imgh.data(), static_cast<uint32_t>(e.imgh.size()),
                      ImageTarget::frame(PixelFormat::rgb888, frame->data(), 64 * 3)),
              Status::ok);
    for (const auto& c : e.imgd) ASSERT_FALSE(vds::is_error(d.feed(c.data(), static_cast<uint32_t>(c.size()))));
    ASSERT_TRUE(d.done());
  };
  std::vector<uint8_t> plain(64 * 48 * 3), timed(64 * 48 * 3);
  decode(nullptr, &plain);
  // A clock that advances by one per reading: each stage gets one unit per entry.
  uint64_t ticks = 0;
  vds::StageClock clock;
  clock.ctx = &ticks;
  clock.now = [](void* ctx) { return ++*static_cast<uint64_t*>(ctx); };
  decode(&clock, &timed);
  EXPECT_EQ(plain, timed);
  const uint64_t blocks = (64 / 16) * (48 / 16) * 6;  // 4:2:0: four luma and two chroma blocks per MCU
  const uint64_t mcus = (64 / 16) * (48 / 16);
  EXPECT_EQ(clock.spent[vds::StageClock::entropy], blocks);
  EXPECT_EQ(clock.spent[vds::StageClock::transform], blocks);
  EXPECT_EQ(clock.spent[vds::StageClock::colour], mcus);
  EXPECT_EQ(clock.current, vds::StageClock::idle);
}

TEST(ImageCodec, TargetsThatDoNotFitAreRefused) {
  const EncodedImage e = vds::enc::encode_image(synth(20, 10, 3), ImageEncodeOptions{});
  uint8_t buf[20 * 10 * 3 + 4];
  EXPECT_EQ(decode_with(e, ImageTarget::frame(PixelFormat::rgb888, buf, 59)), Status::invalid_argument);
  EXPECT_EQ(decode_with(e, ImageTarget::frame(PixelFormat::rgb888, nullptr, 60)), Status::invalid_argument);
  uint8_t* odd = buf + ((reinterpret_cast<uintptr_t>(buf) & 1) ? 0 : 1);
  EXPECT_EQ(decode_with(e, ImageTarget::frame(PixelFormat::rgb565, odd, 40)), Status::invalid_argument);
  EXPECT_EQ(decode_with(e, ImageTarget::planes(buf, 20, nullptr, 10, buf, 10)), Status::invalid_argument);
  EXPECT_EQ(decode_with(e, ImageTarget::planes(buf, 19, buf, 10, buf, 10)), Status::invalid_argument);
  // A residual image on a packed target needs a prediction callback.
  const Planes src = vds::enc::rgb_to_planes(synth(20, 10, 3), ChromaFormat::yuv420);
  ImageEncodeOptions o;
  o.mode = vds::enc::ImageMode::residual;
  o.prediction = &src;
  const EncodedImage r = vds::enc::encode_planes(src, o);
  EXPECT_EQ(decode_with(r, ImageTarget::frame(PixelFormat::rgb888, buf, 60)), Status::invalid_argument);
}

TEST(ImageCodec, WorkspaceIsASmallConstant) {
  EXPECT_LE(ImageDecoder::kWorkspaceBytes, 6u * 1024u);
  std::vector<uint8_t> ws(ImageDecoder::kWorkspaceBytes - 1);
  vds::Arena small(ws.data(), ws.size());
  ImageDecoder d;
  // Alignment slack is part of the constant, so one byte less may still fit
  // when the buffer happens to be aligned; 64 bytes less never does.
  vds::Arena tiny(ws.data(), ws.size() - 64);
  EXPECT_EQ(d.init(tiny), Status::workspace_too_small);
  std::vector<uint8_t> full(ImageDecoder::kWorkspaceBytes);
  for (size_t offset = 0; offset < 8; ++offset) {
    std::vector<uint8_t> buf(ImageDecoder::kWorkspaceBytes + offset);
    vds::Arena a(buf.data() + offset, ImageDecoder::kWorkspaceBytes);
    EXPECT_EQ(d.init(a), Status::ok) << "misaligned by " << offset;
  }
}

// --- hostile input --------------------------------------------------------------------

TEST(ImageCodec, EveryPrefixOfAStreamFailsCleanly) {
  const EncodedImage e = vds::enc::encode_image(synth(40, 24, 71), ImageEncodeOptions{});
  const std::vector<uint8_t> s = stream_of(e);
  for (size_t n = 0; n < s.size(); ++n) {
    const std::vector<uint8_t> prefix(s.begin(), s.begin() + static_cast<ptrdiff_t>(n));
    EXPECT_THROW(vds::enc::decode_stream_image(prefix), std::runtime_error) << "prefix " << n;
  }
  EXPECT_NO_THROW(vds::enc::decode_stream_image(s));
}

TEST(ImageCodec, CorruptPayloadsNeverCrash) {
  ImageEncodeOptions o;
  o.max_chunk_payload = 200;
  const EncodedImage e = vds::enc::encode_image(synth(48, 40, 81), o);
  ASSERT_GE(e.imgd.size(), 2u);
  std::vector<uint8_t> frame(48 * 40 * 3);
  const ImageTarget t = ImageTarget::frame(PixelFormat::rgb888, frame.data(), 48 * 3);
  Rng r{99};
  int errors = 0;
  for (int trial = 0; trial < 300; ++trial) {
    EncodedImage bad = e;
    auto& c = bad.imgd[r.next() % bad.imgd.size()];
    const int flips = 1 + static_cast<int>(r.next() % 3);
    for (int i = 0; i < flips; ++i) c[r.next() % c.size()] ^= static_cast<uint8_t>(1u << (r.next() % 8));
    if (trial % 3 == 0) c.resize(c.size() - 1 - r.next() % (c.size() / 2));
    const Status s = decode_with(bad, t);
    errors += vds::is_error(s) ? 1 : 0;
  }
  // Most corruptions are caught by the exact-length rule of each chunk.
  EXPECT_GT(errors, 250);
}

TEST(ImageCodec, ChunkOrderAndCountAreChecked) {
  ImageEncodeOptions o;
  o.max_chunk_payload = 200;
  const EncodedImage e = vds::enc::encode_image(synth(48, 40, 82), o);
  ASSERT_GE(e.imgd.size(), 3u);
  std::vector<uint8_t> frame(48 * 40 * 3);
  const ImageTarget t = ImageTarget::frame(PixelFormat::rgb888, frame.data(), 48 * 3);
  EncodedImage swapped = e;
  std::swap(swapped.imgd[0], swapped.imgd[1]);
  EXPECT_EQ(decode_with(swapped, t), Status::malformed);
  EncodedImage missing = e;
  missing.imgd.erase(missing.imgd.begin() + 1);
  EXPECT_EQ(decode_with(missing, t), Status::malformed);
  EncodedImage extra = e;
  extra.imgd.push_back(e.imgd.back());
  EXPECT_EQ(decode_with(extra, t), Status::malformed);
  EncodedImage cut = e;
  cut.imgd.pop_back();
  EXPECT_EQ(decode_with(cut, t), Status::more_input);
  // A trailing byte no bin uses.
  EncodedImage trailing = e;
  trailing.imgd[0].push_back(0);
  EXPECT_EQ(decode_with(trailing, t), Status::malformed);
}

}  // namespace

namespace {

// Pinned figures of tests/golden/image-v1.vds.
constexpr size_t kGoldenBytes = 1222;
constexpr uint64_t kGoldenHash = 0xdff830cbf312fea7ull;  // vds::test::golden_hash
constexpr uint32_t kGoldenPlanesCrc = 0xBF0EEE4Du;

// The image codec's version-1 stream, kept forever (tests/golden/): every
// later decoder must decode it to the same pixels. Regenerated only with
// VDS_REGENERATE_GOLDEN=1, which also breaks the pinned size and checksums
// until they are updated on purpose. The encoder may change (better rate-
// distortion decisions); the golden file only has to stay decodable.
TEST(ImageCodec, GoldenStreamV1) {
  const std::string path = std::string(VDS_SOURCE_DIR) + "/tests/golden/image-v1.vds";
  if (const char* regen = std::getenv("VDS_REGENERATE_GOLDEN"); regen && std::string(regen) == "1") {
    ImageEncodeOptions o;
    o.quality = 80;
    o.max_chunk_payload = 1024;  // several IMGD chunks
    vds::enc::write_file(path, stream_of(vds::enc::encode_image(synth(70, 46, 2024), o)));
  }
  const std::vector<uint8_t> golden = vds::enc::read_file(path);
  const vds::enc::DecodedImage d = vds::enc::decode_stream_image(golden);
  EXPECT_EQ(d.kind, "vds");
  EXPECT_EQ(d.rgb.width, 70);
  EXPECT_EQ(d.rgb.height, 46);
  const Planes planes = vds::enc::decode_image_planes(image_chunks_of(golden));
  EXPECT_EQ(d.rgb.pixels, vds::enc::planes_to_rgb(planes).pixels);
  uint32_t planes_crc = 0;
  for (int c = 0; c < 3; ++c) planes_crc = vds::crc32c_update(planes_crc, planes.plane[c].data(), planes.plane[c].size());
  std::printf("golden image-v1.vds: %zu bytes, hash %016llX, decoded planes crc %08X\n", golden.size(),
              static_cast<unsigned long long>(vds::test::golden_hash(golden)), planes_crc);
  EXPECT_EQ(golden.size(), kGoldenBytes);
  EXPECT_EQ(vds::test::golden_hash(golden), kGoldenHash);
  EXPECT_EQ(planes_crc, kGoldenPlanesCrc);
}

}  // namespace
