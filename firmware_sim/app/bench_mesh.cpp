// Progressive mesh decoding on the board: reads vds mesh streams from host
// files (mesh_case0.vds, mesh_case1.vds, ... until one is missing; by
// default the golden test stream), decodes each through the stream parser
// and the mesh decoder, counts the instructions the mesh decoder spends on
// the base and per level, and prints a checksum of the mesh after every
// level. After the base and every level it also draws the model as the
// client does (vds::ModelView, 240x180, the client's orbit step) and counts
// those instructions apart. The host board and the Cortex-M4 board must
// print the same "check" lines, mesh and frame checksums (ctest);
// bench/run_mesh_m4.sh reads the "count" lines.
#include <cstddef>
#include <cstdint>

#include "print.h"
#include "vds/arena.h"
#include "vds/board.h"
#include "vds/container.h"
#include "vds/crc32c.h"
#include "vds/mesh.h"
#include "vds/model_view.h"

#ifndef VDS_APP_WORKSPACE_MAX
#error "VDS_APP_WORKSPACE_MAX (the largest workspace this build can use) must be set by the build"
#endif

namespace {

using vds::fw::Line;
using vds::Status;
namespace board = vds::board;

constexpr uint32_t kChunkBytes = 16384;  // the largest chunk payload accepted
constexpr uint32_t kReadBytes = 4096;     // file bytes fed to the parser at a time
constexpr uint16_t kFrameWidth = 240, kFrameHeight = 180;

alignas(8) uint8_t g_workspace[VDS_APP_WORKSPACE_MAX];
uint8_t g_read[kReadBytes];

struct Run {
  vds::MeshDecoder decoder;
  Status init_status = Status::ok;
  uint64_t instructions = 0;        // inside MeshDecoder::consume, all chunks
  uint64_t level_instructions = 0;  // since the last completed level
  uint64_t last_level_instructions = 0;
  uint32_t tail_from_vertices = 0;  // vertices before the last completed level
  uint32_t level_vertices = 0;      // vertex count when that level completed
  uint64_t base_instructions = 0;
  uint32_t base_vertices = 0;
  uint32_t levels = 0;
  // The model view.
  vds::ModelView view;
  bool view_ready = false;
  size_t view_bytes = 0;
  vds::ModelFrames shown;  // drawn as the client draws
  uint64_t draw_instructions = 0;  // all frames
  uint64_t last_draw = 0;          // the last frame (the whole model)
  uint32_t frame_crc = 0;
};

Run g_run;

// CRC-32C of the positions and corner vertices (each as a uint32_t,
// whatever width the mesh stores them in; both boards are little-endian):
// the mesh after a level.
uint32_t mesh_hash(const vds::MeshState& m) {
  uint32_t h = vds::crc32c(m.positions(), static_cast<size_t>(m.vertex_count()) * 3 * sizeof(uint16_t));
  for (uint32_t c = 0; c < 3 * m.triangle_count(); ++c) {
    const uint32_t v = m.corner_vertex(c);
    h = vds::crc32c_update(h, &v, sizeof v);
  }
  return h;
}

vds::Arena g_arena;

bool on_header(void*, const vds::StreamHeader& h) {
  g_run.init_status = g_run.decoder.init(g_arena, h.max_vertices, h.max_triangles);
  if (g_run.init_status != Status::ok) return false;
  vds::ModelViewConfig vc;
  vc.width = kFrameWidth;
  vc.height = kFrameHeight;
  const size_t mark = g_arena.mark();
  g_run.view_ready = g_run.view.init(vc, g_arena, h.max_vertices, h.max_triangles) == Status::ok;
  g_run.view_bytes = g_arena.mark() - mark;
  if (!g_run.view_ready) board::log("info: the model view does not fit: decoding only\n");
  return true;
}

bool on_frame_band(void*, const vds::Band& b) {
  for (uint16_t row = 0; row < b.height; ++row)
    g_run.frame_crc = vds::crc32c_update(g_run.frame_crc, b.pixels + row * b.stride, static_cast<size_t>(b.width) * 2);
  return true;
}

// Draws the current mesh when the client would and prints the frame's CRC.
void draw_frame_if_due() {
  if (!g_run.view_ready || !g_run.shown.due(g_run.decoder)) return;
  g_run.frame_crc = 0;
  const uint64_t t0 = board::instructions();
  g_run.view.set_up(g_run.decoder.header().up);  // the stream's up axis, as the client shows it
  const Status s = g_run.view.draw(g_run.decoder.mesh(), g_run.shown.angle(), on_frame_band, nullptr);
  g_run.last_draw = board::instructions() - t0;
  g_run.draw_instructions += g_run.last_draw;
  g_run.shown.mark_drawn(g_run.decoder);
  board::log(Line().str("check frame level=").dec(g_run.decoder.levels_done()).str(" status=").str(vds::status_name(s))
                 .str(" crc=0x").hex32(g_run.frame_crc).str("\n").c_str());
}

vds::ChunkResult on_chunk(void*, uint32_t type, const uint8_t* payload, uint32_t size) {
  if (!vds::MeshDecoder::handles(type)) return vds::ChunkResult::unknown;
  const bool had_base = g_run.decoder.drawable();
  const uint32_t levels_before = g_run.decoder.levels_done();
  const uint64_t t0 = board::instructions();
  const Status s = g_run.decoder.consume(type, payload, size);
  const uint64_t spent = board::instructions() - t0;
  g_run.instructions += spent;
  g_run.level_instructions += spent;
  if (s != Status::ok) {
    board::log(Line().str("m4 error: mesh decoder: ").str(vds::status_name(s)).str("\n").c_str());
    return vds::ChunkResult::abort;
  }
  const vds::MeshState& m = g_run.decoder.mesh();
  if (!had_base && g_run.decoder.drawable()) {
    g_run.base_instructions = g_run.level_instructions;
    g_run.base_vertices = m.vertex_count();
    g_run.level_instructions = 0;
    g_run.level_vertices = m.vertex_count();
    board::log(Line().str("check level=0 vertices=").dec(m.vertex_count()).str(" triangles=").dec(m.triangle_count())
                   .str(" hash=0x").hex32(mesh_hash(m)).str("\n").c_str());
  } else if (g_run.decoder.levels_done() != levels_before) {
    const uint32_t splits = m.vertex_count() - g_run.level_vertices;
    Line l;
    l.str("check level=").dec(g_run.decoder.levels_done()).str(" vertices=").dec(m.vertex_count());
    l.str(" triangles=").dec(m.triangle_count()).str(" hash=0x").hex32(mesh_hash(m)).str("\n");
    board::log(l.c_str());
    Line c;
    c.str("count level=").dec(g_run.decoder.levels_done()).str(" splits=").dec(splits);
    c.str(" instructions=").dec(g_run.level_instructions).str("\n");
    board::log(c.c_str());
    g_run.last_level_instructions = g_run.level_instructions;
    g_run.tail_from_vertices = g_run.level_vertices;  // before this level
    g_run.level_instructions = 0;
    g_run.level_vertices = m.vertex_count();
    ++g_run.levels;
  }
  draw_frame_if_due();
  return vds::ChunkResult::consumed;
}

// Decodes one stream file; false when it does not exist.
bool run_file(const char* path, int* failures) {
  const int32_t probe = board::host_file_read(path, 0, g_read, 1);
  if (probe <= 0) return false;
  g_arena = vds::Arena(g_workspace, sizeof g_workspace);
  g_run = Run{};
  vds::StreamParser parser;
  vds::ChunkSink sink;
  sink.on_header = on_header;
  sink.on_chunk = on_chunk;
  Status s = parser.init(g_arena, kChunkBytes, sink);
  uint32_t offset = 0;
  while (s == Status::ok || s == Status::more_input) {
    const int32_t got = board::host_file_read(path, offset, g_read, kReadBytes);
    if (got < 0) {
      s = Status::io_error;
      break;
    }
    if (got == 0) {
      s = parser.finish();
      break;
    }
    offset += static_cast<uint32_t>(got);
    s = parser.feed(g_read, static_cast<size_t>(got));
    if (s == Status::ok) break;
  }
  const vds::MeshState& m = g_run.decoder.mesh();
  const uint32_t splits = m.vertex_count() - g_run.base_vertices;
  const char* base = path;
  for (const char* p = path; *p; ++p)
    if (*p == '/') base = p + 1;
  Line l;
  l.str("m4 stream=").str(base).str(" status=").str(vds::status_name(s)).str(" vertices=").dec(m.vertex_count());
  l.str(" splits=").dec(splits).str(" levels=").dec(g_run.levels).str(" instructions=").dec(g_run.instructions);
  l.str(" base_instructions=").dec(g_run.base_instructions);
  l.str(" workspace=").dec(g_arena.high_water() - g_run.view_bytes).str("\n");
  board::log(l.c_str());
  // A version-2 stream's last level is the single-rate tail: its own count.
  if (g_run.decoder.have_header() && g_run.decoder.header().tail() && g_run.decoder.complete()) {
    Line t;
    t.str("m4 tail stream=").str(base).str(" tail_instructions=").dec(g_run.last_level_instructions);
    t.str(" split_vertices=").dec(g_run.tail_from_vertices - g_run.base_vertices).str("\n");
    board::log(t.c_str());
  }
  Line v;
  v.str("m4 view stream=").str(base).str(" triangles=").dec(m.triangle_count()).str(" view_workspace=").dec(g_run.view_bytes);
  v.str(" frames=").dec(g_run.shown.drawn);
  v.str(" draw_instructions=").dec(g_run.draw_instructions).str(" last_draw=").dec(g_run.last_draw).str("\n");
  board::log(v.c_str());
  if (s != Status::ok || !g_run.decoder.complete()) ++*failures;
  return true;
}

}  // namespace

extern "C" int vds_app_main() {
  board::init();
  int failures = 0;
  int files = 0;
  char name[32] = "mesh_case0.vds";
  for (int i = 0; i < 10; ++i) {
    name[9] = static_cast<char>('0' + i);
    if (!run_file(name, &failures)) break;
    ++files;
  }
  if (files == 0) {
    // No benchmark files: decode the golden test stream (the ctest run).
    if (!run_file(VDS_GOLDEN_MESH_STREAM, &failures)) {
      board::log("m4 error: cannot read " VDS_GOLDEN_MESH_STREAM "\n");
      return 1;
    }
  }
  return failures == 0 ? 0 : 1;
}
