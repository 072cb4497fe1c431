// The vds client firmware: link + player + board. The link (device role)
// receives the stream; the player (vds/player.h) turns its bytes into
// display bands, whatever the stream's mode; the board shows them. Upward
// go a CRC-32C and the per-stage instruction counts of every frame,
// statistics, and the end of the stream. Talks to the hardware only through
// vds/board.h.
#include <cstddef>
#include <cstdint>

#include "print.h"
#include "vds/arena.h"
#include "vds/board.h"
#include "vds/crc32c.h"
#include "vds/link/link.h"
#include "vds/link/messages.h"
#include "vds/player.h"

#ifndef VDS_APP_WORKSPACE_MAX
#error "VDS_APP_WORKSPACE_MAX (the largest workspace this build can use) must be set by the build"
#endif

namespace {

using vds::Status;
using vds::fw::Line;
namespace board = vds::board;
namespace link = vds::link;

constexpr uint32_t kStatsPeriodMs = 1000;   // statistics datagram
constexpr uint32_t kPendingRecords = 8;     // frame records waiting for the checksums channel
constexpr size_t kStreamReadBytes = 256;    // stream bytes handed to the player at a time
constexpr uint32_t kDrainTimeoutMs = 20000;  // after the report, wait at most this long for the host's Goodbye
constexpr uint32_t kGoodbyeWaitMs = 3000;    // once the host has acknowledged everything, this long
constexpr uint32_t kViewerPollMs = 50;       // a model the viewer turns: their controls read this often

alignas(8) uint8_t g_workspace[VDS_APP_WORKSPACE_MAX];

struct Client {
  vds::Arena arena;
  link::Link link;
  vds::Player player;
  size_t stream_mark = 0;  // arena mark below the per-stream state
  uint32_t epoch = 0;

  // The stream.
  Status stream_status = Status::more_input;
  uint32_t stream_bytes = 0;
  uint32_t stream_crc = 0;
  // The workspace holds no more of the model: the client reports early and
  // the host writes no more; stream bytes still in flight are read and
  // dropped (counted, outside the report's bytes and CRC).
  bool full_reported = false;
  uint32_t dropped_bytes = 0;

  // Frames shown.
  uint32_t late_frames = 0;
  uint32_t first_frame_ms = 0;
  uint32_t first_byte_ms = 0;  // when the stream's first byte was taken (a timed stream's clock starts)
  uint32_t viewer_polled_ms = 0;  // when the viewer's controls were last read (Player::view_input)

  // Upward messages.
  link::FrameRecord pending[kPendingRecords];
  uint32_t pending_head = 0, pending_count = 0;
  bool done_sent = false;
  uint32_t last_stats_ms = 0;
  // The host's Goodbye (control channel): it holds the report and records.
  link::MessageReader<link::kGoodbyeBytes> control;
  bool goodbye = false;
};

Client g;

void log_status(const char* what, Status s) {
  board::log(Line().str("client: ").str(what).str(": ").str(vds::status_name(s)).str("\n").c_str());
}

// Keeps the link moving while a frame is decoded and drawn (the player calls
// it between bands and during long mesh levels): what the UART holds goes to
// the link and the acknowledgements it owes go out. Stream bytes wait in the
// link's window until the main loop feeds them to the player, which is
// never re-entered.
void service_link(void*) {
  const uint32_t now = board::millis();
  uint8_t buf[128];
  size_t n = 0;
  while ((n = board::uart_read(buf, sizeof buf)) != 0) g.link.receive(buf, n, now);
  while ((n = g.link.transmit(buf, sizeof buf, now)) != 0) board::uart_write(buf, n);
}

// The player's frame record, with the time it was shown and whether it was
// late, queued for the checksums channel.
void frame_shown(void*, const vds::PlayedFrame& f) {
  const uint32_t now = board::millis();
  const vds::StreamHeader& h = g.player.header();
  if (f.index == 0) g.first_frame_ms = now;
  // A timed stream's frame i is due when its schedule says, counted from
  // the first byte; any other's one period after frame i-1, counted from
  // the first frame. Late: shown more than a period after that.
  bool late = false;
  if (g.player.timed()) {
    late = now - g.first_byte_ms > g.player.due_ms(f.index) + h.frame_period_us / 1000;
  } else if (h.frame_period_us != 0) {
    const uint64_t due_ms = g.first_frame_ms + (static_cast<uint64_t>(f.index) * h.frame_period_us) / 1000;
    late = now > due_ms + h.frame_period_us / 1000;
  }
  if (late) ++g.late_frames;
  if (g.pending_count < kPendingRecords) {
    link::FrameRecord& rec = g.pending[(g.pending_head + g.pending_count) % kPendingRecords];
    rec.index = f.index;
    rec.crc = f.crc;
    rec.parse_instructions = static_cast<uint32_t>(f.parse);
    rec.decode_instructions = static_cast<uint32_t>(f.decode);
    rec.display_instructions = static_cast<uint32_t>(f.display);
    rec.entropy_instructions = static_cast<uint32_t>(f.entropy);
    rec.transform_instructions = static_cast<uint32_t>(f.transform);
    rec.received_ms = now;
    rec.late = late ? 1 : 0;
    rec.steered = f.steered ? 1 : 0;
    ++g.pending_count;
  }
}

void send_messages(uint32_t now);

// A timed stream's frame waits for its time: the link is served and the
// frame records go up meanwhile; the stream bytes stay in the link's window.
void wait_until(void*, uint64_t due_ms) {
  for (;;) {
    const uint32_t now = board::millis();
    const uint32_t since = now - g.first_byte_ms;
    if (since >= due_ms) return;
    service_link(nullptr);
    send_messages(now);
    board::wait_for_event(static_cast<uint32_t>(due_ms - since));
  }
}

// What the player decided about a model larger than the workspace.
void notice(void*, vds::PlayerNotice what, uint32_t a, uint32_t b, uint32_t c) {
  Line l;
  switch (what) {
    case vds::PlayerNotice::model_partial:
      l.str("client: model: the workspace holds ").dec(a).str(" of its ").dec(b).str(" vertices; later levels are skipped\n");
      break;
    case vds::PlayerNotice::model_full:
      l.str("client: model: workspace full after level ").dec(a).str(" of ").dec(b).str(" (").dec(c).str(" vertices)\n");
      break;
    case vds::PlayerNotice::model_base_too_big:
      l.str("client: model: the base mesh needs ").dec(a).str(" bytes of workspace, ").dec(b).str(" are left\n");
      break;
    case vds::PlayerNotice::model_colors_level:
      l.str("client: model: colours down to MIP level ").dec(a).str(" of ").dec(b).str(" fit the workspace\n");
      break;
    case vds::PlayerNotice::model_no_colors:
      l.str(a == 1 ? "client: model: the mesh is not whole: drawn without its colours\n"
                   : "client: model: no room for the colours: drawn without them\n");
      break;
  }
  board::log(l.c_str());
}

// Lets the player read the viewer's controls, once kViewerPollMs have passed
// since it last did: true when it drew a frame for them.
bool poll_viewer(uint32_t now) {
  if (now - g.viewer_polled_ms < kViewerPollMs) return false;
  g.viewer_polled_ms = now;
  return g.player.view_input();  // a model the viewer turns is drawn again for them
}

// (Re)starts the per-stream state above the link's buffers.
Status start_stream() {
  g.arena.rewind(g.stream_mark);
  g.stream_status = Status::more_input;
  g.stream_bytes = 0;
  g.stream_crc = 0;
  g.full_reported = false;
  g.dropped_bytes = 0;
  g.late_frames = 0;
  g.pending_count = 0;
  g.done_sent = false;
  g.control.reset();
  g.goodbye = false;
  vds::PlayerCallbacks cb;
  cb.begin_frame = [](void*, uint16_t w, uint16_t h) {
    board::display_begin_frame(w, h);
    return true;
  };
  cb.band = [](void*, const vds::PixelRect& r) {
    board::display_band(r.y, r.h, reinterpret_cast<const uint16_t*>(r.pixels), static_cast<size_t>(r.stride) / 2);
    return true;
  };
  cb.end_frame = [](void*, uint32_t crc) {
    board::display_end_frame(crc);
    return true;
  };
  cb.frame_shown = frame_shown;
  cb.service = service_link;
  cb.wait_until = wait_until;
  if (board::instruction_resolution() != 0) cb.clock = [](void*) { return board::instructions(); };
  cb.notice = notice;
  // What a mode sends up: the terrain viewer's pose, on the pose channel
  // (a datagram: the newest replaces one not yet sent).
  cb.send_up = [](void*, uint8_t kind, const uint8_t* data, size_t n) {
    if (kind != vds::terrain::kSendPose) return false;
    return g.link.send_datagram(link::channel::kPose, data, n) == Status::ok;
  };
  // The viewer's controls, where the board has any.
  cb.steer = [](void*, vds::terrain::SteerInput* in) { return board::read_controls(in); };
  return g.player.init(g.arena, vds::kClientPlayerConfig, cb);
}

void feed_stream() {
  uint8_t buf[kStreamReadBytes];
  if (g.full_reported) {
    // Reported full: what the host had already sent is read and dropped.
    size_t got = 0;
    while (g.link.read(link::channel::kStream, buf, sizeof buf, &got) == Status::ok && got != 0)
      g.dropped_bytes += static_cast<uint32_t>(got);
    return;
  }
  // Stop taking stream bytes while frame records wait: back-pressure.
  while (g.stream_status == Status::more_input && g.pending_count < kPendingRecords) {
    size_t want = sizeof buf;
    const size_t limit = g.player.feed_limit(kPendingRecords - g.pending_count);
    if (limit < want) want = limit;
    size_t got = 0;
    if (g.link.read(link::channel::kStream, buf, want, &got) != Status::ok || got == 0) return;
    if (g.stream_bytes == 0) g.first_byte_ms = board::millis();
    g.stream_bytes += static_cast<uint32_t>(got);
    g.stream_crc = vds::crc32c_update(g.stream_crc, buf, got);
    const Status s = g.player.feed(buf, got);
    if (s == Status::more_input) continue;
    g.stream_status = s;
    if (s == Status::ok && g.player.workspace_full()) {
      // Every later level would be skipped: the report goes now, and covers
      // the bytes received so far.
      board::log("client: model: asking the host for no more of the stream\n");
      g.full_reported = true;
    }
    if (vds::is_error(s)) {
      Line l;
      l.str("client: stream: ").str(vds::status_name(s)).str(" at byte ").dec(g.player.error_offset()).str(": ");
      board::log(l.str(g.player.error_detail()).str("\n").c_str());
    }
  }
}

void send_messages(uint32_t now) {
  while (g.pending_count > 0 && g.link.writable(link::channel::kChecksums) >= link::kFrameRecordBytes) {
    uint8_t msg[link::kFrameRecordBytes];
    link::encode(g.pending[g.pending_head], msg);
    size_t took = 0;
    if (g.link.write(link::channel::kChecksums, msg, sizeof msg, &took) != Status::ok || took != sizeof msg) break;
    g.pending_head = (g.pending_head + 1) % kPendingRecords;
    --g.pending_count;
  }
  if (now - g.last_stats_ms >= kStatsPeriodMs || (g.stream_status != Status::more_input && !g.done_sent)) {
    g.last_stats_ms = now;
    link::ClientStats st{};
    st.uptime_ms = now;
    st.stream_bytes = g.stream_bytes;
    st.frames_shown = g.player.frames_shown();
    st.late_frames = g.late_frames;
    st.workspace_high_water = static_cast<uint32_t>(g.arena.high_water());
    st.workspace_budget = static_cast<uint32_t>(g.arena.capacity());
    st.stack_high_water = static_cast<uint32_t>(board::stack_high_water());
    st.link_retransmissions = g.link.stats().retransmissions;
    st.link_dropped = g.link.stats().dropped();
    st.instruction_resolution = board::instruction_resolution();
    uint8_t msg[link::kClientStatsBytes];
    link::encode(st, msg);
    g.link.send_datagram(link::channel::kStats, msg, sizeof msg);
  }
  if (g.stream_status != Status::more_input && !g.done_sent && g.pending_count == 0 &&
      g.link.writable(link::channel::kControl) >= link::kDoneReportBytes) {
    link::DoneReport d{static_cast<int32_t>(g.stream_status), g.player.frames_shown(), g.stream_bytes, g.stream_crc,
                       g.full_reported ? link::DoneReason::workspace_full : link::DoneReason::end_of_stream};
    uint8_t msg[link::kDoneReportBytes];
    link::encode(d, msg);
    size_t took = 0;
    if (g.link.write(link::channel::kControl, msg, sizeof msg, &took) == Status::ok && took == sizeof msg)
      g.done_sent = true;
  }
}

// Reads the control channel for the host's Goodbye.
void read_control() {
  while (!g.goodbye && g.control.next(g.link, link::channel::kControl)) {
    link::Goodbye bye{};
    if (link::decode(g.control.bytes, link::kGoodbyeBytes, &bye) != Status::ok) {
      board::log("client: a control message that is not a Goodbye was ignored\n");
      continue;
    }
    g.goodbye = true;
    g.link.flush_acks();  // its acknowledgement goes out before the client stops
    Line l;
    l.str("client: the host said goodbye: report ").str(bye.verified ? "verified" : "NOT verified").str(", ");
    l.dec(bye.frame_records).str(" frame records received\n");
    board::log(l.c_str());
  }
}

}  // namespace

// The firmware's entry point, called by each board's start-up code.
extern "C" int vds_app_main() {
  board::init();
  size_t budget = board::workspace_budget();
  if (budget > sizeof g_workspace) budget = sizeof g_workspace;
  g.arena = vds::Arena(g_workspace, budget);
  const link::LinkConfig cfg = link::device_config(board::millis() + 1, board::uart_rx_ring_bytes());
  Status s = g.link.init(cfg, g.arena);
  if (s != Status::ok) {
    log_status("link", s);
    return 3;
  }
  g.stream_mark = g.arena.mark();
  s = start_stream();
  if (s != Status::ok) {
    log_status("workspace", s);
    return 3;
  }
  board::log(Line().str("client: ready, workspace ").dec(budget).str(" bytes, player from byte ").dec(g.stream_mark).str("\n").c_str());

  uint8_t rx[256];
  uint8_t tx[256];
  bool done_timing = false, drained_timing = false;
  uint32_t done_at = 0, drained_at = 0;
  for (;;) {
    const uint32_t now = board::millis();
    bool busy = false;
    const size_t n = board::uart_read(rx, sizeof rx);
    if (n) {
      g.link.receive(rx, n, now);
      busy = true;
    }
    if (g.link.session_epoch() != g.epoch) {
      // A new session: whatever the previous one delivered is void, and the
      // host starts the stream again from its first byte.
      if (g.epoch != 0) board::log("client: new link session, restarting the stream\n");
      g.epoch = g.link.session_epoch();
      if (g.stream_bytes != 0 && start_stream() != Status::ok) return 3;
    }
    feed_stream();
    poll_viewer(now);
    send_messages(now);
    read_control();
    const size_t m = g.link.transmit(tx, sizeof tx, now);
    if (m) {
      board::uart_write(tx, m);
      busy = true;
    }
    // The host has everything once it says goodbye: stop as soon as the
    // acknowledgement of the Goodbye is on the line.
    if (g.goodbye && m == 0) break;
    if (board::uart_closed()) {
      if (!g.done_sent) board::log("client: the host closed the link before the end of the stream\n");
      break;
    }
    if (g.done_sent) {
      // No Goodbye yet: a host that says none (or whose Goodbye the line
      // lost) is given a while after it has acknowledged every message,
      // and every host the drain timeout.
      if (!done_timing) {
        done_timing = true;
        done_at = now;
      }
      const bool drained = g.link.unacked(link::channel::kChecksums) == 0 && g.link.unacked(link::channel::kControl) == 0;
      if (drained && !drained_timing) {
        drained_timing = true;
        drained_at = now;
      }
      if ((drained_timing && now - drained_at > kGoodbyeWaitMs) || now - done_at > kDrainTimeoutMs) {
        board::log("client: no goodbye from the host\n");
        break;
      }
    }
    if (!busy) board::wait_for_event(1);
  }
  // A model stays in view while a viewer is there to turn it (the host
  // board's live window until it is closed, a controls script until it ends).
  // Only a model the stream showed whole: else nothing reads the controls.
  const bool shown = g.player.have_header() && g.player.header().mode == vds::StreamMode::model &&
                     !vds::is_error(g.stream_status) && g.player.frames_shown() > 0;
  if (shown && board::viewer_present()) {
    board::log("client: the model stays in view for the viewer\n");
    uint32_t viewer_frames = 0;
    while (board::viewer_present()) {
      const uint32_t now = board::millis();
      if (now - g.viewer_polled_ms < kViewerPollMs)
        board::wait_for_event(kViewerPollMs - (now - g.viewer_polled_ms));
      else if (poll_viewer(now))
        ++viewer_frames;
    }
    board::log(Line().str("client: the viewer has gone, ").dec(viewer_frames).str(" frames drawn for them after the stream\n").c_str());
  }
  Line l;
  l.str("client: ").str(vds::status_name(g.stream_status)).str(", ").dec(g.player.frames_shown()).str(" frames, ");
  l.dec(g.stream_bytes).str(" stream bytes");
  if (g.full_reported) l.str(" (workspace full; ").dec(g.dropped_bytes).str(" bytes in flight dropped)");
  l.str(", workspace high-water ").dec(g.arena.high_water()).str(" bytes\n");
  board::log(l.c_str());
  return g.stream_status == Status::ok ? 0 : 1;
}
