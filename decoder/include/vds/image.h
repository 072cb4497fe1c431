// vds client library: the vds image codec decoder (8x8 DCT, Y'CbCr, context-
// adaptive binary arithmetic coding; docs/texture-codec.md) and the pixel
// targets it shares with the baseline JPEG decoder (vds/jpeg.h).
//
// An image travels as one IMGH chunk (ImageHeader) followed by IMGD chunks,
// each holding whole MCUs (docs/stream-format.md). The decoder consumes the
// chunk payloads one by one and writes each MCU to the caller's target as soon
// as it is decoded: into caller-owned Y'CbCr planes, into a caller-owned
// RGB565/RGB888 frame, or by rectangles / bands to a callback.
//
// Memory: the ImageDecoder object (about 300 bytes) plus
// ImageDecoder::kWorkspaceBytes carved from the caller's Arena at init(). Both
// are constants: nothing depends on the image size.
#pragma once
#include <cstddef>
#include <cstdint>

#include "vds/arena.h"
#include "vds/arith.h"
#include "vds/container.h"
#include "vds/image_model.h"
#include "vds/render.h"
#include "vds/status.h"

namespace vds {

// --- Pixel targets (shared with JpegDecoder) ----------------------------------

// Packed pixels use the library's PixelFormat (vds/render.h): rgb565 as
// native-endian 16-bit words (R in bits 15..11), rgb888 as R, G, B bytes.

// A rectangle of packed pixels handed to a callback. `pixels` points at the
// rectangle's top-left pixel, rows `stride` bytes apart; valid only during
// the call.
struct PixelRect {
  uint16_t x, y, w, h;
  const uint8_t* pixels;
  ptrdiff_t stride;
};

// Returns false to stop decoding (the decoder then returns Status::aborted).
using EmitFn = bool (*)(void* ctx, const PixelRect& rect);

// Residual images with a packed or callback target (and, when given, the
// uncoded MCUs of a region image on such a target): fills the prediction of
// the rectangle (x, y, w, h) of the image (luma samples; the chroma
// rectangle is the same scaled by the chroma subsampling, rounded up) into
// y/cb/cr, rows y_stride / c_stride bytes apart. Returns false to abort.
using PredictFn = bool (*)(void* ctx, uint16_t x, uint16_t y, uint16_t w, uint16_t h, uint8_t* y_out,
                           ptrdiff_t y_stride, uint8_t* cb_out, uint8_t* cr_out, ptrdiff_t c_stride);

// Where decoded pixels go. Build one with the helpers below; `planar`
// selects Y'CbCr planes, otherwise `format` gives the packed pixels.
//  - planes: data[0..2] = Y, Cb, Cr planes (Cb/Cr absent for grey), stride[i]
//    bytes per row. Chroma planes are at the coded resolution (4:2:0:
//    ceil(w/2) x ceil(h/2); JPEG 4:2:2: ceil(w/2) x h). A residual image adds
//    to what the planes hold; a region image writes only its blocks.
//  - frame: data[0] = a packed frame of the image's size, stride[0] bytes per
//    row; only pixels inside the image are written.
//  - rects: emit() is called once per MCU with the MCU's pixels (clipped to
//    the image) from the workspace.
//  - bands: data[0] = a caller-owned band buffer at least image-width pixels
//    wide and one MCU row (16 lines at most) high; emit() is called once per
//    MCU row with the band (x = 0, full width). In a region image MCUs
//    that are not coded leave the band buffer as it was, or show the
//    prediction when predict is given.
struct ImageTarget {
  bool planar = false;
  PixelFormat format = PixelFormat::rgb565;
  uint8_t* data[3] = {nullptr, nullptr, nullptr};
  ptrdiff_t stride[3] = {0, 0, 0};
  EmitFn emit = nullptr;
  void* emit_ctx = nullptr;
  PredictFn predict = nullptr;  // residual images with a packed target
  void* predict_ctx = nullptr;

  static ImageTarget planes(uint8_t* y, ptrdiff_t y_stride, uint8_t* cb, ptrdiff_t cb_stride, uint8_t* cr,
                            ptrdiff_t cr_stride) {
    ImageTarget t;
    t.planar = true;
    t.data[0] = y;
    t.data[1] = cb;
    t.data[2] = cr;
    t.stride[0] = y_stride;
    t.stride[1] = cb_stride;
    t.stride[2] = cr_stride;
    return t;
  }
  static ImageTarget frame(PixelFormat f, uint8_t* pixels, ptrdiff_t stride_bytes) {
    ImageTarget t;
    t.format = f;
    t.data[0] = pixels;
    t.stride[0] = stride_bytes;
    return t;
  }
  static ImageTarget rects(PixelFormat f, EmitFn emit, void* ctx) {
    ImageTarget t;
    t.format = f;
    t.emit = emit;
    t.emit_ctx = ctx;
    return t;
  }
  static ImageTarget bands(PixelFormat f, uint8_t* band, ptrdiff_t stride_bytes, EmitFn emit, void* ctx) {
    ImageTarget t = frame(f, band, stride_bytes);
    t.emit = emit;
    t.emit_ctx = ctx;
    return t;
  }
};

// JFIF Y'CbCr -> R'G'B' (full range, ITU-T T.871 clause 7), in Q16 with
// round to nearest; one pixel. Exposed so that host tools reproduce the
// client's colours exactly.
void ycbcr_to_rgb(int y, int cb, int cr, uint8_t rgb[3]);
inline uint16_t pack_rgb565(uint8_t r, uint8_t g, uint8_t b) {
  return static_cast<uint16_t>(((r & 0xF8u) << 8) | ((g & 0xFCu) << 3) | (b >> 3));
}

// --- The vds image header (IMGH chunk) -----------------------------------------

namespace chunk {
constexpr uint32_t kImageHeader = fourcc('I', 'M', 'G', 'H');  // vds image header (ImageHeader)
constexpr uint32_t kImageData = fourcc('I', 'M', 'G', 'D');    // vds image data: whole MCUs
}  // namespace chunk

enum class ChromaFormat : uint8_t {
  grey = 0,  // Y' only
  yuv420 = 1,
  yuv444 = 2,
};

// Header flags.
constexpr uint8_t kImageFlagResidual = 0x01;  // the coded data is added to a prediction
constexpr uint8_t kImageFlagRegion = 0x02;    // a per-MCU "coded" flag; only coded MCUs are written
constexpr uint8_t kImageFlagDcPred = 0x04;    // DC levels are predicted from neighbouring blocks
constexpr uint8_t kImageFlagsKnown = 0x07;

constexpr uint8_t kImageCodecVersion = 1;
constexpr uint32_t kImageHeaderBytes = 12;
constexpr uint16_t kImageMaxSide = 16384;
// Quantiser indices: the base step is 2^(index/32), 1 .. 250 (image_model.h).
constexpr int kQuantIndexMax = 255;
// Largest perceptual slope (16 = the full T.81 Annex K shape).
constexpr int kQuantSlopeMax = 16;

struct ImageHeader {
  uint8_t version = kImageCodecVersion;
  ChromaFormat chroma = ChromaFormat::yuv420;
  uint8_t flags = kImageFlagDcPred;
  uint8_t quant_luma = 64;    // quantiser index of Y'
  uint8_t quant_chroma = 64;  // quantiser index of Cb and Cr
  uint8_t slope = 0;          // perceptual slope 0..16 of the quantisation tables
  uint16_t width = 0;
  uint16_t height = 0;
  uint16_t reserved = 0;  // 0 in version 1

  bool residual() const { return (flags & kImageFlagResidual) != 0; }
  bool region() const { return (flags & kImageFlagRegion) != 0; }
  int components() const { return chroma == ChromaFormat::grey ? 1 : 3; }
  // MCU size in luma pixels: 16x16 for 4:2:0, 8x8 otherwise.
  int mcu_size() const { return chroma == ChromaFormat::yuv420 ? 16 : 8; }
  int mcus_x() const { return (width + mcu_size() - 1) / mcu_size(); }
  int mcus_y() const { return (height + mcu_size() - 1) / mcu_size(); }
  uint32_t mcu_count() const { return static_cast<uint32_t>(mcus_x()) * static_cast<uint32_t>(mcus_y()); }
  int chroma_width() const { return chroma == ChromaFormat::yuv420 ? (width + 1) / 2 : width; }
  int chroma_height() const { return chroma == ChromaFormat::yuv420 ? (height + 1) / 2 : height; }
};

// IMGH payload <-> header. Parsing checks every field (version, chroma,
// flags, indices, sizes, reserved) and refuses a newer version
// (unsupported_version) or unknown flags (unsupported_feature).
Status image_header_from_bytes(const uint8_t* payload, uint32_t size, ImageHeader* out);
void image_header_to_bytes(const ImageHeader& h, uint8_t out[kImageHeaderBytes]);

// The 64 quantiser steps (zig-zag order) for a quantiser index and slope;
// `chroma` selects the chroma shape. Steps are 1..2047.
void image_quant_table(int index, int slope, bool chroma, uint16_t out_zigzag[64]);

// Smooths the edges between 8x8 blocks of a decoded planar image in
// place, where a step across an edge is small enough to come from the
// quantisation of its DC (under four times dc_step / 8) and both sides
// are smooth: flat sides become a ramp over the eight samples, others move the
// two samples next to the edge a quarter of the step together. What the
// walkthrough's views get after their image (docs/walkthrough.md); integer
// arithmetic, the same on every machine.
void image_deblock_plane(uint8_t* plane, int width, int height, ptrdiff_t stride, int dc_step);
// Each plane with its own DC step (the header's quantisers).
void image_deblock(const ImageHeader& h, const ImageTarget& planes);

// IMGD payload: u32 first MCU index, u16 number of MCUs, then the range
// coder's bytes for exactly those MCUs.
constexpr uint32_t kImageDataPrefixBytes = 6;

// --- Stage accounting (measurement builds) ---------------------------------------

// Where a decoder spends its work, for benchmarks and the firmware's frame
// records: the decoder calls `now` (an instruction or cycle counter) where
// each stage begins and adds the difference to that stage's total. The
// caller owns it and reads `spent`; without one (the default) the decoder
// pays one test per block.
struct StageClock {
  enum Stage : int8_t { idle = -1, entropy = 0, transform = 1, colour = 2 };
  static constexpr int kStages = 3;
  uint64_t (*now)(void* ctx) = nullptr;
  void* ctx = nullptr;
  uint64_t spent[kStages] = {};  // entropy decoding; dequantisation and IDCT; colour conversion and output
  uint64_t last = 0;
  int8_t current = idle;

  void enter(Stage s) {
    const uint64_t t = now(ctx);
    if (current != idle) spent[current] += t - last;
    last = t;
    current = s;
  }
};

// --- The decoder -------------------------------------------------------------------

class ImageDecoder {
 public:
  // Workspace carved at init(): the adaptive contexts, one coefficient
  // block, one MCU of Y'CbCr samples and one MCU of packed pixels (the
  // alignment slack of each allocation included).
  static constexpr size_t kCoefBytes = 64 * sizeof(int16_t);
  static constexpr size_t kMcuSampleBytes = 16 * 16 + 2 * 8 * 8;
  static constexpr size_t kPackedBytes = 16 * 16 * 3;
  static constexpr size_t kWorkspaceBytes = sizeof(image_model::PackedContexts) + alignof(image_model::PackedContexts) +
                                            kCoefBytes + alignof(int16_t) + kMcuSampleBytes + kPackedBytes;

  // Carves the workspace from the arena (workspace_too_small if it does not fit).
  Status init(Arena& arena);

  // Starts an image from its IMGH payload. The target must suit the image:
  // planes need the planes (Y only for grey) with strides of at least the
  // plane widths; a frame needs data[0] and a stride of at least
  // width x pixel size; bands need the same and emit; rects need emit. A
  // residual image with a packed target needs predict. invalid_argument
  // otherwise. Resets the contexts.
  Status start(const uint8_t* imgh, uint32_t size, const ImageTarget& target);

  // Decodes one IMGD payload. Returns more_input while MCUs remain, ok after
  // the last MCU, or the first error (latched). Chunks must come in order and
  // each must be consumed exactly (malformed otherwise).
  Status feed(const uint8_t* imgd, uint32_t size);

  // Convenience for a ChunkSink: IMGH starts (with `target`), IMGD feeds.
  // Returns more_input/ok/error as above; other types return ok untouched.
  Status on_chunk(uint32_t type, const uint8_t* payload, uint32_t size, const ImageTarget& target);

  // Accounts the work per stage into `clock` from now on (nullptr: stop).
  // Time spent in the target's callbacks counts as colour output.
  void set_stage_clock(StageClock* clock) { clock_ = clock; }

  bool done() const { return started_ && next_mcu_ == header_.mcu_count() && status_ == Status::ok; }
  Status status() const { return status_; }
  const ImageHeader& header() const { return header_; }
  uint32_t mcus_decoded() const { return next_mcu_; }

  // Neighbour information of a block, for prediction and context selection.
  struct BlockInfo {
    int16_t dc;     // DC level
    uint8_t nz;     // nonzero AC coefficients
    uint8_t flags;  // kInfoAvailable | kInfoCoded | kInfoDcNonzero
  };
  static constexpr uint8_t kInfoAvailable = 1;
  static constexpr uint8_t kInfoCoded = 2;
  static constexpr uint8_t kInfoDcResidual = 4;

 private:
  Status decode_mcu(uint32_t mcu);
  void copy_mcu_planes(int x0, int y0, bool to_target);
  bool fetch_prediction(int x0, int y0);
  Status deliver_mcu(int x0, int y0, bool row_end);
  int decode_block(image_model::RangeDecoder& rd, int comp, int bx, int by, bool first_col, int16_t* coef);

  StageClock* clock_ = nullptr;
  image_model::RangeDecoder rd_{};  // the current IMGD chunk
  image_model::PackedContexts* ctx_ = nullptr;
  int16_t* coef_ = nullptr;     // one block, natural order
  uint8_t* mcu_pix_ = nullptr;  // Y'CbCr samples of one MCU: Y 16x16, Cb 8x8, Cr 8x8
  uint8_t* packed_ = nullptr;   // one MCU of packed pixels (rects targets)
  ImageHeader header_{};
  ImageTarget target_{};
  uint16_t quant_[2][64] = {};  // natural order: luma, chroma
  // Neighbours: the blocks of the MCU being decoded (2x2 for 4:2:0 luma),
  // the right column of the previous MCU and the bottom row of the first MCU
  // of the previous MCU row, per component.
  BlockInfo cur_[3][4] = {};
  BlockInfo left_[3][2] = {};
  BlockInfo row_start_[3][2] = {};
  int16_t last_dc_[3] = {};
  uint8_t last_nz_[3] = {};
  uint32_t next_mcu_ = 0;
  uint8_t prev_coded_ = 1;
  bool started_ = false;
  Status status_ = Status::invalid_argument;
};

}  // namespace vds
