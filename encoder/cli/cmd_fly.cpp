// `vds fly MAP`: the server's replay of a flight over a terrain (docs/terrain.md):
// the scripted flyover (or --flight KEYS), each frame's pose answered by a
// texture update within the link's bytes, and what the client then holds
// drawn next to the ground truth. Prints the paper's compression ratios and
// the rendered PSNR; with --out, writes per-frame figures (frames.csv), a
// contact sheet (truth | vds) and, with --frames-png, every frame and its truth.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <numeric>
#include <stdexcept>
#include <string>

#include "board_run.h"
#include "commands.h"
#include "serve_report.h"
#include "vds/enc/stream_writer.h"
#include "vds/enc/terrain_flight.h"
#include "vds/enc/terrain_map.h"
#include "vds/enc/terrain_server.h"
#include "vds/enc/terrain_stream.h"
#include "vds/enc/frames.h"
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
  uint32_t store = 49152;
  bool frames_png = false;
  // encode-terrain
  std::string output;
  int cache_log2 = 4, cells = 64, half_log2 = 6, frame_budget = 2;
  bool psnr = false;
  // serve-terrain
  BoardArgs board;
  std::string link, stream_out;
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

enc::CameraPath load_flight(const FlyOptions& o, const enc::TerrainCoding& t) {
  if (!o.flight.empty()) {
    const std::vector<uint8_t> b = enc::read_file(o.flight);
    return enc::read_flight(std::string(b.begin(), b.end()), o.flight, t);
  }
  return enc::terrain_flyover(t, o.frames, o.fps);
}

// --frames-png: frame f as the client showed it and its ground truth.
void save_frame_pngs(const std::string& out, size_t f, const io::Image& client, const io::Image& truth) {
  char name[32];
  std::snprintf(name, sizeof name, "frame_%04zu.png", f);
  io::save_png((std::filesystem::path(out) / name).string(), client);
  std::snprintf(name, sizeof name, "truth_%04zu.png", f);
  io::save_png((std::filesystem::path(out) / name).string(), truth);
}

// The contact sheet's pairs (ground truth | client), two a row, as
// out/sheet.png; its path.
std::string save_sheet(const std::string& out, const std::vector<io::Image>& sheet) {
  std::vector<const io::Image*> ptrs;
  for (const io::Image& im : sheet) ptrs.push_back(&im);
  const std::string path = (std::filesystem::path(out) / "sheet.png").string();
  io::save_png(path, io::grid(ptrs, 2));
  return path;
}

void run(const FlyOptions& o) {
  const enc::TerrainMap map = load_map(o);
  const enc::TerrainCoding t = enc::code_terrain(map, o.quantiser);
  const enc::CameraPath path = load_flight(o, t);
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
    if (o.frames_png && !o.out.empty()) save_frame_pngs(o.out, f, client, truth);
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
  const std::string csv_path = (std::filesystem::path(o.out) / "frames.csv").string();
  std::ofstream csv(csv_path);
  csv << "frame,down_bytes,elevation_bytes,up_bytes,grows,intra,shrinks,coefficients_added,coefficients_dropped,blocks_wanted,"
         "coefficients_held,coefficients_needed,blocks_needed,psnr,psnr_client_renderer_full_texture\n";
  for (size_t i = 0; i < r.frames.size(); ++i) {
    const enc::FlightFrame& f = r.frames[i];
    csv << i << ',' << f.down_bytes << ',' << f.elevation_bytes << ',' << f.up_bytes << ',' << f.update.grows << ',' << f.update.intra << ','
        << f.update.shrinks << ',' << f.update.coefficients << ',' << f.update.dropped << ',' << f.update.wanted << ','
        << f.held << ',' << f.update.needed << ',' << f.update.needed_blocks << ',' << f.psnr << ','
        << f.psnr_client_renderer << '\n';
  }
  csv.close();
  if (!csv) throw std::runtime_error(csv_path + ": cannot be written");
  const std::string sheet_path = save_sheet(o.out, sheet);
  std::printf("  %s/frames.csv, %s (ground truth | vds)\n", o.out.c_str(), sheet_path.c_str());
}

enc::TerrainStreamOptions stream_options(const FlyOptions& o, size_t frames) {
  enc::TerrainStreamOptions so;
  so.link.rate_bytes_per_s = o.rate;
  so.link.latency_frames = o.latency;
  so.link.poses_per_s = o.poses;
  so.store_units = o.store;
  so.cache_log2 = o.cache_log2;
  so.max_cells = o.cells;
  so.half_log2 = o.half_log2;
  so.frame_budget = o.frame_budget;
  so.pose.detail = o.detail;
  so.progress = [frames](size_t done) {
    if (done % 25 == 0 || done == frames) std::fprintf(stderr, "\r  frame %zu of %zu", done, frames);
    if (done == frames) std::fprintf(stderr, "\n");
  };
  return so;
}

// `vds encode-terrain`: the terrain stream for a scripted flight, then its
// replay through the client library (every frame's CRC; with --psnr each
// frame against the ground truth).
void run_encode(const FlyOptions& o) {
  const enc::TerrainMap map = load_map(o);
  const enc::TerrainCoding t = enc::code_terrain(map, o.quantiser);
  const enc::CameraPath path = load_flight(o, t);
  const enc::TerrainStreamOptions so = stream_options(o, path.frames.size());
  const enc::TerrainStreamResult r = enc::write_terrain_stream(t, path, so);
  enc::write_file(o.output, r.bytes);
  size_t texture = 0, elevation = 0;
  for (const enc::TerrainStreamFrame& f : r.frames) texture += f.texture_bytes, elevation += f.elevation_bytes;
  std::printf("%s: %zu frames, %zu bytes (%zu before the first frame; fine elevation %zu, whole by frame %u; "
              "texture updates %zu)\n",
              o.output.c_str(), r.frames.size(), r.bytes.size(), r.opening_bytes, elevation, r.elevation_frame, texture);
  std::vector<io::Image> shown;
  const std::vector<uint32_t> crcs = enc::client_frame_crcs(r.bytes, &shown);
  uint32_t all = 0;
  for (uint32_t c : crcs) all = all * 31 + c;
  std::printf("  the client library plays it: %zu frames (CRCs hashed: %08x)\n", crcs.size(), all);
  if (o.psnr || !o.out.empty()) {
    const enc::TerrainTruth truth(t, so.width, so.height);
    std::vector<io::Image> sheet;
    const size_t tiles = std::min<size_t>(8, shown.size());
    if (!o.out.empty()) std::filesystem::create_directories(o.out);
    std::vector<double> per_frame(shown.size());
    for (size_t f = 0; f < shown.size(); ++f) {
      const io::Image g = truth.render(r.flight[f], path.hfov_deg);
      per_frame[f] = io::psnr(g, shown[f]);
      for (size_t k = 0; k < tiles; ++k)
        if (sheet_frame(k, tiles, shown.size()) == f) sheet.push_back(io::side_by_side({&g, &shown[f]}));
      if (o.frames_png && !o.out.empty()) save_frame_pngs(o.out, f, shown[f], g);
    }
    std::printf("  what the client shows against the ground truth: mean %.2f dB\n",
                std::accumulate(per_frame.begin(), per_frame.end(), 0.0) / static_cast<double>(shown.size()));
    if (!o.out.empty()) {
      const std::string sheet_path = save_sheet(o.out, sheet);
      const std::string csv_path = (std::filesystem::path(o.out) / "frames.csv").string();
      std::FILE* csv = std::fopen(csv_path.c_str(), "w");
      if (csv == nullptr) throw std::runtime_error(csv_path + ": cannot be written");
      std::fprintf(csv, "frame,psnr\n");
      for (size_t f = 0; f < per_frame.size(); ++f) std::fprintf(csv, "%zu,%.4f\n", f, per_frame[f]);
      if (std::fclose(csv) != 0) throw std::runtime_error(csv_path + ": cannot be written");
      std::printf("  %s (ground truth | client), %s (each frame's PSNR)\n", sheet_path.c_str(), csv_path.c_str());
    }
  }
}

// `vds serve-terrain`: the server live. The client plays the flight the
// stream's TFLY gives it and sends its pose up every pose period; the
// server answers the newest pose it has received as the frames fall due.
// A viewer who steers (the host board's window or controls script) sends
// steered poses, which the server draws (TFRM with the pose).
// Afterwards the stream as sent is replayed through the client library and
// every frame the board showed must equal the replay's.
void run_serve_terrain(const FlyOptions& o) {
  const enc::TerrainMap map = load_map(o);
  const enc::TerrainCoding t = enc::code_terrain(map, o.quantiser);
  const enc::CameraPath path = load_flight(o, t);
  enc::TerrainLive live(t, path, stream_options(o, path.frames.size()));
  struct Adapter : link::LiveStream {
    enc::TerrainLive& live;
    explicit Adapter(enc::TerrainLive& l) : live(l) {}
    void pose(const uint8_t* d, size_t n) override { live.pose(d, n); }
    bool produce(uint64_t ms, std::vector<uint8_t>& out) override { return live.produce(ms, out); }
  } adapter(live);
  std::vector<uint8_t> made;
  const std::string name = map.name + " (live)";
  const auto serve = [&](const link::ServeOptions& so, const std::function<void(const std::string&)>& say) {
    made.clear();
    return link::serve_live(adapter, so, &made, say);
  };
  BoardResult r;
  if (!o.board.board.empty()) {
    r = run_on_board(o.board, name, serve);
  } else {
    if (o.link.empty()) throw Failure(kExitUsage, "give --board host|qemu, or --link to a client");
    r.options.link = o.link;
    r.options.baud = o.board.baud;
    r.options.timeout_s = o.board.timeout;
    try {
      r.report = serve(r.options, [](const std::string& m) { std::fprintf(stderr, "vds serve-terrain: %s\n", m.c_str()); });
    } catch (const link::BackendError& e) {
      throw backend_failure(e);
    }
  }
  if (!o.stream_out.empty()) enc::write_file(o.stream_out, made);
  size_t texture = 0;
  uint32_t answered = 0;
  for (const enc::TerrainStreamFrame& f : live.frames()) texture += f.texture_bytes, answered += f.texture_bytes != 0;
  std::printf("%s: %zu frames made, %zu bytes; %u poses received (%u refused); %u updates, %zu bytes of texture\n",
              name.c_str(), live.frames().size(), made.size(), live.poses_received(), live.poses_refused(), answered, texture);
  if (live.steered_frames() != 0)
    std::printf("%s: %u frames drawn from the viewer's steered pose\n", name.c_str(), live.steered_frames());
  std::vector<uint32_t> want;
  try {
    want = enc::client_frame_crcs(made);
  } catch (const std::exception& e) {
    throw Failure(kExitBadInput, name + ": the stream as sent does not replay: " + e.what());
  }
  if (!o.board.board.empty()) {
    check_board_frames(o.board, name, r, want);
  } else {
    print_serve_report(name, r.options, r.report);
    check_serve_report(r.report);
  }
  if (live.poses_received() == 0) throw Failure(kExitBadInput, name + ": no pose came up the link");
  if (!o.board.controls.empty() && live.steered_frames() == 0)
    throw Failure(kExitBadInput, name + ": the controls script steered no frame (no steered pose came up the link)");
}

void map_options(CLI::App* sub, FlyOptions* o) {
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
  sub->add_option("--detail", o->detail, "Scale of every mask cutoff (default 1.25)")->check(kPositive);
  sub->add_option("--out", o->out, "Folder for frames.csv and the contact sheet");
  sub->add_flag("--frames-png", o->frames_png, "With --out: every frame the client shows and its ground truth, as PNG (frame_NNNN.png, truth_NNNN.png)");
}

// The terrain client's sizes (encode-terrain, serve-terrain); the store's
// default is the Cortex-M4 board's.
void client_options(CLI::App* sub, FlyOptions* o) {
  o->store = 16384;
  sub->add_option("--store", o->store, "Client block store, 2-byte units: a held block costs its coefficients + 6 (default 16384)")
      ->check(CLI::Range(64u, 1u << 26));
  sub->add_option("--cache-log2", o->cache_log2, "The client's transformed-block window, 2^n cells a side (default 4)")
      ->check(CLI::Range(1, 6));
  sub->add_option("--cells", o->cells, "Cells the client draws with their own texels a frame (default 64)")->check(CLI::Range(1, 4096));
  sub->add_option("--half-log2", o->half_log2, "The client's half-resolution window, 2^n cells a side, 3..7 (default 6; 0: none)")
      ->check(CLI::Range(0, 7));
  sub->add_option("--frame-budget", o->frame_budget, "The client's geometry a frame: 512 n vertices, 2..64 (default 2)")
      ->check(CLI::Range(2, 64));
}

}  // namespace

void add_encode_terrain(CLI::App& app) {
  auto o = std::make_shared<FlyOptions>();
  CLI::App* sub = app.add_subcommand("encode-terrain", "Write the terrain stream of a scripted flight and replay it through the client library (docs/terrain.md)");
  map_options(sub, o.get());
  client_options(sub, o.get());
  sub->add_option("-o,--output", o->output, "The stream to write")->required();
  sub->add_flag("--psnr", o->psnr, "Also each frame the client shows against the ground truth");
  sub->callback([o] { run_encode(*o); });
}

void add_serve_terrain(CLI::App& app) {
  auto o = std::make_shared<FlyOptions>();
  CLI::App* sub = app.add_subcommand("serve-terrain", "Serve a terrain live to a client board, answering the poses it sends up (docs/terrain.md)");
  map_options(sub, o.get());
  client_options(sub, o.get());
  sub->add_option("--board", o->board.board, "host: the host-native board on a pseudo-terminal; qemu: the Cortex-M4 board in QEMU")
      ->check(CLI::IsMember({"host", "qemu"}));
  sub->add_option("--link", o->link, "Without --board: the client's link (pty:PATH, tcp:HOST:PORT, tcp-listen:PORT, usb:VID:PID)");
  sub->add_option("--baud", o->board.baud, "Line rate (default 115200)")->check(CLI::Range(1200u, 4000000u));
  sub->add_option("--board-out", o->board.out, "With --board: the board's log and frame CRCs; on the host board also its frames");
  sub->add_option("--firmware", o->board.firmware, "With --board: the board's client firmware");
  sub->add_option("--qemu", o->board.qemu, "QEMU's Arm system emulator")->capture_default_str();
  sub->add_option("--timeout", o->board.timeout, "Give up after this many seconds (default 600)");
  sub->add_option("--stream-out", o->stream_out, "Write the stream as it was sent");
  sub->add_flag("--window", o->board.window,
                "Host board: show the frames in a live window and steer the viewer with its keys and mouse (W/A/S/D, arrows, R/F, Shift; drag)");
  sub->add_option("--controls", o->board.controls,
                  "Host board: steer the viewer from a script instead (lines 'FRAMES FORWARD RIGHT UP TURN TILT [fast]')")
      ->check(CLI::ExistingFile);
  sub->callback([o] { run_serve_terrain(*o); });
}

void add_fly(CLI::App& app) {
  auto o = std::make_shared<FlyOptions>();
  CLI::App* sub = app.add_subcommand("fly", "Replay a flight over a terrain on the server: updates, ratios, pictures (docs/terrain.md)");
  map_options(sub, o.get());
  sub->add_option("--store", o->store, "Client store, 2-byte units: a held block costs its coefficients + 6 (default 49152: 96 KiB, the tiles' cache)")->check(CLI::Range(64u, 1u << 26));
  sub->add_option("--tiles", o->tiles, "The baseline instead of vds: a tile pyramid, jpeg64, jpeg256, webp64 or webp256")
      ->check(CLI::IsMember({"jpeg64", "jpeg256", "webp64", "webp256"}));
  sub->add_option("--tile-quality", o->tile_quality, "With --tiles: the codec's quality, 1..100 (default 75)")
      ->check(CLI::Range(1, 100));
  sub->add_option("--cache", o->cache, "With --tiles: the client's tile cache, bytes of 4:2:0 texels (default 98304)")
      ->check(CLI::Range(size_t{1024}, size_t{1} << 30));
  sub->callback([o] { run(*o); });
}

}  // namespace vds::cli
