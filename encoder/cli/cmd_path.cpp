// `vds path`: a per-frame camera path (one line per frame).
//   vds path --keys KEYS -o PATH   from a keyframe file, smoothly interpolated (vds/enc/camera_path.h);
//   vds path SCENE -o PATH         a tour through the scene's spawn points that stays out of walls
//                                  (vds/enc/camera_tour.h), with a contact sheet of it.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "commands.h"
#include "vds/enc/camera_path.h"
#include "vds/enc/camera_tour.h"
#include "vds/enc/scene.h"
#include "vds/enc/scene_rays.h"
#include "vds/enc/scene_render.h"
#include "vds/enc/stream_writer.h"
#include "vds/io/image.h"

namespace vds::cli {
namespace {

struct PathOptions {
  std::string scene, keys, out, sheet;
  double fps = 0, speed = 200;
  size_t frames = 600;
};

void write_path(const std::string& out, const enc::CameraPath& p) {
  const std::string text = enc::write_camera_path(p);
  enc::write_file(out, std::vector<uint8_t>(text.begin(), text.end()));
}

void run_keys(const PathOptions& o) {
  const std::vector<uint8_t> bytes = enc::read_file(o.keys);
  enc::CameraKeys k = enc::read_camera_keys(std::string(bytes.begin(), bytes.end()), o.keys);
  if (o.fps > 0) k.fps = o.fps;
  const enc::CameraPath p = enc::interpolate_keyframes(k);
  write_path(o.out, p);
  std::printf("%s: %zu frames at %g frames/s (%.2f s) from %zu keys, horizontal field of view %g degrees\n",
              o.out.c_str(), p.frames.size(), p.fps, static_cast<double>(p.frames.size() - 1) / p.fps, k.keys.size(),
              p.hfov_deg);
}

void run_tour(const PathOptions& o) {
  const enc::Scene scene = enc::load_scene(o.scene);
  const enc::SceneRays rays(scene);
  enc::TourOptions to;
  to.frames = o.frames;
  if (o.fps > 0) to.fps = o.fps;
  to.speed = o.speed;
  enc::TourReport rep;
  const enc::CameraPath p = enc::make_tour(scene, rays, to, &rep);
  write_path(o.out, p);
  std::string stops;
  for (size_t s : rep.stops) stops += (stops.empty() ? "" : " ") + std::to_string(s);
  std::printf("%s: a tour of %s, %zu frames at %g frames/s (%.1f s), %.0f map units; spawn points visited in order: %s\n",
              o.out.c_str(), scene.name.c_str(), p.frames.size(), p.fps, static_cast<double>(p.frames.size()) / p.fps,
              rep.length, stops.c_str());
  if (!rep.unreachable.empty()) {
    std::string u;
    for (size_t s : rep.unreachable) u += (u.empty() ? "" : " ") + std::to_string(s);
    std::printf("  no route found to spawn points %s\n", u.c_str());
  }
  std::printf("  nearest geometry along the way: %.1f map units\n", rep.min_clearance);
  // The contact sheet: 12 frames evenly spread, drawn by the ground-truth renderer.
  const std::string sheet = o.sheet.empty() ? std::filesystem::path(o.out).replace_extension(".png").string() : o.sheet;
  enc::CameraPath picks;
  picks.hfov_deg = p.hfov_deg;
  const size_t tiles = std::min<size_t>(12, p.frames.size());
  for (size_t k = 0; k < tiles; ++k) picks.frames.push_back(p.frames[sheet_frame(k, tiles, p.frames.size())]);
  const enc::SceneRenderer renderer(scene, enc::load_scene_images(scene));
  std::vector<io::Image> tilesv;
  enc::render_path(renderer, picks, 0, [&](size_t, const enc::SceneFrame& f) { tilesv.push_back(f.rgb); });
  std::vector<const io::Image*> ptrs;
  for (const io::Image& im : tilesv) ptrs.push_back(&im);
  io::save_png(sheet, io::grid(ptrs, 4));
  std::printf("  contact sheet: %s\n", sheet.c_str());
}

}  // namespace

void add_path(CLI::App& app) {
  auto o = std::make_shared<PathOptions>();
  CLI::App* sub = app.add_subcommand("path", "Write a per-frame camera path: a tour through a scene, or from keyframes (docs/walkthrough.md)");
  sub->add_option("scene", o->scene, "A scene to tour (a .bsp file or an OpenArena map name)");
  sub->add_option("--keys", o->keys, "Keyframe file: 'time_s x y z yaw_deg pitch_deg' per line");
  sub->add_option("-o,--output", o->out, "Camera path to write: 'frame x y z yaw_deg pitch_deg' per line")->required();
  sub->add_option("--fps", o->fps, "Frame rate (default: the keyframe file's '# fps', else 20)")->check(kPositive);
  sub->add_option("--frames", o->frames, "Tour: frames (default 600)")->check(CLI::Range(1, 1 << 20));
  sub->add_option("--speed", o->speed, "Tour: map units a second while moving (default 200)")->check(kPositive);
  sub->add_option("--sheet", o->sheet, "Tour: contact sheet to write (default: the path's name with .png)");
  sub->callback([o] {
    if (o->scene.empty() == o->keys.empty()) throw Failure(kExitUsage, "give either a SCENE to tour or --keys KEYS");
    if (!o->keys.empty()) run_keys(*o);
    else run_tour(*o);
  });
}

}  // namespace vds::cli
