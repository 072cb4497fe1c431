// vds client library: the one status enum every entry point returns.
// Numbering is stable across versions: values are only ever added.
#pragma once
#include <cstdint>

namespace vds {

enum class Status : int32_t {
  ok = 0,                    // done; output is valid
  more_input = 1,            // not an error: the call consumed everything and wants more bytes
  truncated = -1,            // input ended inside an item that cannot be resumed
  workspace_too_small = -2,  // the caller's workspace cannot hold what the stream declares
  malformed = -3,            // bytes that no valid encoder produces (bad code, out-of-range value)
  unsupported_version = -4,  // stream major version newer than this decoder
  unsupported_feature = -5,  // valid stream using a feature this build leaves out
  aborted = -6,              // a caller callback returned false
  bad_crc = -7,              // a CRC-32C did not match the data it covers
  invalid_argument = -8,     // caller misuse: null pointer, zero size, call out of order
  output_too_small = -9,     // the caller's output buffer is smaller than the result
  io_error = -10,            // a caller-supplied read callback reported failure
};

constexpr bool is_error(Status s) { return static_cast<int32_t>(s) < 0; }

// Short fixed name of a status ("ok", "truncated", ...). With
// VDS_CONFIG_STATUS_NAMES == 0 every name is "" so the strings cost no flash.
const char* status_name(Status s);

}  // namespace vds
