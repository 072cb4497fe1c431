// Walkthrough and terrain playback on the board: reads vds streams from
// host files (walk_case0.vds, walk_case1.vds, ... until one is missing,
// then terrain_case0.vds, ...) and plays each through vds::Player. A
// walkthrough plays twice: in the client firmware's workspace
// (VDS_CLIENT_WORKSPACE, less what the client's link takes from it
// first, with the client's player configuration: what the client does,
// its caches sized by what is left), then in a workspace as large as the
// board's RAM allows (the arena's high-water mark: what the stream takes
// with every cache); a terrain plays in the latter only. Per frame it
// prints a "frame" line: the frame's CRC and its instruction counts
// (parse, decode, display: the player's frame records); per run an
// "m4 walk" (or "m4 terrain") summary naming its budget. The host board
// and the Cortex-M4 board must print the same CRCs
// (bench/run_walkthrough_m4.sh compares them, and the CRCs with the
// encoder's replay).
#include <cstddef>
#include <cstdint>

#include "host_cases.h"
#include "print.h"
#include "vds/arena.h"
#include "vds/board.h"
#include "vds/link/link.h"
#include "vds/player.h"

#ifndef VDS_APP_WORKSPACE_MAX
#error "VDS_APP_WORKSPACE_MAX (the largest workspace this build can use) must be set by the build"
#endif
#ifndef VDS_CLIENT_WORKSPACE
#error "VDS_CLIENT_WORKSPACE (the client firmware's workspace) must be set by the build"
#endif
static_assert(VDS_CLIENT_WORKSPACE <= VDS_APP_WORKSPACE_MAX, "the client's workspace fits the benchmark's");

namespace {

using vds::fw::Line;
using vds::Status;
namespace board = vds::board;

constexpr uint32_t kChunkBytes = 32768;  // the largest chunk payload accepted
constexpr uint32_t kReadBytes = 4096;    // file bytes fed to the player at a time

alignas(8) uint8_t g_workspace[VDS_APP_WORKSPACE_MAX];
uint8_t g_read[kReadBytes];

struct Run {
  uint32_t frames = 0;
  uint64_t total = 0, worst = 0;  // parse + decode + display per frame
  uint32_t worst_frame = 0;
  uint64_t parse = 0, decode = 0, display = 0;
};

Run g_run;

uint64_t clock(void*) { return board::instructions(); }

void on_frame(void*, const vds::PlayedFrame& f) {
  const uint64_t all = f.parse + f.decode + f.display;
  ++g_run.frames;
  g_run.total += all;
  g_run.parse += f.parse;
  g_run.decode += f.decode;
  g_run.display += f.display;
  if (all > g_run.worst) g_run.worst = all, g_run.worst_frame = f.index;
  Line l;
  l.str("frame ").dec(f.index).str(" crc=0x").hex32(f.crc).str(" parse=").dec(f.parse).str(" decode=").dec(f.decode);
  board::log(l.str(" display=").dec(f.display).str("\n").c_str());
}

// Plays one stream file; false when it does not exist. `label`: "walk"
// or "terrain", for the summary lines; `client`: in the client's workspace
// (a stream that does not fit it is reported, not a failure), else in the
// whole of the board's.
bool run_file(const char* path, const char* label, bool client, int* failures) {
  if (!vds::fw::host_file_exists(path)) return false;
  vds::Arena arena(g_workspace, client ? VDS_CLIENT_WORKSPACE : sizeof g_workspace);
  vds::PlayerConfig config = vds::kClientPlayerConfig;
  if (client) {
    // The client's link first, as the client firmware carves it.
    static vds::link::Link link;
    const vds::link::LinkConfig lc = vds::link::device_config(1, board::uart_rx_ring_bytes());
    if (link.init(lc, arena) != Status::ok) {
      board::log("m4 walk error: the client's link does not fit its workspace\n");
      ++*failures;
      return true;
    }
  } else {
    config.max_chunk_bytes = kChunkBytes;
  }
  const size_t link_bytes = arena.used();
  g_run = Run{};
  vds::PlayerCallbacks cb;
  cb.clock = clock;
  cb.frame_shown = on_frame;
  static vds::Player player;
  const Status s = vds::fw::play_host_file(player, player.init(arena, config, cb), path, g_read, kReadBytes);
  const char* base = vds::fw::file_name(path);
  const char* budget = client ? "client" : "board";
  Line l;
  l.str("m4 ").str(label).str(" stream=").str(base).str(" budget=").str(budget).str(" status=").str(vds::status_name(s));
  l.str(" frames=").dec(g_run.frames).str(" needs=").dec(player.plan().needs);
  l.str(" instructions=").dec(g_run.total).str(" worst=").dec(g_run.worst).str(" worst_frame=").dec(g_run.worst_frame);
  board::log(l.str("\n").c_str());
  Line parts;
  parts.str("m4 ").str(label).str("_parts stream=").str(base).str(" budget=").str(budget).str(" parse=").dec(g_run.parse);
  parts.str(" decode=").dec(g_run.decode).str(" display=").dec(g_run.display).str(" workspace=").dec(arena.high_water());
  parts.str(" link=").dec(link_bytes).str(" chunk_buffer=").dec(config.max_chunk_bytes);
  board::log(parts.str("\n").c_str());
  if (s != Status::ok && !(client && s == Status::workspace_too_small)) {
    board::log(Line().str("m4 ").str(label).str(" error: ").str(player.error_detail()).str("\n").c_str());
    ++*failures;
  }
  return true;
}

}  // namespace

extern "C" int vds_app_main() {
  board::init();
  int failures = 0;
  // A walkthrough in both workspaces (its caches take what is spare), a
  // terrain in the board's (bench/run_terrain_m4.sh reports its store).
  const int walks = vds::fw::run_cases("walk_case", [&](const char* name) {
    return run_file(name, "walk", true, &failures) && run_file(name, "walk", false, &failures);
  });
  const int terrains =
      vds::fw::run_cases("terrain_case", [&](const char* name) { return run_file(name, "terrain", false, &failures); });
  if (walks + terrains == 0) {
    board::log("m4 walk error: no walk_case0.vds or terrain_case0.vds in the working folder\n");
    return 1;
  }
  return failures == 0 ? 0 : 1;
}
