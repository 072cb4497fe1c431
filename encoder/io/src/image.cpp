// Host image files through stb_image (read) and libpng (write).
#include "vds/io/image.h"

#include <png.h>
#include <stb_image.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <limits>
#include <memory>
#include <stdexcept>

namespace vds::io {

Image decode_image(const uint8_t* data, size_t size, const std::string& what, int want_channels) {
  if (want_channels < 0 || want_channels > 4 || want_channels == 2)
    throw std::invalid_argument("want_channels must be 0, 1, 3 or 4");
  if (size > static_cast<size_t>(std::numeric_limits<int>::max())) throw std::runtime_error(what + ": file too large");
  int w = 0, h = 0, c = 0;
  std::unique_ptr<stbi_uc, void (*)(void*)> px(
      stbi_load_from_memory(data, static_cast<int>(size), &w, &h, &c, want_channels), stbi_image_free);
  if (!px) throw std::runtime_error(what + ": not a readable image (" + stbi_failure_reason() + ")");
  const int channels = want_channels ? want_channels : c;
  if (channels == 2) {  // grey + alpha: keep grey only
    Image img(w, h, 1);
    for (size_t i = 0; i < img.pixels.size(); ++i) img.pixels[i] = px.get()[2 * i];
    return img;
  }
  Image img(w, h, channels);
  std::copy(px.get(), px.get() + img.pixels.size(), img.pixels.begin());
  return img;
}

Image load_image(const std::string& path, int want_channels) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error(path + ": cannot open");
  const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  if (f.bad()) throw std::runtime_error(path + ": read error");
  return decode_image(bytes.data(), bytes.size(), path, want_channels);
}

void save_png(const std::string& path, const Image& img) {
  if (img.width <= 0 || img.height <= 0 || img.pixels.size() != static_cast<size_t>(img.width) * img.height * img.channels)
    throw std::invalid_argument(path + ": image has no pixels or inconsistent size");
  int color = 0;
  switch (img.channels) {
    case 1: color = PNG_COLOR_TYPE_GRAY; break;
    case 3: color = PNG_COLOR_TYPE_RGB; break;
    case 4: color = PNG_COLOR_TYPE_RGBA; break;
    default: throw std::invalid_argument(path + ": PNG needs 1, 3 or 4 channels");
  }
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) throw std::runtime_error(path + ": cannot open for writing");
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info) {
    std::fclose(f);
    png_destroy_write_struct(&png, nullptr);
    throw std::runtime_error(path + ": libpng initialisation failed");
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    std::fclose(f);
    throw std::runtime_error(path + ": PNG write failed");
  }
  png_init_io(png, f);
  png_set_IHDR(png, info, static_cast<png_uint_32>(img.width), static_cast<png_uint_32>(img.height), 8, color,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int y = 0; y < img.height; ++y) png_write_row(png, const_cast<png_bytep>(img.row(y)));
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  if (std::fclose(f) != 0) throw std::runtime_error(path + ": write error");
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

}  // namespace vds::io
