// vds link core: the messages the client application sends up the link
// (docs/protocol.md, "Application messages"): a checksum record per
// displayed frame on the checksums channel, a statistics snapshot on the
// stats datagram channel, and the end-of-stream report on the control
// channel; and the one message the host sends down besides the stream, its
// goodbye on the control channel. Fixed little-endian layouts, each opened
// by a type byte.
#pragma once
#include <cstddef>
#include <cstdint>

#include "vds/link/link.h"
#include "vds/status.h"

namespace vds::link {

enum class MessageType : uint8_t {
  frame = 1,  // FrameRecord, checksums channel
  stats = 2,  // ClientStats, stats channel
  done = 3,   // DoneReport, control channel
  goodbye = 4,  // Goodbye, control channel, host to client
};

// One displayed frame: its CRC-32C (RGB565 pixels, little-endian, rows top
// to bottom) and the instructions each stage took on boards that count them.
struct FrameRecord {
  uint32_t index;
  uint32_t crc;
  uint32_t parse_instructions;   // container parsing and chunk verification
  uint32_t decode_instructions;  // entropy decoding, inverse transform, colour conversion
  uint32_t entropy_instructions;    // of which entropy decoding (0 if not measured)
  uint32_t transform_instructions;  // of which dequantisation and inverse transform (0 if not measured)
  uint32_t display_instructions; // band output and the frame CRC
  uint32_t received_ms;          // when its last byte arrived (board clock)
  uint8_t late;                  // 1 if it missed its presentation time
  uint8_t steered = 0;           // 1 if drawn as the viewer turned it: a replay of the stream does not show it
};
constexpr size_t kFrameRecordBytes = 1 + 8 * 4 + 1;

struct ClientStats {
  uint32_t uptime_ms;
  uint32_t stream_bytes;          // stream bytes received and parsed
  uint32_t frames_shown;
  uint32_t late_frames;
  uint32_t workspace_high_water;  // bytes of the workspace ever used
  uint32_t workspace_budget;
  uint32_t stack_high_water;      // 0 when the board cannot tell
  uint32_t link_retransmissions;  // the device's own resends
  uint32_t link_dropped;          // frames the device's link layer dropped
  uint32_t instruction_resolution;  // 0: the board counts no instructions
};
constexpr size_t kClientStatsBytes = 1 + 10 * 4;

// Why the client reports: it read the whole stream (the END chunk, or the
// first error), or it holds as much of a model as its workspace can and
// wants no more of the stream: its bytes and CRC then cover a prefix.
enum class DoneReason : uint8_t {
  end_of_stream = 0,
  workspace_full = 1,
};

// Sent once, after the END chunk or the first error, or as soon as a model
// client's workspace is full.
struct DoneReport {
  int32_t status;  // vds::Status of the stream (ok for a full workspace)
  uint32_t frames_shown;
  uint32_t stream_bytes;  // stream bytes received (for workspace_full, those the report covers)
  uint32_t stream_crc;    // CRC-32C of those bytes
  DoneReason reason = DoneReason::end_of_stream;
};
constexpr size_t kDoneReportBytes = 1 + 4 * 4 + 1;

// Sent by the host once it holds the client's DoneReport and every frame
// record the report announced (or has stopped waiting for them): the client
// need not wait for acknowledgements of what it sent, and may stop.
struct Goodbye {
  uint8_t verified;        // 1: the report's status is ok and its byte count and CRC match what the host sent (or, workspace full, its prefix)
  uint32_t frame_records;  // FrameRecords the host received
};
constexpr size_t kGoodbyeBytes = 1 + 1 + 4;

size_t encode(const FrameRecord& m, uint8_t out[kFrameRecordBytes]);
size_t encode(const ClientStats& m, uint8_t out[kClientStatsBytes]);
size_t encode(const DoneReport& m, uint8_t out[kDoneReportBytes]);
size_t encode(const Goodbye& m, uint8_t out[kGoodbyeBytes]);

// Each returns malformed for a wrong type byte, a short message or a field
// out of its range (a DoneReport's reason, a Goodbye's verified flag).
Status decode(const uint8_t* p, size_t n, FrameRecord* m);
Status decode(const uint8_t* p, size_t n, ClientStats* m);
Status decode(const uint8_t* p, size_t n, DoneReport* m);
Status decode(const uint8_t* p, size_t n, Goodbye* m);

// Collects fixed-size messages of N bytes from a reliable channel, which
// may hand them over in pieces: next() is true each time `bytes` holds a
// whole one (the following call starts on the next).
template <size_t N>
struct MessageReader {
  uint8_t bytes[N] = {};
  size_t len = 0;

  bool next(Link& link, uint8_t ch) {
    if (len == N) len = 0;
    size_t n = 0;
    while (len < N && link.read(ch, bytes + len, N - len, &n) == Status::ok && n != 0) len += n;
    return len == N;
  }
  void reset() { len = 0; }
};

}  // namespace vds::link
