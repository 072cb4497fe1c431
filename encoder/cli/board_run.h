// Playing on a simulated client board (`vds play`, `vds serve-terrain`):
// starts the client firmware on the board — the host-native board as an
// ordinary process whose UART is a new pseudo-terminal, or the Cortex-M4
// build in QEMU (mps2-an386, -icount shift=0) whose UART0 is a TCP socket —
// serves it over the link, and checks every frame's CRC against the host
// replay of the client.
#pragma once
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "vds/link/serve.h"

namespace vds::cli {

struct BoardArgs {
  std::string board, out, firmware, qemu = "qemu-system-arm";
  uint32_t baud = 115200;
  uint32_t timeout = 600;
  bool window = false;
  std::string controls;  // host board: a controls script (the viewer's keys, scripted)
  // A viewer who may turn a model: the host board with its window or a controls script.
  bool has_viewer() const { return board == "host" && (window || !controls.empty()); }
};

struct BoardResult {
  link::ServeReport report;
  link::ServeOptions options;  // the link it was served over
  int status = 0;  // the board's exit status (-1: it had to be killed)
  std::filesystem::path dir, log;
};

using ServeFn = std::function<link::ServeReport(const link::ServeOptions& o, const std::function<void(const std::string&)>& log)>;

// Starts the board and serves it with `serve` (retrying while QEMU comes up).
BoardResult run_on_board(const BoardArgs& a, const std::string& name, const ServeFn& serve);

// Prints the report and what the board showed against the replay's frame
// CRCs (`want`), writes crcs.txt; throws unless every frame the board showed
// is the replay's (all of them, unless its workspace held a model's prefix)
// and the board exited cleanly.
void check_board_frames(const BoardArgs& a, const std::string& name, const BoardResult& r, const std::vector<uint32_t>& want);

}  // namespace vds::cli
