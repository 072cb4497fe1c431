// Host writer of the vds stream container (docs/stream-format.md).
#include "vds/enc/stream_writer.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>

#include "vds/crc32c.h"

namespace vds::enc {
namespace {

void append_u32(std::vector<uint8_t>& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<uint8_t>(v >> (8 * i)));
}

}  // namespace

StreamHeader default_header(StreamMode mode, uint16_t width, uint16_t height) {
  StreamHeader h{};
  h.version_major = kStreamVersionMajor;
  h.version_minor = kStreamVersionMinor;
  h.mode = mode;
  h.width = width;
  h.height = height;
  return h;
}

StreamWriter::StreamWriter(const StreamHeader& header) : header_(header) {
  header_.version_major = kStreamVersionMajor;
  header_.version_minor = kStreamVersionMinor;
  uint8_t payload[kHeaderPayloadV1];
  header_to_bytes(header_, payload);
  StreamHeader check{};
  const Status s = header_from_bytes(payload, kHeaderPayloadV1, kStreamVersionMajor, kStreamVersionMinor, &check);
  if (s != Status::ok) throw std::invalid_argument(std::string("stream header refused: ") + status_name(s));
  out_.insert(out_.end(), std::begin(kStreamMagic), std::end(kStreamMagic));
  out_.push_back(kStreamVersionMajor);
  out_.push_back(kStreamVersionMinor);
  out_.push_back(0);
  out_.push_back(0);
  put_chunk(chunk::kHeader, payload);
}

void StreamWriter::put_chunk(uint32_t type, std::span<const uint8_t> payload) {
  // HEAD's CRC also covers the preamble (docs/stream-format.md).
  const size_t start = type == chunk::kHeader ? 0 : out_.size();
  append_u32(out_, type);
  append_u32(out_, static_cast<uint32_t>(payload.size()));
  out_.insert(out_.end(), payload.begin(), payload.end());
  append_u32(out_, crc32c(out_.data() + start, out_.size() - start));
  ++chunks_;
}

void StreamWriter::add_chunk(uint32_t type, std::span<const uint8_t> payload) {
  if (finished_) throw std::logic_error("stream already finished");
  if (type == chunk::kHeader || type == chunk::kEnd)
    throw std::invalid_argument("HEAD and END chunks are written by the stream writer itself");
  if (payload.size() > header_.max_chunk_payload)
    throw std::invalid_argument("chunk " + fourcc_name(type) + " payload of " + std::to_string(payload.size()) +
                                " bytes exceeds the header's max_chunk_payload of " +
                                std::to_string(header_.max_chunk_payload));
  put_chunk(type, payload);
}

void StreamWriter::add_meta(const std::string& key, const std::string& value) {
  if (key.find_first_of("=\n") != std::string::npos || value.find('\n') != std::string::npos)
    throw std::invalid_argument("META key must not contain '=' or newlines, value must not contain newlines");
  const std::string line = key + "=" + value + "\n";
  add_chunk(chunk::kMeta, std::span(reinterpret_cast<const uint8_t*>(line.data()), line.size()));
}

std::vector<uint8_t> StreamWriter::finish() {
  if (finished_) throw std::logic_error("stream already finished");
  uint8_t count[4];
  for (int i = 0; i < 4; ++i) count[i] = static_cast<uint8_t>(chunks_ >> (8 * i));
  put_chunk(chunk::kEnd, count);
  finished_ = true;
  return std::move(out_);
}

std::vector<uint8_t> read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open for reading");
  std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw std::runtime_error(path + ": read error");
  return bytes;
}

void write_file(const std::string& path, std::span<const uint8_t> bytes) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error(path + ": cannot open for writing");
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    if (!out) throw std::runtime_error(path + ": write error");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw std::runtime_error(path + ": cannot replace: " + ec.message());
}

std::string fourcc_name(uint32_t type) {
  std::string s;
  for (int i = 0; i < 4; ++i) {
    const unsigned char c = static_cast<unsigned char>(type >> (8 * i));
    if (c >= 0x20 && c < 0x7F) {
      s += static_cast<char>(c);
    } else {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02X", c);
      s += buf;
    }
  }
  return s;
}

uint32_t fourcc_from_string(const std::string& s) {
  if (s.size() != 4) throw std::invalid_argument("chunk type '" + s + "' must be exactly 4 characters");
  for (char c : s)
    if (c < 0x20 || c > 0x7E) throw std::invalid_argument("chunk type '" + s + "' must be printable ASCII");
  return fourcc(s[0], s[1], s[2], s[3]);
}

}  // namespace vds::enc
