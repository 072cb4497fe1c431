// Host image files: load PNG (libpng), JPEG (libjpeg-turbo), BMP (stb_image), PNM and TGA,
// write PNG (libpng), and the measures every benchmark uses (PSNR). A leaf library
// (libpng, libjpeg-turbo and stb_image only, nothing of vds) that the encoder and the
// host-native board both use.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace vds::io {

// 8-bit interleaved pixels, rows top to bottom, no padding.
struct Image {
  int width = 0;
  int height = 0;
  int channels = 0;  // 1 grey, 3 RGB, 4 RGBA
  std::vector<uint8_t> pixels;

  Image() = default;
  Image(int w, int h, int c) : width(w), height(h), channels(c), pixels(static_cast<size_t>(w) * h * c) {}
  uint8_t* row(int y) { return pixels.data() + static_cast<size_t>(y) * width * channels; }
  const uint8_t* row(int y) const { return pixels.data() + static_cast<size_t>(y) * width * channels; }
  uint8_t& at(int x, int y, int c) { return pixels[(static_cast<size_t>(y) * width + x) * channels + c]; }
  uint8_t at(int x, int y, int c) const { return pixels[(static_cast<size_t>(y) * width + x) * channels + c]; }
};

// The largest image read: kMaxImageSide on a side and kMaxImagePixels in
// all. A file that declares more is refused before its pixels are decoded
// (a few hundred compressed bytes can declare gigabytes).
constexpr int kMaxImageSide = 16384;
constexpr int64_t kMaxImagePixels = int64_t{64} << 20;

// Loads an image file; `want_channels` 0 keeps the file's own, 1/3/4 converts.
// Throws std::runtime_error naming the file and the reason.
Image load_image(const std::string& path, int want_channels = 0);
// Decodes an in-memory image file (PNG, JPEG, BMP, binary PNM or TGA; the kind from its
// first bytes, TGA when none matches).
Image decode_image(const uint8_t* data, size_t size, const std::string& what, int want_channels = 0);
// A heightmap: one height per pixel, in the file's own levels. Grey images
// give their sample (8-bit, or 16-bit from a 16-bit PNG or a PGM of maxval
// above 255); colour images the sum of R, G and B (units_per_level 3: a
// grey drawn in colour keeps the small differences between its channels).
// Alpha is ignored. Throws as load_image does.
struct Heightmap {
  int width = 0;
  int height = 0;
  int units_per_level = 1;   // values per level of the file (3 for colour)
  std::vector<uint16_t> values;
};
Heightmap decode_heightmap(const uint8_t* data, size_t size, const std::string& what);

// Writes a PNG (1, 3 or 4 channels). Throws std::runtime_error on failure.
// The file appears whole or not at all (written beside it, then renamed);
// what was at `path` before stays until then.
void save_png(const std::string& path, const Image& img);

// A PNG written row by row, in memory of one row: for images too large to
// hold whole. The file appears at `path` only at finish(); a writer
// destroyed before then removes what it wrote. Throws std::runtime_error.
class PngRowWriter {
 public:
  PngRowWriter(const std::string& path, int width, int height, int channels);
  ~PngRowWriter();
  PngRowWriter(const PngRowWriter&) = delete;
  PngRowWriter& operator=(const PngRowWriter&) = delete;
  // The next `rows` rows, `stride` bytes apart (width x channels bytes each).
  void write_rows(const uint8_t* pixels, int rows, ptrdiff_t stride);
  // Every row written: closes the file and moves it to `path`.
  void finish();

 private:
  struct State;
  void discard();  // frees everything; removes the unfinished file
  State* s_ = nullptr;
};

// Same size and channels, else throws std::invalid_argument.
double mse(const Image& a, const Image& b);

// An RGB image box-filtered to half its size (rounded up; the last row and
// column repeat where the size is odd), each channel rounded: one level of
// a pyramid.
Image halve(const Image& rgb);

// An RGB image sampled bilinearly at (x, y) in texels (texel (i, j) covers
// [i, i+1) x [j, j+1)), coordinates repeating; channels 0..255, unrounded.
std::array<double, 3> bilinear_repeat(const Image& rgb, double x, double y);
// 10·log10(255² / MSE); identical images give +infinity.
double psnr(const Image& a, const Image& b);

// One RGB565 pixel (bits 15..11 red, 10..5 green, 4..0 blue) as 8-bit RGB,
// the high bits replicated into the low ones so white stays 255: how the
// host shows what a client displays.
inline void rgb565_to_rgb888(uint16_t p, uint8_t out[3]) {
  const uint32_t r = (p >> 11) & 31, g = (p >> 5) & 63, b = p & 31;
  out[0] = static_cast<uint8_t>((r << 3) | (r >> 2));
  out[1] = static_cast<uint8_t>((g << 2) | (g >> 4));
  out[2] = static_cast<uint8_t>((b << 3) | (b >> 2));
}

// Places images side by side in one row with a gap of `gap` pixels (grey).
Image side_by_side(const std::vector<const Image*>& images, int gap = 4);
// Places images in rows of `columns` (a contact sheet), `gap` pixels apart (grey).
Image grid(const std::vector<const Image*>& images, int columns, int gap = 4);

}  // namespace vds::io
