// libFuzzer: the host's image import (vds/io/image.h: PNG through libpng,
// JPEG through libjpeg-turbo, TGA and binary PNM through the project's readers,
// behind the project's size limit; BMP refused), which every encoder
// command that takes a picture uses. The first byte picks the channels
// asked for; the rest is the file. Invariants: no crash, sanitizer report
// or hang; a refusal is a std::runtime_error naming the input; an accepted
// image is at most kMaxImageSide on a side and kMaxImagePixels in all, and
// its pixel count matches its size.
//
// Seed corpus: when the corpus directory is empty, small valid files are
// written to it first (a PNG of each channel count, an uncompressed and an
// RLE TGA, a baseline JPEG, a binary PPM, a BMP, which is refused).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "jpeg_sample_422.h"
#include "seed_corpus.h"
#include "vds/io/image.h"

namespace {

void write(const std::filesystem::path& p, const std::vector<uint8_t>& bytes) {
  std::ofstream(p, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

std::vector<uint8_t> read(const std::filesystem::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::vector<uint8_t>((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

void seed(const std::filesystem::path& dir) {
  for (int c : {1, 3, 4}) {
    vds::io::Image img(7, 5, c);
    for (size_t i = 0; i < img.pixels.size(); ++i) img.pixels[i] = static_cast<uint8_t>(i * 37);
    const std::filesystem::path png = dir / ("seed_png" + std::to_string(c));
    vds::io::save_png(png.string(), img);
    std::vector<uint8_t> bytes = read(png);
    bytes.insert(bytes.begin(), static_cast<uint8_t>(c));
    write(png, bytes);
  }
  // TGA: 4x2 true colour, uncompressed (type 2) and RLE (type 10).
  std::vector<uint8_t> tga = {3, 0, 0, 2, 0, 0, 0, 0, 0, 0, 0, 0, 0, 4, 0, 2, 0, 24, 0};
  for (int i = 0; i < 8; ++i) tga.insert(tga.end(), {static_cast<uint8_t>(i * 30), 80, 200});
  write(dir / "seed_tga", tga);
  std::vector<uint8_t> rle = {3, 0, 0, 10, 0, 0, 0, 0, 0, 0, 0, 0, 0, 4, 0, 2, 0, 24, 0, 0x83, 10, 20, 30, 0x03, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};
  write(dir / "seed_tga_rle", rle);
  std::vector<uint8_t> jpeg = {3};
  jpeg.insert(jpeg.end(), vds::test::kJpeg422, vds::test::kJpeg422 + sizeof vds::test::kJpeg422);
  write(dir / "seed_jpeg", jpeg);
  // BMP: 2x2, 24 bits, rows padded to 4 bytes.
  std::vector<uint8_t> bmp = {3, 'B', 'M', 70, 0, 0, 0, 0, 0, 0, 0, 54, 0, 0, 0, 40, 0, 0, 0, 2, 0, 0, 0, 2, 0, 0, 0, 1, 0, 24, 0,
                              0, 0, 0, 0, 16, 0, 0, 0, 0x13, 0x0B, 0, 0, 0x13, 0x0B, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  for (int i = 0; i < 2; ++i) bmp.insert(bmp.end(), {10, 20, 30, 40, 50, 60, 0, 0});
  write(dir / "seed_bmp", bmp);
  std::vector<uint8_t> pnm = {0};
  const std::string head = "P6\n# seed\n3 2\n255\n";
  pnm.insert(pnm.end(), head.begin(), head.end());
  for (int i = 0; i < 18; ++i) pnm.push_back(static_cast<uint8_t>(i * 13));
  write(dir / "seed_pnm", pnm);
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  vds::test::seed_corpus_if_empty(*argc, *argv, seed);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const int kChannels[] = {0, 1, 3, 4};
  const int want = kChannels[data[0] % 4];
  try {
    const vds::io::Image img = vds::io::decode_image(data + 1, size - 1, "input", want);
    if (img.width <= 0 || img.height <= 0 || img.width > vds::io::kMaxImageSide ||
        img.height > vds::io::kMaxImageSide || int64_t{img.width} * img.height > vds::io::kMaxImagePixels)
      abort();
    if (img.pixels.size() != static_cast<size_t>(img.width) * img.height * img.channels) abort();
    if (want != 0 && img.channels != want) abort();
  } catch (const std::runtime_error& e) {
    if (std::strncmp(e.what(), "input: ", 7) != 0) abort();  // the refusal names the input
  }
  return 0;
}
