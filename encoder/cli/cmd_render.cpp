// `vds render SCENE --path PATH -o OUT`: the ground truth of a walkthrough
// (vds/enc/scene_render.h), every frame of a camera path as a viewer with
// the whole scene would see it. Writes
//   OUT.y4m  the frames (Y'CbCr 4:4:4, full-range BT.601);
//   OUT.rgb  the same frames exactly, as raw 8-bit RGB (what figures are measured against);
//   OUT.vis  per frame, the triangle and depth seen at each pixel centre (format below);
// and on request a PNG per frame and a contact sheet.
//
// OUT.vis: a 16-byte header "VDSVIS01", width and height (uint32, little
// endian); then per frame width x height triangle indices (uint32,
// 0xFFFFFFFF for none) followed by width x height depths (float32,
// camera-space z in scene units, +infinity for none), rows top to bottom.
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include "commands.h"
#include "vds/enc/camera_path.h"
#include "vds/enc/scene.h"
#include "vds/enc/scene_render.h"
#include "vds/enc/stream_writer.h"
#include "vds/io/image.h"
#include "vds/io/y4m.h"

namespace vds::cli {
namespace {

struct RenderCmdOptions {
  std::string scene, path, out, png_dir, sheet, size = "240x180";
  int supersample = 2, aniso = 8, threads = 0, overbright = 2;
};

void parse_size(const std::string& s, int* w, int* h) {
  if (std::sscanf(s.c_str(), "%dx%d", w, h) != 2 || *w < 16 || *h < 16 || *w > 4096 || *h > 4096)
    throw Failure(kExitUsage, "--size must be WIDTHxHEIGHT, each 16..4096, not '" + s + "'");
}

void put32(std::ofstream& f, uint32_t v) {
  const uint8_t b[4] = {static_cast<uint8_t>(v), static_cast<uint8_t>(v >> 8), static_cast<uint8_t>(v >> 16), static_cast<uint8_t>(v >> 24)};
  f.write(reinterpret_cast<const char*>(b), 4);
}

void run_render(const RenderCmdOptions& o) {
  const enc::Scene scene = enc::load_scene(o.scene);
  const std::vector<uint8_t> text = enc::read_file(o.path);
  const enc::CameraPath path = enc::read_camera_path(std::string(text.begin(), text.end()), o.path);
  if (path.frames.empty()) throw Failure(kExitBadInput, o.path + ": no frames");
  enc::RenderOptions ro;
  parse_size(o.size, &ro.width, &ro.height);
  ro.supersample = o.supersample;
  ro.max_aniso = o.aniso;
  ro.overbright_bits = o.overbright;
  const enc::SceneRenderer renderer(scene, enc::load_scene_images(scene), ro);

  std::string base = o.out;
  if (base.size() > 4 && base.compare(base.size() - 4, 4, ".y4m") == 0) base.resize(base.size() - 4);
  io::Y4mWriter y4m(base + ".y4m.part", static_cast<int>(std::lround(path.fps)));
  std::ofstream rgb(base + ".rgb.part", std::ios::binary | std::ios::trunc);
  std::ofstream vis(base + ".vis.part", std::ios::binary | std::ios::trunc);
  if (!rgb || !vis) throw Failure(kExitBadInput, base + ": cannot write its .rgb or .vis file");
  vis.write("VDSVIS01", 8);
  put32(vis, static_cast<uint32_t>(ro.width));
  put32(vis, static_cast<uint32_t>(ro.height));
  if (!o.png_dir.empty()) std::filesystem::create_directories(o.png_dir);
  // The contact sheet: 12 frames evenly spread.
  const size_t n = path.frames.size(), tiles = std::min<size_t>(12, n);
  std::vector<io::Image> sheet;
  const auto t0 = std::chrono::steady_clock::now();
  const auto sink = [&](size_t i, const enc::SceneFrame& f) {
    y4m.write(f.rgb);
    rgb.write(reinterpret_cast<const char*>(f.rgb.pixels.data()), static_cast<std::streamsize>(f.rgb.pixels.size()));
    static_assert(sizeof(float) == 4 && sizeof(uint32_t) == 4, "the .vis file holds 32-bit values");
    vis.write(reinterpret_cast<const char*>(f.ids.data()), static_cast<std::streamsize>(f.ids.size() * 4));
    vis.write(reinterpret_cast<const char*>(f.depth.data()), static_cast<std::streamsize>(f.depth.size() * 4));
    if (!o.png_dir.empty()) {
      char name[32];
      std::snprintf(name, sizeof name, "/%05zu.png", i);
      io::save_png(o.png_dir + name, f.rgb);
    }
    if (sheet.size() < tiles && i == sheet_frame(sheet.size(), tiles, n)) sheet.push_back(f.rgb);
  };
  const auto progress = [&](size_t done) {
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::fprintf(stderr, "\rrender: %zu/%zu frames, %.1f s", done, n, s);
    std::fflush(stderr);
  };
  // Nothing half-written is left behind: the .part files go if anything fails.
  const auto remove_parts = [&] {
    std::error_code ec;
    for (const char* ext : {".y4m", ".rgb", ".vis"}) std::filesystem::remove(base + ext + ".part", ec);
  };
  try {
    enc::render_path(renderer, path, o.threads, sink, progress);
    std::fprintf(stderr, "\n");
    rgb.close();
    vis.close();
    if (!rgb || !vis) throw Failure(kExitBadInput, base + ": writing its .rgb or .vis file failed (disk full?)");
    y4m.close();
  } catch (...) {
    rgb.close();
    vis.close();
    remove_parts();
    throw;
  }
  for (const char* ext : {".y4m", ".rgb", ".vis"}) std::filesystem::rename(base + ext + ".part", base + ext);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!o.sheet.empty()) {
    std::vector<const io::Image*> ptrs;
    for (const io::Image& im : sheet) ptrs.push_back(&im);
    if (!ptrs.empty()) io::save_png(o.sheet, io::grid(ptrs, 4));
  }
  std::printf("%s: %zu frames of %dx%d (%dx%d samples each) at %g frames/s in %.1f s (%.1f ms a frame); %s.y4m, %s.rgb, %s.vis\n",
              scene.name.c_str(), n, ro.width, ro.height, ro.supersample, ro.supersample, path.fps, secs, 1000 * secs / n,
              base.c_str(), base.c_str(), base.c_str());
}

}  // namespace

void add_render(CLI::App& app) {
  auto o = std::make_shared<RenderCmdOptions>();
  CLI::App* sub = app.add_subcommand("render", "Render a camera path through a scene: the ground truth of a walkthrough (docs/walkthrough.md)");
  sub->add_option("scene", o->scene, "A .bsp file or an OpenArena map name (oa_dm4)")->required();
  sub->add_option("--path", o->path, "Camera path: 'frame x y z yaw_deg pitch_deg' per line")->required();
  sub->add_option("-o,--output", o->out, "Output base name: writes OUT.y4m, OUT.rgb, OUT.vis")->required();
  sub->add_option("--size", o->size, "Frame size WIDTHxHEIGHT (default 240x180)");
  sub->add_option("--supersample", o->supersample, "n x n samples per pixel (default 2)")->check(CLI::Range(1, 8));
  sub->add_option("--aniso", o->aniso, "Most texture samples along a stretched footprint (default 8; 1 is plain trilinear)")
      ->check(CLI::Range(1, 16));
  sub->add_option("--overbright-bits", o->overbright, "Lightmaps x 2^bits (default 2, the game's)")->check(CLI::Range(0, 4));
  sub->add_option("--threads", o->threads, "Threads (default: one per core)")->check(CLI::Range(0, 256));
  sub->add_option("--png", o->png_dir, "Also write each frame as DIR/NNNNN.png");
  sub->add_option("--sheet", o->sheet, "Also write a contact sheet of 12 frames (PNG)");
  sub->callback([o] { run_render(*o); });
}

}  // namespace vds::cli
