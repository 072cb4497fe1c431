// `vds play STREAM --board host|qemu`: plays a stream on a simulated client.
// Starts the client firmware on the board — the host-native board as an
// ordinary process whose UART is a new pseudo-terminal, or the Cortex-M4
// build in QEMU (mps2-an386, -icount shift=0) whose UART0 is a TCP socket —
// serves the stream to it over the link at --baud, prints what the client
// reported, and checks every frame's CRC against the host replay of the
// client (what `vds frames` computes). On the host board a model can be
// turned by the viewer (--window, --controls): those frames are marked
// steered and not compared.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "board_run.h"
#include "commands.h"
#include "vds/enc/frames.h"
#include "vds/enc/stream_writer.h"

namespace vds::cli {
namespace {

struct PlayArgs : BoardArgs {
  std::string stream;
};

// The board's workspace as its log states it ("client: ready, workspace B
// bytes, player from byte U"), if it does.
bool board_arena(const std::filesystem::path& log, enc::ClientArena* out) {
  std::ifstream f(log);
  std::string line;
  while (std::getline(f, line)) {
    unsigned long long b = 0, u = 0;
    if (std::sscanf(line.c_str(), "client: ready, workspace %llu bytes, player from byte %llu", &b, &u) == 2) {
      *out = enc::ClientArena{static_cast<size_t>(b), static_cast<size_t>(u)};
      return true;
    }
  }
  return false;
}

void run_play(const PlayArgs& a) {
  const std::vector<uint8_t> bytes = enc::read_file(a.stream);  // (main reports its refusal, naming the file)
  // What any client must show; the stream is checked before it is served.
  std::vector<uint32_t> want;
  try {
    want = enc::client_frame_crcs(bytes);
  } catch (const std::exception& e) {
    throw Failure(kExitBadInput, a.stream + ": " + e.what());
  }
  const BoardResult r = run_on_board(a, a.stream, [&](const link::ServeOptions& o, const std::function<void(const std::string&)>& say) {
    return link::serve_stream(bytes, o, say);
  });
  // What this board must show: its workspace decides how fine a model's colours are.
  enc::ClientArena board;
  if (board_arena(r.log, &board)) want = enc::client_frame_crcs(bytes, nullptr, &board);
  check_board_frames(a, a.stream, r, want);
}

}  // namespace

void add_play(CLI::App& app) {
  auto a = std::make_shared<PlayArgs>();
  CLI::App* sub = app.add_subcommand("play", "Play a stream on a simulated client board and check its frames against the replay");
  sub->add_option("STREAM", a->stream, "Stream file")->required();
  sub->add_option("--board", a->board, "host: the host-native board on a pseudo-terminal; qemu: the Cortex-M4 board in QEMU")
      ->required()
      ->check(CLI::IsMember({"host", "qemu"}));
  sub->add_option("--baud", a->baud, "Line rate")->capture_default_str()->check(CLI::Range(1200u, 4000000u));
  sub->add_option("--out", a->out,
                  "Directory for the board's log and frame CRCs; on the host board also every frame as PNG, a Y4M and a contact sheet");
  sub->add_option("--firmware", a->firmware,
                  "The board's client firmware (default: the build's firmware_sim/vds_fw_client_host or cm4/firmware_sim/vds_fw_client.elf)");
  sub->add_option("--qemu", a->qemu, "QEMU's Arm system emulator")->capture_default_str();
  sub->add_option("--timeout", a->timeout, "Give up after this many seconds")->capture_default_str();
  sub->add_flag("--window", a->window,
                "Host board: show the frames in a live window (SDL2); a model is turned by dragging the mouse (or Left/Right) and stays in view until the window is closed");
  sub->add_option("--controls", a->controls,
                  "Host board: the viewer's controls from a script instead of the window's (lines 'FRAMES FORWARD RIGHT UP TURN TILT [fast]'; a model turns by TURN degrees a poll)");
  sub->callback([a] { run_play(*a); });
}

}  // namespace vds::cli
