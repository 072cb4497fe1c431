// vds image codec: the IMGH header and the quantisation tables (perceptual
// shapes from ITU-T T.81 Annex K, scaled by a quantiser index and a slope).
#include "vds/image.h"
#include "vds/bytes.h"

namespace vds {

namespace {

// The shapes of T.81's Annex K tables (image_model::kAnnexKLuma, kAnnexKChroma)
// are used only relative to their DC entries.

// Q8 (256 = 1.0) weight of each zig-zag position at full slope: K[k] / K[0].
constexpr int kWeightFracBits = 8;
struct Shape {
  int16_t w[64];
};
constexpr Shape make_shape(const uint8_t* k) {
  Shape s{};
  for (int i = 0; i < 64; ++i) {
    const int v = k[image_model::kZigzag[i]];
    s.w[i] = static_cast<int16_t>((v * (1 << kWeightFracBits) + k[0] / 2) / k[0]);
  }
  return s;
}
constexpr Shape kLumaShape = make_shape(image_model::kAnnexKLuma);
constexpr Shape kChromaShape = make_shape(image_model::kAnnexKChroma);

// 2^(j/32) in Q15 for j = 0..31: the base step of index i is
// 2^(i >> 5) * kPow2FracQ15[i & 31] / 2^15.
constexpr int kPowFracBits = 15;
constexpr uint32_t kPow2FracQ15[32] = {32768, 33486, 34219, 34968, 35734, 36516, 37316, 38133,
                                       38968, 39821, 40693, 41584, 42495, 43425, 44376, 45348,
                                       46341, 47356, 48393, 49452, 50535, 51642, 52773, 53928,
                                       55109, 56316, 57549, 58809, 60097, 61413, 62757, 64132};
// Base step in Q8: Q15 mantissa shifted down by 15 - 8 bits.
constexpr int kBaseFracBits = 8;
// base (Q8) * weight (Q8) is the step in Q16; round to nearest.
constexpr int kStepShift = kBaseFracBits + kWeightFracBits;
constexpr uint32_t kStepRound = uint32_t{1} << (kStepShift - 1);
constexpr int kMaxStep = 2047;


}  // namespace

void image_quant_table(int index, int slope, bool chroma, uint16_t out[64]) {
  if (index < 0) index = 0;
  if (index > kQuantIndexMax) index = kQuantIndexMax;
  if (slope < 0) slope = 0;
  if (slope > kQuantSlopeMax) slope = kQuantSlopeMax;
  // index <= 255: the shift is at most 7 and the Q8 base at most 64132.
  const uint32_t base_q8 = (kPow2FracQ15[index & 31] << (index >> 5)) >> (kPowFracBits - kBaseFracBits);
  const Shape& shape = chroma ? kChromaShape : kLumaShape;
  for (int k = 0; k < 64; ++k) {
    // Weight 1.0 + (shape - 1.0) * slope / 16, in Q8; at least 1/256.
    const int32_t excess = shape.w[k] - (1 << kWeightFracBits);
    int32_t w = (1 << kWeightFracBits) + (excess * slope) / kQuantSlopeMax;
    if (w < 1) w = 1;
    const uint32_t step = (base_q8 * static_cast<uint32_t>(w) + kStepRound) >> kStepShift;
    out[k] = static_cast<uint16_t>(step < 1 ? 1 : (step > kMaxStep ? kMaxStep : step));
  }
}

Status image_header_from_bytes(const uint8_t* p, uint32_t size, ImageHeader* out) {
  if (p == nullptr || out == nullptr) return Status::invalid_argument;
  if (size < kImageHeaderBytes) return Status::truncated;
  if (size > kImageHeaderBytes) return Status::malformed;
  ImageHeader h;
  h.version = p[0];
  if (h.version != kImageCodecVersion) return h.version > kImageCodecVersion ? Status::unsupported_version
                                                                             : Status::malformed;
  if (p[1] > static_cast<uint8_t>(ChromaFormat::yuv444)) return Status::unsupported_feature;
  h.chroma = static_cast<ChromaFormat>(p[1]);
  h.flags = p[2];
  if ((h.flags & ~kImageFlagsKnown) != 0) return Status::unsupported_feature;
  h.quant_luma = p[3];
  h.quant_chroma = p[4];
  h.slope = p[5];
  if (h.slope > kQuantSlopeMax) return Status::malformed;
  h.width = load_le16(p + 6);
  h.height = load_le16(p + 8);
  h.reserved = load_le16(p + 10);
  if (h.width == 0 || h.height == 0 || h.width > kImageMaxSide || h.height > kImageMaxSide) return Status::malformed;
  if (h.reserved != 0) return Status::malformed;
  *out = h;
  return Status::ok;
}

void image_header_to_bytes(const ImageHeader& h, uint8_t out[kImageHeaderBytes]) {
  out[0] = h.version;
  out[1] = static_cast<uint8_t>(h.chroma);
  out[2] = h.flags;
  out[3] = h.quant_luma;
  out[4] = h.quant_chroma;
  out[5] = h.slope;
  out[6] = static_cast<uint8_t>(h.width);
  out[7] = static_cast<uint8_t>(h.width >> 8);
  out[8] = static_cast<uint8_t>(h.height);
  out[9] = static_cast<uint8_t>(h.height >> 8);
  out[10] = static_cast<uint8_t>(h.reserved);
  out[11] = static_cast<uint8_t>(h.reserved >> 8);
}

}  // namespace vds
