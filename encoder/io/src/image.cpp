// Host image files: loading a file (the readers are in image_read.cpp),
// writing PNG through libpng, and the measures.
#include "vds/io/image.h"

#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <limits>
#include <memory>
#include <stdexcept>

namespace vds::io {

Image load_image(const std::string& path, int want_channels) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error(path + ": cannot open");
  const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  if (f.bad()) throw std::runtime_error(path + ": read error");
  return decode_image(bytes.data(), bytes.size(), path, want_channels);
}

struct PngRowWriter::State {
  std::string path, temp;
  std::FILE* f = nullptr;
  png_structp png = nullptr;
  png_infop info = nullptr;
  int width = 0, height = 0, channels = 0, written = 0;
};

namespace {

// Runs a libpng call under its error handler; false if libpng failed.
template <class F>
bool png_call(png_structp png, F&& f) {
  if (setjmp(png_jmpbuf(png))) return false;
  f();
  return true;
}

}  // namespace

PngRowWriter::PngRowWriter(const std::string& path, int width, int height, int channels) {
  if (width <= 0 || height <= 0) throw std::invalid_argument(path + ": image has no pixels");
  int color = 0;
  switch (channels) {
    case 1: color = PNG_COLOR_TYPE_GRAY; break;
    case 3: color = PNG_COLOR_TYPE_RGB; break;
    case 4: color = PNG_COLOR_TYPE_RGBA; break;
    default: throw std::invalid_argument(path + ": PNG needs 1, 3 or 4 channels");
  }
  s_ = new State;
  s_->path = path;
  s_->temp = path + ".part";
  s_->width = width;
  s_->height = height;
  s_->channels = channels;
  s_->f = std::fopen(s_->temp.c_str(), "wb");
  if (s_->f == nullptr) {
    delete s_;
    s_ = nullptr;
    throw std::runtime_error(path + ": cannot open for writing");
  }
  s_->png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  s_->info = s_->png ? png_create_info_struct(s_->png) : nullptr;
  if (s_->png == nullptr || s_->info == nullptr) {
    discard();
    throw std::runtime_error(path + ": libpng initialisation failed");
  }
  png_structp png = s_->png;
  png_infop info = s_->info;
  std::FILE* f = s_->f;
  const bool ok = png_call(png, [&] {
    png_init_io(png, f);
    png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), 8, color,
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
  });
  if (!ok) {
    discard();
    throw std::runtime_error(path + ": PNG write failed");
  }
}

PngRowWriter::~PngRowWriter() { discard(); }

void PngRowWriter::discard() {
  if (s_ == nullptr) return;
  if (s_->png != nullptr) png_destroy_write_struct(&s_->png, s_->info != nullptr ? &s_->info : nullptr);
  if (s_->f != nullptr) {
    std::fclose(s_->f);
    std::remove(s_->temp.c_str());
  }
  delete s_;
  s_ = nullptr;
}

void PngRowWriter::write_rows(const uint8_t* pixels, int rows, ptrdiff_t stride) {
  if (s_ == nullptr || s_->f == nullptr) throw std::logic_error("PngRowWriter: write after finish or failure");
  if (rows < 0 || s_->written + rows > s_->height) throw std::logic_error(s_->path + ": more rows than the image has");
  png_structp png = s_->png;
  const bool ok = png_call(png, [&] {
    for (int r = 0; r < rows; ++r) png_write_row(png, const_cast<png_bytep>(pixels + r * stride));
  });
  if (!ok) {
    // libpng's state is undefined now: the writer is done.
    const std::string path = s_->path;
    discard();
    throw std::runtime_error(path + ": PNG write failed");
  }
  s_->written += rows;
}

void PngRowWriter::finish() {
  if (s_ == nullptr || s_->f == nullptr) throw std::logic_error("PngRowWriter: finish twice");
  if (s_->written != s_->height) throw std::logic_error(s_->path + ": finish before every row was written");
  png_structp png = s_->png;
  if (!png_call(png, [&] { png_write_end(png, nullptr); })) throw std::runtime_error(s_->path + ": PNG write failed");
  png_destroy_write_struct(&s_->png, &s_->info);
  s_->png = nullptr;
  const int closed = std::fclose(s_->f);
  s_->f = nullptr;
  if (closed != 0 || std::rename(s_->temp.c_str(), s_->path.c_str()) != 0) {
    std::remove(s_->temp.c_str());
    throw std::runtime_error(s_->path + ": write error");
  }
}

void save_png(const std::string& path, const Image& img) {
  if (img.width <= 0 || img.height <= 0 || img.pixels.size() != static_cast<size_t>(img.width) * img.height * img.channels)
    throw std::invalid_argument(path + ": image has no pixels or inconsistent size");
  PngRowWriter w(path, img.width, img.height, img.channels);
  w.write_rows(img.pixels.data(), img.height, static_cast<ptrdiff_t>(img.width) * img.channels);
  w.finish();
}

Image halve(const Image& a) {
  Image b(std::max(1, (a.width + 1) / 2), std::max(1, (a.height + 1) / 2), 3);
  for (int y = 0; y < b.height; ++y)
    for (int x = 0; x < b.width; ++x)
      for (int c = 0; c < 3; ++c) {
        int s = 0;
        for (int dy = 0; dy < 2; ++dy)
          for (int dx = 0; dx < 2; ++dx) s += a.at(std::min(2 * x + dx, a.width - 1), std::min(2 * y + dy, a.height - 1), c);
        b.at(x, y, c) = static_cast<uint8_t>((s + 2) / 4);
      }
  return b;
}

std::array<double, 3> bilinear_repeat(const Image& img, double x, double y) {
  x -= 0.5;
  y -= 0.5;
  const double fx = std::floor(x), fy = std::floor(y);
  const double ax = x - fx, ay = y - fy;
  // Coordinates far outside the image repeat: reduce before converting to int.
  auto wrap = [](double i, int n) {
    const int r = static_cast<int>(std::fmod(i, static_cast<double>(n)));
    return ((r % n) + n) % n;
  };
  const int x0 = wrap(fx, img.width), y0 = wrap(fy, img.height);
  const int x1 = (x0 + 1) % img.width, y1 = (y0 + 1) % img.height;
  std::array<double, 3> out{};
  for (int c = 0; c < 3; ++c)
    out[c] = (img.at(x0, y0, c) * (1 - ax) + img.at(x1, y0, c) * ax) * (1 - ay) +
             (img.at(x0, y1, c) * (1 - ax) + img.at(x1, y1, c) * ax) * ay;
  return out;
}

double mse(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height || a.channels != b.channels)
    throw std::invalid_argument("images differ in size or channels");
  if (a.pixels.empty()) return 0;
  double sum = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) {
    const double d = static_cast<double>(a.pixels[i]) - static_cast<double>(b.pixels[i]);
    sum += d * d;
  }
  return sum / static_cast<double>(a.pixels.size());
}

double psnr(const Image& a, const Image& b) {
  const double m = mse(a, b);
  if (m == 0) return std::numeric_limits<double>::infinity();
  return 10.0 * std::log10(255.0 * 255.0 / m);
}

Image side_by_side(const std::vector<const Image*>& images, int gap) {
  if (images.empty()) throw std::invalid_argument("side_by_side needs at least one image");
  int w = 0, h = 0;
  const int c = images.front()->channels;
  for (const Image* im : images) {
    if (im->channels != c) throw std::invalid_argument("side_by_side: images differ in channels");
    w += im->width;
    h = std::max(h, im->height);
  }
  w += gap * static_cast<int>(images.size() - 1);
  Image out(w, h, c);
  std::fill(out.pixels.begin(), out.pixels.end(), 128);
  int x0 = 0;
  for (const Image* im : images) {
    for (int y = 0; y < im->height; ++y)
      std::copy(im->row(y), im->row(y) + static_cast<size_t>(im->width) * c, out.row(y) + static_cast<size_t>(x0) * c);
    x0 += im->width + gap;
  }
  return out;
}

Image grid(const std::vector<const Image*>& images, int columns, int gap) {
  if (images.empty() || columns < 1) throw std::invalid_argument("grid needs at least one image and one column");
  std::vector<Image> rows;
  for (size_t i = 0; i < images.size(); i += static_cast<size_t>(columns)) {
    const std::vector<const Image*> row(images.begin() + static_cast<std::ptrdiff_t>(i),
                                        images.begin() + static_cast<std::ptrdiff_t>(std::min(images.size(), i + static_cast<size_t>(columns))));
    rows.push_back(side_by_side(row, gap));
  }
  int w = 0, h = 0;
  for (const Image& r : rows) w = std::max(w, r.width), h += r.height;
  h += gap * static_cast<int>(rows.size() - 1);
  Image out(w, h, rows.front().channels);
  std::fill(out.pixels.begin(), out.pixels.end(), 128);
  int y0 = 0;
  for (const Image& r : rows) {
    for (int y = 0; y < r.height; ++y) std::copy(r.row(y), r.row(y) + static_cast<size_t>(r.width) * r.channels, out.row(y0 + y));
    y0 += r.height + gap;
  }
  return out;
}

}  // namespace vds::io
