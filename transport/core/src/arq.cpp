// Reliable link channels: selective-repeat ARQ over 16-bit byte offsets with
// cumulative + selective acknowledgements (after TCP SACK, RFC 2018); flow
// control and loss detection from the receiver's line report (the last data
// frame it took off the line intact, as TCP's timestamp echo names a
// segment, and the wire bytes it took since): a frame is lost only once the
// receiver has taken it and not accepted it, never because it is late; RTO
// from Jacobson/Karels smoothing (RFC 6298, Karn's rule) with back-off, which
// only sends a small probe; and a frame size chosen from the loss rate.
#include <cstring>

#include "vds/bytes.h"
#include "vds/link/link.h"

namespace vds::link {

using detail::Range;
using detail::RxReliable;
using detail::Segment;
using detail::SegState;
using detail::TxReliable;

namespace {

// Offsets are 32-bit counters that may wrap: compare by signed difference.
int32_t diff(uint32_t a, uint32_t b) { return static_cast<int32_t>(a - b); }

// The full offset nearest `ref` whose low 16 bits are `v` (the wire carries
// 16 bits; windows stay far below 32 KiB so the nearest one is the one meant).
uint32_t widen(uint16_t v, uint32_t ref) {
  return ref + static_cast<uint32_t>(static_cast<int32_t>(static_cast<int16_t>(static_cast<uint16_t>(v - ref))));
}

// Frame overhead the size rule charges: header, CRC, one COBS code byte and
// the delimiter.
constexpr uint32_t kWireOverhead = kFrameOverhead + 2;
// Frames whose fate is known are averaged over about this many wire bytes
// (both counters halve when it is exceeded).
constexpr uint32_t kEstimateWindow = 16384;
constexpr uint32_t kLostOne = 256;  // one lost frame in est_lost_q8_ (Q8)
constexpr uint8_t kMaxBackoff = 16;
// Line report, byte 0: the channel of the echoed frame, and two flags.
constexpr uint8_t kEchoChannelMask = 0x0F;
constexpr uint8_t kEchoValid = 0x10;      // a data frame was taken intact this session
constexpr uint8_t kEchoDuplicate = 0x20;  // it carried nothing new
constexpr uint8_t kAnchored = 0x40;       // no data frame yet: `after` counts from the session's first frame
// A probe resends at most this many bytes: the tail of the oldest frame.
constexpr uint16_t kProbePayload = 16;

uint64_t isqrt64(uint64_t x) {
  uint64_t r = 0;
  uint64_t bit = uint64_t{1} << 62;
  while (bit > x) bit >>= 2;
  while (bit != 0) {
    if (x >= r + bit) {
      x -= r + bit;
      r = (r >> 1) + bit;
    } else {
      r >>= 1;
    }
    bit >>= 2;
  }
  return r;
}

}  // namespace

// ---------------------------------------------------------------- receiver

void Link::rx_data(uint8_t c, uint16_t seq, const uint8_t* p, size_t n) {
  RxReliable& r = *ch_[c].rxr;
  // Whatever becomes of it, this frame left the line intact: the next line
  // report names it.
  echo_valid_ = true;
  echo_ch_ = c;
  echo_seq_ = seq;
  echo_end_ = rx_wire_;
  echo_dup_ = false;
  if (n == 0) {
    r.ack_due = true;
    return;
  }
  // Every data frame is answered, at once unless it is the next in order
  // on a line with no holes (then every second frame, or kAckDelayMs).
  const uint32_t off = widen(seq, r.nxt);
  if (off == r.nxt && r.range_count == 0) {
    if (r.held++ == 0) r.held_since_ms = now_;
    if (r.held >= kAckEveryFrames) r.ack_due = true;
  } else {
    r.ack_due = true;
  }
  const uint32_t end = off + static_cast<uint32_t>(n);
  if (diff(end, r.rd + r.cap) > 0) {
    ++stats_.out_of_window;
    return;
  }
  if (diff(end, r.nxt) <= 0) {
    ++stats_.duplicates;
    echo_dup_ = true;
    return;
  }
  const uint32_t start = diff(off, r.nxt) < 0 ? r.nxt : off;
  if (start != r.nxt) {
    // Above a hole: record the block (merged with its neighbours).
    uint32_t s = start, e = end;
    uint8_t first = r.range_count, last = 0, merged = 0;
    for (uint8_t i = 0; i < r.range_count; ++i) {
      const Range& g = r.ranges[i];
      if (diff(g.start, e) > 0 || diff(g.end, s) < 0) continue;
      if (diff(g.start, s) <= 0 && diff(g.end, e) >= 0) {
        ++stats_.duplicates;  // wholly inside what we hold
        echo_dup_ = true;
        return;
      }
      if (merged == 0) first = i;
      last = i;
      ++merged;
      if (diff(g.start, s) < 0) s = g.start;
      if (diff(g.end, e) > 0) e = g.end;
    }
    if (merged == 0) {
      if (r.range_count == kRxRanges) {
        ++stats_.ooo_dropped;
        return;
      }
      uint8_t at = 0;
      while (at < r.range_count && diff(r.ranges[at].start, s) < 0) ++at;
      memmove(&r.ranges[at + 1], &r.ranges[at], sizeof(Range) * (r.range_count - at));
      r.ranges[at] = Range{s, e};
      ++r.range_count;
      r.latest = at;
    } else {
      r.ranges[first] = Range{s, e};
      const uint8_t gone = static_cast<uint8_t>(last - first);
      memmove(&r.ranges[first + 1], &r.ranges[last + 1], sizeof(Range) * (r.range_count - last - 1));
      r.range_count = static_cast<uint8_t>(r.range_count - gone);
      r.latest = first;
    }
  }
  // Copy [start, end) into the ring (it lies inside [rd, rd + cap)).
  const uint8_t* src = p + (start - off);
  uint32_t len = end - start;
  uint32_t pos = (r.rd_pos + (start - r.rd)) % r.cap;
  const uint32_t first_part = len < r.cap - pos ? len : r.cap - pos;
  memcpy(r.ring + pos, src, first_part);
  if (len > first_part) memcpy(r.ring, src + first_part, len - first_part);
  if (start == r.nxt) {
    r.nxt = end;
    while (r.range_count != 0 && diff(r.ranges[0].start, r.nxt) <= 0) {
      if (diff(r.ranges[0].end, r.nxt) > 0) r.nxt = r.ranges[0].end;
      memmove(&r.ranges[0], &r.ranges[1], sizeof(Range) * (r.range_count - 1));
      --r.range_count;
      r.latest = r.latest == 0 || r.latest == 0xFF ? 0xFF : static_cast<uint8_t>(r.latest - 1);
    }
    if (r.range_count == 0 || r.latest >= r.range_count) r.latest = 0xFF;
  }
  const uint32_t top = r.range_count != 0 ? r.ranges[r.range_count - 1].end : r.nxt;
  if (top - r.rd > r.peak) r.peak = top - r.rd;
}

bool Link::build_ack(uint8_t c) {
  RxReliable& r = *ch_[c].rxr;
  uint8_t p[kAckMaxPayload];
  const uint32_t wnd = r.rd + r.cap - r.nxt;
  store_le16(p, wnd);
  // The line report: the last data frame taken intact (any channel) and
  // the wire bytes taken after its delimiter (saturating).
  const uint32_t after = rx_wire_ - (echo_valid_ ? echo_end_ : anchor_end_);
  const uint16_t after16 = after > 0xFFFF ? 0xFFFF : static_cast<uint16_t>(after);
  p[2] = echo_valid_     ? static_cast<uint8_t>(kEchoValid | (echo_dup_ ? kEchoDuplicate : 0) | echo_ch_)
         : anchor_valid_ ? kAnchored
                         : 0;
  store_le16(p + 3, echo_seq_);
  store_le16(p + 5, after16);
  size_t n = kAckFixedBytes;
  // The block with the newest arrival first (the sender's loss detection
  // needs it), then the highest others.
  uint8_t order[kSackBlocks];
  uint8_t blocks = 0;
  if (r.latest < r.range_count) order[blocks++] = r.latest;
  for (int i = r.range_count - 1; i >= 0 && blocks < kSackBlocks; --i) {
    if (static_cast<uint8_t>(i) != r.latest) order[blocks++] = static_cast<uint8_t>(i);
  }
  for (uint8_t b = 0; b < blocks; ++b) {
    const Range& g = r.ranges[order[b]];
    store_le16(p + n, g.start);
    store_le16(p + n + 2, g.end);
    n += 4;
  }
  FrameHeader h;
  h.type = FrameType::ack;
  h.channel = c;
  h.tag = tag_;
  h.seq = static_cast<uint16_t>(r.nxt);
  r.ack_due = false;
  r.held = 0;
  r.last_ack_ms = now_;
  r.advertised_end = r.rd + r.cap;
  return emit(h, p, n);
}

Status Link::read(uint8_t c, uint8_t* out, size_t max, size_t* got) {
  if (!ready_ || c >= kChannels || ch_[c].rxr == nullptr || got == nullptr || (out == nullptr && max != 0))
    return Status::invalid_argument;
  RxReliable& r = *ch_[c].rxr;
  uint32_t avail = r.nxt - r.rd;
  const uint32_t k = max < avail ? static_cast<uint32_t>(max) : avail;
  const uint32_t first_part = k < r.cap - r.rd_pos ? k : r.cap - r.rd_pos;
  if (k != 0) {
    memcpy(out, r.ring + r.rd_pos, first_part);
    if (k > first_part) memcpy(out + first_part, r.ring, k - first_part);
  }
  r.rd += k;
  r.rd_pos = (r.rd_pos + k) % r.cap;
  *got = k;
  // Announce a window that grew by a quarter or more at once; smaller
  // growth rides on the next ack.
  const uint32_t quarter = r.cap / 4 != 0 ? r.cap / 4 : 1;
  if (established_ && r.rd + r.cap - r.advertised_end >= quarter) r.ack_due = true;
  return Status::ok;
}

size_t Link::readable(uint8_t c) const {
  if (c >= kChannels || ch_[c].rxr == nullptr) return 0;
  return ch_[c].rxr->nxt - ch_[c].rxr->rd;
}

uint32_t Link::rx_peak(uint8_t c) const {
  if (c >= kChannels || ch_[c].rxr == nullptr) return 0;
  return ch_[c].rxr->peak;
}

uint32_t Link::rx_window(uint8_t c) const {
  if (c >= kChannels || ch_[c].rxr == nullptr) return 0;
  return ch_[c].rxr->cap;
}

// ------------------------------------------------------------------ sender

Status Link::write(uint8_t c, const uint8_t* data, size_t n, size_t* accepted) {
  if (!ready_ || c >= kChannels || ch_[c].txr == nullptr || accepted == nullptr || (data == nullptr && n != 0))
    return Status::invalid_argument;
  *accepted = 0;
  if (established_ && ch_[c].peer_rx != Mode::reliable) return Status::unsupported_feature;
  TxReliable& t = *ch_[c].txr;
  const uint32_t used = t.wr - t.base;
  const uint32_t room = t.cap - used;
  const uint32_t k = n < room ? static_cast<uint32_t>(n) : room;
  const uint32_t pos = (t.base_pos + used) % t.cap;
  const uint32_t first_part = k < t.cap - pos ? k : t.cap - pos;
  if (k != 0) {
    memcpy(t.ring + pos, data, first_part);
    if (k > first_part) memcpy(t.ring, data + first_part, k - first_part);
  }
  t.wr += k;
  *accepted = k;
  return Status::ok;
}

size_t Link::writable(uint8_t c) const {
  if (c >= kChannels || ch_[c].txr == nullptr) return 0;
  return ch_[c].txr->cap - (ch_[c].txr->wr - ch_[c].txr->base);
}

size_t Link::unacked(uint8_t c) const {
  if (c >= kChannels || ch_[c].txr == nullptr) return 0;
  return ch_[c].txr->wr - ch_[c].txr->base;
}

size_t Link::in_flight(uint8_t c) const {
  if (c >= kChannels || ch_[c].txr == nullptr) return 0;
  return ch_[c].txr->nxt - ch_[c].txr->base;
}

size_t Link::peer_room(uint8_t c) const {
  if (c >= kChannels || ch_[c].txr == nullptr) return 0;
  const TxReliable& t = *ch_[c].txr;
  return diff(t.wnd_end, t.nxt) > 0 ? t.wnd_end - t.nxt : 0;
}

void Link::rtt_sample(uint32_t ms) {
  const int32_t r = static_cast<int32_t>(ms > 60000 ? 60000 : ms);
  if (!have_rtt_) {
    srtt_q3_ = r << 3;    // srtt = r
    rttvar_q2_ = r << 1;  // rttvar = r / 2, in Q2
    have_rtt_ = true;
  } else {
    int32_t delta = r - (srtt_q3_ >> 3);
    srtt_q3_ += delta;  // srtt += (r - srtt) / 8
    if (delta < 0) delta = -delta;
    delta -= rttvar_q2_ >> 2;
    rttvar_q2_ += delta;  // rttvar += (|r - srtt| - rttvar) / 4
  }
  // RTO = srtt + 4 * rttvar, where rttvar_q2_ already is 4 * rttvar; at
  // least twice srtt, because on a serial line the round trip is mostly
  // frame serialisation and barely varies, and a spurious timeout costs a
  // whole frame (losses are found by later acks long before the RTO).
  const int32_t srtt = srtt_q3_ >> 3;
  int32_t rto = srtt + (rttvar_q2_ > 1 ? rttvar_q2_ : 1);
  if (rto < 2 * srtt) rto = 2 * srtt;
  if (rto < cfg_.rto_min_ms) rto = cfg_.rto_min_ms;
  if (rto > cfg_.rto_max_ms) rto = cfg_.rto_max_ms;
  rto_ms_ = static_cast<uint32_t>(rto);
}

void Link::note_outcome(uint16_t len, bool lost) {
  est_bytes_ += len + kWireOverhead;
  est_frames_q8_ += kLostOne;
  if (lost) est_lost_q8_ += kLostOne;
  if (est_bytes_ > kEstimateWindow) {
    est_bytes_ >>= 1;
    est_frames_q8_ >>= 1;
    est_lost_q8_ >>= 1;
  }
  update_frame_size();
}

// With a per-byte loss probability q and h bytes of overhead per frame,
// selective repeat delivers (L - h) / L * (1 - q)^L of the line rate with
// frames of L wire bytes; the optimum satisfies L^2 - h*L = h/q (first order
// in q), so L = h/2 + sqrt(h^2/4 + h/q). q is estimated from the frames
// whose fate is known: a frame of W bytes is lost with probability
// f = 1 - (1-q)^W ~ qW (1 - qW/2), so q ~ lost / (bytes (1 - f/2)), f the
// fraction of frames lost (lost / bytes alone underestimates q by f/2,
// 15 % at a bit-error rate of 1e-3, and picks frames too long).
void Link::update_frame_size() {
  uint32_t cap = cfg_.max_tx_payload;
  if (peer_max_payload_ != 0 && peer_max_payload_ < cap) cap = peer_max_payload_;
  if (peer_line_bytes_ != 0) {
    // A whole frame (and a leading delimiter) must fit the peer's line
    // buffer less the reserve, or it would wait forever.
    const uint32_t limit = peer_line_bytes_ - line_reserve(peer_line_bytes_);
    const uint32_t fit = limit - 14 - limit / 254;
    if (fit < cap) cap = fit;
  }
  uint32_t fp = cap;
  if (cfg_.adaptive && est_lost_q8_ != 0 && est_frames_q8_ != 0) {
    const uint64_t h = kWireOverhead;
    const uint64_t bytes = est_bytes_ - static_cast<uint64_t>(est_bytes_) * est_lost_q8_ / (2u * est_frames_q8_);
    const uint64_t h_over_q = h * bytes * kLostOne / est_lost_q8_;
    const uint64_t wire = h / 2 + isqrt64(h * h / 4 + h_over_q);
    fp = wire > h + cap ? cap : static_cast<uint32_t>(wire - h);
  }
  if (fp < cfg_.min_tx_payload) fp = cfg_.min_tx_payload;
  if (fp > cap) fp = cap;
  frame_payload_ = static_cast<uint16_t>(fp);
}

void Link::segment_acked(Segment& s) {
  if (s.state == SegState::sacked) return;
  if (s.tries == 1) rtt_sample(now_ - s.sent_ms);  // Karn: never time a retransmitted frame
  note_outcome(s.len, false);
  s.state = SegState::sacked;
}

// The peer has taken every wire byte below `wire` off its line: the data
// frames that ended there are out of the pipe, accepted or not.
void Link::resolve_to(uint32_t wire) {
  if (diff(wire, tx_wire_) > 0) wire = tx_wire_;
  if (diff(wire, resolved_wire_) <= 0) return;
  resolved_wire_ = wire;
  progress_ms_ = rto_from_ms_ = now_;
  backoff_ = 0;
  while (log_count_ != 0 && diff(log_[log_head_].wire_end, wire) <= 0) {
    const detail::Sent& e = log_[log_head_];
    // A frame split after it was sent leaves pieces with its order: all of
    // them were on the line in that frame.
    if (e.ch < kChannels && ch_[e.ch].txr != nullptr) {
      TxReliable& t = *ch_[e.ch].txr;
      for (uint16_t i = 0; i < t.seg_count; ++i)
        if (t.segs[i].order == e.order) t.segs[i].taken = true;
    }
    log_head_ = static_cast<uint16_t>((log_head_ + 1) % log_cap_);
    --log_count_;
  }
}

// A line report (docs/protocol.md, "Flow control and loss"): find the
// echoed frame in the log (the oldest copy not yet known to be taken: the
// pipe keeps order), and count the wire bytes taken after it. Every
// misreading errs towards "still in flight": a report that repeats the last
// echo is read as that frame, even if a later copy with the same offset
// arrived, and bytes lost on the line are never counted as taken.
void Link::on_line_report(const uint8_t* p) {
  report_ms_ = now_;
  const uint32_t after = load_le16(p + 3);
  if ((p[0] & kEchoValid) == 0) {
    // No data frame taken yet: the peer counts from the end of the first
    // frame of ours it took, which lies at or after where our first one
    // started.
    if ((p[0] & kAnchored) != 0 && first_tagged_sent_) resolve_to(first_tagged_wire_ + after);
    return;
  }
  const uint8_t ch = p[0] & kEchoChannelMask;
  const uint16_t seq = load_le16(p + 1);
  uint32_t base = 0;
  if (last_echo_valid_ && last_echo_ch_ == ch && last_echo_seq_ == seq) {
    base = last_echo_end_;
  } else {
    uint16_t i = 0;
    while (i < log_count_) {
      const detail::Sent& e = log_[(log_head_ + i) % log_cap_];
      if (e.ch == ch && e.seq == seq) break;
      ++i;
    }
    if (i == log_count_) return;  // stale: about a frame already accounted for
    const detail::Sent& e = log_[(log_head_ + i) % log_cap_];
    base = e.wire_end;
    if ((p[0] & kEchoDuplicate) != 0 && !e.probe) ++stats_.spurious;
    last_echo_valid_ = true;
    last_echo_ch_ = ch;
    last_echo_seq_ = seq;
    last_echo_end_ = base;
  }
  resolve_to(base + after);
}

// Frames of channel `c` the peer took off its line and did not accept
// (damaged, cut short, or refused) are lost: only now, never for being late.
void Link::declare_taken_lost(uint8_t c) {
  TxReliable& t = *ch_[c].txr;
  for (uint16_t i = 0; i < t.seg_count; ++i) {
    Segment& g = t.segs[i];
    if (g.state != SegState::in_flight || !g.taken) continue;
    g.state = SegState::lost;
    g.taken = false;
    ++stats_.losses;
    note_outcome(g.len, true);
  }
}

void Link::rx_ack(uint8_t c, uint16_t seq, const uint8_t* p, size_t n) {
  TxReliable& t = *ch_[c].txr;
  if (n < kAckFixedBytes || (n - kAckFixedBytes) % 4 != 0 || (n - kAckFixedBytes) / 4 > kSackBlocks ||
      (p[2] & ~(kEchoValid | kEchoDuplicate | kAnchored | kEchoChannelMask)) != 0) {
    ++stats_.bad_ack;
    return;
  }
  // Acks never go backwards on a FIFO pipe; anything outside [base, nxt] is
  // stale or bogus.
  const uint32_t ack = t.base + static_cast<uint16_t>(seq - static_cast<uint16_t>(t.base));
  const uint32_t wnd = load_le16(p);
  if (diff(ack, t.nxt) > 0 || wnd > kMaxWindow) {
    ++stats_.bad_ack;
    return;
  }
  if (diff(ack + wnd, t.wnd_end) > 0) t.wnd_end = ack + wnd;
  uint16_t done = 0;
  while (done < t.seg_count && diff(t.segs[done].start + t.segs[done].len, ack) <= 0) {
    segment_acked(t.segs[done]);
    ++done;
  }
  if (done != 0) {
    memmove(&t.segs[0], &t.segs[done], sizeof(Segment) * (t.seg_count - done));
    t.seg_count = static_cast<uint16_t>(t.seg_count - done);
  }
  if (t.seg_count != 0 && diff(ack, t.segs[0].start) > 0) {
    const uint32_t cut = ack - t.segs[0].start;
    t.segs[0].start = ack;
    t.segs[0].len = static_cast<uint16_t>(t.segs[0].len - cut);
  }
  if (diff(ack, t.base) > 0) {
    t.base_pos = (t.base_pos + (ack - t.base)) % t.cap;
    t.base = ack;
    backoff_ = 0;
    progress_ms_ = rto_from_ms_ = now_;
  }
  for (size_t b = kAckFixedBytes; b < n; b += 4) {
    const uint32_t s = widen(load_le16(p + b), ack);
    const uint32_t e = widen(load_le16(p + b + 2), ack);
    if (diff(s, ack) <= 0 || diff(e, s) <= 0 || diff(e, t.nxt) > 0) {
      ++stats_.bad_ack;
      continue;
    }
    // Segments are in offset order: find the first inside the block.
    uint16_t lo = 0, hi = t.seg_count;
    while (lo < hi) {
      const uint16_t mid = static_cast<uint16_t>((lo + hi) / 2);
      if (diff(t.segs[mid].start, s) < 0) lo = static_cast<uint16_t>(mid + 1);
      else hi = mid;
    }
    for (uint16_t i = lo; i < t.seg_count && diff(t.segs[i].start + t.segs[i].len, e) <= 0; ++i)
      segment_acked(t.segs[i]);
  }
  // The report was made after the acknowledgements it travels with, so a
  // frame it shows taken and they do not show accepted is lost.
  on_line_report(p + 2);
  declare_taken_lost(c);
}

// The frame still leaving the transmit buffer has not been sent yet.
bool Link::leaving(const Segment& g) const {
  return txf_pos_ < txf_len_ && txf_type_ == FrameType::data && g.order == txf_order_;
}

// Cuts segment i of `t` after its first `head` bytes: the rest becomes
// segment i + 1 with the same state (the caller has checked seg_count <
// seg_cap).
void Link::split_segment(TxReliable& t, uint16_t i, uint16_t head) {
  Segment& g = t.segs[i];
  memmove(&t.segs[i + 2], &t.segs[i + 1], sizeof(Segment) * (t.seg_count - i - 1));
  Segment tail = g;
  tail.start = g.start + head;
  tail.len = static_cast<uint16_t>(g.len - head);
  t.segs[i + 1] = tail;
  ++t.seg_count;
  g.len = head;
}

// The RTO (with back-off) counts from the later of the oldest frame in
// flight leaving and the last progress (bytes taken or acknowledged). When
// it fires nothing is declared lost: the peer may only be slow. One probe
// goes out instead, the last few bytes of the oldest frame, so a line
// whose last frame and its report were lost still moves.
void Link::check_timeouts() {
  uint32_t rto = rto_ms_ << backoff_;
  if (backoff_ >= kMaxBackoff || rto > cfg_.rto_max_ms) rto = cfg_.rto_max_ms;
  const uint32_t from = diff(rto_from_ms_, oldest_sent_ms_) > 0 ? rto_from_ms_ : oldest_sent_ms_;
  if (now_ - from < rto) return;
  uint32_t oldest = now_;
  bool pending = false;
  for (detail::Channel& ch : ch_) {
    if (ch.txr == nullptr) continue;
    const TxReliable& t = *ch.txr;
    for (uint16_t i = 0; i < t.seg_count; ++i) {
      const Segment& g = t.segs[i];
      if (g.state != SegState::in_flight || leaving(g)) continue;
      if (diff(g.sent_ms, oldest) < 0) oldest = g.sent_ms;
      pending = true;
    }
  }
  oldest_sent_ms_ = oldest;
  if (!pending || now_ - (diff(rto_from_ms_, oldest) > 0 ? rto_from_ms_ : oldest) < rto) return;
  ++stats_.timeouts;
  if (backoff_ < kMaxBackoff) ++backoff_;
  rto_from_ms_ = now_;  // the next RTO counts from here
  probe_due_ = true;
  lost_on_line_ = now_ - progress_ms_ >= rto && report_ms_ - progress_ms_ >= rto && log_count_ != 0;
}

// Whether a frame of `wire` bytes may go now without the peer's line
// buffer holding more than it declared. New data leaves line_reserve() for
// the small frames that are never held back, and probes.
bool Link::line_has_room(size_t wire, bool probe) const {
  if (peer_line_bytes_ == 0) return true;
  const uint32_t limit = probe ? peer_line_bytes_ : peer_line_bytes_ - line_reserve(peer_line_bytes_);
  return line_in_flight() + wire <= limit;
}

// One probe after an RTO: the last bytes of the oldest frame in flight,
// sent as a frame of their own (a new offset, so the peer's report of it
// cannot be mistaken for the original's). If the line has no room even for
// that, and the peer has kept reporting for an RTO since the last progress
// without taking what we count as in flight, those bytes never reached it
// (dropped on the line): forget them, and their frames are lost.
bool Link::build_probe() {
  probe_due_ = false;
  const bool dropped = lost_on_line_;
  lost_on_line_ = false;
  for (uint8_t c = 0; c < kChannels; ++c) {
    detail::Channel& ch = ch_[c];
    if (ch.txr == nullptr || ch.peer_rx != Mode::reliable) continue;
    TxReliable& t = *ch.txr;
    for (uint16_t i = 0; i < t.seg_count; ++i) {
      Segment& g = t.segs[i];
      if (g.state != SegState::in_flight || leaving(g)) continue;
      const uint16_t plen = g.len < kProbePayload ? g.len : kProbePayload;
      if (!line_has_room(frame_wire_bound(plen) + 1, true) || log_count_ == log_cap_ ||
          (g.len > plen && t.seg_count == t.seg_cap)) {
        if (dropped) {
          resolve_to(tx_wire_);
          for (uint8_t k = 0; k < kChannels; ++k)
            if (ch_[k].txr != nullptr) declare_taken_lost(k);
        }
        return false;
      }
      if (g.len > plen) {
        split_segment(t, i, static_cast<uint16_t>(g.len - plen));
        ++i;
      }
      ++stats_.probes;
      return send_segment(c, t.segs[i], true);
    }
  }
  return false;
}

bool Link::build_data(uint8_t c) {
  detail::Channel& ch = ch_[c];
  // Data waits until the peer is established: before that it would drop
  // every frame, and the line would fill with bytes no report accounts for.
  if (ch.peer_rx != Mode::reliable || !peer_est_) return false;
  TxReliable& t = *ch.txr;
  for (uint16_t i = 0; i < t.seg_count; ++i) {
    Segment& g = t.segs[i];
    if (g.state != SegState::lost) continue;
    // Resend in frames near the current size when that is much smaller:
    // split into k nearly equal pieces (k = ceil(len / size)), so no tiny
    // tail frame pays a whole frame's overhead.
    if (g.len > frame_payload_ + frame_payload_ / 2 && t.seg_count < t.seg_cap) {
      const uint32_t pieces = (g.len + frame_payload_ - 1u) / frame_payload_;
      split_segment(t, i, static_cast<uint16_t>((g.len + pieces - 1u) / pieces));
    }
    if (!line_has_room(frame_wire_bound(g.len) + 1, false) || log_count_ == log_cap_) {
      ++stats_.line_waits;
      return false;  // lost data goes first, when the line has room
    }
    ++stats_.retransmissions;
    return send_segment(c, g, false);
  }
  const uint32_t avail = t.wr - t.nxt;
  const uint32_t room = diff(t.wnd_end, t.nxt) > 0 ? t.wnd_end - t.nxt : 0;
  const uint32_t want = avail < frame_payload_ ? avail : frame_payload_;
  const uint32_t len = want < room ? want : room;
  // Avoid a silly window: while frames are in flight, wait until a
  // whole frame fits rather than dribbling small ones.
  if (avail == 0 || len == 0 || t.seg_count == t.seg_cap || (len != want && t.seg_count != 0)) return false;
  if (!line_has_room(frame_wire_bound(len) + 1, false) || log_count_ == log_cap_) {
    ++stats_.line_waits;
    return false;
  }
  Segment& g = t.segs[t.seg_count++];
  g = Segment{t.nxt, static_cast<uint16_t>(len), SegState::in_flight, 0, 0, 0, false};
  t.nxt += len;
  return send_segment(c, g, false);
}

// Puts one segment of channel `c` into the transmit buffer as a data frame.
bool Link::send_segment(uint8_t c, Segment& seg, bool probe) {
  TxReliable& t = *ch_[c].txr;
  seg.state = SegState::in_flight;
  seg.taken = false;
  ++seg.tries;
  if (seg.tries == 0) seg.tries = 2;  // saturate: still "retransmitted"
  seg.sent_ms = now_;
  seg.order = ++order_;
  if (order_ == 0) seg.order = order_ = 1;
  FrameHeader h;
  h.type = FrameType::data;
  h.channel = c;
  h.tag = tag_;
  h.seq = static_cast<uint16_t>(seg.start);
  const uint32_t pos = (t.base_pos + (seg.start - t.base)) % t.cap;
  const uint32_t first_part = seg.len < t.cap - pos ? seg.len : t.cap - pos;
  ++stats_.data_frames_sent;
  stats_.payload_sent += seg.len;
  if (!emit_parts(h, t.ring + pos, first_part, t.ring, seg.len - first_part)) return false;
  txf_order_ = seg.order;
  txf_seq_ = h.seq;
  txf_probe_ = probe;
  return true;
}

}  // namespace vds::link
