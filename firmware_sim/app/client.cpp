// The vds client firmware: handshake over the link, receive the stream,
// verify and parse it, decode each image into bands inside the workspace
// (or, for a model stream, decode the progressive mesh and draw it after its
// base and after every level), present them on the board's display, and
// report upward a CRC-32C and the per-stage instruction counts of every
// frame, statistics, and the end of the stream. Talks to the hardware only
// through vds/board.h.
#include <cstddef>
#include <cstdint>

#include "print.h"
#include "vds/arena.h"
#include "vds/board.h"
#include "vds/container.h"
#include "vds/crc32c.h"
#include "vds/image.h"
#include "vds/link/link.h"
#include "vds/link/messages.h"
#include "vds/mesh.h"
#include "vds/model_view.h"

#ifndef VDS_APP_WORKSPACE_MAX
#error "VDS_APP_WORKSPACE_MAX (the largest workspace this build can use) must be set by the build"
#endif
#ifndef VDS_APP_CHUNK_BYTES
#define VDS_APP_CHUNK_BYTES 4096  // the largest chunk payload the client accepts
#endif

namespace {

using vds::Status;
using vds::fw::Line;
namespace board = vds::board;
namespace link = vds::link;

constexpr uint32_t kBandRows = 16;          // one MCU row of a 4:2:0 image
constexpr uint32_t kStatsPeriodMs = 1000;   // statistics datagram
constexpr uint32_t kPendingRecords = 8;     // frame records waiting for the checksums channel
constexpr size_t kStreamReadBytes = 256;    // stream bytes handed to the parser at a time
constexpr uint32_t kMeshServiceItems = 64;  // mesh items decoded between two services of the link
constexpr uint32_t kDrainTimeoutMs = 20000;  // after the report, wait at most this long for the host's Goodbye
constexpr uint32_t kGoodbyeWaitMs = 3000;    // once the host has acknowledged everything, this long

alignas(8) uint8_t g_workspace[VDS_APP_WORKSPACE_MAX];

struct Client {
  vds::Arena arena;
  link::Link link;
  vds::StreamParser parser;
  vds::ImageDecoder decoder;
  // Model streams: the progressive mesh and its picture.
  vds::MeshDecoder mesh;
  vds::ModelView view;
  bool model = false;
  bool model_started = false;  // MSHH seen: decoder and view set up
  // The workspace holds no more of the model: the client reports early and
  // the host writes no more; stream bytes still in flight are read and
  // dropped (counted, outside the report's bytes and CRC).
  bool full = false;
  uint32_t dropped_bytes = 0;
  vds::ModelFrames model_frames;
  size_t stream_mark = 0;  // arena mark below the per-stream state
  uint32_t epoch = 0;

  // The stream.
  vds::StreamHeader header{};
  bool have_header = false;
  uint16_t* band = nullptr;
  Status stream_status = Status::more_input;
  uint32_t stream_bytes = 0;
  uint32_t stream_crc = 0;

  // The frame being drawn.
  bool in_frame = false;
  uint32_t frame_crc = 0;
  uint32_t frames_shown = 0;
  uint32_t late_frames = 0;
  uint32_t first_frame_ms = 0;
  // Instruction counts, cumulative over the run; a frame's record is the
  // difference from the snapshot taken when its header chunk arrived.
  // Parsing is the time inside StreamParser::feed outside the callbacks.
  uint64_t parse_total = 0, decode_total = 0, display_total = 0;
  uint64_t link_total = 0;  // instructions spent servicing the link inside a frame: in no stage (work_clock)
  uint64_t parse_at_start = 0, decode_at_start = 0, display_at_start = 0;
  vds::StageClock stages;  // the image decoder's split of decode_total (boards with a counter)
  uint64_t entropy_at_start = 0, transform_at_start = 0;
  uint64_t feed_mark = 0;  // instructions() where parser time last started to count

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

// Keeps the link moving while a frame is decoded and drawn, between its
// bands: what the UART holds goes to the link (the receive buffer must not
// overrun) and the acknowledgements it owes go out (the host must not time
// out while a long frame is drawn). Stream bytes wait in the link's window
// until the main loop feeds them to the parser.
void service_link() {
  const uint64_t t0 = board::instructions();
  const uint32_t now = board::millis();
  uint8_t buf[128];
  size_t n = 0;
  while ((n = board::uart_read(buf, sizeof buf)) != 0) g.link.receive(buf, n, now);
  while ((n = g.link.transmit(buf, sizeof buf, now)) != 0) board::uart_write(buf, n);
  g.link_total += board::instructions() - t0;
}

// The clock every stage count reads: the board's instruction counter less
// the time spent in service_link, which belongs to no stage.
uint64_t work_clock() { return board::instructions() - g.link_total; }

// Display callback of the image decoder: one band of full-width RGB565 rows.
bool on_band(void*, const vds::PixelRect& r) {
  const uint64_t t0 = work_clock();
  const size_t stride_pixels = static_cast<size_t>(r.stride) / 2;
  for (uint16_t row = 0; row < r.h; ++row)
    g.frame_crc = vds::crc32c_update(g.frame_crc, r.pixels + row * r.stride, static_cast<size_t>(r.w) * 2);
  board::display_band(r.y, r.h, reinterpret_cast<const uint16_t*>(r.pixels), stride_pixels);
  service_link();
  g.display_total += work_clock() - t0;
  return true;
}

void finish_frame() {
  const uint64_t t0 = work_clock();
  board::display_end_frame(g.frame_crc);
  g.display_total += work_clock() - t0;
  const uint32_t now = board::millis();
  if (g.frames_shown == 0) g.first_frame_ms = now;
  // Frame i is due one period after frame i-1, counted from the first one.
  bool late = false;
  if (g.header.frame_period_us != 0) {
    const uint64_t due_ms = g.first_frame_ms + (static_cast<uint64_t>(g.frames_shown) * g.header.frame_period_us) / 1000;
    late = now > due_ms + g.header.frame_period_us / 1000;
  }
  if (late) ++g.late_frames;
  if (g.pending_count < kPendingRecords) {
    link::FrameRecord& rec = g.pending[(g.pending_head + g.pending_count) % kPendingRecords];
    rec.index = g.frames_shown;
    rec.crc = g.frame_crc;
    rec.parse_instructions = static_cast<uint32_t>(g.parse_total - g.parse_at_start);
    rec.decode_instructions = static_cast<uint32_t>(g.decode_total - g.decode_at_start);
    rec.display_instructions = static_cast<uint32_t>(g.display_total - g.display_at_start);
    rec.entropy_instructions = static_cast<uint32_t>(g.stages.spent[vds::StageClock::entropy] - g.entropy_at_start);
    rec.transform_instructions = static_cast<uint32_t>(g.stages.spent[vds::StageClock::transform] - g.transform_at_start);
    rec.received_ms = now;
    rec.late = late ? 1 : 0;
    ++g.pending_count;
  }
  ++g.frames_shown;
  g.in_frame = false;
}

// Snapshot of the counters a frame record is measured from.
void start_frame_counts(uint64_t parse_total) {
  g.parse_at_start = parse_total;
  g.decode_at_start = g.decode_total;
  g.display_at_start = g.display_total;
  g.entropy_at_start = g.stages.spent[vds::StageClock::entropy];
  g.transform_at_start = g.stages.spent[vds::StageClock::transform];
}

// Band callback of the model view: the same CRC and display path as images.
bool on_render_band(void*, const vds::Band& b) {
  const vds::PixelRect r{0, b.y, b.width, b.height, b.pixels, static_cast<ptrdiff_t>(b.stride)};
  return on_band(nullptr, r);
}

// A model stream's mesh decoder and view are set up when its MSHH arrives,
// for as much of the model as the workspace holds (vds::start_model): a
// client smaller than the full resolution plays the levels that fit.
bool start_model(const uint8_t* mshh, uint32_t size) {
  vds::ModelViewConfig vc;
  vc.width = g.header.width;
  vc.height = g.header.height;
  vc.band_height = kBandRows;
  vds::ModelCapacity cap;
  const size_t left = g.arena.remaining();
  const Status s = vds::start_model(g.arena, mshh, size, vc, g.mesh, g.view, &cap);
  if (s == Status::workspace_too_small && cap.bytes > 0) {
    Line l;
    l.str("client: model: the base mesh needs ").dec(cap.bytes).str(" bytes of workspace, ");
    l.dec(left).str(" are left\n");
    board::log(l.c_str());
    return false;
  }
  if (s != Status::ok) {
    log_status("model", s);
    return false;
  }
  if (cap.vertices < g.header.max_vertices) {
    Line l;
    l.str("client: model: the workspace holds ").dec(cap.vertices).str(" of its ");
    l.dec(g.header.max_vertices).str(" vertices; later levels are skipped\n");
    board::log(l.c_str());
  }
  // A level's chunk can take long to decode: keep the link moving meanwhile.
  g.mesh.set_progress([](void*) { service_link(); }, nullptr, kMeshServiceItems);
  g.model_started = true;
  return true;
}

bool on_header(void*, const vds::StreamHeader& h) {
  if (h.mode != vds::StreamMode::images && h.mode != vds::StreamMode::model) {
    board::log("client: this firmware plays image and model streams only\n");
    return false;
  }
  g.header = h;
  g.have_header = true;
  if (h.mode == vds::StreamMode::model) {
    g.model = true;
    g.model_started = false;
    g.model_frames = vds::ModelFrames{};
    start_frame_counts(g.parse_total);
    return true;
  }
  // The parser has checked that the declared workspace fits what is left.
  const Status s = g.decoder.init(g.arena);
  if (s != Status::ok) {
    log_status("image decoder", s);
    return false;
  }
  if (board::instruction_resolution() != 0) {
    g.stages = vds::StageClock{};
    g.stages.now = [](void*) { return work_clock(); };
    g.decoder.set_stage_clock(&g.stages);
  }
  g.band = g.arena.alloc_array<uint16_t>(static_cast<size_t>(h.width) * kBandRows);
  if (g.band == nullptr) {
    log_status("band buffer", Status::workspace_too_small);
    return false;
  }
  return true;
}

// A model stream: every mesh chunk goes to the decoder; once the base is in,
// and after every completed level, the mesh is drawn as a frame. A frame's
// record counts the chunks of its level (decode) and the drawing (display).
vds::ChunkResult on_model_chunk(uint32_t type, const uint8_t* payload, uint32_t size) {
  if (!vds::MeshDecoder::handles(type)) return vds::ChunkResult::unknown;
  if (!g.model_started && (type != vds::chunk::kMeshHeader || !start_model(payload, size))) {
    if (type != vds::chunk::kMeshHeader) log_status("mesh: first mesh chunk is not MSHH", Status::malformed);
    return vds::ChunkResult::abort;
  }
  const uint64_t t0 = work_clock();
  g.parse_total += t0 - g.feed_mark;
  const Status s = g.mesh.consume(type, payload, size);
  const uint64_t t1 = work_clock();
  g.decode_total += t1 - t0;
  vds::ChunkResult result = vds::ChunkResult::consumed;
  if (vds::is_error(s)) {
    log_status("mesh", s);
    result = vds::ChunkResult::abort;
  } else if (g.mesh.capacity_reached() && !g.full) {
    g.full = true;
    Line l;
    l.str("client: model: workspace full after level ").dec(g.mesh.levels_done()).str(" of ");
    l.dec(g.mesh.header().levels).str(" (").dec(g.mesh.mesh().vertex_count()).str(" vertices)\n");
    board::log(l.c_str());
  }
  // The level a chunk completed is drawn even when the decoder knows at once
  // that the next one will not fit (a version-2 stream's tail).
  if (result == vds::ChunkResult::consumed && g.model_frames.due(g.mesh)) {
    board::display_begin_frame(g.header.width, g.header.height);
    g.in_frame = true;
    g.frame_crc = 0;
    const uint64_t band_before = g.display_total;
    const Status d = g.view.draw(g.mesh.mesh(), g.model_frames.angle(), on_render_band, nullptr);
    g.model_frames.mark_drawn(g.mesh);
    // Drawing counts as display: on_band has added its part, add the renderer's.
    g.display_total += (work_clock() - t1) - (g.display_total - band_before);
    if (d != Status::ok) {
      log_status("model view", d);
      result = vds::ChunkResult::abort;
    } else {
      finish_frame();
      start_frame_counts(g.parse_total);
    }
  }
  g.feed_mark = work_clock();
  return result;
}

vds::ChunkResult on_chunk(void*, uint32_t type, const uint8_t* payload, uint32_t size) {
  if (g.model) return on_model_chunk(type, payload, size);
  if (type != vds::chunk::kImageHeader && type != vds::chunk::kImageData) return vds::ChunkResult::unknown;
  const uint64_t t0 = work_clock();
  const uint64_t parse_before = g.parse_total;
  g.parse_total += t0 - g.feed_mark;
  const uint64_t display_before = g.display_total;
  if (type == vds::chunk::kImageHeader) {
    board::display_begin_frame(g.header.width, g.header.height);
    g.in_frame = true;
    g.frame_crc = 0;
    // The parser checked this chunk's CRC before the call: that belongs to the new frame.
    start_frame_counts(parse_before);
  }
  const vds::ImageTarget target = vds::ImageTarget::bands(vds::PixelFormat::rgb565, reinterpret_cast<uint8_t*>(g.band),
                                                          static_cast<ptrdiff_t>(g.header.width) * 2, on_band, nullptr);
  const Status s = g.decoder.on_chunk(type, payload, size, target);
  g.decode_total += (work_clock() - t0) - (g.display_total - display_before);
  vds::ChunkResult result = vds::ChunkResult::consumed;
  if (vds::is_error(s)) {
    log_status("image", s);
    result = vds::ChunkResult::abort;
  } else if (type == vds::chunk::kImageData && s == Status::ok) {
    finish_frame();
  }
  g.feed_mark = work_clock();
  return result;
}

// (Re)starts the per-stream state above the link's buffers.
Status start_stream() {
  g.arena.rewind(g.stream_mark);
  g.have_header = false;
  g.band = nullptr;
  g.model = false;
  g.stream_status = Status::more_input;
  g.stream_bytes = 0;
  g.stream_crc = 0;
  g.full = false;
  g.dropped_bytes = 0;
  g.in_frame = false;
  g.frames_shown = 0;
  g.late_frames = 0;
  g.pending_count = 0;
  g.done_sent = false;
  g.control.reset();
  g.goodbye = false;
  vds::ChunkSink sink;
  sink.on_header = on_header;
  sink.on_chunk = on_chunk;
  sink.model_prefix = true;  // a model larger than the workspace plays the levels that fit
  return g.parser.init(g.arena, VDS_APP_CHUNK_BYTES, sink);
}

void feed_stream() {
  uint8_t buf[kStreamReadBytes];
  if (g.full && g.stream_status == Status::ok) {
    // Reported full: what the host had already sent is read and dropped.
    size_t got = 0;
    while (g.link.read(link::channel::kStream, buf, sizeof buf, &got) == Status::ok && got != 0)
      g.dropped_bytes += static_cast<uint32_t>(got);
    return;
  }
  // Stop taking stream bytes while frame records wait: back-pressure.
  while (g.stream_status == Status::more_input && g.pending_count < kPendingRecords) {
    // An image frame spans many chunks, but a model draws after every level
    // and a coarse level can be a single small chunk: take no more bytes than
    // can finish as many chunks (12 bytes of framing at least) as there are
    // free frame records.
    size_t want = sizeof buf;
    if (g.model) {
      constexpr size_t kMinChunk = vds::kChunkHeadBytes + vds::kChunkTailBytes;
      const size_t limit = kMinChunk * (kPendingRecords - g.pending_count - 1) + 1;
      if (limit < want) want = limit;
    }
    size_t got = 0;
    if (g.link.read(link::channel::kStream, buf, want, &got) != Status::ok || got == 0) return;
    g.stream_bytes += static_cast<uint32_t>(got);
    g.stream_crc = vds::crc32c_update(g.stream_crc, buf, got);
    g.feed_mark = work_clock();
    Status s = g.parser.feed(buf, got);
    g.parse_total += work_clock() - g.feed_mark;
    if (s == Status::more_input && g.full) {
      // Every later level would be skipped: the report goes now, and covers
      // the bytes received so far.
      board::log("client: model: asking the host for no more of the stream\n");
      s = Status::ok;
    }
    if (s == Status::more_input) continue;
    g.stream_status = s;
    if (vds::is_error(s)) {
      Line l;
      l.str("client: stream: ").str(vds::status_name(s)).str(" at byte ").dec(g.parser.error_offset()).str(": ");
      board::log(l.str(g.parser.error_detail()).str("\n").c_str());
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
    st.frames_shown = g.frames_shown;
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
    link::DoneReport d{static_cast<int32_t>(g.stream_status), g.frames_shown, g.stream_bytes, g.stream_crc,
                       g.full ? link::DoneReason::workspace_full : link::DoneReason::end_of_stream};
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
  board::log(Line().str("client: ready, workspace ").dec(budget).str(" bytes\n").c_str());

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
  Line l;
  l.str("client: ").str(vds::status_name(g.stream_status)).str(", ").dec(g.frames_shown).str(" frames, ");
  l.dec(g.stream_bytes).str(" stream bytes");
  if (g.full) l.str(" (workspace full; ").dec(g.dropped_bytes).str(" bytes in flight dropped)");
  l.str(", workspace high-water ").dec(g.arena.high_water()).str(" bytes\n");
  board::log(l.c_str());
  return g.stream_status == Status::ok ? 0 : 1;
}
