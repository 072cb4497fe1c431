// Host side of the stream container: writes the preamble, HEAD, chunks with
// their CRC-32C, and END (docs/stream-format.md).
#pragma once
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "vds/container.h"

namespace vds::enc {

// A header with the defaults of container v1.0: version filled in, no
// timing, no camera, budgets zero. Callers set what their mode needs.
StreamHeader default_header(StreamMode mode, uint16_t width, uint16_t height);

class StreamWriter {
 public:
  // Throws std::invalid_argument if the header would be refused by a client
  // with unlimited workspace (the same checks as header_from_bytes).
  explicit StreamWriter(const StreamHeader& header);

  // Appends a chunk. Throws std::invalid_argument for HEAD/END (written by
  // the writer itself) or a payload above header.max_chunk_payload.
  void add_chunk(uint32_t type, std::span<const uint8_t> payload);
  void add_meta(const std::string& key, const std::string& value);

  // Appends END and returns the whole stream; the writer is then spent.
  std::vector<uint8_t> finish();

  const StreamHeader& header() const { return header_; }
  size_t size() const { return out_.size(); }
  // The stream so far (HEAD and the chunks added), before END.
  std::span<const uint8_t> bytes() const { return out_; }

 private:
  void put_chunk(uint32_t type, std::span<const uint8_t> payload);

  StreamHeader header_;
  std::vector<uint8_t> out_;
  uint32_t chunks_ = 0;
  bool finished_ = false;
};

// Reads a whole file; throws std::runtime_error naming the file on failure.
std::vector<uint8_t> read_file(const std::string& path);
// Writes a whole file atomically enough for tools (temp + rename).
void write_file(const std::string& path, std::span<const uint8_t> bytes);

// "HEAD" from a type code; non-printable bytes as \xNN.
std::string fourcc_name(uint32_t type);
// Parses "ABCD" (exactly four printable ASCII bytes); throws otherwise.
uint32_t fourcc_from_string(const std::string& s);

}  // namespace vds::enc
