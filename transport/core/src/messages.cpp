// Encoding of the link's application messages (vds/link/messages.h).
#include "vds/link/messages.h"

#include "vds/bytes.h"

namespace vds::link {
namespace {

// Field by field, the cursor moving on.
void put32(uint8_t*& p, uint32_t v) {
  store_le32(p, v);
  p += 4;
}
uint32_t get32(const uint8_t*& p) {
  const uint32_t v = load_le32(p);
  p += 4;
  return v;
}
bool opens(const uint8_t* p, size_t n, size_t want, MessageType t) {
  return p != nullptr && n >= want && p[0] == static_cast<uint8_t>(t);
}

}  // namespace

size_t encode(const FrameRecord& m, uint8_t out[kFrameRecordBytes]) {
  uint8_t* p = out;
  *p++ = static_cast<uint8_t>(MessageType::frame);
  put32(p, m.index);
  put32(p, m.crc);
  put32(p, m.parse_instructions);
  put32(p, m.decode_instructions);
  put32(p, m.entropy_instructions);
  put32(p, m.transform_instructions);
  put32(p, m.display_instructions);
  put32(p, m.received_ms);
  *p++ = static_cast<uint8_t>((m.late ? 1 : 0) | (m.steered ? 2 : 0));  // bit 0 late, bit 1 steered
  return kFrameRecordBytes;
}

size_t encode(const ClientStats& m, uint8_t out[kClientStatsBytes]) {
  uint8_t* p = out;
  *p++ = static_cast<uint8_t>(MessageType::stats);
  put32(p, m.uptime_ms);
  put32(p, m.stream_bytes);
  put32(p, m.frames_shown);
  put32(p, m.late_frames);
  put32(p, m.workspace_high_water);
  put32(p, m.workspace_budget);
  put32(p, m.stack_high_water);
  put32(p, m.link_retransmissions);
  put32(p, m.link_dropped);
  put32(p, m.instruction_resolution);
  return kClientStatsBytes;
}

size_t encode(const DoneReport& m, uint8_t out[kDoneReportBytes]) {
  uint8_t* p = out;
  *p++ = static_cast<uint8_t>(MessageType::done);
  put32(p, static_cast<uint32_t>(m.status));
  put32(p, m.frames_shown);
  put32(p, m.stream_bytes);
  put32(p, m.stream_crc);
  *p++ = static_cast<uint8_t>(m.reason);
  return kDoneReportBytes;
}

size_t encode(const Goodbye& m, uint8_t out[kGoodbyeBytes]) {
  uint8_t* p = out;
  *p++ = static_cast<uint8_t>(MessageType::goodbye);
  *p++ = m.verified;
  put32(p, m.frame_records);
  return kGoodbyeBytes;
}

Status decode(const uint8_t* p, size_t n, FrameRecord* m) {
  if (m == nullptr || !opens(p, n, kFrameRecordBytes, MessageType::frame)) return Status::malformed;
  ++p;
  m->index = get32(p);
  m->crc = get32(p);
  m->parse_instructions = get32(p);
  m->decode_instructions = get32(p);
  m->entropy_instructions = get32(p);
  m->transform_instructions = get32(p);
  m->display_instructions = get32(p);
  m->received_ms = get32(p);
  if ((*p & ~3u) != 0) return Status::malformed;
  m->late = *p & 1;
  m->steered = (*p >> 1) & 1;
  return Status::ok;
}

Status decode(const uint8_t* p, size_t n, ClientStats* m) {
  if (m == nullptr || !opens(p, n, kClientStatsBytes, MessageType::stats)) return Status::malformed;
  ++p;
  m->uptime_ms = get32(p);
  m->stream_bytes = get32(p);
  m->frames_shown = get32(p);
  m->late_frames = get32(p);
  m->workspace_high_water = get32(p);
  m->workspace_budget = get32(p);
  m->stack_high_water = get32(p);
  m->link_retransmissions = get32(p);
  m->link_dropped = get32(p);
  m->instruction_resolution = get32(p);
  return Status::ok;
}

Status decode(const uint8_t* p, size_t n, DoneReport* m) {
  if (m == nullptr || !opens(p, n, kDoneReportBytes, MessageType::done) ||
      p[kDoneReportBytes - 1] > static_cast<uint8_t>(DoneReason::workspace_full))
    return Status::malformed;
  ++p;
  m->status = static_cast<int32_t>(get32(p));
  m->frames_shown = get32(p);
  m->stream_bytes = get32(p);
  m->stream_crc = get32(p);
  m->reason = static_cast<DoneReason>(*p);
  return Status::ok;
}

Status decode(const uint8_t* p, size_t n, Goodbye* m) {
  if (m == nullptr || !opens(p, n, kGoodbyeBytes, MessageType::goodbye) || p[1] > 1) return Status::malformed;
  ++p;
  m->verified = *p++;
  m->frame_records = get32(p);
  return Status::ok;
}

}  // namespace vds::link
