// vds link core: the frame layer (docs/protocol.md, "Frames"). A frame is
// header | payload | CRC-32C, COBS-encoded and ended by one 0x00 delimiter,
// so a receiver resynchronises at the next delimiter after any damage.
#pragma once
#include <cstddef>
#include <cstdint>

#include "vds/link/cobs.h"
#include "vds/status.h"

namespace vds::link {

// Frame types (high nibble of header byte 0). Other values are refused.
enum class FrameType : uint8_t {
  data = 0,      // reliable channel bytes; seq = 16-bit byte offset of the first payload byte
  datagram = 1,  // unreliable latest-wins message; seq = per-channel message counter
  ack = 2,       // acknowledgement of a reliable channel; seq = cumulative ack offset
  hello = 3,     // session handshake; channel, tag and seq are 0
};
constexpr uint8_t kFrameTypeCount = 4;

// Header: byte 0 = type << 4 | channel, byte 1 = session tag, bytes 2..3 =
// seq (little-endian). The CRC-32C of header and payload follows the
// payload, little-endian.
constexpr size_t kHeaderBytes = 4;
constexpr size_t kCrcBytes = 4;
constexpr size_t kFrameOverhead = kHeaderBytes + kCrcBytes;
constexpr uint8_t kMaxChannelId = 15;  // a 4-bit field

struct FrameHeader {
  FrameType type = FrameType::data;
  uint8_t channel = 0;
  uint8_t tag = 0;
  uint16_t seq = 0;
};

// Bytes on the wire for a frame with an n-byte payload, delimiter included,
// in the worst case (COBS adds one byte per 254 and at least one).
constexpr size_t frame_wire_bound(size_t payload) { return cobs_encoded_bound(payload + kFrameOverhead) + 1; }

// Buffer a receiver needs to take frames of up to `max_payload` bytes.
constexpr size_t frame_rx_buffer_size(size_t max_payload) { return cobs_encoded_bound(max_payload + kFrameOverhead); }

// Encodes one frame: COBS(header | payload | CRC) followed by 0x00. `out`
// must hold frame_wire_bound(n) bytes, else output_too_small.
Status frame_encode(const FrameHeader& h, const uint8_t* payload, size_t n, uint8_t* out, size_t out_size,
                    size_t* out_len);
// The same with the payload in two pieces (a ring buffer that wraps).
Status frame_encode_parts(const FrameHeader& h, const uint8_t* a, size_t na, const uint8_t* b, size_t nb,
                          uint8_t* out, size_t out_size, size_t* out_len);

// What FrameReceiver::push found.
enum class RxEvent : uint8_t {
  none = 0,       // consumed everything without finishing a frame
  frame = 1,      // a valid frame (header, payload) is available
  empty = 2,      // a delimiter with nothing before it (idle line): not an error
  too_long = 3,   // more bytes than the buffer holds before a delimiter
  bad_cobs = 4,   // the bytes are not a valid COBS encoding
  too_short = 5,  // decoded frame shorter than header + CRC
  bad_crc = 6,    // CRC-32C mismatch
};

struct RxFrame {
  FrameHeader header;
  const uint8_t* payload = nullptr;  // valid until the next push()
  size_t size = 0;
};

// Gathers wire bytes into a caller-owned buffer, and at each delimiter
// decodes in place and checks the CRC. Never reads or writes outside the
// buffer; an over-long frame is discarded up to its delimiter.
class FrameReceiver {
 public:
  void init(uint8_t* buffer, size_t capacity) {
    buf_ = buffer;
    cap_ = capacity;
    len_ = 0;
    overflow_ = false;
  }
  // Consumes bytes up to and including the first delimiter (or all of
  // them) and returns how many; `*event` says what ended the call.
  size_t push(const uint8_t* data, size_t n, RxEvent* event, RxFrame* frame);
  // Forgets a partly gathered frame.
  void reset() {
    len_ = 0;
    overflow_ = false;
  }
  size_t capacity() const { return cap_; }

 private:
  uint8_t* buf_ = nullptr;
  size_t cap_ = 0;
  size_t len_ = 0;
  bool overflow_ = false;
};

}  // namespace vds::link
