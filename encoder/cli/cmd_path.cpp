// `vds path --keys KEYS -o PATH`: a per-frame camera path (one line per
// frame) from a keyframe file, smoothly interpolated (vds/enc/camera_path.h).
#include <cstdio>
#include <memory>
#include <string>

#include "commands.h"
#include "vds/enc/camera_path.h"
#include "vds/enc/stream_writer.h"

namespace vds::cli {
namespace {

struct PathOptions {
  std::string keys;
  std::string out;
  double fps = 0;
};

void run_path(const PathOptions& o) {
  const std::vector<uint8_t> bytes = enc::read_file(o.keys);
  enc::CameraKeys k = enc::read_camera_keys(std::string(bytes.begin(), bytes.end()), o.keys);
  if (o.fps > 0) k.fps = o.fps;
  const enc::CameraPath p = enc::interpolate_keyframes(k);
  const std::string text = enc::write_camera_path(p);
  enc::write_file(o.out, std::vector<uint8_t>(text.begin(), text.end()));
  std::printf("%s: %zu frames at %g frames/s (%.2f s) from %zu keys, horizontal field of view %g degrees\n",
              o.out.c_str(), p.frames.size(), p.fps, static_cast<double>(p.frames.size() - 1) / p.fps, k.keys.size(),
              p.hfov_deg);
}

}  // namespace

void add_path(CLI::App& app) {
  auto o = std::make_shared<PathOptions>();
  CLI::App* sub = app.add_subcommand("path", "Write a per-frame camera path from keyframes (docs/walkthrough.md)");
  sub->add_option("--keys", o->keys, "Keyframe file: 'time_s x y z yaw_deg pitch_deg' per line")->required();
  sub->add_option("-o,--output", o->out, "Camera path to write: 'frame x y z yaw_deg pitch_deg' per line")->required();
  sub->add_option("--fps", o->fps, "Frame rate (default: the keyframe file's '# fps', else 20)")->check(kPositive);
  sub->callback([o] { run_path(*o); });
}

}  // namespace vds::cli
