// vds encoder: quality scale and rate control of the vds image codec (a
// bisection over the quantiser index, whose coded size falls and whose PSNR
// falls as it grows), and the image's stream chunks.
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>

#include "image_coder.h"
#include "vds/enc/image_codec.h"

namespace vds::enc {

int quality_to_index(int quality) {
  quality = std::clamp(quality, 1, 100);
  // libjpeg's quality scaling (percent of the base table), applied to a base
  // DC step of 16: quality 50 -> 16, 75 -> 8, 90 -> 3.2.
  const double scale = quality < 50 ? 5000.0 / quality : 200.0 - 2.0 * quality;
  const double step = std::max(16.0 * scale / 100.0, 1.0);
  return std::clamp(static_cast<int>(std::lround(32.0 * std::log2(step))), 0, kQuantIndexMax);
}

size_t EncodedImage::coded_bytes() const {
  size_t n = imgh.size() + kChunkHeadBytes + kChunkTailBytes;
  for (const auto& d : imgd) n += d.size() + kChunkHeadBytes + kChunkTailBytes;
  return n;
}

uint32_t EncodedImage::max_payload() const {
  size_t n = imgh.size();
  for (const auto& d : imgd) n = std::max(n, d.size());
  return static_cast<uint32_t>(n);
}

namespace {

template <typename EncodeAt>
EncodedImage rate_control(const ImageEncodeOptions& o, EncodeAt encode_at) {
  if (o.target_bytes > 0 && o.target_psnr > 0)
    throw std::invalid_argument("encode: give a size target or a PSNR target, not both");
  if (o.target_bytes == 0 && o.target_psnr <= 0) return encode_at(quality_to_index(o.quality));
  std::map<int, EncodedImage> memo;
  const auto at = [&](int i) -> const EncodedImage& {
    auto it = memo.find(i);
    if (it == memo.end()) it = memo.emplace(i, encode_at(i)).first;
    return it->second;
  };
  int lo = 0, hi = kQuantIndexMax;
  if (o.target_bytes > 0) {
    // The finest index whose coded size fits.
    if (at(hi).coded_bytes() > o.target_bytes) {
      EncodedImage e = at(hi);
      e.target_met = false;
      return e;
    }
    while (lo < hi) {
      const int mid = (lo + hi) / 2;
      if (at(mid).coded_bytes() <= o.target_bytes)
        hi = mid;
      else
        lo = mid + 1;
    }
    return at(hi);
  }
  // The coarsest index that still reaches the PSNR.
  if (at(lo).psnr < o.target_psnr) {
    EncodedImage e = at(lo);
    e.target_met = false;
    return e;
  }
  while (lo < hi) {
    const int mid = (lo + hi + 1) / 2;
    if (at(mid).psnr >= o.target_psnr)
      lo = mid;
    else
      hi = mid - 1;
  }
  return at(lo);
}

int chroma_index(int luma, const ImageEncodeOptions& o, ChromaFormat c) {
  const int delta = o.chroma_delta == 999 ? detail::default_chroma_delta(c) : o.chroma_delta;
  return std::clamp(luma + delta, 0, kQuantIndexMax);
}

double rgb_psnr(const Image& src, const Image& rgb, bool grey) {
  double sse = 0, n = 0;
  const int ch = grey ? 1 : 3;
  for (int y = 0; y < src.height; ++y)
    for (int x = 0; x < src.width; ++x)
      for (int c = 0; c < ch; ++c) {
        const int s = src.channels >= 3 ? src.at(x, y, c) : src.at(x, y, 0);
        const double d = static_cast<double>(s) - rgb.at(x, y, c);
        sse += d * d;
        n += 1;
      }
  if (sse == 0) return std::numeric_limits<double>::infinity();
  return 10.0 * std::log10(255.0 * 255.0 * n / sse);
}

}  // namespace

EncodedImage encode_planes(const Planes& src, const ImageEncodeOptions& o) {
  return rate_control(o, [&](int i) { return encode_planes_at(src, i, chroma_index(i, o, src.chroma), o); });
}

EncodedImage encode_image(const Image& img, const ImageEncodeOptions& o) {
  const Planes src = rgb_to_planes(img, o.chroma);
  const bool grey = o.chroma == ChromaFormat::grey;
  return rate_control(o, [&](int i) {
    EncodedImage e = encode_planes_at(src, i, chroma_index(i, o, src.chroma), o);
    e.psnr = rgb_psnr(img, planes_to_rgb(e.recon), grey);
    return e;
  });
}

void add_image_chunks(StreamWriter& w, const EncodedImage& e) {
  w.add_chunk(chunk::kImageHeader, e.imgh);
  for (const auto& d : e.imgd) w.add_chunk(chunk::kImageData, d);
}

std::vector<uint8_t> image_stream(const EncodedImage& e) {
  StreamHeader h = default_header(StreamMode::images, e.header.width, e.header.height);
  h.frame_count = 1;
  h.max_chunk_payload = e.max_payload();
  h.workspace_bytes = static_cast<uint32_t>(ImageDecoder::kWorkspaceBytes);
  StreamWriter w(h);
  add_image_chunks(w, e);
  return w.finish();
}

}  // namespace vds::enc
