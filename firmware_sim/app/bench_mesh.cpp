// Progressive mesh decoding on the board: reads vds mesh streams from host
// files (mesh_case0.vds, mesh_case1.vds, ... until one is missing; by
// default the golden test stream) and plays each through vds::Player, as
// the client does: the player's level records give the instructions the
// mesh decoder spends on the base and per level, and the bench prints a
// checksum of the mesh after every level; its frame records give the
// drawing of the model after the base and every level (vds::ModelView at
// the stream's frame size, the client's orbit step), counted apart. The host board and the Cortex-M4 board must
// print the same "check" lines, mesh and frame checksums (ctest);
// bench/run_mesh_m4.sh reads the "count" lines.
#include <cstddef>
#include <cstdint>

#include "host_cases.h"
#include "print.h"
#include "vds/arena.h"
#include "vds/board.h"
#include "vds/crc32c.h"
#include "vds/player.h"

#ifndef VDS_APP_WORKSPACE_MAX
#error "VDS_APP_WORKSPACE_MAX (the largest workspace this build can use) must be set by the build"
#endif

namespace {

using vds::fw::Line;
using vds::Status;
namespace board = vds::board;

constexpr uint32_t kChunkBytes = 16384;  // the largest chunk payload accepted
constexpr uint32_t kReadBytes = 4096;     // file bytes fed to the player at a time

alignas(8) uint8_t g_workspace[VDS_APP_WORKSPACE_MAX];
uint8_t g_read[kReadBytes];

vds::Player g_player;

struct Run {
  uint64_t instructions = 0;        // mesh decoding, all chunks
  uint64_t last_level_instructions = 0;
  uint32_t tail_from_vertices = 0;  // vertices before the last completed level
  uint32_t level_vertices = 0;      // vertex count when that level completed
  uint64_t base_instructions = 0;
  uint32_t base_vertices = 0;
  uint32_t levels = 0;
  uint32_t frames = 0;
  uint64_t draw_instructions = 0;  // all frames
  uint64_t last_draw = 0;          // the last frame (the whole model)
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

uint64_t clock(void*) { return board::instructions(); }

void on_level(void*, const vds::PlayedLevel& l) {
  const vds::MeshState& m = g_player.mesh.mesh();
  g_run.instructions += l.decode;
  board::log(Line().str("check level=").dec(l.level).str(" vertices=").dec(l.vertices).str(" triangles=")
                 .dec(l.triangles).str(" hash=0x").hex32(mesh_hash(m)).str("\n").c_str());
  if (l.level == 0) {
    g_run.base_instructions = l.decode;
    g_run.base_vertices = l.vertices;
  } else {
    Line c;
    c.str("count level=").dec(l.level).str(" splits=").dec(l.vertices - g_run.level_vertices);
    c.str(" instructions=").dec(l.decode).str("\n");
    board::log(c.c_str());
    g_run.last_level_instructions = l.decode;
    g_run.tail_from_vertices = g_run.level_vertices;  // before this level
    ++g_run.levels;
  }
  g_run.level_vertices = l.vertices;
}

// Each frame drawn, as the client draws it: its CRC, and the drawing's instructions.
void on_frame(void*, const vds::PlayedFrame& f) {
  ++g_run.frames;
  g_run.last_draw = f.display;
  g_run.draw_instructions += f.display;
  board::log(Line().str("check frame level=").dec(g_player.mesh.levels_done()).str(" status=ok crc=0x")
                 .hex32(f.crc).str("\n").c_str());
}

// Plays one stream file; false when it does not exist.
bool run_file(const char* path, int* failures) {
  if (!vds::fw::host_file_exists(path)) return false;
  vds::Arena arena(g_workspace, sizeof g_workspace);
  g_run = Run{};
  vds::PlayerConfig config = vds::kClientPlayerConfig;
  config.max_chunk_bytes = kChunkBytes;
  vds::PlayerCallbacks cb;
  cb.clock = clock;
  cb.level = on_level;
  cb.frame_shown = on_frame;
  vds::Player& player = g_player;
  const Status s = vds::fw::play_host_file(player, player.init(arena, config, cb), path, g_read, kReadBytes);
  const vds::MeshState& m = player.mesh.mesh();
  const uint32_t splits = m.vertex_count() - g_run.base_vertices;
  const char* base = vds::fw::file_name(path);
  // The model view's share of the workspace, from the plan the player made.
  size_t view_bytes = 0;
  if (player.plan().known) {
    vds::ModelViewConfig vc;
    vc.width = player.header().width;
    vc.height = player.header().height;
    vc.band_height = config.band_rows;
    view_bytes = vds::ModelView::workspace_bytes(vc, player.plan().vertices, player.plan().triangles);
  }
  Line l;
  l.str("m4 stream=").str(base).str(" status=").str(vds::status_name(s)).str(" vertices=").dec(m.vertex_count());
  l.str(" splits=").dec(splits).str(" levels=").dec(g_run.levels).str(" instructions=").dec(g_run.instructions);
  l.str(" base_instructions=").dec(g_run.base_instructions);
  l.str(" workspace=").dec(arena.high_water() - view_bytes).str("\n");
  board::log(l.c_str());
  // A version-2 stream's last level is the single-rate tail: its own count.
  if (player.mesh.have_header() && player.mesh.header().tail() && player.mesh.complete()) {
    Line t;
    t.str("m4 tail stream=").str(base).str(" tail_instructions=").dec(g_run.last_level_instructions);
    t.str(" split_vertices=").dec(g_run.tail_from_vertices - g_run.base_vertices).str("\n");
    board::log(t.c_str());
  }
  Line v;
  v.str("m4 view stream=").str(base).str(" triangles=").dec(m.triangle_count()).str(" view_workspace=").dec(view_bytes);
  v.str(" frames=").dec(g_run.frames);
  v.str(" draw_instructions=").dec(g_run.draw_instructions).str(" last_draw=").dec(g_run.last_draw).str("\n");
  board::log(v.c_str());
  if (s != Status::ok || !player.mesh.complete()) ++*failures;
  return true;
}

}  // namespace

extern "C" int vds_app_main() {
  board::init();
  int failures = 0;
  if (vds::fw::run_cases("mesh_case", [&](const char* name) { return run_file(name, &failures); }) == 0) {
    // No benchmark files: decode the golden test stream (the ctest run).
    if (!run_file(VDS_GOLDEN_MESH_STREAM, &failures)) {
      board::log("m4 error: cannot read " VDS_GOLDEN_MESH_STREAM "\n");
      return 1;
    }
  }
  return failures == 0 ? 0 : 1;
}
