// vds encoder: R'G'B' <-> Y'CbCr for the image codec (JFIF equations, ITU-T
// T.871 clause 7), 4:2:0 chroma by 2x2 means, and PSNR over planes.
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "vds/enc/image_codec.h"

namespace vds::enc {

namespace {
uint8_t to_u8(double v) { return static_cast<uint8_t>(std::clamp(std::lround(v), 0L, 255L)); }
}  // namespace

Planes::Planes(int w, int h, ChromaFormat c) : width(w), height(h), chroma(c) {
  if (w <= 0 || h <= 0) throw std::invalid_argument("Planes: size must be positive");
  for (int i = 0; i < components(); ++i)
    plane[i].assign(static_cast<size_t>(plane_width(i)) * plane_height(i), i == 0 ? 0 : 128);
}

Planes rgb_to_planes(const Image& img, ChromaFormat chroma) {
  if (img.width <= 0 || img.height <= 0 || img.channels < 1 || img.channels > 4)
    throw std::invalid_argument("rgb_to_planes: empty image or unsupported channel count");
  Planes p(img.width, img.height, chroma);
  const bool colour = img.channels >= 3;
  std::vector<double> cb(static_cast<size_t>(img.width) * img.height, 128.0);
  std::vector<double> cr(cb.size(), 128.0);
  for (int y = 0; y < img.height; ++y) {
    for (int x = 0; x < img.width; ++x) {
      const size_t i = static_cast<size_t>(y) * img.width + x;
      if (!colour) {
        p.plane[0][i] = img.at(x, y, 0);
        continue;
      }
      const double r = img.at(x, y, 0), g = img.at(x, y, 1), b = img.at(x, y, 2);
      p.plane[0][i] = to_u8(0.299 * r + 0.587 * g + 0.114 * b);
      cb[i] = -0.168736 * r - 0.331264 * g + 0.5 * b + 128.0;
      cr[i] = 0.5 * r - 0.418688 * g - 0.081312 * b + 128.0;
    }
  }
  if (chroma == ChromaFormat::grey) return p;
  const int s = chroma == ChromaFormat::yuv420 ? 2 : 1;
  for (int cy = 0; cy < p.plane_height(1); ++cy) {
    for (int cx = 0; cx < p.plane_width(1); ++cx) {
      double sb = 0, sr = 0;
      int n = 0;
      for (int dy = 0; dy < s; ++dy)
        for (int dx = 0; dx < s; ++dx) {
          const int x = cx * s + dx, y = cy * s + dy;
          if (x >= img.width || y >= img.height) continue;
          const size_t i = static_cast<size_t>(y) * img.width + x;
          sb += cb[i];
          sr += cr[i];
          ++n;
        }
      p.row(1, cy)[cx] = to_u8(sb / n);
      p.row(2, cy)[cx] = to_u8(sr / n);
    }
  }
  return p;
}

Image planes_to_rgb(const Planes& p) {
  Image out(p.width, p.height, 3);
  const int s = p.chroma == ChromaFormat::yuv420 ? 1 : 0;
  for (int y = 0; y < p.height; ++y) {
    for (int x = 0; x < p.width; ++x) {
      const int yy = p.row(0, y)[x];
      uint8_t* d = &out.at(x, y, 0);
      if (p.chroma == ChromaFormat::grey) {
        d[0] = d[1] = d[2] = static_cast<uint8_t>(yy);
      } else {
        ycbcr_to_rgb(yy, p.row(1, y >> s)[x >> s], p.row(2, y >> s)[x >> s], d);
      }
    }
  }
  return out;
}

namespace {
double psnr_of(double sse, double n) {
  if (sse == 0) return std::numeric_limits<double>::infinity();
  return 10.0 * std::log10(255.0 * 255.0 * n / sse);
}
void check_same(const Planes& a, const Planes& b) {
  if (a.width != b.width || a.height != b.height || a.chroma != b.chroma)
    throw std::invalid_argument("planes differ in size or chroma format");
}
}  // namespace

double planes_psnr(const Planes& a, const Planes& b) {
  check_same(a, b);
  double sse = 0, n = 0;
  for (int c = 0; c < a.components(); ++c) {
    for (size_t i = 0; i < a.plane[c].size(); ++i) {
      const double d = static_cast<double>(a.plane[c][i]) - b.plane[c][i];
      sse += d * d;
    }
    n += static_cast<double>(a.plane[c].size());
  }
  return psnr_of(sse, n);
}

double luma_psnr(const Planes& a, const Planes& b) {
  check_same(a, b);
  double sse = 0;
  for (size_t i = 0; i < a.plane[0].size(); ++i) {
    const double d = static_cast<double>(a.plane[0][i]) - b.plane[0][i];
    sse += d * d;
  }
  return psnr_of(sse, static_cast<double>(a.plane[0].size()));
}

}  // namespace vds::enc
