// libFuzzer: the vds image codec. Mode 0 decodes the input as an IMGH payload
// and IMGD payloads; mode 1 applies the input as edits to valid encoded
// images (intra, residual, region); mode 2 round-trips a small picture made
// from the input through the encoder and the client decoder, which must
// agree bit for bit. The decoder must never crash, never write outside the
// image, and repeat a latched error.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "pixel_bounds.h"
#include "vds/enc/image_codec.h"
#include "vds/image.h"

namespace {

using vds::ChromaFormat;
using vds::Status;

using vds::fuzz::check_rect;

bool grey_prediction(void*, uint16_t, uint16_t, uint16_t w, uint16_t h, uint8_t* y, ptrdiff_t ys, uint8_t* cb,
                     uint8_t* cr, ptrdiff_t cs) {
  for (int r = 0; r < h; ++r) std::memset(y + r * ys, 100, w);
  if (cb != nullptr)  // at most one 8x8 chroma block per component
    for (int r = 0; r < 8; ++r) {
      std::memset(cb + r * cs, 128, 8);
      std::memset(cr + r * cs, 128, 8);
    }
  return true;
}

// Decodes a header and data payloads with a target chosen by `kind`.
void decode(const std::vector<uint8_t>& imgh, const std::vector<std::vector<uint8_t>>& imgd, int kind) {
  static std::vector<uint8_t> ws(vds::ImageDecoder::kWorkspaceBytes);
  vds::Arena arena(ws.data(), ws.size());
  vds::ImageDecoder dec;
  if (dec.init(arena) != Status::ok) __builtin_trap();
  vds::ImageHeader h;
  const bool valid = vds::image_header_from_bytes(imgh.data(), static_cast<uint32_t>(imgh.size()), &h) == Status::ok;
  const bool small = valid && static_cast<uint32_t>(h.width) * h.height <= (1u << 16);
  vds::fuzz::PixelBounds bounds{valid ? h.width : 0u, valid ? h.height : 0u, 3, 0};  // rgb888
  std::vector<uint8_t> frame, planes[3], band;
  vds::ImageTarget t = vds::ImageTarget::rects(vds::PixelFormat::rgb888, check_rect, &bounds);
  if (small && kind == 1) {
    frame.assign(static_cast<size_t>(h.width) * h.height * 3, 0);
    t = vds::ImageTarget::frame(vds::PixelFormat::rgb888, frame.data(), h.width * 3);
  } else if (small && kind == 2) {
    for (int c = 0; c < 3; ++c)
      planes[c].assign(static_cast<size_t>(c == 0 ? h.width : h.chroma_width()) * (c == 0 ? h.height : h.chroma_height()), 77);
    t = vds::ImageTarget::planes(planes[0].data(), h.width, planes[1].data(), h.chroma_width(), planes[2].data(),
                                 h.chroma_width());
  } else if (small && kind == 3) {
    band.assign(static_cast<size_t>(h.width) * 3 * 16, 0);
    t = vds::ImageTarget::bands(vds::PixelFormat::rgb888, band.data(), h.width * 3, check_rect, &bounds);
  }
  t.predict = grey_prediction;
  Status s = dec.start(imgh.data(), static_cast<uint32_t>(imgh.size()), t);
  if (s != Status::ok) return;
  // The image is unfinished until a feed says ok (an input may hold a
  // header and no data at all).
  s = Status::more_input;
  for (const auto& d : imgd) {
    s = dec.feed(d.data(), static_cast<uint32_t>(d.size()));
    if (vds::is_error(s)) {
      if (dec.feed(d.data(), static_cast<uint32_t>(d.size())) != s) __builtin_trap();
      return;
    }
  }
  if (s == Status::ok && !dec.done()) __builtin_trap();
}

struct Seeds {
  std::vector<vds::enc::EncodedImage> images;
  Seeds() {
    vds::enc::Image img(40, 30, 3);
    for (int y = 0; y < 30; ++y)
      for (int x = 0; x < 40; ++x)
        for (int c = 0; c < 3; ++c) img.at(x, y, c) = static_cast<uint8_t>(x * 5 + y * 3 * (c + 1) + ((x * y) & 15));
    vds::enc::ImageEncodeOptions o;
    o.quality = 90;
    o.max_chunk_payload = 400;
    images.push_back(vds::enc::encode_image(img, o));
    const vds::enc::Planes src = vds::enc::rgb_to_planes(img, ChromaFormat::yuv444);
    vds::enc::Planes pred = src;
    for (auto& v : pred.plane[0]) v = static_cast<uint8_t>(v / 2 + 40);
    o.chroma = ChromaFormat::yuv444;
    o.mode = vds::enc::ImageMode::residual;
    o.prediction = &pred;
    o.region.assign(static_cast<size_t>(5 * 4), 1);
    o.region[3] = o.region[7] = 0;
    images.push_back(vds::enc::encode_planes(src, o));
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 2) return 0;
  const int mode = data[0] % 3;
  const int kind = (data[0] / 3) % 4;
  data += 1;
  size -= 1;
  if (mode == 0) {
    // IMGH = 12 bytes, then payloads each prefixed by a one-byte length.
    if (size < vds::kImageHeaderBytes) return 0;
    std::vector<uint8_t> imgh(data, data + vds::kImageHeaderBytes);
    std::vector<std::vector<uint8_t>> imgd;
    for (size_t at = vds::kImageHeaderBytes; at < size;) {
      const size_t n = data[at++];
      const size_t take = n < size - at ? n : size - at;
      imgd.emplace_back(data + at, data + at + take);
      at += take;
    }
    decode(imgh, imgd, kind);
  } else if (mode == 1) {
    static const Seeds seeds;
    const vds::enc::EncodedImage& e = seeds.images[data[0] % seeds.images.size()];
    std::vector<uint8_t> imgh = e.imgh;
    std::vector<std::vector<uint8_t>> imgd = e.imgd;
    for (size_t i = 1; i + 2 < size; i += 3) {
      auto& chunk = imgd[data[i] % imgd.size()];
      if (chunk.empty()) continue;
      const size_t off = data[i + 1] % (chunk.size() + 1);
      if (off == chunk.size())
        chunk.resize(data[i + 2] % chunk.size());
      else
        chunk[off] ^= data[i + 2];
    }
    decode(imgh, imgd, kind);
  } else {
    // Round trip of a small picture: width, height, options, then pixels.
    if (size < 4) return 0;
    const int w = 1 + data[0] % 24, h = 1 + data[1] % 24;
    vds::enc::Image img(w, h, 3);
    const size_t n = size - 4;
    for (size_t i = 0; i < img.pixels.size(); ++i)
      img.pixels[i] = static_cast<uint8_t>((n != 0 ? data[4 + i % n] : 0) ^ i);
    vds::enc::ImageEncodeOptions o;
    o.quality = data[2] % 101;
    o.chroma = static_cast<ChromaFormat>(data[3] % 3);
    o.rdo = (data[3] & 4) != 0;
    o.slope = (data[3] >> 3) % 17;
    o.max_chunk_payload = 1u << 16;
    const vds::enc::EncodedImage e = vds::enc::encode_image(img, o);
    if (!(vds::enc::decode_image_planes(e) == e.recon)) __builtin_trap();
    const vds::enc::DecodedImage d = vds::enc::decode_stream_image(vds::enc::image_stream(e));
    if (d.rgb.pixels != vds::enc::planes_to_rgb(e.recon).pixels) __builtin_trap();
  }
  return 0;
}
