// Link session: initialisation from the caller's workspace, the hello
// handshake with session nonces and its re-establishment rule, the choice
// of the next frame to send, and datagram channels (docs/protocol.md).
#include <cstring>

#include "vds/crc32c.h"
#include "vds/link/link.h"
#include "vds/bytes.h"

namespace vds::link {

using detail::Channel;
using detail::RxDatagram;
using detail::RxReliable;
using detail::TxDatagram;
using detail::TxReliable;

namespace {

constexpr uint8_t kHelloFlagEstablished = 0x01;
constexpr uint8_t kHelloFlagDevice = 0x02;
constexpr uint8_t kCapabilities = kCapSelectiveAck | kCapDatagram | kCapAdaptiveFrames;


template <typename T>
T* carve(Arena& a, size_t count = 1) {
  T* p = a.alloc_array<T>(count);
  if (p != nullptr) {
    for (size_t i = 0; i < count; ++i) p[i] = T{};
  }
  return p;
}

}  // namespace

Status Link::init(const LinkConfig& c, Arena& arena) {
  ready_ = false;
  if (c.max_rx_payload < kMinFramePayload || c.max_rx_payload > kMaxFramePayload ||
      c.max_tx_payload < kMinFramePayload || c.max_tx_payload > kMaxFramePayload ||
      c.min_tx_payload < kMinFramePayload || c.min_tx_payload > c.max_tx_payload || c.rto_min_ms == 0 ||
      c.rto_initial_ms < c.rto_min_ms || c.rto_max_ms < c.rto_initial_ms || c.hello_interval_ms == 0 ||
      c.keepalive_ms == 0 || (c.rx_line_bytes != 0 && c.rx_line_bytes < kMinLineBytes))
    return Status::invalid_argument;
  for (const ChannelConfig& ch : c.channels) {
    if (ch.tx == Mode::reliable && (ch.tx_bytes == 0 || ch.tx_segments == 0)) return Status::invalid_argument;
    if (ch.tx == Mode::datagram && (ch.tx_bytes == 0 || ch.tx_bytes > c.max_tx_payload))
      return Status::invalid_argument;
    if (ch.rx == Mode::reliable && (ch.rx_bytes == 0 || ch.rx_bytes > kMaxWindow)) return Status::invalid_argument;
    if (ch.rx == Mode::datagram && (ch.rx_bytes == 0 || ch.rx_bytes > c.max_rx_payload))
      return Status::invalid_argument;
  }
  // Start over field by field (a Link may be initialised again); a
  // temporary Link would cost its whole size in stack.
  cfg_ = c;
  txf_ = nullptr;
  txf_cap_ = txf_len_ = txf_pos_ = 0;
  line_idle_ = true;
  txf_type_ = FrameType::hello;
  txf_channel_ = 0;
  txf_order_ = 0;
  txf_seq_ = 0;
  txf_probe_ = false;
  for (Channel& ch : ch_) ch = Channel{};
  rr_ = 0;
  now_ = 0;
  established_ = false;
  peer_est_ = false;
  hello_due_ = true;
  hello_next_ms_ = my_nonce_ = peer_nonce_ = 0;
  tag_ = peer_caps_ = 0;
  peer_max_payload_ = 0;
  epoch_ = 0;
  last_reset_ = ResetReason::none;
  heard_ms_ = 0;
  have_rtt_ = false;
  srtt_q3_ = rttvar_q2_ = 0;
  rto_ms_ = 0;
  backoff_ = 0;
  order_ = oldest_sent_ms_ = 0;
  probe_due_ = false;
  rx_wire_ = echo_end_ = 0;
  echo_seq_ = 0;
  echo_ch_ = 0;
  echo_valid_ = echo_dup_ = damaged_ = false;
  anchor_valid_ = first_tagged_sent_ = false;
  anchor_end_ = first_tagged_wire_ = 0;
  tx_wire_ = resolved_wire_ = 0;
  log_ = nullptr;
  log_cap_ = log_head_ = log_count_ = 0;
  last_echo_valid_ = false;
  last_echo_ch_ = 0;
  last_echo_seq_ = 0;
  last_echo_end_ = 0;
  peer_line_bytes_ = 0;
  report_ms_ = progress_ms_ = rto_from_ms_ = 0;
  lost_on_line_ = false;
  est_bytes_ = est_lost_q8_ = est_frames_q8_ = 0;
  frame_payload_ = 0;
  stats_ = LinkStats{};

  const size_t rx_cap =
      frame_rx_buffer_size(c.max_rx_payload > kHelloMaxPayload ? c.max_rx_payload : kHelloMaxPayload);
  uint8_t* rxbuf = carve<uint8_t>(arena, rx_cap);
  txf_cap_ = tx_frame_buffer_size(c);
  txf_ = carve<uint8_t>(arena, txf_cap_);
  if (rxbuf == nullptr || txf_ == nullptr) return Status::workspace_too_small;
  rx_.init(rxbuf, rx_cap);
  const size_t log_entries = detail::sent_log_entries(c);
  if (log_entries > UINT16_MAX) return Status::invalid_argument;
  if (log_entries != 0) {
    log_ = carve<detail::Sent>(arena, log_entries);
    if (log_ == nullptr) return Status::workspace_too_small;
    log_cap_ = static_cast<uint16_t>(log_entries);
  }

  for (uint8_t i = 0; i < kChannels; ++i) {
    const ChannelConfig& cc = c.channels[i];
    Channel& ch = ch_[i];
    if (cc.tx == Mode::reliable) {
      ch.txr = carve<TxReliable>(arena);
      if (ch.txr == nullptr) return Status::workspace_too_small;
      ch.txr->ring = carve<uint8_t>(arena, cc.tx_bytes);
      ch.txr->segs = carve<detail::Segment>(arena, cc.tx_segments);
      if (ch.txr->ring == nullptr || ch.txr->segs == nullptr) return Status::workspace_too_small;
      ch.txr->cap = cc.tx_bytes;
      ch.txr->seg_cap = cc.tx_segments;
    } else if (cc.tx == Mode::datagram) {
      ch.txd = carve<TxDatagram>(arena);
      if (ch.txd == nullptr) return Status::workspace_too_small;
      ch.txd->buf = carve<uint8_t>(arena, cc.tx_bytes);
      if (ch.txd->buf == nullptr) return Status::workspace_too_small;
      ch.txd->cap = cc.tx_bytes;
    }
    if (cc.rx == Mode::reliable) {
      ch.rxr = carve<RxReliable>(arena);
      if (ch.rxr == nullptr) return Status::workspace_too_small;
      ch.rxr->ring = carve<uint8_t>(arena, cc.rx_bytes);
      if (ch.rxr->ring == nullptr) return Status::workspace_too_small;
      ch.rxr->cap = cc.rx_bytes;
    } else if (cc.rx == Mode::datagram) {
      ch.rxd = carve<RxDatagram>(arena);
      if (ch.rxd == nullptr) return Status::workspace_too_small;
      ch.rxd->buf = carve<uint8_t>(arena, cc.rx_bytes);
      if (ch.rxd->buf == nullptr) return Status::workspace_too_small;
      ch.rxd->cap = cc.rx_bytes;
    }
  }
  reset_channels();
  my_nonce_ = next_nonce(c.nonce_seed);
  rto_ms_ = c.rto_initial_ms;
  frame_payload_ = c.max_tx_payload;
  hello_due_ = true;
  ready_ = true;
  return Status::ok;
}

// A 32-bit integer mix (xorshift-multiply), so consecutive seeds give
// unrelated nonces. 0 means "no nonce" on the wire and is never used.
uint32_t Link::next_nonce(uint32_t x) const {
  x += 0x9E3779B9u;
  x ^= x >> 16;
  x *= 0x7FEB352Du;
  x ^= x >> 15;
  x *= 0x846CA68Bu;
  x ^= x >> 16;
  return x == 0 ? 1u : x;
}

void Link::reset_channels() {
  for (Channel& ch : ch_) {
    if (ch.txr != nullptr) {
      TxReliable& t = *ch.txr;
      t.base = t.base_pos = t.wr = t.nxt = t.wnd_end = 0;
      t.seg_count = 0;
    }
    if (ch.txd != nullptr) {
      ch.txd->len = 0;
      ch.txd->counter = 0;
      ch.txd->pending = false;
    }
    if (ch.rxr != nullptr) {
      RxReliable& r = *ch.rxr;
      r.rd = r.rd_pos = r.nxt = 0;
      r.advertised_end = r.cap;
      r.last_ack_ms = now_;
      r.peak = 0;
      r.range_count = 0;
      r.latest = 0xFF;
      r.ack_due = false;
      r.held = 0;
      r.held_since_ms = 0;
    }
    if (ch.rxd != nullptr) {
      ch.rxd->len = 0;
      ch.rxd->counter = 0;
      ch.rxd->have = ch.rxd->fresh = false;
    }
    ch.peer_rx = Mode::none;
    ch.peer_window = 0;
  }
}

void Link::flush_acks() {
  for (Channel& ch : ch_)
    if (ch.rxr != nullptr && ch.rxr->held != 0) ch.rxr->ack_due = true;
}

void Link::restart() {
  if (!ready_) return;
  end_session(ResetReason::local);
}

// The last byte of the frame in txf_ has left: a data frame's round trip
// and retransmission timer start now, and it joins the sent-frame log at
// its place on the line.
void Link::frame_left() {
  if (txf_type_ != FrameType::data || txf_channel_ >= kChannels || ch_[txf_channel_].txr == nullptr) return;
  TxReliable& t = *ch_[txf_channel_].txr;
  for (uint16_t i = 0; i < t.seg_count; ++i)
    if (t.segs[i].order == txf_order_) t.segs[i].sent_ms = now_;
  if (log_count_ == log_cap_) return;  // never: build_data waits for room
  detail::Sent& e = log_[(log_head_ + log_count_) % log_cap_];
  e = detail::Sent{tx_wire_, txf_order_, txf_seq_, txf_channel_, txf_probe_};
  ++log_count_;
}

void Link::end_session(ResetReason why) {
  if (established_) ++stats_.resets;
  established_ = false;
  peer_est_ = false;
  last_reset_ = why;
  reset_channels();
  my_nonce_ = next_nonce(my_nonce_);
  peer_nonce_ = 0;
  tag_ = 0;
  hello_due_ = true;
  // A frame cut short here reaches the peer as noise; a delimiter before
  // the next HELLO ends it, so the HELLO itself arrives intact.
  if (txf_pos_ != 0 && txf_pos_ < txf_len_) line_idle_ = true;
  txf_len_ = txf_pos_ = 0;
  forget_line();
}

// Nothing of a session's line accounting outlives it.
void Link::forget_line() {
  resolved_wire_ = tx_wire_;
  log_head_ = log_count_ = 0;
  last_echo_valid_ = false;
  echo_valid_ = echo_dup_ = damaged_ = false;
  anchor_valid_ = false;
  first_tagged_sent_ = false;
  probe_due_ = false;
}

void Link::establish() {
  established_ = true;
  peer_est_ = false;
  ++epoch_;
  ++stats_.sessions;
  // The tag marks every non-HELLO frame of this session; derived from both
  // nonces so each side computes it alone.
  uint8_t ids[8];
  const bool host = cfg_.role == Role::host;
  store_le32(ids, host ? my_nonce_ : peer_nonce_);
  store_le32(ids + 4, host ? peer_nonce_ : my_nonce_);
  tag_ = static_cast<uint8_t>(crc32c(ids, sizeof ids));
  have_rtt_ = false;
  oldest_sent_ms_ = now_;
  // The first RTO is rto_initial_ms, not the HELLO's round trip: a HELLO is
  // short and meets an empty line, a data frame may queue behind a full
  // line buffer. Losses are found from the peer's line reports, so the
  // RTO only decides when to probe a line that has gone quiet.
  rto_ms_ = cfg_.rto_initial_ms;
  backoff_ = 0;
  forget_line();
  report_ms_ = progress_ms_ = rto_from_ms_ = now_;
  lost_on_line_ = false;
  est_bytes_ = est_lost_q8_ = est_frames_q8_ = 0;
  update_frame_size();
  // Until the first data frame is acknowledged the line's error rate is
  // unknown: start with frames small enough to get through a bad line, so
  // the peer's first line report comes at once (it names a frame it took
  // intact); the first outcome sets the size from what was seen.
  if (frame_payload_ > kFirstFramePayload) frame_payload_ = kFirstFramePayload < cfg_.min_tx_payload ? cfg_.min_tx_payload : kFirstFramePayload;
  for (Channel& ch : ch_) {
    if (ch.txr != nullptr) ch.txr->wnd_end = ch.txr->base + (ch.peer_rx == Mode::reliable ? ch.peer_window : 0);
    if (ch.rxr != nullptr) {
      ch.rxr->ack_due = true;  // tell the peer our window at once
      ch.rxr->last_ack_ms = now_;
    }
  }
}

// Handshake (docs/protocol.md, "Session"): HELLO carries my nonce and the
// peer's nonce as I know it (echo). An endpoint is established once it
// holds a HELLO echoing its own current nonce. An established endpoint that
// receives a HELLO with another peer nonce, or an echo that is not its own
// nonce, knows the peer has lost the session: it ends its own and answers.
void Link::on_hello(const uint8_t* p, size_t n) {
  if (n < kHelloFixedBytes) {
    ++stats_.bad_hello;
    return;
  }
  if (p[0] != kVersionMajor) {
    ++stats_.bad_version;
    return;
  }
  const uint8_t flags = p[2];
  const uint32_t nonce = load_le32(p + 4);
  const uint32_t echo = load_le32(p + 8);
  const uint16_t max_payload = load_le16(p + 12);
  const uint8_t count = p[14];
  const uint16_t line_bytes = load_le16(p + 16);
  const bool peer_device = (flags & kHelloFlagDevice) != 0;
  if (nonce == 0 || count > kMaxChannelId + 1 || n != kHelloFixedBytes + kHelloChannelBytes * count ||
      peer_device == (cfg_.role == Role::device) || max_payload < kMinFramePayload ||
      (line_bytes != 0 && line_bytes < kMinLineBytes)) {
    ++stats_.bad_hello;
    return;
  }
  const bool peer_established = (flags & kHelloFlagEstablished) != 0;
  if (established_) {
    if (nonce == peer_nonce_ && echo == my_nonce_) {
      if (!peer_established) hello_due_ = true;
      else peer_est_ = true;
      return;
    }
    end_session(ResetReason::peer_restarted);
  }
  peer_nonce_ = nonce;
  peer_caps_ = p[3];
  peer_max_payload_ = max_payload;
  peer_line_bytes_ = line_bytes;
  for (Channel& ch : ch_) {
    ch.peer_rx = Mode::none;
    ch.peer_window = 0;
  }
  for (uint8_t i = 0; i < count; ++i) {
    const uint8_t* e = p + kHelloFixedBytes + kHelloChannelBytes * i;
    if (e[0] >= kChannels) continue;  // a channel this build cannot have: never used
    const Mode m = e[1] == static_cast<uint8_t>(Mode::reliable)   ? Mode::reliable
                   : e[1] == static_cast<uint8_t>(Mode::datagram) ? Mode::datagram
                                                                  : Mode::none;
    uint16_t w = load_le16(e + 2);
    if (w > kMaxWindow) w = static_cast<uint16_t>(kMaxWindow);
    ch_[e[0]].peer_rx = m;
    ch_[e[0]].peer_window = w;
  }
  if (echo == my_nonce_) establish();
  if (established_ && peer_established) peer_est_ = true;
  if (!(peer_established && established_)) hello_due_ = true;
}

void Link::on_frame(const RxFrame& f) {
  const uint8_t type = static_cast<uint8_t>(f.header.type);
  if (type >= kFrameTypeCount) {
    ++stats_.unknown_type;
    return;
  }
  if (f.header.type == FrameType::hello) {
    on_hello(f.payload, f.size);
    return;
  }
  const uint8_t c = f.header.channel;
  if (c >= kChannels) {
    ++stats_.unknown_channel;
    return;
  }
  if (!established_) {
    ++stats_.not_established;
    return;
  }
  if (f.header.tag != tag_) {
    ++stats_.bad_session;
    return;
  }
  peer_est_ = true;  // only an established peer tags its frames
  if (!anchor_valid_) {
    anchor_valid_ = true;
    anchor_end_ = rx_wire_;
  }
  Channel& ch = ch_[c];
  switch (f.header.type) {
    case FrameType::data:
      if (ch.rxr == nullptr) {
        ++stats_.unknown_channel;
        return;
      }
      rx_data(c, f.header.seq, f.payload, f.size);
      return;
    case FrameType::ack:
      if (ch.txr == nullptr) {
        ++stats_.unknown_channel;
        return;
      }
      rx_ack(c, f.header.seq, f.payload, f.size);
      return;
    case FrameType::datagram: {
      if (ch.rxd == nullptr) {
        ++stats_.unknown_channel;
        return;
      }
      RxDatagram& d = *ch.rxd;
      if (f.size > d.cap) {
        ++stats_.too_long;
        return;
      }
      if (d.have && static_cast<int16_t>(static_cast<uint16_t>(f.header.seq - d.counter)) <= 0) {
        ++stats_.stale_datagrams;
        return;
      }
      if (f.size != 0) memcpy(d.buf, f.payload, f.size);
      d.len = static_cast<uint16_t>(f.size);
      d.counter = f.header.seq;
      d.have = d.fresh = true;
      return;
    }
    default:
      ++stats_.unknown_type;
      return;
  }
}

void Link::receive(const uint8_t* data, size_t n, uint32_t now_ms) {
  if (!ready_ || (data == nullptr && n != 0)) return;
  now_ = now_ms;
  stats_.rx_bytes += n;
  while (n != 0) {
    RxEvent ev = RxEvent::none;
    RxFrame f;
    const size_t k = rx_.push(data, n, &ev, &f);
    data += k;
    n -= k;
    rx_wire_ += static_cast<uint32_t>(k);  // a frame's delimiter is counted before it is handled
    switch (ev) {
      case RxEvent::frame:
        ++stats_.frames_ok;
        heard_ms_ = now_ms;
        on_frame(f);
        break;
      case RxEvent::too_long: ++stats_.too_long; damaged_ = true; break;
      case RxEvent::bad_cobs: ++stats_.bad_cobs; damaged_ = true; break;
      case RxEvent::too_short: ++stats_.too_short; damaged_ = true; break;
      case RxEvent::bad_crc: ++stats_.bad_crc; damaged_ = true; break;
      case RxEvent::none:
      case RxEvent::empty: break;
    }
  }
}

void Link::poll(uint32_t now_ms) {
  if (!ready_) return;
  now_ = now_ms;
  if (!established_) {
    if (static_cast<int32_t>(now_ms - hello_next_ms_) >= 0) {
      hello_due_ = true;
      hello_next_ms_ = now_ms + cfg_.hello_interval_ms;
    }
    return;
  }
  // Acks: a delayed one falls due; a damaged frame was taken off the line
  // (report the line at once on every channel that carries data to us, so
  // the sender learns of the loss in one round trip); keepalives, only on
  // channels that have carried data (the others' windows went in the
  // HELLO), or on the first channel if none has, so the peer still hears
  // from us and the line report still travels.
  bool any = false;
  for (Channel& ch : ch_) {
    if (ch.rxr != nullptr && ch.rxr->held != 0 && now_ms - ch.rxr->held_since_ms >= kAckDelayMs) ch.rxr->ack_due = true;
    if (ch.rxr == nullptr || ch.rxr->nxt == 0) continue;
    any = true;
    if (now_ms - ch.rxr->last_ack_ms >= cfg_.keepalive_ms || damaged_) ch.rxr->ack_due = true;
  }
  for (Channel& ch : ch_) {
    if (any || ch.rxr == nullptr) continue;
    if (now_ms - ch.rxr->last_ack_ms >= cfg_.keepalive_ms) ch.rxr->ack_due = true;
    break;
  }
  damaged_ = false;
  check_timeouts();
}

bool Link::emit(const FrameHeader& h, const uint8_t* payload, size_t n) {
  return emit_parts(h, payload, n, nullptr, 0);
}

bool Link::emit_parts(const FrameHeader& h, const uint8_t* a, size_t na, const uint8_t* b, size_t nb) {
  size_t at = 0;
  if (line_idle_) {
    txf_[at++] = 0;  // flush whatever the peer's receiver gathered while the line was idle
    line_idle_ = false;
  }
  size_t len = 0;
  if (frame_encode_parts(h, a, na, b, nb, txf_ + at, txf_cap_ - at, &len) != Status::ok) return false;
  if (h.type != FrameType::hello && !first_tagged_sent_) {
    first_tagged_sent_ = true;
    first_tagged_wire_ = tx_wire_;  // the transmit buffer was empty: this frame starts here
  }
  txf_len_ = at + len;
  txf_pos_ = 0;
  txf_type_ = h.type;
  txf_channel_ = h.channel;
  ++stats_.frames_sent;
  return true;
}

bool Link::build_hello() {
  uint8_t p[kHelloMaxPayload];
  p[0] = kVersionMajor;
  p[1] = kVersionMinor;
  p[2] = static_cast<uint8_t>((established_ ? kHelloFlagEstablished : 0) |
                              (cfg_.role == Role::device ? kHelloFlagDevice : 0));
  p[3] = kCapabilities;
  store_le32(p + 4, my_nonce_);
  store_le32(p + 8, peer_nonce_);
  store_le16(p + 12, cfg_.max_rx_payload);
  uint8_t count = 0;
  for (uint8_t i = 0; i < kChannels; ++i) {
    const ChannelConfig& cc = cfg_.channels[i];
    if (cc.rx == Mode::none) continue;
    uint8_t* e = p + kHelloFixedBytes + kHelloChannelBytes * count;
    e[0] = i;
    e[1] = static_cast<uint8_t>(cc.rx);
    store_le16(e + 2, cc.rx_bytes);
    ++count;
  }
  p[14] = count;
  p[15] = 0;
  store_le16(p + 16, cfg_.rx_line_bytes);
  FrameHeader h;
  h.type = FrameType::hello;
  return emit(h, p, kHelloFixedBytes + kHelloChannelBytes * count);
}

// Priority: handshake, acks (they keep the peer's window moving), datagrams
// (latest-wins traffic is latency-sensitive and small), then reliable data
// round-robin over channels, retransmissions before new bytes.
bool Link::build_next_frame() {
  if (hello_due_) {
    hello_due_ = false;
    if (build_hello()) return true;
  }
  if (!established_) return false;
  if (probe_due_ && build_probe()) return true;
  // Acks and datagrams are never held back for new data, but they too
  // wait when the peer's line buffer is full (a paused peer).
  if (!line_has_room(frame_wire_bound(kAckMaxPayload > kHelloMaxPayload ? kAckMaxPayload : kHelloMaxPayload) + 1, true))
    return false;
  for (uint8_t i = 0; i < kChannels; ++i) {
    if (ch_[i].rxr != nullptr && ch_[i].rxr->ack_due && build_ack(i)) return true;
  }
  for (uint8_t i = 0; i < kChannels; ++i) {
    Channel& ch = ch_[i];
    if (ch.txd == nullptr || !ch.txd->pending) continue;
    ch.txd->pending = false;
    if (ch.peer_rx != Mode::datagram) continue;
    FrameHeader h;
    h.type = FrameType::datagram;
    h.channel = i;
    h.tag = tag_;
    h.seq = ++ch.txd->counter;
    if (emit(h, ch.txd->buf, ch.txd->len)) return true;
  }
  for (uint8_t k = 0; k < kChannels; ++k) {
    const uint8_t i = static_cast<uint8_t>((rr_ + k) % kChannels);
    if (ch_[i].txr != nullptr && build_data(i)) {
      rr_ = static_cast<uint8_t>((i + 1) % kChannels);
      return true;
    }
  }
  return false;
}

size_t Link::transmit(uint8_t* out, size_t max, uint32_t now_ms) {
  if (!ready_ || out == nullptr) return 0;
  poll(now_ms);
  size_t w = 0;
  while (w < max) {
    if (txf_pos_ == txf_len_) {
      txf_pos_ = txf_len_ = 0;
      if (!build_next_frame()) {
        line_idle_ = true;
        break;
      }
    }
    size_t k = txf_len_ - txf_pos_;
    if (k > max - w) k = max - w;
    memcpy(out + w, txf_ + txf_pos_, k);
    txf_pos_ += k;
    w += k;
    tx_wire_ += static_cast<uint32_t>(k);
    if (txf_pos_ == txf_len_) frame_left();
  }
  stats_.tx_bytes += w;
  return w;
}

Status Link::send_datagram(uint8_t c, const uint8_t* data, size_t n) {
  if (!ready_ || c >= kChannels || ch_[c].txd == nullptr || (data == nullptr && n != 0))
    return Status::invalid_argument;
  TxDatagram& d = *ch_[c].txd;
  if (n > d.cap) return Status::output_too_small;
  if (established_ && ch_[c].peer_rx != Mode::datagram) return Status::unsupported_feature;
  if (n != 0) memcpy(d.buf, data, n);
  d.len = static_cast<uint16_t>(n);
  d.pending = true;
  return Status::ok;
}

Status Link::read_datagram(uint8_t c, uint8_t* out, size_t max, size_t* got) {
  if (!ready_ || c >= kChannels || ch_[c].rxd == nullptr || got == nullptr) return Status::invalid_argument;
  RxDatagram& d = *ch_[c].rxd;
  *got = 0;
  if (!d.fresh) return Status::more_input;
  if (max < d.len || (out == nullptr && d.len != 0)) return Status::output_too_small;
  if (d.len != 0) memcpy(out, d.buf, d.len);
  *got = d.len;
  d.fresh = false;
  return Status::ok;
}

}  // namespace vds::link
