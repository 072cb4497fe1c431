// vds link core: Consistent Overhead Byte Stuffing, the frame encoding of
// the link (docs/protocol.md). Encoded data contains no 0x00 byte, so 0x00
// delimits frames and a receiver resynchronises at the next delimiter.
#pragma once
#include <cstddef>
#include <cstdint>

#include "vds/status.h"

namespace vds::link {

// Worst-case encoded size of `n` bytes (without the 0x00 delimiter): one
// code byte per started block of 254 data bytes, and at least one.
constexpr size_t cobs_encoded_bound(size_t n) { return n + n / 254 + 1; }

// Encodes `in` into `out` (which must hold cobs_encoded_bound(n) bytes).
// Writes no delimiter. Returns output_too_small (writing nothing useful)
// when `out_size` is below the bound.
Status cobs_encode(const uint8_t* in, size_t n, uint8_t* out, size_t out_size, size_t* out_len);

// Decodes one frame body (no delimiter). A zero byte inside, a code byte
// that points past the end, or output overflow is an error; `out` may alias
// `in` (decoding in place never writes ahead of reading).
Status cobs_decode(const uint8_t* in, size_t n, uint8_t* out, size_t out_size, size_t* out_len);

}  // namespace vds::link
