// Serving a stream file over a link: what `vds serve` runs. The host end
// streams the file on the stream channel, starting over whenever a new
// session begins (the client lost its state); over the loopback an
// in-process client (the freestanding core's receiving end plus the stream
// container parser) receives and verifies it. The client's DoneReport on
// the control channel (vds/link/messages.h) confirms byte count and CRC —
// of the whole stream, or of the prefix a client whose workspace is full
// took, after which the host writes no more — and the host's Goodbye on the
// same channel tells the client it may stop.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "vds/link/link.h"
#include "vds/link/loopback.h"
#include "vds/link/messages.h"
#include "vds/link/sim.h"

namespace vds::link {

struct ServeOptions {
  std::string link = "loopback";  // loopback | pty:PATH | tcp:HOST:PORT | tcp-listen:PORT | usb:VID:PID
  uint32_t baud = 115200;
  bool paced = true;         // pty and TCP: pace writes at baud (false: only the client's flow control)
  FaultConfig faults;        // loopback only: faults on both directions (seeds differ per direction)
  DrainProfile drain;        // loopback only: a client that takes bytes off its line slowly
  uint32_t timeout_s = 0;    // real links: give up after this many seconds (0: wait forever)
  uint32_t nonce_seed = 0;   // 0: from the clock
};

struct ServeReport {
  uint64_t bytes = 0;         // stream size
  uint32_t stream_crc = 0;    // CRC-32C of the stream
  bool simulated = false;     // loopback: times are simulated
  double seconds = 0;         // from session start to the client's receipt (or last ack)
  double goodput = 0;         // bytes / seconds / (baud / 10)
  uint32_t sessions = 0;      // sessions the host established
  // The client's end-of-stream report (DoneReport on the control channel,
  // vds/link/messages.h): arrived, stream ok, and byte count and CRC match
  // the stream's, or a prefix's when the client's workspace was full.
  bool receipt = false;
  bool receipt_prefix = false;  // the client reported its workspace full: it wanted no more
  uint64_t bytes_written = 0;   // stream bytes the host wrote to the link (less than `bytes` after a full report)
  uint64_t bytes_acked = 0;     // of those, acknowledged by the client when the host closed
  bool report_seen = false;
  int32_t report_status = 0;
  uint64_t receipt_bytes = 0;
  uint32_t receipt_crc = 0;
  uint32_t frame_records = 0;  // FrameRecords received on the checksums channel
  std::vector<FrameRecord> frames;  // those records, in order (the last session's)
  bool have_stats = false;          // a ClientStats datagram arrived
  ClientStats stats{};              // the newest one
  // The host's Goodbye (after the report and its frame records): the client
  // acknowledged it; loopback: the in-process client read it, and it said
  // the report was verified.
  bool goodbye_sent = false;
  bool goodbye_acked = false;
  bool client_closed = false;  // real links: the client closed the line after its report
  bool client_goodbye = false;
  bool client_goodbye_verified = false;
  uint32_t client_chunks = 0;  // loopback: chunks the client's parser verified
  LinkStats host;
  LinkStats client;  // loopback only
  DrainStats drain;  // loopback with a DrainProfile: the client's UART ring
  uint16_t final_frame_payload = 0;
};

// Throws BackendError for link failures, std::runtime_error for a stream
// the client refuses or a timeout.
ServeReport serve_stream(const std::vector<uint8_t>& stream, const ServeOptions& options,
                         const std::function<void(const std::string&)>& log = {});

// A stream made while it is served (the terrain server, `vds
// serve-terrain`): produce() is called as the link runs, with the
// milliseconds since the session began, and appends what is due; pose()
// gets each message from the client's pose channel (latest wins: a pose
// not yet read is replaced by a newer one).
class LiveStream {
 public:
  virtual ~LiveStream() = default;
  virtual void pose(const uint8_t* data, size_t n) = 0;
  // true once the stream is whole (its END appended).
  virtual bool produce(uint64_t ms, std::vector<uint8_t>& out) = 0;
};

// Serves a live stream to a client board (not loopback: its client does not
// play streams); *made receives the whole stream as sent. A new session
// sends the client what was made from its first byte again.
ServeReport serve_live(LiveStream& live, const ServeOptions& options, std::vector<uint8_t>* made,
                       const std::function<void(const std::string&)>& log = {});

}  // namespace vds::link
