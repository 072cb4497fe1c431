// libFuzzer: the terrain mode's parsers. The first byte picks one:
//   0  a Trigger Rally .level file (vds/enc/terrain_map.h: parse_level)
//   1  a heightmap and colour image pair (read_terrain; the second byte
//      splits the rest between them)
//   2  the client's elevation decoder (vds/terrain.h: decode_elevation),
//      both passes, on a grid whose size the next two bytes give
//   3  the client's texture-update reader on a grid the next two bytes give,
//      every block it returns applied to a store of masks, over several
//      updates (the rest split at 0xFF bytes)
// Invariants: no crash, sanitizer report or hang; host refusals are
// std::runtime_error naming the input; the client decoders return a status,
// every height decoded is in range, every mask they leave is valid and a
// grow never takes a block below what it held.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include <cmath>
#include <fstream>

#include "seed_corpus.h"
#include "vds/enc/scene_render.h"
#include "vds/enc/terrain_map.h"
#include "vds/enc/terrain_server.h"
#include "vds/terrain.h"

namespace {

void host_refusal(const std::runtime_error& e, const char* name) {
  if (std::strncmp(e.what(), name, std::strlen(name)) != 0) abort();
}

struct Store {
  std::vector<vds::terrain::Mask> masks;
  static vds::terrain::Mask held(void* ctx, uint32_t id) { return static_cast<Store*>(ctx)->masks[id]; }
  // Any value: the reader must stay in range whatever the client shows.
  static int shown_dc(void*, uint32_t id) { return static_cast<int>(id * 37 % 301) - 150; }
};

void write_seed(const std::filesystem::path& dir, const char* name, uint8_t kind, const std::vector<uint8_t>& body) {
  std::ofstream out(dir / name, std::ios::binary);
  out.put(static_cast<char>(kind));
  out.write(reinterpret_cast<const char*>(body.data()), static_cast<std::streamsize>(body.size()));
}

// Valid inputs of each kind, made by the host side.
void seed(const std::filesystem::path& dir) {
  const std::string level =
      "<level><terrain heightmap=\"h.png\" colormap=\"c.jpg\" horizontalscale=\"2\" verticalscale=\"0.5\"/></level>";
  write_seed(dir, "level", 0, std::vector<uint8_t>(level.begin(), level.end()));
  // A 12 x 10 map: the elevation and a first update.
  vds::enc::TerrainMap m;
  m.width = 13, m.height = 11;
  m.heights.resize(13 * 11);
  for (size_t i = 0; i < m.heights.size(); ++i) m.heights[i] = static_cast<uint16_t>(300 + 40 * std::sin(i * 0.3));
  m.colour = vds::io::Image(96, 80, 3);
  for (size_t i = 0; i < m.colour.pixels.size(); ++i) m.colour.pixels[i] = static_cast<uint8_t>(i * 13 + (i >> 7));
  const vds::enc::TerrainCoding t = vds::enc::code_terrain(m, 4);
  std::vector<uint8_t> e = {static_cast<uint8_t>(t.points_x() - 1), static_cast<uint8_t>(t.points_y() - 1)};
  const std::vector<uint8_t> ec =
      vds::enc::encode_elevation(t.heights.data(), t.points_x(), t.points_y(), vds::terrain::ElevationPass::coarse);
  e.insert(e.end(), ec.begin(), ec.end());
  write_seed(dir, "elevation", 2, e);
  vds::enc::TerrainServer server(t, 4000);
  vds::enc::CameraPose pose;
  pose.x = 20, pose.y = 20, pose.z = 60, pose.yaw_deg = 45, pose.pitch_deg = -30;
  std::vector<uint8_t> u = {static_cast<uint8_t>(t.grid.cells_x - 1), static_cast<uint8_t>(t.grid.cells_y - 1)};
  const std::vector<uint8_t> uc = server.update(vds::enc::scene_camera(pose, 70, 240, 180), 0, 2000, {});
  u.insert(u.end(), uc.begin(), uc.end());
  write_seed(dir, "update", 3, u);
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  vds::test::seed_corpus_if_empty(*argc, *argv, seed);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 3) return 0;
  const uint8_t kind = data[0] & 3;
  const uint8_t* rest = data + 1;
  const size_t n = size - 1;
  if (kind == 0) {
    try {
      vds::enc::parse_level(rest, n, "input");
    } catch (const std::runtime_error& e) {
      host_refusal(e, "input");
    }
  } else if (kind == 1) {
    const size_t split = n > 1 ? (rest[0] * (n - 1)) / 255 : 0;
    try {
      const vds::enc::TerrainMap m =
          vds::enc::read_terrain(rest + 1, split, "heights", rest + 1 + split, n - 1 - split, "colour", 1.0, 1.0);
      if (m.heights.size() != static_cast<size_t>(m.width) * m.height) abort();
    } catch (const std::runtime_error& e) {
      if (std::strncmp(e.what(), "heights", 7) != 0 && std::strncmp(e.what(), "colour", 6) != 0) abort();
    }
  } else if (kind == 2) {
    const int w = 1 + rest[0] % 64, h = 1 + rest[1] % 64;
    std::vector<uint16_t> out(static_cast<size_t>(w) * h, 0);
    // Both passes over the same bytes: the fine pass after whatever the
    // coarse one left.
    vds::terrain::decode_elevation(rest + 2, n - 2, w, h, vds::terrain::ElevationPass::coarse, out.data());
    vds::terrain::decode_elevation(rest + 2, n - 2, w, h, vds::terrain::ElevationPass::fine, out.data());
    vds::terrain::fill_from_coarse(w, h, out.data());
  } else {
    vds::terrain::BlockGrid g;
    g.cells_x = static_cast<uint16_t>(1 + rest[0] % 40);
    g.cells_y = static_cast<uint16_t>(1 + rest[1] % 40);
    Store store;
    store.masks.assign(g.blocks(), 0);
    size_t at = 2;
    while (at < n) {
      size_t end = at;
      while (end < n && rest[end] != 0xFF) ++end;
      vds::terrain::TextureUpdateReader r;
      if (r.init(rest + at, end - at, g, &Store::held, &Store::shown_dc, &store) == vds::Status::ok) {
        vds::terrain::BlockUpdate u;
        while (r.next(&u) == vds::Status::ok) {
          if (!vds::terrain::mask_valid(u.mask) || u.id >= g.blocks()) abort();
          store.masks[u.id] = u.mask;
        }
      }
      at = end + 1;
    }
  }
  return 0;
}
