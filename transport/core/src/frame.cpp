// Link frame layer: header | payload | CRC-32C (RFC 3720 polynomial),
// COBS-encoded (Cheshire & Baker 1999) with a 0x00 delimiter after each frame.
#include "vds/link/frame.h"

#include <cstring>

#include "vds/bytes.h"
#include "vds/crc32c.h"

namespace vds::link {

namespace {

constexpr uint8_t kCobsMaxCode = 0xFF;  // a block of 254 non-zero bytes, no implied zero

// COBS over data that arrives in pieces (header, payload, CRC) so the frame
// never needs to exist unencoded in one buffer.
struct CobsWriter {
  uint8_t* out;
  size_t code_at = 0;
  size_t w = 1;
  uint8_t code = 1;

  void put(const uint8_t* p, size_t n) {
    for (size_t i = 0; i < n; ++i) {
      if (p[i] == 0) {
        close_block();
        continue;
      }
      out[w++] = p[i];
      if (++code == kCobsMaxCode) close_block();
    }
  }
  void close_block() {
    out[code_at] = code;
    code_at = w++;
    code = 1;
  }
  size_t finish() {
    out[code_at] = code;
    return w;
  }
};

}  // namespace

Status frame_encode(const FrameHeader& h, const uint8_t* payload, size_t n, uint8_t* out, size_t out_size,
                    size_t* out_len) {
  return frame_encode_parts(h, payload, n, nullptr, 0, out, out_size, out_len);
}

Status frame_encode_parts(const FrameHeader& h, const uint8_t* a, size_t na, const uint8_t* b, size_t nb,
                          uint8_t* out, size_t out_size, size_t* out_len) {
  if ((a == nullptr && na != 0) || (b == nullptr && nb != 0) || out == nullptr || out_len == nullptr || h.channel > kMaxChannelId ||
      static_cast<uint8_t>(h.type) >= kFrameTypeCount)
    return Status::invalid_argument;
  const size_t n = na + nb;
  if (n < na || out_size < frame_wire_bound(n)) return Status::output_too_small;
  const uint8_t head[kHeaderBytes] = {static_cast<uint8_t>(static_cast<uint8_t>(h.type) << 4 | h.channel), h.tag,
                                      static_cast<uint8_t>(h.seq & 0xFF), static_cast<uint8_t>(h.seq >> 8)};
  const uint32_t crc = crc32c_update(crc32c_update(crc32c_update(0, head, kHeaderBytes), a, na), b, nb);
  const uint8_t tail[kCrcBytes] = {static_cast<uint8_t>(crc), static_cast<uint8_t>(crc >> 8),
                                   static_cast<uint8_t>(crc >> 16), static_cast<uint8_t>(crc >> 24)};
  CobsWriter cw{out};
  cw.put(head, kHeaderBytes);
  cw.put(a, na);
  cw.put(b, nb);
  cw.put(tail, kCrcBytes);
  size_t len = cw.finish();
  out[len++] = 0;
  *out_len = len;
  return Status::ok;
}

size_t FrameReceiver::push(const uint8_t* data, size_t n, RxEvent* event, RxFrame* frame) {
  *event = RxEvent::none;
  size_t i = 0;
  while (i < n) {
    // Gather the run of non-zero bytes up to the next delimiter at once.
    size_t run = 0;
    while (i + run < n && data[i + run] != 0) ++run;
    if (run != 0) {
      if (!overflow_) {
        const size_t fit = cap_ - len_;
        const size_t k = run < fit ? run : fit;
        memcpy(buf_ + len_, data + i, k);
        len_ += k;
        // Keep discarding to the delimiter; report once, at the delimiter.
        if (run > fit) overflow_ = true;
      }
      i += run;
      continue;
    }
    ++i;
    // Delimiter: judge what was gathered.
    const size_t got = len_;
    const bool over = overflow_;
    len_ = 0;
    overflow_ = false;
    if (over) {
      *event = RxEvent::too_long;
      return i;
    }
    if (got == 0) {
      *event = RxEvent::empty;
      return i;
    }
    size_t dec = 0;
    if (cobs_decode(buf_, got, buf_, cap_, &dec) != Status::ok) {
      *event = RxEvent::bad_cobs;
      return i;
    }
    if (dec < kFrameOverhead) {
      *event = RxEvent::too_short;
      return i;
    }
    const size_t body = dec - kCrcBytes;
    const uint32_t want = static_cast<uint32_t>(buf_[body]) | static_cast<uint32_t>(buf_[body + 1]) << 8 |
                          static_cast<uint32_t>(buf_[body + 2]) << 16 | static_cast<uint32_t>(buf_[body + 3]) << 24;
    if (crc32c(buf_, body) != want) {
      *event = RxEvent::bad_crc;
      return i;
    }
    frame->header.type = static_cast<FrameType>(buf_[0] >> 4);
    frame->header.channel = static_cast<uint8_t>(buf_[0] & 0x0F);
    frame->header.tag = buf_[1];
    frame->header.seq = load_le16(buf_ + 2);
    frame->payload = buf_ + kHeaderBytes;
    frame->size = body - kHeaderBytes;
    *event = RxEvent::frame;
    return i;
  }
  return i;
}

}  // namespace vds::link
