// JFIF / ITU-T T.871 full-range Y'CbCr -> R'G'B' in Q16, shared by the image
// output stage and the renderer's texel fetch so both give the same pixels:
// R = Y + 1.402 Cr', G = Y - 0.34414 Cb' - 0.71414 Cr', B = Y + 1.772 Cb',
// with Cb' = Cb - 128, Cr' = Cr - 128; each coefficient round(c * 2^16).
#pragma once
#include <cstdint>

namespace vds::colour {

constexpr int kFracBits = 16;
constexpr int32_t kCrToR = 91881;
constexpr int32_t kCbToG = 22554;
constexpr int32_t kCrToG = 46802;
constexpr int32_t kCbToB = 116130;
constexpr int32_t kHalf = int32_t{1} << (kFracBits - 1);  // round to nearest before the shift
constexpr int kChromaCentre = 128;

}  // namespace vds::colour
