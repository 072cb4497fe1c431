// `vds frames STREAM`: what a client displays, frame by frame: decodes the
// stream through the client library exactly as the firmware does and prints
// each frame's CRC-32C; optionally writes the frames as PNG.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "vds/enc/frames.h"
#include "vds/enc/stream_writer.h"

namespace vds::cli {
namespace {

struct Options {
  std::string file;
  std::string png_dir;
  size_t workspace = 0;
  size_t player_from = 0;
  bool notices = false;
};

void run(const Options& o) {
  const std::vector<uint8_t> stream = enc::read_file(o.file);
  std::vector<enc::Image> frames;
  std::vector<uint32_t> crcs;
  std::vector<std::string> notices;
  try {
    const enc::ClientArena board{o.workspace, o.player_from};
    crcs = enc::client_frame_crcs(stream, o.png_dir.empty() ? nullptr : &frames, o.workspace ? &board : nullptr,
                                  o.notices ? &notices : nullptr);
  } catch (const std::runtime_error& e) {
    throw Failure(kExitBadInput, o.file + ": " + e.what());
  }
  for (const std::string& n : notices) std::fprintf(stderr, "%s\n", n.c_str());
  if (!o.png_dir.empty()) std::filesystem::create_directories(o.png_dir);
  for (size_t i = 0; i < crcs.size(); ++i) {
    std::printf("%08x\n", crcs[i]);
    if (!o.png_dir.empty()) {
      char name[32];
      std::snprintf(name, sizeof name, "/frame%04zu.png", i);
      enc::save_png(o.png_dir + name, frames[i]);
    }
  }
}

}  // namespace

void add_frames(CLI::App& app) {
  auto o = std::make_shared<Options>();
  CLI::App* sub = app.add_subcommand("frames", "Print the CRC-32C of every frame a client displays");
  sub->add_option("STREAM", o->file, "vds stream")->required();
  sub->add_option("--png", o->png_dir, "Also write each frame as DIR/frameNNNN.png");
  auto* w = sub->add_option("--workspace", o->workspace,
                            "Replay a board: its workspace, bytes (its log: \"client: ready, workspace B bytes, player from byte U\")")
                ->check(CLI::Range(size_t{1024}, size_t{1} << 30));
  sub->add_option("--player-from", o->player_from, "With --workspace: where the board's player starts in it (U)")
      ->needs(w);
  sub->add_flag("--notices", o->notices, "Print what the player decided about a model (on stderr)");
  sub->callback([o] { run(*o); });
}

}  // namespace vds::cli
