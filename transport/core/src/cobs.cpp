// COBS (Cheshire & Baker, "Consistent Overhead Byte Stuffing", 1999):
// each block is a code byte c followed by c-1 non-zero data bytes; c < 0xFF
// means a zero byte follows the block (except at the very end).
#include "vds/link/cobs.h"

namespace vds::link {

namespace {
constexpr uint8_t kMaxCode = 0xFF;  // a block of 254 data bytes with no implied zero
}

Status cobs_encode(const uint8_t* in, size_t n, uint8_t* out, size_t out_size, size_t* out_len) {
  if ((in == nullptr && n != 0) || out == nullptr || out_len == nullptr) return Status::invalid_argument;
  if (out_size < cobs_encoded_bound(n)) return Status::output_too_small;
  size_t code_at = 0;  // where the current block's code byte goes
  size_t w = 1;
  uint8_t code = 1;
  for (size_t i = 0; i < n; ++i) {
    if (in[i] == 0) {
      out[code_at] = code;
      code_at = w++;
      code = 1;
      continue;
    }
    out[w++] = in[i];
    if (++code == kMaxCode) {
      out[code_at] = code;
      code_at = w++;
      code = 1;
    }
  }
  out[code_at] = code;
  *out_len = w;
  return Status::ok;
}

Status cobs_decode(const uint8_t* in, size_t n, uint8_t* out, size_t out_size, size_t* out_len) {
  if ((in == nullptr && n != 0) || (out == nullptr && out_size != 0) || out_len == nullptr)
    return Status::invalid_argument;
  if (n == 0) return Status::malformed;
  size_t r = 0;
  size_t w = 0;
  while (r < n) {
    const uint8_t code = in[r++];
    if (code == 0) return Status::malformed;
    const size_t data = static_cast<size_t>(code) - 1;
    if (data > n - r) return Status::malformed;
    if (data > out_size - w) return Status::output_too_small;
    for (size_t k = 0; k < data; ++k) {
      const uint8_t b = in[r++];
      if (b == 0) return Status::malformed;
      out[w++] = b;
    }
    // A block shorter than the maximum implies a zero, unless it ends the frame.
    if (code != kMaxCode && r < n) {
      if (w >= out_size) return Status::output_too_small;
      out[w++] = 0;
    }
  }
  *out_len = w;
  return Status::ok;
}

}  // namespace vds::link
