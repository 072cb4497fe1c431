// vds encoder: the vds image codec (docs/texture-codec.md). Colour conversion
// to Y'CbCr, perceptual quantisation tables driven by one quality setting,
// rate-distortion optimised quantisation (a trellis over the arithmetic
// coder's own cost estimates), the three modes (intra, residual, region),
// rate control to a size or a PSNR, and the stream chunks (IMGH, IMGD).
//
// The encoder reconstructs with the client library's own integer IDCT, so
// EncodedImage::recon is bit for bit what vds::ImageDecoder produces.
#pragma once
#include <cstddef>
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "vds/enc/image_io.h"
#include "vds/enc/stream_writer.h"
#include "vds/image.h"

namespace vds::enc {

// Y'CbCr planes at the coded resolution (4:2:0 chroma: ceil(w/2) x ceil(h/2)),
// rows packed without padding.
struct Planes {
  int width = 0;
  int height = 0;
  ChromaFormat chroma = ChromaFormat::yuv420;
  std::vector<uint8_t> plane[3];  // Y, Cb, Cr (Cb/Cr empty for grey)

  Planes() = default;
  Planes(int w, int h, ChromaFormat c);
  int components() const { return chroma == ChromaFormat::grey ? 1 : 3; }
  int plane_width(int c) const { return c == 0 || chroma != ChromaFormat::yuv420 ? width : (width + 1) / 2; }
  int plane_height(int c) const { return c == 0 || chroma != ChromaFormat::yuv420 ? height : (height + 1) / 2; }
  uint8_t* row(int c, int y) { return plane[c].data() + static_cast<size_t>(y) * plane_width(c); }
  const uint8_t* row(int c, int y) const { return plane[c].data() + static_cast<size_t>(y) * plane_width(c); }
  bool operator==(const Planes& o) const = default;
};

// RGB (or grey, alpha ignored) -> Y'CbCr by the JFIF equations (T.871),
// rounded; 4:2:0 chroma is the mean of each 2x2 block. A 1-channel image
// may be coded as grey; any other converts with Cb = Cr = 128.
Planes rgb_to_planes(const Image& img, ChromaFormat chroma);
// Y'CbCr -> RGB exactly as the client's rgb888 output (replicated chroma).
Image planes_to_rgb(const Planes& p);

// PSNR over all samples of all planes (sizes and formats must match).
double planes_psnr(const Planes& a, const Planes& b);
// PSNR of the luma plane only.
double luma_psnr(const Planes& a, const Planes& b);

enum class ImageMode : uint8_t { intra, residual };

struct ImageEncodeOptions {
  // Quality 0..100 (roughly the scale of JPEG quality): sets the quantiser
  // index (quality_to_index). Ignored when a rate target is set.
  int quality = 75;
  // Rate control (at most one): the best quality whose coded size is at most
  // target_bytes, or the smallest size whose PSNR is at least target_psnr
  // (RGB PSNR for encode_image, Y'CbCr PSNR of all samples for encode_planes).
  size_t target_bytes = 0;
  double target_psnr = 0;
  ChromaFormat chroma = ChromaFormat::yuv420;
  ImageMode mode = ImageMode::intra;
  // Residual mode: the prediction the decoder will add to (same size and
  // chroma format as the source). Region mode: what the destination holds
  // outside the region (may be null for intra: zeros).
  const Planes* prediction = nullptr;
  // Region mode when non-empty: one byte per MCU in raster order (MCUs are
  // 16x16 for 4:2:0, 8x8 otherwise); non-zero = code this MCU.
  std::vector<uint8_t> region;
  // Tuning (the defaults are what the benchmarks measure).
  int slope = -1;          // perceptual slope 0..16 of the tables; -1 = default
  int chroma_delta = 999;  // chroma quantiser index - luma index; 999 = default
  double lambda_scale = 1.0;
  bool rdo = true;         // trellis quantisation; false = round to nearest
  uint32_t max_chunk_payload = 4096;  // IMGD payload limit (the stream's max_chunk_payload)
  // Tools (bench_texture_train): zeros and ones coded per context, added up
  // over encodes, in the declaration order of vds::image_model::Contexts.
  std::vector<std::array<uint64_t, 2>>* context_counts = nullptr;
};

struct EncodedImage {
  ImageHeader header;
  std::vector<uint8_t> imgh;               // IMGH payload
  std::vector<std::vector<uint8_t>> imgd;  // IMGD payloads in order
  Planes recon;                            // what the client decoder will hold
  double psnr = 0;                         // against the source (see ImageEncodeOptions)
  bool target_met = true;                  // false if a rate target could not be reached

  // Bytes the image adds to a stream: payloads plus chunk framing.
  size_t coded_bytes() const;
  // Largest IMGD payload (the max_chunk_payload a stream needs for it).
  uint32_t max_payload() const;
};

// Quality 0..100 -> luma quantiser index 0..255 (JPEG-like scale: quality 50
// gives a DC step of 16, every 32 index steps double the step).
int quality_to_index(int quality);

// Encodes Y'CbCr planes; throws std::invalid_argument on bad options (sizes,
// a residual without prediction, a region mask of the wrong size, a chunk
// limit too small for one MCU).
EncodedImage encode_planes(const Planes& src, const ImageEncodeOptions& o);
// Encodes an RGB/grey image (converted with rgb_to_planes); psnr is RGB PSNR
// (grey PSNR for grey coding).
EncodedImage encode_image(const Image& img, const ImageEncodeOptions& o);

// One encode at explicit quantiser indices (no rate control).
EncodedImage encode_planes_at(const Planes& src, int quant_luma, int quant_chroma, const ImageEncodeOptions& o);

// Appends IMGH and the IMGD chunks.
void add_image_chunks(StreamWriter& w, const EncodedImage& e);
// A whole images-mode stream holding this image (HEAD, IMGH, IMGD..., END),
// with max_chunk_payload and workspace_bytes set for it.
std::vector<uint8_t> image_stream(const EncodedImage& e);

// --- Host wrappers around the client decoders (vds::ImageDecoder,
// vds::JpegDecoder), as a device would run them ------------------------------

struct DecodedImage {
  Image rgb;         // the first image of the stream as the client shows it, RGB888
  std::string kind;  // "vds" or "jpeg"
};

// Where play_stream_image puts the first image's RGB888 rows: begin() once
// with the image's size (as its header declares it: refuse there what is
// too large to take), then rows() top to bottom. An exception from either
// ends the play and is thrown by play_stream_image.
struct ImageRowSink {
  virtual ~ImageRowSink() = default;
  virtual void begin(int width, int height) = 0;
  virtual void rows(int y, int count, const uint8_t* pixels, ptrdiff_t stride) = 0;
};

// Plays a stream through the client's vds::Player (RGB888 bands), the first
// image to `sink`, in memory of one band; returns its kind ("vds" or
// "jpeg"). The stream must be whole and well formed; same throws as below.
std::string play_stream_image(std::span<const uint8_t> stream, const Planes* prediction, ImageRowSink& sink);

// Plays a stream through the client's vds::Player (RGB888 bands) and keeps
// its first image (IMGH/IMGD or JPEG chunks). `prediction` is the
// destination's prior content for residual and region images (null:
// black). Throws std::runtime_error with the client's status and detail.
DecodedImage decode_stream_image(std::span<const uint8_t> stream, const Planes* prediction = nullptr);

// The client image decoder's Y'CbCr reconstruction of an encoded image (its
// IMGH and IMGD payloads, no stream around them): what `recon` must equal.
// `prediction` as above. Throws std::runtime_error.
Planes decode_image_planes(const EncodedImage& e, const Planes* prediction = nullptr);

}  // namespace vds::enc
