// Host image files in: PNG through libpng, JPEG through libjpeg-turbo (its
// TurboJPEG interface), BMP through stb_image (Debian's libstb), TGA and
// binary PNM (P5, P6) through the readers below (uncompressed and RLE,
// true colour and grey: what game textures use). Every reader checks the
// size an image declares against vds/io/image.h's limits before a pixel is
// decoded, and refuses with the file's name, what is wrong and where.
#include <png.h>
#include <stb_image.h>
#include <turbojpeg.h>

#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>

#include "vds/io/image.h"

namespace vds::io {

namespace {

[[noreturn]] void refuse(const std::string& what, const std::string& why) { throw std::runtime_error(what + ": " + why); }

void check_size(const std::string& what, const char* format, int64_t w, int64_t h) {
  if (w <= 0 || h <= 0 || w > kMaxImageSide || h > kMaxImageSide || w * h > kMaxImagePixels)
    refuse(what, std::string(format) + " declares a " + std::to_string(w) + "x" + std::to_string(h) +
                     " image; the most read is " + std::to_string(kMaxImageSide) + " on a side and " +
                     std::to_string(kMaxImagePixels >> 20) + " Mpixels");
}

// JFIF luma of 8-bit R'G'B', as the earlier reader computed it.
uint8_t luma(const uint8_t* p) { return static_cast<uint8_t>((p[0] * 77 + p[1] * 150 + p[2] * 29) >> 8); }

// `in` (1 grey, 2 grey+alpha, 3 RGB, 4 RGBA) to `want` channels (0: keep,
// except that grey+alpha keeps grey only).
Image convert(const Image& in, int want) {
  const int c = in.channels;
  if (want == 0) want = c == 2 ? 1 : c;
  if (want == c) return in;
  Image out(in.width, in.height, want);
  const size_t n = static_cast<size_t>(in.width) * in.height;
  for (size_t i = 0; i < n; ++i) {
    const uint8_t* s = &in.pixels[i * c];
    uint8_t* d = &out.pixels[i * want];
    const bool colour = c >= 3;
    const uint8_t alpha = c == 2 ? s[1] : c == 4 ? s[3] : 255;
    if (want == 1) {
      d[0] = colour ? luma(s) : s[0];
    } else {
      d[0] = s[0];
      d[1] = colour ? s[1] : s[0];
      d[2] = colour ? s[2] : s[0];
      if (want == 4) d[3] = alpha;
    }
  }
  return out;
}

// --- BMP ------------------------------------------------------------------------

// Windows bitmaps (older models' skins): palettised, 16, 24 and 32 bits,
// uncompressed. stb_image reads them; its header pass gives the size,
// checked before any pixel is decoded, and the rows it will read must be in
// the file (stb_image reads zeros past the end).
Image read_bmp(const uint8_t* data, size_t size, const std::string& what) {
  if (size > static_cast<size_t>(INT32_MAX)) refuse(what, "a BMP file over 2 GiB");
  if (size < 30) refuse(what, "a BMP file of " + std::to_string(size) + " bytes ends inside its header");
  const int n = static_cast<int>(size);
  int w = 0, h = 0, c = 0;
  if (stbi_info_from_memory(data, n, &w, &h, &c) == 0)
    refuse(what, std::string("not a BMP file this tool reads (") + stbi_failure_reason() + ")");
  check_size(what, "the BMP", w, h);
  const auto le32 = [data](size_t at) {
    return uint32_t{data[at]} | uint32_t{data[at + 1]} << 8 | uint32_t{data[at + 2]} << 16 | uint32_t{data[at + 3]} << 24;
  };
  if (size < 54 || le32(14) < 40) refuse(what, "an OS/2 BMP or a BMP header of under 40 bytes (Windows BMPs are read)");
  const uint32_t bits = uint32_t{data[28]} | uint32_t{data[29]} << 8;
  const uint32_t compression = le32(30);
  if (compression != 0 && compression != 3)
    refuse(what, "a compressed BMP (compression " + std::to_string(compression) + "; uncompressed ones are read)");
  const uint64_t row = (uint64_t{static_cast<uint32_t>(w)} * bits + 31) / 32 * 4;
  const uint64_t need = uint64_t{le32(10)} + row * static_cast<uint32_t>(h);
  if (need > size)
    refuse(what, "the BMP's " + std::to_string(w) + "x" + std::to_string(h) + " pixels of " + std::to_string(bits) +
                     " bits end at byte " + std::to_string(need) + ", past the file's " + std::to_string(size));
  const int want = c == 4 ? 4 : 3;
  std::unique_ptr<stbi_uc, void (*)(void*)> px(stbi_load_from_memory(data, n, &w, &h, &c, want), stbi_image_free);
  if (!px) refuse(what, std::string("damaged BMP file (") + stbi_failure_reason() + ")");
  Image img(w, h, want);
  std::memcpy(img.pixels.data(), px.get(), static_cast<size_t>(w) * h * want);
  return img;
}

// --- PNG ------------------------------------------------------------------------

struct PngSource {
  const uint8_t* data;
  size_t size, at;
};

// keep16: a 16-bit PNG keeps its samples, two bytes each (big-endian) in
// an Image of twice the channels; *wide says whether it did.
Image read_png(const uint8_t* data, size_t size, const std::string& what, bool keep16 = false,
               bool* wide = nullptr) {
  if (wide != nullptr) *wide = false;
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (png == nullptr || info == nullptr) {
    png_destroy_read_struct(&png, nullptr, nullptr);
    throw std::runtime_error(what + ": libpng initialisation failed");
  }
  // libpng reports errors by longjmp: nothing with a destructor lives in
  // this frame between setjmp and the end of the read.
  struct Read {
    Image img;
    std::string error;
  };
  std::unique_ptr<Read> r(new Read);
  png_set_error_fn(
      png, r.get(),
      [](png_structp p, png_const_charp msg) {
        static_cast<Read*>(png_get_error_ptr(p))->error = msg;
        png_longjmp(p, 1);
      },
      [](png_structp, png_const_charp) {});
  PngSource src{data, size, 0};
  png_set_read_fn(png, &src, [](png_structp p, png_bytep out, png_size_t n) {
    PngSource& s = *static_cast<PngSource*>(png_get_io_ptr(p));
    if (n > s.size - s.at) png_error(p, "the file ends inside the image");
    std::memcpy(out, s.data + s.at, n);
    s.at += n;
  });
  // A limit on what libpng itself allocates for ancillary chunks.
  png_set_chunk_malloc_max(png, 8u << 20);
  bool too_big = false, cannot_hold = false;
  png_uint_32 w = 0, h = 0;
  // An exception (memory exhausted) must not leave libpng's state behind.
  struct Guard {
    png_structp* png;
    png_infop* info;
    ~Guard() { png_destroy_read_struct(png, info, nullptr); }
  } guard{&png, &info};
  if (setjmp(png_jmpbuf(png)) == 0) {
    png_read_info(png, info);
    w = png_get_image_width(png, info);
    h = png_get_image_height(png, info);
    too_big = w == 0 || h == 0 || w > static_cast<png_uint_32>(kMaxImageSide) || h > static_cast<png_uint_32>(kMaxImageSide) ||
              int64_t{w} * h > kMaxImagePixels;
    // Deflate expands at most 1032-fold: rows the file cannot hold are
    // refused before they are allocated.
    const int64_t raw = int64_t{h} * (1 + (int64_t{w} * png_get_channels(png, info) * png_get_bit_depth(png, info) + 7) / 8);
    cannot_hold = !too_big && raw > 1032 * static_cast<int64_t>(size) + 4096;
    if (!too_big && !cannot_hold) {
      // 8 bits per channel: palettes and low bit depths expanded, 16 bits
      // cut to their high byte, transparency as an alpha channel.
      png_set_expand(png);
      const int bytes = keep16 && png_get_bit_depth(png, info) == 16 ? 2 : 1;
      if (bytes == 1) png_set_strip_16(png);
      png_set_interlace_handling(png);
      png_read_update_info(png, info);
      const int channels = png_get_channels(png, info);
      if (channels < 1 || channels > 4 ||
          png_get_rowbytes(png, info) != static_cast<size_t>(w) * channels * bytes)
        png_error(png, "unexpected row layout");
      r->img = Image(static_cast<int>(w), static_cast<int>(h), channels * bytes);
      if (wide != nullptr) *wide = bytes == 2;
      // Rows one at a time (interlaced images take several passes).
      const int passes = png_set_interlace_handling(png);
      for (int pass = 0; pass < passes; ++pass)
        for (png_uint_32 y = 0; y < h; ++y) png_read_row(png, r->img.row(static_cast<int>(y)), nullptr);
      png_read_end(png, nullptr);
    }
  } else {
    refuse(what, "not a readable PNG (" + r->error + ")");
  }
  if (too_big) check_size(what, "the PNG", w, h);
  if (cannot_hold)
    refuse(what, "the PNG declares " + std::to_string(w) + "x" + std::to_string(h) + " pixels, more than its " +
                     std::to_string(size) + " bytes can hold");
  return std::move(r->img);
}

// --- JPEG -----------------------------------------------------------------------

Image read_jpeg(const uint8_t* data, size_t size, const std::string& what) {
  std::unique_ptr<void, int (*)(tjhandle)> tj(tjInitDecompress(), tjDestroy);
  if (!tj) throw std::runtime_error(what + ": libjpeg-turbo initialisation failed");
  int w = 0, h = 0, sub = 0, cs = 0;
  if (size > 0xFFFFFFFFu ||
      tjDecompressHeader3(tj.get(), data, static_cast<unsigned long>(size), &w, &h, &sub, &cs) != 0)
    refuse(what, std::string("not a readable JPEG (") + tjGetErrorStr2(tj.get()) + ")");
  if (w <= 0 || h <= 0) refuse(what, "not a readable JPEG (no frame header)");
  check_size(what, "the JPEG", w, h);
  // Even a flat picture takes bits for every 8x8 block: more than 1024
  // pixels a byte of file is a declared size the file cannot hold.
  if (int64_t{w} * h > 1024 * static_cast<int64_t>(size) + (int64_t{1} << 20))
    refuse(what, "the JPEG declares " + std::to_string(w) + "x" + std::to_string(h) + " pixels in " +
                     std::to_string(size) + " bytes (more than 1024 pixels a byte)");
  if (cs == TJCS_CMYK || cs == TJCS_YCCK) refuse(what, "a CMYK JPEG (RGB or grey are read)");
  const bool grey = cs == TJCS_GRAY;
  Image img(w, h, grey ? 1 : 3);
  if (tjDecompress2(tj.get(), data, static_cast<unsigned long>(size), img.pixels.data(), w, 0, h,
                    grey ? TJPF_GRAY : TJPF_RGB, TJFLAG_ACCURATEDCT | TJFLAG_STOPONWARNING | TJFLAG_LIMITSCANS) != 0)
    refuse(what, std::string("not a readable JPEG (") + tjGetErrorStr2(tj.get()) + ")");
  return img;
}

// --- TGA (Truevision TGA 2.0: image types 2, 3, 10 and 11) ---------------------

Image read_tga(const uint8_t* data, size_t size, const std::string& what) {
  constexpr size_t kHeader = 18;
  if (size < kHeader) refuse(what, "not an image file (PNG, JPEG, PNM or TGA): too short for a TGA header");
  const int id_len = data[0], map_type = data[1], type = data[2];
  const int map_len = data[5] | (data[6] << 8), map_bits = data[7];
  const int w = data[12] | (data[13] << 8), h = data[14] | (data[15] << 8);
  const int bits = data[16], desc = data[17];
  const bool rle = type == 10 || type == 11, grey = type == 3 || type == 11;
  if (type != 2 && type != 3 && type != 10 && type != 11)
    refuse(what, "not an image file this tool reads (PNG, JPEG, PNM, or a true-colour or grey TGA; TGA image type " +
                     std::to_string(type) + ")");
  if (map_type > 1) refuse(what, "TGA colour map type " + std::to_string(map_type) + " (byte 1)");
  check_size(what, "the TGA", w, h);
  if (grey ? bits != 8 : (bits != 16 && bits != 24 && bits != 32))
    refuse(what, "TGA of " + std::to_string(bits) + " bits per pixel for image type " + std::to_string(type) + " (byte 16)");
  const int bpp = bits / 8;
  // 16-bit pixels are read as RGB (their attribute bit is not alpha in
  // every writer's files).
  const int channels = grey ? 1 : bits == 32 ? 4 : 3;
  size_t at = kHeader + static_cast<size_t>(id_len) + (map_type == 1 ? static_cast<size_t>(map_len) * ((map_bits + 7) / 8) : 0);
  if (at > size) refuse(what, "the TGA ends inside its image ID or colour map");
  const size_t pixels = static_cast<size_t>(w) * h;
  // Every pixel takes at least one byte of the file (RLE: a packet of 128
  // pixels takes 1 + bpp bytes): refuse what the file cannot hold before
  // allocating the image.
  const size_t least = rle ? (pixels + 127) / 128 * (1 + static_cast<size_t>(bpp)) : pixels * static_cast<size_t>(bpp);
  if (size - at < least)
    refuse(what, "the TGA declares " + std::to_string(w) + "x" + std::to_string(h) + " pixels, at least " +
                     std::to_string(least) + " bytes, but " + std::to_string(size - at) + " follow its header");
  Image img(w, h, channels);
  auto put = [&](size_t i, const uint8_t* p) {
    uint8_t* d = &img.pixels[i * channels];
    if (grey) {
      d[0] = p[0];
    } else if (bpp == 2) {
      const int v = p[0] | (p[1] << 8);
      d[0] = static_cast<uint8_t>(((v >> 10) & 31) * 255 / 31);
      d[1] = static_cast<uint8_t>(((v >> 5) & 31) * 255 / 31);
      d[2] = static_cast<uint8_t>((v & 31) * 255 / 31);
    } else {
      d[0] = p[2];
      d[1] = p[1];
      d[2] = p[0];
      if (channels == 4) d[3] = p[3];
    }
  };
  if (!rle) {
    for (size_t i = 0; i < pixels; ++i) put(i, data + at + i * bpp);
  } else {
    size_t i = 0;
    while (i < pixels) {
      if (at >= size) refuse(what, "the TGA ends inside its pixels (pixel " + std::to_string(i) + ", byte " + std::to_string(at) + ")");
      const int head = data[at++];
      const size_t n = static_cast<size_t>(head & 127) + 1;
      if (n > pixels - i) refuse(what, "a TGA run passes the last pixel (byte " + std::to_string(at - 1) + ")");
      const size_t need = (head & 128) ? static_cast<size_t>(bpp) : n * bpp;
      if (size - at < need) refuse(what, "the TGA ends inside its pixels (pixel " + std::to_string(i) + ", byte " + std::to_string(at) + ")");
      for (size_t k = 0; k < n; ++k) put(i + k, data + at + ((head & 128) ? 0 : k * bpp));
      at += need;
      i += n;
    }
  }
  // Rows are stored bottom to top unless the descriptor's bit 5 says top first.
  if ((desc & 0x20) == 0) {
    const size_t row = static_cast<size_t>(w) * channels;
    for (int y = 0; y < h / 2; ++y) std::swap_ranges(img.row(y), img.row(y) + row, img.row(h - 1 - y));
  }
  return img;
}

// --- PNM (P5 grey, P6 RGB; maxval up to 65535, read to 8 bits) ------------------

// keep16: a PNM of maxval > 255 keeps its samples, two bytes each
// (big-endian) in an Image of twice the channels, and *wide is set.
Image read_pnm(const uint8_t* data, size_t size, const std::string& what, bool keep16 = false,
               bool* wide = nullptr) {
  if (wide != nullptr) *wide = false;
  const bool grey = data[1] == '5';
  size_t at = 2;
  if (size < 3 || !(data[2] == ' ' || data[2] == '\t' || data[2] == '\r' || data[2] == '\n'))
    refuse(what, "not a binary PNM (P5 or P6 and whitespace)");
  int64_t field[3];
  for (int k = 0; k < 3; ++k) {
    // Whitespace and comments, then a decimal number.
    for (;;) {
      while (at < size && (data[at] == ' ' || data[at] == '\t' || data[at] == '\r' || data[at] == '\n')) ++at;
      if (at < size && data[at] == '#') {
        while (at < size && data[at] != '\n') ++at;
        continue;
      }
      break;
    }
    int64_t v = 0;
    const size_t s = at;
    while (at < size && data[at] >= '0' && data[at] <= '9') {
      if (at - s == 9) refuse(what, "a PNM header field of more than 9 digits (byte " + std::to_string(s) + ")");
      v = v * 10 + (data[at++] - '0');
    }
    if (at == s) refuse(what, "a PNM header field is not a number (byte " + std::to_string(at) + ")");
    field[k] = v;
  }
  if (at >= size || !(data[at] == ' ' || data[at] == '\t' || data[at] == '\r' || data[at] == '\n'))
    refuse(what, "the PNM header does not end in whitespace (byte " + std::to_string(at) + ")");
  ++at;
  const int64_t w = field[0], h = field[1], maxval = field[2];
  check_size(what, "the PNM", w, h);
  if (maxval < 1 || maxval > 65535) refuse(what, "PNM maxval " + std::to_string(maxval) + " (1..65535)");
  const int channels = grey ? 1 : 3;
  const size_t sample = maxval > 255 ? 2 : 1;
  const size_t need = static_cast<size_t>(w) * h * channels * sample;
  if (size - at < need)
    refuse(what, "the PNM declares " + std::to_string(w) + "x" + std::to_string(h) + " pixels, " + std::to_string(need) +
                     " bytes, but " + std::to_string(size - at) + " follow its header");
  if (keep16 && sample == 2) {
    Image img(static_cast<int>(w), static_cast<int>(h), channels * 2);
    std::memcpy(img.pixels.data(), data + at, need);
    if (wide != nullptr) *wide = true;
    return img;
  }
  Image img(static_cast<int>(w), static_cast<int>(h), channels);
  for (size_t i = 0; i < img.pixels.size(); ++i) {
    const int64_t v = sample == 2 ? (data[at + 2 * i] << 8) | data[at + 2 * i + 1] : data[at + i];
    img.pixels[i] = static_cast<uint8_t>(maxval == 255 ? v : (v > maxval ? 255 : (v * 255 + maxval / 2) / maxval));
  }
  return img;
}

}  // namespace

Image decode_image(const uint8_t* data, size_t size, const std::string& what, int want_channels) {
  if (want_channels < 0 || want_channels > 4 || want_channels == 2)
    throw std::invalid_argument("want_channels must be 0, 1, 3 or 4");
  if (size == 0) refuse(what, "the file is empty");
  Image img;
  if (size >= 8 && png_sig_cmp(data, 0, 8) == 0)
    img = read_png(data, size, what);
  else if (size >= 3 && data[0] == 0xFF && data[1] == 0xD8 && data[2] == 0xFF)
    img = read_jpeg(data, size, what);
  else if (size >= 3 && data[0] == 'P' && (data[1] == '5' || data[1] == '6'))
    img = read_pnm(data, size, what);
  else if (size >= 2 && data[0] == 'B' && data[1] == 'M')
    img = read_bmp(data, size, what);
  else
    img = read_tga(data, size, what);
  return convert(img, want_channels);
}

Heightmap decode_heightmap(const uint8_t* data, size_t size, const std::string& what) {
  if (size == 0) refuse(what, "the file is empty");
  Heightmap hm;
  Image img;
  bool wide = false;
  if (size >= 8 && png_sig_cmp(data, 0, 8) == 0) {
    img = read_png(data, size, what, true, &wide);
  } else if (size >= 3 && data[0] == 'P' && (data[1] == '5' || data[1] == '6')) {
    img = read_pnm(data, size, what, true, &wide);
  } else {
    img = decode_image(data, size, what);
  }
  const int bytes = wide ? 2 : 1;
  const int channels = img.channels / bytes;
  hm.width = img.width;
  hm.height = img.height;
  const bool colour = channels >= 3;
  if (colour && wide) refuse(what, "a colour heightmap of 16-bit samples (16-bit heightmaps are read in grey)");
  hm.units_per_level = colour ? 3 : 1;
  const size_t n = static_cast<size_t>(img.width) * img.height;
  hm.values.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const uint8_t* p = &img.pixels[i * img.channels];
    auto sample = [&](int c) { return bytes == 2 ? (p[2 * c] << 8) | p[2 * c + 1] : p[c]; };
    const int v = colour ? sample(0) + sample(1) + sample(2) : sample(0);
    hm.values[i] = static_cast<uint16_t>(v);
  }
  return hm;
}

}  // namespace vds::io
