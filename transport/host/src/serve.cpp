// Serving a stream over a link (`vds serve`), with an in-process verifying
// client for the loopback link.
#include "vds/link/serve.h"

#include <chrono>
#include <cstring>
#include <memory>
#include <optional>
#include <stdexcept>

#include "vds/container.h"
#include "vds/crc32c.h"
#include "vds/link/backend.h"
#include "vds/link/messages.h"
#include "vds/link/sim.h"

namespace vds::link {

namespace {

// Host side: writes the stream, restarting it with each new session,
// collects the client's end-of-stream report and answers it with a Goodbye.
// A client whose workspace is full reports early: the host writes no more.
struct Server {
  explicit Server(const std::vector<uint8_t>& s) : stream(s) {}
  // A live stream: made while it is served, into `made`.
  explicit Server(LiveStream& l) : stream(made), live(&l), complete(false) {}
  std::vector<uint8_t> made;
  const std::vector<uint8_t>& stream;
  LiveStream* live = nullptr;
  bool complete = true;  // the stream is whole (a file always)
  uint64_t written = 0;
  uint32_t epoch = 0;
  uint64_t started_ms = 0;
  MessageReader<kDoneReportBytes> ctl;
  MessageReader<kFrameRecordBytes> sums;
  bool receipt = false;
  DoneReport report{};
  bool goodbye_sent = false;
  uint32_t frame_records = 0;
  std::vector<FrameRecord> frames;
  bool have_stats = false;
  ClientStats stats{};
  std::function<void(const std::string&)> log;

  void pump(Link& h, uint64_t now) {
    if (!h.established()) return;
    if (h.session_epoch() != epoch) {
      if (epoch != 0 && log) log("session " + std::to_string(h.session_epoch()) + ": the client lost the session, sending the stream again");
      epoch = h.session_epoch();
      written = 0;
      ctl.reset();
      sums.reset();
      receipt = false;
      goodbye_sent = false;
      frame_records = 0;
      frames.clear();
      started_ms = now;
    }
    if (live != nullptr) {
      // The client's poses, then what is due by now. A new session starts
      // the client again from the first byte of what was made.
      uint8_t pose[64];
      size_t n = 0;
      while (h.read_datagram(channel::kPose, pose, sizeof pose, &n) == Status::ok) live->pose(pose, n);
      if (!complete) complete = live->produce(now - started_ms, made);
    }
    while (written < stream.size() && !wants_no_more()) {
      size_t acc = 0;
      if (h.write(channel::kStream, stream.data() + written, stream.size() - written, &acc) != Status::ok || acc == 0)
        break;
      written += acc;
    }
    // Frame records (checksums channel) are counted; the DoneReport
    // (control channel) ends the transfer.
    while (sums.next(h, channel::kChecksums)) {
      FrameRecord fr{};
      if (decode(sums.bytes, kFrameRecordBytes, &fr) == Status::ok) {
        ++frame_records;
        frames.push_back(fr);
      }
    }
    uint8_t st[kClientStatsBytes];
    size_t n = 0;
    while (h.read_datagram(channel::kStats, st, sizeof st, &n) == Status::ok)
      if (decode(st, n, &stats) == Status::ok) have_stats = true;
    while (!receipt && ctl.next(h, channel::kControl)) receipt = decode(ctl.bytes, kDoneReportBytes, &report) == Status::ok;
  }
  bool acked(Link& h) const {
    return complete && h.established() && written == stream.size() && h.unacked(channel::kStream) == 0;
  }
  // The client has reported that its workspace is full.
  bool wants_no_more() const { return receipt && report.reason == DoneReason::workspace_full; }
  // The report's status is ok and its byte count and CRC are the stream's,
  // or, from a client whose workspace is full, those of a prefix of it.
  bool verified(uint32_t crc) const {
    if (!receipt || report.status != static_cast<int32_t>(Status::ok)) return false;
    if (report.reason == DoneReason::end_of_stream)
      return report.stream_bytes == static_cast<uint32_t>(stream.size()) && report.stream_crc == crc;
    return report.stream_bytes <= stream.size() && report.stream_crc == crc32c(stream.data(), report.stream_bytes);
  }
  void say_goodbye(Link& h, uint32_t crc) {
    if (goodbye_sent || !h.established() || h.writable(channel::kControl) < kGoodbyeBytes) return;
    uint8_t msg[kGoodbyeBytes];
    encode(Goodbye{static_cast<uint8_t>(verified(crc) ? 1 : 0), frame_records}, msg);
    size_t acc = 0;
    goodbye_sent = h.write(channel::kControl, msg, sizeof msg, &acc) == Status::ok && acc == sizeof msg;
  }
  // The client holds the Goodbye: the host may close.
  bool goodbye_acked(Link& h) const { return goodbye_sent && h.established() && h.unacked(channel::kControl) == 0; }
};

// The loopback client: link core + container parser, as firmware would
// run them, plus the end-of-stream report.
struct Client {
  std::vector<uint64_t> ws;
  Arena arena;
  StreamParser parser;
  uint32_t epoch = 0;
  uint64_t got = 0;
  uint32_t crc = 0;
  bool sent_receipt = false;
  bool goodbye = false;  // the host's Goodbye arrived
  Goodbye bye{};
  MessageReader<kGoodbyeBytes> ctl;
  Status status = Status::more_input;
  uint32_t chunks = 0;
  size_t budget;

  explicit Client(size_t workspace) : ws((workspace + 7) / 8), arena(ws.data(), ws.size() * 8), budget(workspace) {}
  void restart() {
    arena = Arena(ws.data(), ws.size() * 8);
    const uint32_t cap = static_cast<uint32_t>(budget / 2);
    status = parser.init(arena, cap, ChunkSink{}) == Status::ok ? Status::more_input : Status::workspace_too_small;
    got = 0;
    crc = 0;
    sent_receipt = false;
    goodbye = false;
    ctl.reset();
  }
  void pump(Link& d) {
    if (d.session_epoch() != epoch) {
      epoch = d.session_epoch();
      restart();
    }
    uint8_t buf[1024];
    size_t n = 0;
    while (d.read(channel::kStream, buf, sizeof buf, &n) == Status::ok && n != 0) {
      crc = crc32c_update(crc, buf, n);
      got += n;
      if (status == Status::more_input) status = parser.feed(buf, n);
    }
    if (status == Status::ok && !sent_receipt && d.established() && d.writable(channel::kControl) >= kDoneReportBytes) {
      const DoneReport rep{static_cast<int32_t>(status), 0, static_cast<uint32_t>(got), crc};
      uint8_t msg[kDoneReportBytes];
      encode(rep, msg);
      size_t acc = 0;
      sent_receipt = d.write(channel::kControl, msg, sizeof msg, &acc) == Status::ok && acc == sizeof msg;
    }
    while (!goodbye && ctl.next(d, channel::kControl)) goodbye = decode(ctl.bytes, kGoodbyeBytes, &bye) == Status::ok;
    chunks = parser.chunks();
  }
};

uint32_t seed_from_clock() {
  return static_cast<uint32_t>(std::chrono::steady_clock::now().time_since_epoch().count()) | 1u;
}

}  // namespace

namespace {

ServeReport serve(Server& srv, const ServeOptions& o, const std::function<void(const std::string&)>& log) {
  const std::vector<uint8_t>& stream = srv.stream;
  ServeReport rep;
  rep.bytes = stream.size();
  rep.stream_crc = crc32c(stream.data(), stream.size());
  const uint32_t seed = o.nonce_seed != 0 ? o.nonce_seed : seed_from_clock();
  srv.log = log;

  if (o.link == "loopback") {
    if (srv.live != nullptr) throw std::runtime_error("a live stream needs a client that plays it: a board, not loopback");
    // Size the client's workspace from the stream's own header.
    StreamHeader hdr{};
    if (stream.size() < kPreambleBytes + kChunkHeadBytes + kHeaderPayloadV1 ||
        header_from_bytes(stream.data() + kPreambleBytes + kChunkHeadBytes, kHeaderPayloadV1, stream[4], stream[5],
                          &hdr) != Status::ok)
      throw std::runtime_error("not a vds stream (no valid header)");
    const size_t chunk = hdr.max_chunk_payload > kHeaderPayloadMax ? hdr.max_chunk_payload : kHeaderPayloadMax;
    Client cli(2 * chunk + hdr.workspace_bytes + 64);
    FaultConfig up = o.faults;
    up.seed = o.faults.seed + 0x5EED;
    const uint16_t line = o.drain.ring_bytes != 0 ? static_cast<uint16_t>(o.drain.ring_bytes) : 4096;
    LinkSim sim(o.baud, o.faults, up, host_config(seed, o.baud / 10), device_config(seed + 1, line), 1, o.drain);
    rep.simulated = true;
    // Simulated time is free; still bound it so a broken link cannot spin forever.
    const uint64_t rate = o.drain.ring_bytes != 0 && o.drain.rate_permille != 0 ? o.drain.rate_permille : 1000;
    const uint64_t limit_ms = 1000ull * (60 + stream.size() * 10 * 200 / o.baud * 1000 / rate);
    while (sim.now_ms() < limit_ms) {
      srv.pump(sim.host(), sim.now_ms());
      sim.step();
      cli.pump(sim.device());
      if (is_error(cli.status))
        throw std::runtime_error(std::string("the client refused the stream: ") + status_name(cli.status) + " (" +
                                 cli.parser.error_detail() + ")");
      if (srv.receipt && (srv.acked(sim.host()) || srv.wants_no_more())) srv.say_goodbye(sim.host(), rep.stream_crc);
      if (srv.goodbye_acked(sim.host()) && cli.goodbye) break;
    }
    if (!srv.receipt) throw std::runtime_error("the transfer did not finish within " + std::to_string(limit_ms / 1000) + " simulated seconds");
    rep.seconds = static_cast<double>(sim.now_ms() - srv.started_ms) / 1000.0;
    rep.client = sim.device().stats();
    if (sim.slow_device() != nullptr) rep.drain = sim.slow_device()->stats();
    rep.client_chunks = cli.chunks;
    rep.host = sim.host().stats();
    rep.sessions = sim.host().session_epoch();
    rep.final_frame_payload = sim.host().frame_payload();
    rep.goodbye_acked = srv.goodbye_acked(sim.host());
    rep.client_goodbye = cli.goodbye;
    rep.client_goodbye_verified = cli.goodbye && cli.bye.verified == 1;
    rep.bytes_acked = srv.written - sim.host().unacked(channel::kStream);
  } else {
    std::unique_ptr<Backend> b = open_backend(o.link, o.baud, o.paced);
    if (log) log("link " + b->describe() + " open; waiting for the client");
    const LinkConfig hc = host_config(seed, o.paced && o.link.rfind("usb:", 0) != 0 ? o.baud / 10 : 0);
    std::vector<uint64_t> ws((link_workspace_size(hc) + 7) / 8);
    Arena arena(ws.data(), ws.size() * 8);
    Link host;
    if (host.init(hc, arena) != Status::ok) throw std::runtime_error("link init failed");
    Pump pump(host, *b);
    const uint32_t t0 = monotonic_ms();
    uint32_t acked_at = 0;
    uint32_t owed_at = 0;  // last time the client's stats showed frame records still to come
    uint32_t record_at = 0;  // last time a frame record arrived
    size_t records_seen = 0;
    std::optional<uint32_t> receipt_at, goodbye_at;  // when the report had arrived, when the Goodbye went
    constexpr uint32_t kRecordWaitMs = 5000;   // frame records missing after this are reported missing
    constexpr uint32_t kGoodbyeWaitMs = 10000;  // a client that does not acknowledge the Goodbye by then has gone (a loaded machine may hold an emulated client back for seconds)
    bool announced = false;
    for (;;) {
      const uint32_t now = monotonic_ms();
      srv.pump(host, now);
      try {
        pump.step(now, 1);
      } catch (const BackendError& e) {
        // A client that has reported may power off (QEMU exits) while this
        // side still lingers: that is the end, not a failure.
        if (!(srv.receipt && e.kind() == BackendError::Kind::disconnected)) throw;
        rep.client_closed = true;
        break;
      }
      if (host.established() && !announced) {
        announced = true;
        if (log) log("session established (client nonce " + std::to_string(host.peer_nonce()) + ")");
      }
      if (srv.acked(host) && acked_at == 0) acked_at = now;
      if (srv.receipt && !receipt_at) receipt_at = now;
      // The report is in: collect the frame records still on their way (a
      // separate channel), then say goodbye, and close once the client has
      // acknowledged it: it stops on the Goodbye, without waiting for
      // acknowledgements of its own last messages.
      if (srv.live != nullptr && srv.complete && rep.bytes != stream.size()) {
        rep.bytes = stream.size();
        rep.stream_crc = crc32c(stream.data(), stream.size());
      }
      if (receipt_at) {
        const bool all_records = srv.frames.size() >= srv.report.frames_shown;
        if (all_records || now - *receipt_at > kRecordWaitMs) srv.say_goodbye(host, rep.stream_crc);
        if (srv.goodbye_sent && !goodbye_at) goodbye_at = now;
        if (srv.goodbye_acked(host)) {
          rep.goodbye_acked = true;
          break;
        }
        if (goodbye_at && now - *goodbye_at > kGoodbyeWaitMs) break;
      }
      // All acknowledged: wait briefly for the report (a client may not send
      // one), counted from when the client stopped owing frame records: one
      // whose stats show more frames than have arrived is still sending, and
      // its report follows its records; so is one whose records still
      // arrive (frames drawn from bytes it already holds, e.g. a model's
      // orbit).
      const bool records_owed = srv.have_stats && srv.stats.frames_shown > srv.frames.size();
      if (records_owed) owed_at = now;
      if (srv.frames.size() != records_seen) {
        records_seen = srv.frames.size();
        record_at = now;
      }
      uint32_t quiet_from = owed_at > acked_at ? owed_at : acked_at;
      if (record_at > quiet_from) quiet_from = record_at;
      if (!srv.receipt && acked_at != 0 && !records_owed && now - quiet_from > 2000) break;
      if (o.timeout_s != 0 && now - t0 > o.timeout_s * 1000u)
        throw std::runtime_error(std::string(host.established() ? "the transfer did not finish" : "no client answered") +
                                 " within " + std::to_string(o.timeout_s) + " s on " + b->describe());
    }
    rep.seconds = static_cast<double>(monotonic_ms() - static_cast<uint32_t>(srv.started_ms)) / 1000.0;
    rep.host = host.stats();
    rep.sessions = host.session_epoch();
    rep.final_frame_payload = host.frame_payload();
    rep.bytes_acked = srv.written - host.unacked(channel::kStream);
  }
  if (srv.live != nullptr) {
    rep.bytes = stream.size();
    rep.stream_crc = crc32c(stream.data(), stream.size());
  }
  rep.goodbye_sent = srv.goodbye_sent;
  rep.report_seen = srv.receipt;
  rep.report_status = srv.report.status;
  rep.receipt_bytes = srv.report.stream_bytes;
  rep.receipt_crc = srv.report.stream_crc;
  rep.receipt = srv.verified(rep.stream_crc);
  rep.receipt_prefix = srv.wants_no_more();
  rep.bytes_written = srv.written;
  rep.frame_records = srv.frame_records;
  rep.frames = srv.frames;
  rep.have_stats = srv.have_stats;
  rep.stats = srv.stats;
  const double delivered = rep.receipt_prefix ? static_cast<double>(rep.receipt_bytes) : static_cast<double>(stream.size());
  if (rep.seconds > 0) rep.goodput = delivered / rep.seconds / (o.baud / 10.0);
  return rep;
}

}  // namespace

ServeReport serve_stream(const std::vector<uint8_t>& stream, const ServeOptions& o,
                         const std::function<void(const std::string&)>& log) {
  Server srv(stream);
  return serve(srv, o, log);
}

ServeReport serve_live(LiveStream& live, const ServeOptions& o, std::vector<uint8_t>* made,
                       const std::function<void(const std::string&)>& log) {
  Server srv(live);
  ServeReport r = serve(srv, o, log);
  if (made != nullptr) *made = srv.made;
  return r;
}

}  // namespace vds::link
