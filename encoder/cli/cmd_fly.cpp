// `vds fly MAP`: the server's replay of a flight over a terrain (docs/terrain.md):
// the scripted flyover (or --flight KEYS), each frame's pose answered by a
// texture update within the link's bytes, and what the client then holds
// drawn next to the ground truth. Prints the paper's compression ratios and
// the rendered PSNR; with --out, writes per-frame figures (frames.csv), a
// contact sheet (truth | vds) and, with --frames-png, every frame.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include "commands.h"
#include "vds/enc/stream_writer.h"
#include "vds/enc/terrain_flight.h"
#include "vds/enc/terrain_map.h"
#include "vds/enc/terrain_server.h"
#include "vds/enc/terrain_tiles.h"
#include "vds/io/image.h"

namespace vds::cli {
namespace {

struct FlyOptions {
  std::string map, heightmap, colour, flight, out, tiles;
  int tile_quality = 75;
  size_t cache = 98304;
  std::vector<double> scale;
  int frames = 300, quantiser = 4, latency = 2, poses = 5;
  double fps = 20, rate = 2000, detail = 1.25;
  uint32_t store = 98304;
  bool frames_png = false;
};

enc::TerrainMap load_map(const FlyOptions& o) {
  if (!o.heightmap.empty() || !o.colour.empty()) {
    if (o.heightmap.empty() || o.colour.empty() || o.scale.size() != 2)
      throw Failure(kExitUsage, "a heightmap needs --colour and --scale H,V too");
    return enc::load_terrain_files(o.heightmap, o.colour, o.scale[0], o.scale[1]);
  }
  if (o.map.empty()) throw Failure(kExitUsage, "give a MAP, or --heightmap, --colour and --scale");
  return enc::load_terrain(o.map);
}

void run(const FlyOptions& o) {
  const enc::TerrainMap map = load_map(o);
  const enc::TerrainCoding t = enc::code_terrain(map, o.quantiser);
  enc::CameraPath path;
  if (!o.flight.empty()) {
    const std::vector<uint8_t> b = enc::read_file(o.flight);
    path = enc::read_flight(std::string(b.begin(), b.end()), o.flight, t);
  } else {
    path = enc::terrain_flyover(t, o.frames, o.fps);
  }
  std::printf("%s: %dx%d colour map, %dx%d cells of %.2f m, heights to %.1f m; %zu frames at %g frames/s\n",
              map.name.c_str(), map.colour.width, map.colour.height, t.grid.cells_x, t.grid.cells_y, t.cell_m,
              *std::max_element(t.heights.begin(), t.heights.end()) * t.metres_per_unit, path.frames.size(), path.fps);
  enc::FlightOptions fo;
  fo.link.rate_bytes_per_s = o.rate;
  fo.link.latency_frames = o.latency;
  fo.link.poses_per_s = o.poses;
  fo.capacity = o.store;
  fo.pose.detail = o.detail;
  fo.client_renderer = o.tiles.empty();
  const size_t tiles = std::min<size_t>(8, path.frames.size());
  std::vector<io::Image> sheet;
  if (!o.out.empty()) std::filesystem::create_directories(o.out);
  fo.frame_sink = [&](size_t f, const io::Image& truth, const io::Image& client) {
    bool pick = false;
    for (size_t k = 0; k < tiles; ++k) pick = pick || sheet_frame(k, tiles, path.frames.size()) == f;
    if (pick) sheet.push_back(io::side_by_side({&truth, &client}));
    if (o.frames_png && !o.out.empty()) {
      char name[32];
      std::snprintf(name, sizeof name, "frame_%04zu.png", f);
      io::save_png((std::filesystem::path(o.out) / name).string(), client);
    }
  };
  fo.progress = [&](size_t done) {
    if (done % 25 == 0 || done == path.frames.size()) std::fprintf(stderr, "\r  frame %zu of %zu", done, path.frames.size());
    if (done == path.frames.size()) std::fprintf(stderr, "\n");
  };
  enc::FlightResult r;
  if (o.tiles.empty()) {
    r = enc::fly(t, path, fo);
  } else {
    enc::TileOptions to = enc::parse_tile_variant(o.tiles);
    to.quality = o.tile_quality;
    to.cache_bytes = o.cache;
    std::printf("  the baseline instead of vds: %s tiles of %d texels at quality %d, a %zu-byte cache\n",
                to.codec == enc::TileCodec::jpeg ? "JPEG" : "WebP", to.tile, to.quality, to.cache_bytes);
    r = enc::fly_tiles(t, path, fo, to);
  }

  // The paper's ratios against the raw 24-bit texture.
  const double raw = 3.0 * map.colour.width * map.colour.height;
  size_t down = 0, up = 0, later = 0;
  double psnr = 0;
  for (const enc::FlightFrame& f : r.frames) {
    down += f.down_bytes;
    up += f.up_bytes;
    psnr += f.psnr;
  }
  later = down - r.first_update_bytes;
  const size_t later_frames = r.frames.size() - r.first_update_frames - 1;
  psnr /= static_cast<double>(r.frames.size());
  std::printf("  elevation: %zu bytes for %d points (%.2f bits a point): %zu coarse first, the rest whole by frame %u\n",
              r.elevation_bytes, t.points_x() * t.points_y(), 8.0 * r.elevation_bytes / (t.points_x() * t.points_y()),
              r.coarse_elevation_bytes, r.elevation_frame);
  if (!r.first_update_done) {
    std::printf("  intra: the first pose's data was not all sent within the flight (%zu bytes sent)\n",
                r.first_update_bytes);
  } else {
    std::printf("  intra (the first pose whole, by frame %u): %zu bytes, 1:%.0f\n", r.first_update_frames,
                r.first_update_bytes, raw / std::max<size_t>(1, r.first_update_bytes));
    std::printf("  inter (the %zu frames after): %zu bytes, 1:%.0f per frame\n", later_frames, later,
                later > 0 ? raw * static_cast<double>(later_frames) / static_cast<double>(later) : 0.0);
  }
  std::printf("  overall: %zu bytes down over %zu frames, 1:%.0f per frame; %zu bytes of poses up\n", down,
              r.frames.size(), raw * static_cast<double>(r.frames.size()) / static_cast<double>(std::max<size_t>(1, down)),
              up);
  std::printf("  rendered PSNR against the ground truth (coding loss only: both drawn by the reference renderer): "
              "mean %.2f dB\n", psnr);
  if (fo.client_renderer) {
    double full = 0;
    for (const enc::FlightFrame& f : r.frames) full += f.psnr_client_renderer / static_cast<double>(r.frames.size());
    std::printf("  the client library's renderer with the whole texture against the ground truth (rendering loss "
                "only): mean %.2f dB\n", full);
  }
  if (o.out.empty()) return;
  std::ofstream csv(std::filesystem::path(o.out) / "frames.csv");
  csv << "frame,down_bytes,elevation_bytes,up_bytes,grows,intra,shrinks,coefficients_added,coefficients_dropped,blocks_wanted,"
         "coefficients_held,coefficients_needed,blocks_needed,psnr,psnr_client_renderer_full_texture\n";
  for (size_t i = 0; i < r.frames.size(); ++i) {
    const enc::FlightFrame& f = r.frames[i];
    csv << i << ',' << f.down_bytes << ',' << f.elevation_bytes << ',' << f.up_bytes << ',' << f.update.grows << ',' << f.update.intra << ','
        << f.update.shrinks << ',' << f.update.coefficients << ',' << f.update.dropped << ',' << f.update.wanted << ','
        << f.held << ',' << f.update.needed << ',' << f.update.needed_blocks << ',' << f.psnr << ','
        << f.psnr_client_renderer << '\n';
  }
  std::vector<const io::Image*> ptrs;
  for (const io::Image& im : sheet) ptrs.push_back(&im);
  const std::string sheet_path = (std::filesystem::path(o.out) / "sheet.png").string();
  io::save_png(sheet_path, io::grid(ptrs, 2));
  std::printf("  %s/frames.csv, %s (ground truth | vds)\n", o.out.c_str(), sheet_path.c_str());
}

}  // namespace

void add_fly(CLI::App& app) {
  auto o = std::make_shared<FlyOptions>();
  CLI::App* sub = app.add_subcommand("fly", "Replay a flight over a terrain on the server: updates, ratios, pictures (docs/terrain.md)");
  sub->add_option("map", o->map, "A Trigger Rally map name, ZIP:NAME, a .level file or a folder with one");
  sub->add_option("--heightmap", o->heightmap, "Instead of a map: a heightmap (8/16-bit grey PNG or PGM, or colour: R+G+B)");
  sub->add_option("--colour", o->colour, "With --heightmap: the colour map");
  sub->add_option("--scale", o->scale, "With --heightmap: metres between samples and per height level")->expected(2)->delimiter(',');
  sub->add_option("--flight", o->flight, "Camera keys in metres over the map (default: the scripted flyover)");
  sub->add_option("--frames", o->frames, "Flyover frames (default 300)")->check(CLI::Range(2, 100000));
  sub->add_option("--fps", o->fps, "Frame rate (default 20)")->check(kPositive);
  sub->add_option("--rate", o->rate, "Downlink bytes a second (default 2000; 0: unlimited, every pose answered whole)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--latency", o->latency, "Frames from a pose to its update (default 2)")->check(CLI::Range(0, 1000));
  sub->add_option("--poses", o->poses, "Poses sent up a second (default 5)")->check(CLI::Range(1, 1000));
  sub->add_option("--quantiser", o->quantiser, "Quantiser scale, 1..62 (default 4)")->check(CLI::Range(1, 62));
  sub->add_option("--store", o->store, "Client store, coefficients (default 98304)")->check(CLI::Range(64u, 1u << 26));
  sub->add_option("--detail", o->detail, "Scale of every mask cutoff (default 1.25)")->check(kPositive);
  sub->add_option("--out", o->out, "Folder for frames.csv and the contact sheet");
  sub->add_flag("--frames-png", o->frames_png, "With --out: every frame the client shows, as PNG");
  sub->add_option("--tiles", o->tiles, "The baseline instead of vds: a tile pyramid, jpeg64, jpeg256, webp64 or webp256")
      ->check(CLI::IsMember({"jpeg64", "jpeg256", "webp64", "webp256"}));
  sub->add_option("--tile-quality", o->tile_quality, "With --tiles: the codec's quality, 1..100 (default 75)")
      ->check(CLI::Range(1, 100));
  sub->add_option("--cache", o->cache, "With --tiles: the client's tile cache, bytes of 4:2:0 texels (default 98304)")
      ->check(CLI::Range(size_t{1024}, size_t{1} << 30));
  sub->callback([o] { run(*o); });
}

}  // namespace vds::cli
