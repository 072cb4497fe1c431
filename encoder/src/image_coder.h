// vds encoder, private: the block coder of the vds image codec, the exact
// mirror of vds::ImageDecoder's block syntax (vds/image_model.h), and the
// rate-distortion optimised choice of levels that uses its cost estimates.
#pragma once
#include <array>
#include <cstdint>

#include "vds/enc/arith_encoder.h"
#include "vds/image.h"
#include "vds/image_model.h"

namespace vds::enc::detail {

using Info = vds::ImageDecoder::BlockInfo;

// Everything the coder carries from block to block (contexts and the
// neighbour information the decoder keeps). Plain data: copied to roll an
// MCU back when it does not fit the current chunk.
struct CoderState {
  image_model::Contexts ctx;
  Info cur[3][4];
  Info left[3][2];
  Info row_start[3][2];
  int16_t last_dc[3];
  uint8_t last_nz[3];
  uint8_t prev_coded;
  // Training statistics: when set, zeros and ones coded per context (in the
  // declaration order of image_model::Contexts).
  std::array<uint64_t, 2>* counts;

  void reset(int quant_luma, int quant_chroma);
};

// Codes a bin with a context of `s`, counting it when training.
inline void code_bin(ArithEncoder& ae, CoderState& s, ArithContext& ctx, int bin) {
  if (s.counts != nullptr) {
    const size_t i = static_cast<size_t>(reinterpret_cast<const uint8_t*>(&ctx) - reinterpret_cast<const uint8_t*>(&s.ctx)) /
                     sizeof(ArithContext);
    ++s.counts[i][bin];
  }
  ae.encode_bit(ctx, bin);
}

// What the neighbours of a block give it: DC prediction, predicted nz and
// the context indices that depend on them.
struct BlockEnv {
  int cls;
  int32_t pred_dc;
  uint32_t pred_nz;
  int cbf_ctx;
  int dz_ctx;
};

BlockEnv block_env(const CoderState& s, const ImageHeader& h, int comp, int bx, int by, bool first_col);

// Codes one block. levels[0] is the DC level, levels[1..63] the AC levels in
// zig-zag order. Updates contexts and neighbour information.
void encode_block(ArithEncoder& ae, CoderState& s, const ImageHeader& h, const BlockEnv& env, int comp, int bx,
                  int by, const int32_t levels[64]);

// After the blocks of an MCU (mx = its column): neighbours for the next MCU.
void end_mcu(CoderState& s, const ImageHeader& h, int mx);
// A region MCU that is not coded.
void skip_mcu(CoderState& s, int mx);

struct RdoParams {
  bool rdo;       // false: round to nearest
  double lambda;  // squared error (luma units) per bit
  double weight;  // distortion weight of this component
};

// Chooses the levels of a block: coef_zz are the DCT coefficients in
// zig-zag order, q the steps (zig-zag order).
void choose_levels(const CoderState& s, const BlockEnv& env, const double coef_zz[64], const uint16_t q[64],
                   const RdoParams& p, int32_t levels[64]);

// Default chroma quantiser index minus luma index.
int default_chroma_delta(ChromaFormat c);

// Dequantised coefficient as the decoder computes it.
inline int16_t dequantise_ac(int32_t level, uint32_t q) {
  const uint32_t mag = static_cast<uint32_t>(level < 0 ? -level : level);
  const uint64_t v = static_cast<uint64_t>(mag) * q;
  return static_cast<int16_t>(level < 0 ? -static_cast<int32_t>(v > 2048 ? 2048 : v)
                                        : static_cast<int32_t>(v > 2047 ? 2047 : v));
}
inline int16_t dequantise_dc(int32_t level, uint32_t q) {
  const int64_t v = static_cast<int64_t>(level) * q;
  return static_cast<int16_t>(v < -2048 ? -2048 : (v > 2047 ? 2047 : v));
}

}  // namespace vds::enc::detail
