// Incremental parser of the vds stream container (docs/stream-format.md):
// preamble, then CRC-32C-checked, length-prefixed chunks, HEAD first, END last.
#include "vds/container.h"

#include <cstring>

#include "vds/config.h"
#include "vds/crc32c.h"
#include "vds/bytes.h"

namespace vds {
namespace {

constexpr uint32_t kMaxFrameSide = 16384;
constexpr uint32_t kMaxChunkPayloadLimit = 1u << 24;  // 16 MiB: far beyond any client


}  // namespace

void header_to_bytes(const StreamHeader& h, uint8_t out[kHeaderPayloadV1]) {
  out[0] = static_cast<uint8_t>(h.mode);
  out[1] = h.flags;
  store_le16(out + 2, h.width);
  store_le16(out + 4, h.height);
  store_le32(out + 6, h.frame_period_us);
  store_le32(out + 10, h.frame_count);
  store_le32(out + 14, static_cast<uint32_t>(h.focal_x_q16));
  store_le32(out + 18, static_cast<uint32_t>(h.focal_y_q16));
  store_le32(out + 22, static_cast<uint32_t>(h.center_x_q16));
  store_le32(out + 26, static_cast<uint32_t>(h.center_y_q16));
  store_le32(out + 30, static_cast<uint32_t>(h.near_q16));
  store_le32(out + 34, static_cast<uint32_t>(h.far_q16));
  store_le32(out + 38, h.max_chunk_payload);
  store_le32(out + 42, h.workspace_bytes);
  store_le32(out + 46, h.max_vertices);
  store_le32(out + 50, h.max_triangles);
}

Status header_from_bytes(const uint8_t* p, uint32_t size, uint8_t version_major, uint8_t version_minor,
                         StreamHeader* out) {
  if (p == nullptr || out == nullptr) return Status::invalid_argument;
  if (size < kHeaderPayloadV1) return Status::malformed;
  StreamHeader h{};
  h.version_major = version_major;
  h.version_minor = version_minor;
  if (p[0] >= kStreamModeCount) return Status::unsupported_feature;
  h.mode = static_cast<StreamMode>(p[0]);
  h.flags = p[1];
  if ((h.flags & ~kHeaderFlagInteractive) != 0 && version_minor <= kStreamVersionMinor) return Status::malformed;
  h.width = load_le16(p + 2);
  h.height = load_le16(p + 4);
  h.frame_period_us = load_le32(p + 6);
  h.frame_count = load_le32(p + 10);
  h.focal_x_q16 = load_le32s(p + 14);
  h.focal_y_q16 = load_le32s(p + 18);
  h.center_x_q16 = load_le32s(p + 22);
  h.center_y_q16 = load_le32s(p + 26);
  h.near_q16 = load_le32s(p + 30);
  h.far_q16 = load_le32s(p + 34);
  h.max_chunk_payload = load_le32(p + 38);
  h.workspace_bytes = load_le32(p + 42);
  h.max_vertices = load_le32(p + 46);
  h.max_triangles = load_le32(p + 50);
  if (h.width == 0 || h.height == 0 || h.width > kMaxFrameSide || h.height > kMaxFrameSide) return Status::malformed;
  if (h.max_chunk_payload > kMaxChunkPayloadLimit) return Status::malformed;
  if (h.focal_x_q16 < 0 || h.focal_y_q16 < 0) return Status::malformed;
  // Clip planes are either absent (both zero) or 0 < near < far.
  if (!(h.near_q16 == 0 && h.far_q16 == 0) && !(h.near_q16 > 0 && h.far_q16 > h.near_q16)) return Status::malformed;
  *out = h;
  return Status::ok;
}

Status StreamParser::init(Arena& arena, uint32_t chunk_capacity, const ChunkSink& sink) {
  *this = StreamParser();
  if (chunk_capacity < kHeaderPayloadMax) return fail(Status::invalid_argument, 0, VDS_DETAIL("chunk buffer below 256 bytes"));
  buf_ = arena.alloc_array<uint8_t>(chunk_capacity);
  if (buf_ == nullptr) return fail(Status::workspace_too_small, 0, VDS_DETAIL("workspace cannot hold the chunk buffer"));
  arena_ = &arena;
  capacity_ = chunk_capacity;
  sink_ = sink;
  state_ = State::preamble;
  status_ = Status::more_input;
  return Status::ok;
}

Status StreamParser::fail(Status s, uint64_t at, const char* detail) {
  state_ = State::failed;
  status_ = s;
  error_offset_ = at;
  error_detail_ = detail;
  return s;
}

Status StreamParser::on_chunk_head() {
  type_ = load_le32(small_);
  length_ = load_le32(small_ + 4);
  if (!have_header_ && type_ != chunk::kHeader)
    return fail(Status::malformed, item_offset_, VDS_DETAIL("first chunk is not HEAD"));
  if (have_header_ && type_ == chunk::kHeader)
    return fail(Status::malformed, item_offset_, VDS_DETAIL("second HEAD chunk"));
  if (length_ > limit_)
    return fail(Status::malformed, item_offset_, VDS_DETAIL("chunk payload longer than the stream's max_chunk_payload"));
  crc_ = crc32c_update(type_ == chunk::kHeader ? preamble_crc_ : 0, small_, kChunkHeadBytes);
  have_ = 0;
  state_ = length_ == 0 ? State::crc : State::payload;
  return Status::more_input;
}

Status StreamParser::on_chunk_complete() {
  const uint32_t stored = load_le32(small_);
  if (stored != crc_) return fail(Status::bad_crc, item_offset_, VDS_DETAIL("chunk CRC-32C mismatch"));
  ++chunks_;
  if (type_ == chunk::kHeader) {
    const Status s = header_from_bytes(buf_, length_, version_major_, version_minor_, &header_);
    if (s != Status::ok) return fail(s, item_offset_, VDS_DETAIL("invalid HEAD field"));
    if (header_.max_chunk_payload > capacity_)
      return fail(Status::workspace_too_small, item_offset_, VDS_DETAIL("stream's max_chunk_payload exceeds the chunk buffer"));
    const bool prefix = sink_.model_prefix && header_.mode == StreamMode::model;
    if (header_.workspace_bytes > arena_->remaining() && !prefix)
      return fail(Status::workspace_too_small, item_offset_, VDS_DETAIL("stream's workspace_bytes exceed the workspace left"));
    have_header_ = true;
    limit_ = header_.max_chunk_payload;
    if (sink_.on_header != nullptr && !sink_.on_header(sink_.ctx, header_))
      return fail(Status::aborted, item_offset_, VDS_DETAIL("header callback stopped the stream"));
  } else if (type_ == chunk::kEnd) {
    if (length_ != 4 || load_le32(buf_) != chunks_ - 1)
      return fail(Status::malformed, item_offset_, VDS_DETAIL("END chunk count does not match the chunks read"));
    state_ = State::done;
    status_ = Status::ok;
    return Status::ok;
  } else {
    const ChunkResult r = sink_.on_chunk != nullptr ? sink_.on_chunk(sink_.ctx, type_, buf_, length_) : ChunkResult::unknown;
    if (r == ChunkResult::abort) return fail(Status::aborted, item_offset_, VDS_DETAIL("chunk callback stopped the stream"));
    if (r == ChunkResult::unknown) ++skipped_;
  }
  state_ = State::chunk_head;
  have_ = 0;
  item_offset_ = offset_;
  return Status::more_input;
}

Status StreamParser::feed(const uint8_t* data, size_t size) {
  if (state_ == State::failed) return status_;
  if (data == nullptr && size != 0) return fail(Status::invalid_argument, offset_, VDS_DETAIL("null input"));
  size_t i = 0;
  while (i < size) {
    switch (state_) {
      case State::preamble: {
        small_[have_++] = data[i++];
        ++offset_;
        if (have_ < kPreambleBytes) break;
        for (uint32_t k = 0; k < sizeof kStreamMagic; ++k)
          if (small_[k] != kStreamMagic[k]) return fail(Status::malformed, 0, VDS_DETAIL("not a vds stream (bad magic)"));
        version_major_ = small_[4];
        version_minor_ = small_[5];
        if (version_major_ != kStreamVersionMajor)
          return fail(Status::unsupported_version, 4, VDS_DETAIL("stream major version not supported"));
        if (small_[6] != 0 || small_[7] != 0)
          return fail(Status::unsupported_feature, 6, VDS_DETAIL("unknown preamble flags"));
        // HEAD's CRC also covers the preamble, so a damaged version is caught.
        preamble_crc_ = crc32c(small_, kPreambleBytes);
        state_ = State::chunk_head;
        have_ = 0;
        item_offset_ = offset_;
        break;
      }
      case State::chunk_head: {
        small_[have_++] = data[i++];
        ++offset_;
        if (have_ < kChunkHeadBytes) break;
        const Status s = on_chunk_head();
        if (is_error(s)) return s;
        break;
      }
      case State::payload: {
        size_t take = length_ - have_;
        if (take > size - i) take = size - i;
        memcpy(buf_ + have_, data + i, take);
        crc_ = crc32c_update(crc_, data + i, take);
        have_ += static_cast<uint32_t>(take);
        i += take;
        offset_ += take;
        if (have_ == length_) {
          state_ = State::crc;
          have_ = 0;
        }
        break;
      }
      case State::crc: {
        small_[have_++] = data[i++];
        ++offset_;
        if (have_ < kChunkTailBytes) break;
        const Status s = on_chunk_complete();
        if (is_error(s)) return s;
        break;
      }
      case State::done:
        return fail(Status::malformed, offset_, VDS_DETAIL("bytes after the END chunk"));
      case State::failed:
        return status_;
    }
  }
  return state_ == State::done ? Status::ok : Status::more_input;
}

Status StreamParser::pump(ReadFn read, void* ctx, uint8_t* scratch, uint32_t scratch_size) {
  if (read == nullptr || scratch == nullptr || scratch_size == 0) return Status::invalid_argument;
  for (;;) {
    if (state_ == State::failed) return status_;
    const int32_t n = read(ctx, scratch, scratch_size);
    if (n < 0) return fail(Status::io_error, offset_, VDS_DETAIL("read callback failed"));
    if (n == 0) return finish();
    if (static_cast<uint32_t>(n) > scratch_size) return fail(Status::invalid_argument, offset_, VDS_DETAIL("read callback overran its buffer"));
    const Status s = feed(scratch, static_cast<size_t>(n));
    if (s != Status::more_input) return s;
  }
}

Status StreamParser::finish() {
  if (state_ == State::failed) return status_;
  if (state_ == State::done) return Status::ok;
  return fail(Status::truncated, offset_, VDS_DETAIL("stream ends before its END chunk"));
}

}  // namespace vds
