// Y4M output (vds/io/y4m.h).
#include "vds/io/y4m.h"

#include <algorithm>
#include <stdexcept>
#include <vector>

namespace vds::io {

void Y4mWriter::write(const Image& img) {
  if (img.channels < 3) throw std::invalid_argument(path_ + ": Y4M frames are RGB");
  if (!out_.is_open()) {
    out_.open(path_, std::ios::binary | std::ios::trunc);
    if (!out_) throw std::runtime_error(path_ + ": cannot open for writing");
    width_ = img.width;
    height_ = img.height;
    out_ << "YUV4MPEG2 W" << width_ << " H" << height_ << " F" << fps_ << ":1 Ip A1:1 C444 XCOLORRANGE=FULL\n";
  }
  if (img.width != width_ || img.height != height_)
    throw std::invalid_argument(path_ + ": every frame must be " + std::to_string(width_) + "x" + std::to_string(height_));
  const size_t n = static_cast<size_t>(img.width) * img.height;
  std::vector<uint8_t> planes(3 * n);
  for (size_t i = 0; i < n; ++i) {
    const uint8_t* p = img.pixels.data() + i * static_cast<size_t>(img.channels);
    const double r = p[0], g = p[1], b = p[2];
    const auto clamp = [](double v) { return static_cast<uint8_t>(std::clamp(v + 0.5, 0.0, 255.0)); };
    planes[i] = clamp(0.299 * r + 0.587 * g + 0.114 * b);
    planes[n + i] = clamp(128 - 0.168736 * r - 0.331264 * g + 0.5 * b);
    planes[2 * n + i] = clamp(128 + 0.5 * r - 0.418688 * g - 0.081312 * b);
  }
  out_ << "FRAME\n";
  out_.write(reinterpret_cast<const char*>(planes.data()), static_cast<std::streamsize>(planes.size()));
  if (!out_) throw std::runtime_error(path_ + ": write error");
}

void Y4mWriter::close() {
  if (!out_.is_open()) return;
  out_.close();
  if (!out_) throw std::runtime_error(path_ + ": write error");
}

}  // namespace vds::io
