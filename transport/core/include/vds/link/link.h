// vds link core: one endpoint of a link session (docs/protocol.md). The same
// code runs on the host and on the client: hello handshake with session
// nonces, reliable in-order channels with selective-repeat ARQ (cumulative +
// selective acks, a window the receiver sets), flow control by the wire
// bytes the receiver has taken off its line (so a slow reader makes the
// sender wait instead of overrunning it, and delay is never taken for loss),
// latest-wins datagram channels, and a data frame size adapted to losses.
// No heap, no float: every buffer is carved from the caller's Arena at init
// and all time comes from the caller's millisecond clock.
#pragma once
#include <cstddef>
#include <cstdint>

#include "vds/arena.h"
#include "vds/config.h"
#include "vds/link/frame.h"
#include "vds/status.h"

namespace vds::link {

// Protocol version carried in HELLO. A peer with another major version is
// refused (no session); minor versions only add optional fields.
constexpr uint8_t kVersionMajor = 2;
constexpr uint8_t kVersionMinor = 0;

constexpr uint8_t kChannels = VDS_CONFIG_LINK_CHANNELS;
constexpr uint8_t kRxRanges = VDS_CONFIG_LINK_RX_RANGES;
constexpr uint32_t kMaxWindow = VDS_CONFIG_LINK_MAX_WINDOW;
static_assert(kChannels <= kMaxChannelId + 1, "channel ids are 4 bits");

// HELLO payload: 18 fixed bytes, then 4 bytes per channel the sender receives.
constexpr size_t kHelloFixedBytes = 18;
constexpr size_t kHelloChannelBytes = 4;
constexpr size_t kHelloMaxPayload = kHelloFixedBytes + kHelloChannelBytes * kChannels;
// ACK payload: 2-byte window, 5-byte line report (the last data frame taken
// off the line intact and the wire bytes taken since), then up to 3
// selective-ack blocks of 4 bytes.
constexpr uint8_t kSackBlocks = 3;
constexpr size_t kAckFixedBytes = 7;
constexpr size_t kAckMaxPayload = kAckFixedBytes + 4 * kSackBlocks;
// Of a peer's line buffer, what new data leaves free for frames the sender
// does not hold back (acks, datagrams, a hello) and for retransmission
// probes: a quarter of it, at most 128 bytes. The smallest line buffer a
// HELLO may declare is kMinLineBytes.
constexpr uint16_t kMinLineBytes = 256;
constexpr uint32_t line_reserve(uint32_t line_bytes) { return line_bytes / 4 < 128 ? line_bytes / 4 : 128; }
// Delayed acknowledgement: in-order data is acknowledged every second frame
// or this long after the first unacknowledged one; anything else at once.
constexpr uint8_t kAckEveryFrames = 2;
constexpr uint32_t kAckDelayMs = 10;
// Data frame payload of a new session until its first frame is acknowledged.
constexpr uint16_t kFirstFramePayload = 128;
// Smallest data frame payload the adaptation may choose, and the largest a
// frame may carry (the 16-bit window arithmetic needs far less than 32 KiB).
constexpr uint16_t kMinFramePayload = 8;
constexpr uint16_t kMaxFramePayload = 4096;
// The largest data frame payload a sender uses on a line carrying
// `line_bytes_per_s` (0: unknown): a frame holds the line for at most
// kMaxFrameLineMs, so the acknowledgements and messages sharing its
// direction wait no longer, and a byte reaches the receiver no later, than
// that after the line carried it. Never below 64 bytes nor above `cap`.
constexpr uint32_t kMaxFrameLineMs = 100;
constexpr uint16_t line_frame_payload(uint32_t line_bytes_per_s, uint16_t cap) {
  if (line_bytes_per_s == 0) return cap;
  const uint64_t p = static_cast<uint64_t>(line_bytes_per_s) * kMaxFrameLineMs / 1000;
  return p < 64 ? (cap < 64 ? cap : 64) : p < cap ? static_cast<uint16_t>(p) : cap;
}

// HELLO capability bits (informative in version 1.0: every 1.0 endpoint has all).
constexpr uint8_t kCapSelectiveAck = 0x01;
constexpr uint8_t kCapDatagram = 0x02;
constexpr uint8_t kCapAdaptiveFrames = 0x04;

// The channels vds uses. Any endpoint may configure others.
namespace channel {
constexpr uint8_t kStream = 0;     // host -> device, reliable: the stream file
constexpr uint8_t kControl = 1;    // both ways, reliable: commands and replies
constexpr uint8_t kPose = 2;       // device -> host, datagram: viewer pose, latest wins
constexpr uint8_t kStats = 3;      // device -> host, datagram: client statistics, latest wins
constexpr uint8_t kChecksums = 4;  // device -> host, reliable: CRC-32C of displayed frames
}  // namespace channel

enum class Role : uint8_t { host = 0, device = 1 };
enum class Mode : uint8_t { none = 0, reliable = 1, datagram = 2 };

// Why the last session ended.
enum class ResetReason : uint8_t {
  none = 0,
  peer_restarted = 1,  // a HELLO showed the peer no longer knows this session
  local = 2,           // the application called restart()
};

struct ChannelConfig {
  Mode tx = Mode::none;
  uint16_t tx_bytes = 0;     // reliable: send buffer; datagram: largest message
  uint16_t tx_segments = 0;  // reliable: frames in flight the sender can track
  Mode rx = Mode::none;
  uint16_t rx_bytes = 0;  // reliable: the receive window; datagram: largest message
};

struct LinkConfig {
  Role role = Role::host;
  uint32_t nonce_seed = 1;        // entropy for session nonces (a reboot counter, a timer, a random number)
  uint16_t max_rx_payload = 1024;  // largest frame payload this endpoint accepts
  uint16_t max_tx_payload = 1024;  // largest data frame payload it sends
  uint16_t min_tx_payload = 16;    // the adaptation never goes below this
  bool adaptive = true;            // adapt the data frame size to observed losses
  uint16_t rto_initial_ms = 1000;  // before the first round-trip sample of a data frame (RFC 6298)
  uint16_t rto_min_ms = 50;
  uint16_t rto_max_ms = 4000;  // cap of the exponential back-off
  // Wire bytes this endpoint can hold between its line and receive() (a
  // UART receive ring), declared in HELLO: the peer never has more than
  // this on the line unread. 0 = no limit (a host reading a pipe).
  uint16_t rx_line_bytes = 0;
  uint16_t hello_interval_ms = 250;
  uint16_t keepalive_ms = 500;  // an idle receiver repeats its ack this often
  ChannelConfig channels[kChannels] = {};
};

namespace detail {
enum class SegState : uint8_t { in_flight = 0, sacked = 1, lost = 2 };
struct Segment {
  uint32_t start;
  uint16_t len;
  SegState state;
  uint8_t tries;
  uint32_t sent_ms;
  uint32_t order;  // transmission order of its last copy
  bool taken;      // the peer has taken its last copy off the line (accepted or not)
};
// One data frame on the line, in transmission order (the pipe keeps order):
// where its last byte lies in this endpoint's count of wire bytes sent.
struct Sent {
  uint32_t wire_end;
  uint32_t order;
  uint16_t seq;  // low 16 bits of its offset, as the peer echoes it
  uint8_t ch;
  bool probe;    // a probe after an RTO (a few bytes, not a whole frame)
};
struct TxReliable {
  uint8_t* ring;
  uint32_t cap;
  uint32_t base;      // oldest unacknowledged offset
  uint32_t base_pos;  // its index in ring
  uint32_t wr;        // end of the application's data
  uint32_t nxt;       // next never-sent offset
  uint32_t wnd_end;   // the peer lets us send below this offset
  Segment* segs;      // in offset order, covering [base, nxt)
  uint16_t seg_cap;
  uint16_t seg_count;
};
struct Range {
  uint32_t start, end;
};
struct RxReliable {
  uint8_t* ring;
  uint32_t cap;
  uint32_t rd;      // next offset the application reads
  uint32_t rd_pos;  // its index in ring
  uint32_t nxt;     // everything below is received (cumulative ack)
  uint32_t advertised_end;
  uint32_t last_ack_ms;
  uint32_t peak;  // most bytes ever held (asserted <= cap by the tests)
  Range ranges[kRxRanges];  // received blocks above nxt, ascending, disjoint
  uint8_t range_count;
  uint8_t latest;  // range holding the newest arrival, reported first
  bool ack_due;
  uint8_t held;  // in-order frames received since the last ack (delayed ack)
  uint32_t held_since_ms;
};
struct TxDatagram {
  uint8_t* buf;
  uint16_t cap, len;
  uint16_t counter;
  bool pending;
};
struct RxDatagram {
  uint8_t* buf;
  uint16_t cap, len;
  uint16_t counter;
  bool have, fresh;
};
struct Channel {
  TxReliable* txr = nullptr;
  TxDatagram* txd = nullptr;
  RxReliable* rxr = nullptr;
  RxDatagram* rxd = nullptr;
  Mode peer_rx = Mode::none;  // what the peer declared it receives on this channel
  uint16_t peer_window = 0;
};

constexpr size_t carve(size_t bytes, size_t align) { return bytes + align - 1; }
// Entries of the sent-frame log: every frame in flight on every channel, and
// the retransmission probes (one per segment at most).
constexpr size_t sent_log_entries(const LinkConfig& c) {
  size_t n = 0;
  for (const ChannelConfig& ch : c.channels)
    if (ch.tx == Mode::reliable) n += 2u * ch.tx_segments;
  return n;
}
constexpr uint16_t max16(uint16_t a, uint16_t b) { return a > b ? a : b; }
}  // namespace detail

// Transmit frame buffer size: the larger of a data frame and a HELLO, with
// an optional leading delimiter.
constexpr size_t tx_frame_buffer_size(const LinkConfig& c) {
  return frame_wire_bound(detail::max16(c.max_tx_payload, static_cast<uint16_t>(kHelloMaxPayload))) + 1;
}

// Workspace bytes Link::init carves for `c` (alignment padding included).
constexpr size_t link_workspace_size(const LinkConfig& c) {
  using namespace detail;
  size_t n = carve(frame_rx_buffer_size(c.max_rx_payload > kHelloMaxPayload ? c.max_rx_payload : kHelloMaxPayload), 1) +
             carve(tx_frame_buffer_size(c), 1) + carve(sizeof(Sent) * sent_log_entries(c), alignof(Sent));
  for (const ChannelConfig& ch : c.channels) {
    if (ch.tx == Mode::reliable)
      n += carve(sizeof(TxReliable), alignof(TxReliable)) + carve(ch.tx_bytes, 1) +
           carve(sizeof(Segment) * ch.tx_segments, alignof(Segment));
    else if (ch.tx == Mode::datagram)
      n += carve(sizeof(TxDatagram), alignof(TxDatagram)) + carve(ch.tx_bytes, 1);
    if (ch.rx == Mode::reliable)
      n += carve(sizeof(RxReliable), alignof(RxReliable)) + carve(ch.rx_bytes, 1);
    else if (ch.rx == Mode::datagram)
      n += carve(sizeof(RxDatagram), alignof(RxDatagram)) + carve(ch.rx_bytes, 1);
  }
  return n;
}

// The client's configuration: a 4 x 1 KiB stream window, small upward
// channels, and the board's UART receive ring (`line_bytes`) declared to the
// host. Its RAM (sizeof(Link) + workspace) is the figure in
// bench/results/link.md.
constexpr LinkConfig device_config(uint32_t nonce_seed, uint16_t line_bytes = 4096) {
  LinkConfig c{};
  c.role = Role::device;
  c.nonce_seed = nonce_seed;
  c.rx_line_bytes = line_bytes;
  c.max_rx_payload = 1024;
  c.max_tx_payload = 128;
  c.channels[channel::kStream] = {Mode::none, 0, 0, Mode::reliable, 4096};
  c.channels[channel::kControl] = {Mode::reliable, 256, 8, Mode::reliable, 256};
  c.channels[channel::kPose] = {Mode::datagram, 32, 0, Mode::none, 0};
  c.channels[channel::kStats] = {Mode::datagram, 64, 0, Mode::none, 0};
  c.channels[channel::kChecksums] = {Mode::reliable, 256, 8, Mode::none, 0};
  return c;
}

// The host's configuration matching device_config, for a line carrying
// `line_bytes_per_s` (0: unknown; line_frame_payload).
constexpr LinkConfig host_config(uint32_t nonce_seed, uint32_t line_bytes_per_s = 0) {
  LinkConfig c{};
  c.role = Role::host;
  c.nonce_seed = nonce_seed;
  c.keepalive_ms = 2000;  // its acks share the line with the stream
  c.max_rx_payload = 256;
  c.max_tx_payload = line_frame_payload(line_bytes_per_s, 1024);
  c.channels[channel::kStream] = {Mode::reliable, 16384, 512, Mode::none, 0};
  c.channels[channel::kControl] = {Mode::reliable, 1024, 16, Mode::reliable, 1024};
  c.channels[channel::kPose] = {Mode::none, 0, 0, Mode::datagram, 64};
  c.channels[channel::kStats] = {Mode::none, 0, 0, Mode::datagram, 128};
  c.channels[channel::kChecksums] = {Mode::none, 0, 0, Mode::reliable, 1024};
  return c;
}

// Counters of everything the endpoint saw and did. Every dropped frame is
// counted under exactly one reason.
struct LinkStats {
  // Received frames and why the bad ones were dropped.
  uint32_t frames_ok = 0;        // passed the frame layer (CRC good)
  uint32_t too_long = 0;         // more bytes than the receive buffer before a delimiter
  uint32_t bad_cobs = 0;
  uint32_t too_short = 0;
  uint32_t bad_crc = 0;
  uint32_t unknown_type = 0;
  uint32_t unknown_channel = 0;  // a channel/type this endpoint does not receive
  uint32_t not_established = 0;  // channel traffic outside a session
  uint32_t bad_session = 0;      // session tag of another session
  uint32_t bad_hello = 0;        // malformed HELLO, or a peer of the same role
  uint32_t bad_version = 0;      // HELLO of another major version
  uint32_t bad_ack = 0;          // acks outside what was sent
  uint32_t out_of_window = 0;    // data beyond the window this endpoint advertised
  uint32_t ooo_dropped = 0;      // data needing more out-of-order ranges than kRxRanges
  uint32_t duplicates = 0;       // data already received (delivered once, never again)
  uint32_t stale_datagrams = 0;  // older than the latest held
  uint64_t rx_bytes = 0;         // wire bytes received
  // Sent frames.
  uint32_t frames_sent = 0;
  uint32_t data_frames_sent = 0;
  uint32_t retransmissions = 0;
  uint32_t timeouts = 0;  // RTO expiries (each sends a probe and doubles the RTO up to rto_max_ms)
  uint32_t losses = 0;    // frames the peer took off the line and did not accept (damaged or cut)
  uint32_t probes = 0;    // small retransmissions sent when a frame's fate was unknown for an RTO
  uint32_t spurious = 0;  // retransmitted frames the peer reported receiving twice
  uint32_t line_waits = 0;  // times new data waited because the peer's line buffer was full
  uint64_t tx_bytes = 0;     // wire bytes sent
  uint64_t payload_sent = 0;  // reliable payload bytes sent, retransmissions included
  // Sessions.
  uint32_t sessions = 0;  // sessions established
  uint32_t resets = 0;    // sessions ended

  uint32_t dropped() const {
    return too_long + bad_cobs + too_short + bad_crc + unknown_type + unknown_channel + not_established +
           bad_session + bad_hello + bad_version + out_of_window + ooo_dropped;
  }
};

class Link {
 public:
  // Carves every buffer from `arena` (link_workspace_size(config) bytes).
  // invalid_argument for an inconsistent configuration, workspace_too_small
  // when the arena cannot hold it.
  Status init(const LinkConfig& config, Arena& arena);

  // Wire side. Feed every received byte; take bytes to send with
  // transmit() whenever the line can accept `max` more (a UART FIFO, a USB
  // packet, the pacing of a simulated link). transmit() never holds back
  // a partly sent frame; it runs poll() first.
  void receive(const uint8_t* data, size_t n, uint32_t now_ms);
  size_t transmit(uint8_t* out, size_t max, uint32_t now_ms);
  // Timers: hello repetition, retransmission timeouts, keepalive acks.
  void poll(uint32_t now_ms);

  // Application side of reliable channels. write() copies what fits in the
  // send buffer (`*accepted`); read() copies delivered bytes in order.
  // invalid_argument for a channel not configured that way;
  // unsupported_feature when the peer does not receive the channel.
  Status write(uint8_t ch, const uint8_t* data, size_t n, size_t* accepted);
  Status read(uint8_t ch, uint8_t* out, size_t max, size_t* got);
  size_t writable(uint8_t ch) const;    // free send buffer
  size_t unacked(uint8_t ch) const;     // written but not yet acknowledged
  size_t readable(uint8_t ch) const;    // delivered, not yet read
  size_t in_flight(uint8_t ch) const;   // sent at least once, not yet acknowledged
  size_t peer_room(uint8_t ch) const;   // what the peer's window still lets us send
  uint32_t rx_peak(uint8_t ch) const;   // most bytes the receive window ever held
  uint32_t rx_window(uint8_t ch) const;  // the window size (receive buffer)

  // Datagram channels: latest wins. send_datagram replaces any message not
  // yet sent; read_datagram returns ok with the newest unread message, or
  // more_input when there is none.
  Status send_datagram(uint8_t ch, const uint8_t* data, size_t n);
  Status read_datagram(uint8_t ch, uint8_t* out, size_t max, size_t* got);

  // Makes every acknowledgement this endpoint holds back (delayed acks) due
  // now: for an application about to stop, whose last received message
  // must still be acknowledged by the next transmit().
  void flush_acks();

  // Ends the session (discarding unsent and undelivered data) and starts a
  // new handshake with a fresh nonce.
  void restart();

  bool established() const { return established_; }
  // Counts established sessions: a change tells the application that the
  // previous session's unread data and unacknowledged writes were dropped.
  uint32_t session_epoch() const { return epoch_; }
  ResetReason last_reset() const { return last_reset_; }
  uint32_t nonce() const { return my_nonce_; }
  uint32_t peer_nonce() const { return peer_nonce_; }
  uint8_t session_tag() const { return tag_; }
  uint16_t peer_max_payload() const { return peer_max_payload_; }
  // The payload size of the next new data frame (adapted to losses).
  uint16_t frame_payload() const { return frame_payload_; }
  // Wire bytes sent that the peer may not have taken off its line yet, and
  // the most it declared it can hold (0: no limit).
  uint32_t line_in_flight() const { return tx_wire_ - resolved_wire_; }
  uint16_t peer_line_bytes() const { return peer_line_bytes_; }
  uint32_t rto_ms() const { return rto_ms_; }
  uint32_t last_heard_ms() const { return heard_ms_; }
  const LinkStats& stats() const { return stats_; }

 private:
  // Session (link.cpp).
  void on_frame(const RxFrame& f);
  void on_hello(const uint8_t* p, size_t n);
  void establish();
  void end_session(ResetReason why);
  void reset_channels();
  void forget_line();
  bool build_next_frame();
  bool build_hello();
  bool emit(const FrameHeader& h, const uint8_t* payload, size_t n);
  bool emit_parts(const FrameHeader& h, const uint8_t* a, size_t na, const uint8_t* b, size_t nb);
  uint32_t next_nonce(uint32_t x) const;
  // Reliable channels and adaptation (arq.cpp).
  void rx_data(uint8_t ch, uint16_t seq, const uint8_t* p, size_t n);
  void rx_ack(uint8_t ch, uint16_t seq, const uint8_t* p, size_t n);
  bool build_ack(uint8_t ch);
  bool build_data(uint8_t ch);
  void check_timeouts();
  void rtt_sample(uint32_t ms);
  void note_outcome(uint16_t len, bool lost);
  void update_frame_size();
  void segment_acked(detail::Segment& s);
  void frame_left();
  void on_line_report(const uint8_t* p);
  void resolve_to(uint32_t wire);
  void declare_taken_lost(uint8_t ch);
  bool line_has_room(size_t wire_bytes, bool probe) const;
  bool build_probe();
  bool send_segment(uint8_t ch, detail::Segment& seg, bool probe);
  bool leaving(const detail::Segment& g) const;
  void split_segment(detail::TxReliable& t, uint16_t i, uint16_t head);

  LinkConfig cfg_{};
  bool ready_ = false;
  FrameReceiver rx_;
  uint8_t* txf_ = nullptr;
  size_t txf_cap_ = 0;
  size_t txf_len_ = 0;
  size_t txf_pos_ = 0;
  bool line_idle_ = true;  // the next frame starts with a delimiter
  // What the frame in txf_ is, so its send time can be taken when its last
  // byte leaves: round trips then exclude the frame's own serialisation.
  FrameType txf_type_ = FrameType::hello;
  uint8_t txf_channel_ = 0;
  uint32_t txf_order_ = 0;
  uint16_t txf_seq_ = 0;
  bool txf_probe_ = false;
  detail::Channel ch_[kChannels];
  uint8_t rr_ = 0;  // round-robin start among sending channels
  uint32_t now_ = 0;

  bool established_ = false;
  bool peer_est_ = false;  // the peer is established too (it said so, or tagged a frame): data may go
  bool hello_due_ = true;
  uint32_t hello_next_ms_ = 0;
  uint32_t my_nonce_ = 0;
  uint32_t peer_nonce_ = 0;
  uint8_t tag_ = 0;
  uint8_t peer_caps_ = 0;
  uint16_t peer_max_payload_ = 0;
  uint32_t epoch_ = 0;
  ResetReason last_reset_ = ResetReason::none;
  uint32_t heard_ms_ = 0;

  // Round trip (RFC 6298, integer ms): srtt in Q3 (1/8 ms), rttvar in Q2.
  bool have_rtt_ = false;
  int32_t srtt_q3_ = 0;
  int32_t rttvar_q2_ = 0;
  uint32_t rto_ms_ = 0;
  uint8_t backoff_ = 0;
  uint32_t order_ = 0;  // transmission counter of data frames
  uint32_t oldest_sent_ms_ = 0;  // no in-flight frame was sent before this
  bool probe_due_ = false;       // the RTO fired: send one small retransmission

  // The line, as the receiver reports it (flow control and loss detection).
  // Receiving: wire bytes taken, and the last data frame taken intact.
  uint32_t rx_wire_ = 0;
  uint32_t echo_end_ = 0;  // rx_wire_ just after that frame's delimiter
  uint16_t echo_seq_ = 0;
  uint8_t echo_ch_ = 0;
  bool echo_valid_ = false;
  bool echo_dup_ = false;  // it carried nothing new (a retransmission that was not needed)
  // Before any data frame: the end of the first frame of this session taken
  // intact, so keepalives and acks taken before any data are reported too.
  bool anchor_valid_ = false;
  uint32_t anchor_end_ = 0;
  bool damaged_ = false;   // a damaged frame was taken: report the line at once
  // Sending: wire bytes sent, how far the peer is known to have taken them,
  // the data frames beyond that (a ring in transmission order), and the
  // last frame the peer echoed, so later reports of it still count.
  uint32_t tx_wire_ = 0;
  uint32_t resolved_wire_ = 0;
  detail::Sent* log_ = nullptr;
  uint16_t log_cap_ = 0;
  uint16_t log_head_ = 0;
  uint16_t log_count_ = 0;
  bool last_echo_valid_ = false;
  uint8_t last_echo_ch_ = 0;
  uint16_t last_echo_seq_ = 0;
  uint32_t last_echo_end_ = 0;
  uint16_t peer_line_bytes_ = 0;
  // Where this session's first tagged frame started on our line: the peer's
  // anchor lies at or after its end.
  bool first_tagged_sent_ = false;
  uint32_t first_tagged_wire_ = 0;
  uint32_t report_ms_ = 0;    // when the last line report arrived
  uint32_t progress_ms_ = 0;  // when a report or an ack last moved the transfer on
  uint32_t rto_from_ms_ = 0;  // the RTO counts from here (or the oldest frame's send)
  bool lost_on_line_ = false;  // the peer reports but has taken nothing for an RTO
  // Loss estimate for frame-size adaptation: wire bytes of frames whose
  // fate is known, and how many of them were lost (Q8: 256 per frame).
  uint32_t est_bytes_ = 0;
  uint32_t est_lost_q8_ = 0;
  uint32_t est_frames_q8_ = 0;  // frames whose fate is known (Q8)
  uint16_t frame_payload_ = 0;

  LinkStats stats_{};
};

}  // namespace vds::link
