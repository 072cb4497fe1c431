// libFuzzer: the client's player (vds/player.h) on hostile streams, fed in
// pieces of sizes the input chooses. The first byte picks the stream:
// chunks of the input's bytes in a valid images-, model- or terrain-mode
// container (every CRC right, so the modes themselves see the bytes), raw
// bytes, or a valid image, JPEG-image, model or terrain stream whose chunk
// payloads the input's bytes flip (CRCs recomputed, so the decoders meet
// the damage);
// and the band format (RGB565 or RGB888) and whether a prediction is given.
// Invariants: no crash or sanitizer report; every band lies inside its
// frame and is at most config.band_rows high; bands come only between a
// frame's begin and end; the player ends with ok, more_input or an error,
// never anything else, and never reads past the workspace.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>
#include <array>

#include "jpeg_sample_422.h"
#include "vds/bytes.h"
#include "vds/container.h"
#include "vds/enc/frames.h"
#include "vds/enc/mesh_encoder.h"
#include "vds/enc/model_stream.h"
#include "vds/mesh_colors.h"
#include "vds/enc/stream_writer.h"
#include "vds/enc/terrain_stream.h"
#include "vds/image.h"
#include "vds/mesh.h"
#include "vds/player.h"

namespace {

struct Watch {
  uint16_t w = 0, h = 0;
  bool open = false;
};

std::vector<uint8_t> container(vds::StreamMode mode, const uint8_t* data, size_t size) {
  vds::StreamHeader h = vds::enc::default_header(mode, 64, 48);
  h.max_chunk_payload = 4096;
  h.workspace_bytes = 96 * 1024;
  if (mode == vds::StreamMode::model) {
    h.max_vertices = 2048;
    h.max_triangles = 4096;
  }
  vds::enc::StreamWriter w(h);
  const uint32_t images[] = {vds::chunk::kImageHeader, vds::chunk::kImageData, vds::chunk::kJpeg};
  const uint32_t meshes[] = {vds::chunk::kMeshHeader, vds::chunk::kMeshBase, vds::chunk::kMeshLevel,
                             vds::chunk::kMeshTail, vds::mc::kChunkHeader, vds::mc::kChunkLevel,
                             vds::mc::kChunkVertices, vds::kModelOrbitChunk};
  size_t at = 0;
  while (at + 2 <= size) {
    const uint8_t pick = data[at];
    const size_t len = data[at + 1] * 8u % 600;
    at += 2;
    const size_t n = len < size - at ? len : size - at;
    const uint32_t type = mode == vds::StreamMode::images ? images[pick % 3] : meshes[pick % 8];
    w.add_chunk(type, std::vector<uint8_t>(data + at, data + at + n));
    at += n;
  }
  return w.finish();
}

// The terrain chunks of a valid stream's header, in the order and with the
// payloads the input gives.
std::vector<uint8_t> container_terrain(const uint8_t* data, size_t size);

// A valid stream's chunks (after HEAD), rewrapped with the input's bytes
// XORed over their payloads.
std::vector<uint8_t> flipped(const std::vector<uint8_t>& valid, const uint8_t* data, size_t size) {
  vds::StreamHeader h{};
  uint32_t head_len = 0;
  std::memcpy(&head_len, valid.data() + vds::kPreambleBytes + 4, 4);
  const uint8_t* head = valid.data() + vds::kPreambleBytes + vds::kChunkHeadBytes;
  if (vds::header_from_bytes(head, head_len, valid[4], valid[5], &h) != vds::Status::ok) abort();
  vds::enc::StreamWriter w(h);
  size_t at = vds::kPreambleBytes + vds::kChunkHeadBytes + head_len + vds::kChunkTailBytes;
  size_t k = 0;
  while (at + vds::kChunkHeadBytes <= valid.size()) {
    uint32_t type = 0, len = 0;
    std::memcpy(&type, valid.data() + at, 4);
    std::memcpy(&len, valid.data() + at + 4, 4);
    std::vector<uint8_t> p(valid.begin() + static_cast<long>(at + 8), valid.begin() + static_cast<long>(at + 8 + len));
    for (uint8_t& b : p)
      if (size != 0) b ^= data[k++ % size];
    if (type != vds::chunk::kEnd) w.add_chunk(type, p);
    at += vds::kChunkHeadBytes + len + vds::kChunkTailBytes;
  }
  return w.finish();
}

const std::vector<uint8_t>& valid_images() {
  static const std::vector<uint8_t> s = [] {
    std::vector<vds::enc::Image> frames;
    for (int f = 0; f < 2; ++f) {
      vds::enc::Image im(48, 32, 3);
      for (size_t i = 0; i < im.pixels.size(); ++i) im.pixels[i] = static_cast<uint8_t>(i * 7 + f * 50);
      frames.push_back(im);
    }
    vds::enc::FrameSequenceOptions o;
    o.width = 48;
    o.height = 32;
    return vds::enc::encode_frames(frames, o).stream;
  }();
  return s;
}

// Two 24x18 JPEG images in 100-byte JPEG chunks.
const std::vector<uint8_t>& valid_jpeg_images() {
  static const std::vector<uint8_t> s = [] {
    vds::StreamHeader h = vds::enc::default_header(vds::StreamMode::images, 24, 18);
    h.max_chunk_payload = 100;
    h.workspace_bytes = static_cast<uint32_t>(vds::Player::jpeg_workspace_bytes(24, vds::kClientPlayerConfig));
    vds::enc::StreamWriter w(h);
    const std::vector<uint8_t> file(vds::test::kJpeg422, vds::test::kJpeg422 + sizeof vds::test::kJpeg422);
    for (int image = 0; image < 2; ++image)
      for (size_t at = 0; at < file.size(); at += 100)
        w.add_chunk(vds::chunk::kJpeg, std::vector<uint8_t>(file.begin() + static_cast<long>(at),
                                                          file.begin() + static_cast<long>(std::min(file.size(), at + 100))));
    return w.finish();
  }();
  return s;
}

// A textured 8 x 8-point grid (a 32 x 32 random texture): its mesh, then
// its mesh colors (vds encode-model's stream).
const std::vector<uint8_t>& valid_model() {
  static const std::vector<uint8_t> s = [] {
    vds::enc::TexturedModel m;
    for (int y = 0; y < 8; ++y)
      for (int x = 0; x < 8; ++x) m.positions.push_back({double(x), double(y), double((x * y) % 3)});
    for (uint32_t y = 0; y + 1 < 8; ++y)
      for (uint32_t x = 0; x + 1 < 8; ++x) {
        const uint32_t a = y * 8 + x, b = a + 1, c = a + 8, d = c + 1;
        for (const std::array<uint32_t, 3>& t : {std::array<uint32_t, 3>{a, b, d}, std::array<uint32_t, 3>{a, d, c}}) {
          m.triangles.push_back(t);
          std::array<std::array<double, 2>, 3> uv{};
          for (int k = 0; k < 3; ++k) uv[k] = {(t[k] % 8) / 7.0, (t[k] / 8) / 7.0};
          m.uv.push_back(uv);
          m.colour.push_back({{{1, 1, 1}, {1, 1, 1}, {1, 1, 1}}});
          m.material.push_back(0);
        }
      }
    vds::enc::Image tex(32, 32, 3);
    uint32_t x = 7;
    for (auto& p : tex.pixels) p = static_cast<uint8_t>((x = x * 1103515245u + 12345u) >> 24);
    m.textures = {tex};
    m.texture_files = {"noise"};
    m.materials = {vds::enc::TexturedMaterial{0, {1, 1, 1}}};
    vds::enc::ModelStreamOptions o;
    o.colors.max_res_log2 = 4;
    o.mesh.max_chunk_payload = 512;
    o.orbit_frames = 3;
    return vds::enc::encode_model_stream(m, o).stream;
  }();
  return s;
}

// A terrain flight of 8 frames over a 13 x 11-point heightmap with a
// 96 x 80 colour map (12 x 10 cells), drawn 64 x 48, steered from frame 3.
const std::vector<uint8_t>& valid_terrain() {
  static const std::vector<uint8_t> s = [] {
    vds::enc::TerrainMap m;
    m.name = "fuzz";
    m.width = 13;
    m.height = 11;
    m.horizontal_scale = 4;
    m.metres_per_unit = 0.1;
    for (int y = 0; y < m.height; ++y)
      for (int x = 0; x < m.width; ++x) m.heights.push_back(static_cast<uint16_t>(100 + 37 * ((x * 7 + y * 3) % 11)));
    m.colour = vds::io::Image(96, 80, 3);
    for (size_t i = 0; i < m.colour.pixels.size(); ++i) m.colour.pixels[i] = static_cast<uint8_t>(i * 13 + (i >> 7));
    const vds::enc::TerrainCoding t = vds::enc::code_terrain(m, 6);
    vds::enc::CameraPath path;
    path.fps = 20;
    path.hfov_deg = 70;
    for (int f = 0; f < 8; ++f) {
      vds::enc::CameraPose p;
      p.x = 5 + 3 * f;
      p.y = 10;
      p.z = 30;
      p.yaw_deg = 30 + 10 * f;
      p.pitch_deg = -30;
      path.frames.push_back(p);
    }
    vds::enc::TerrainStreamOptions o;
    o.width = 64;
    o.height = 48;
    o.store_units = 2000;
    o.max_cells = 16;
    o.cache_log2 = 2;
    o.link.latency_frames = 0;
    o.link.rate_bytes_per_s = 0;
    // From frame 3 on, the viewer's steered pose (TFRM with a pose).
    vds::enc::TerrainLive live(t, path, o);
    for (uint32_t f = 0; f < 8; ++f) {
      if (f == 3) {
        uint8_t msg[vds::terrain::kPoseMessageBytes];
        vds::store_le32(msg, 2 | vds::terrain::kPoseSteered);
        vds::WalkPose p = live.sender().pose(2);
        p.yaw = static_cast<uint16_t>(p.yaw + 3000);
        vds::terrain::pose_to_bytes(p, msg + 4);
        if (!live.pose(msg, sizeof msg)) abort();
      }
      live.next_frame();
    }
    if (live.steered_frames() != 5) abort();
    return live.bytes();
  }();
  return s;
}

}  // namespace

namespace {
std::vector<uint8_t> container_terrain(const uint8_t* data, size_t size) {
  const std::vector<uint8_t>& valid = valid_terrain();
  vds::StreamHeader h{};
  uint32_t head_len = 0;
  std::memcpy(&head_len, valid.data() + vds::kPreambleBytes + 4, 4);
  if (vds::header_from_bytes(valid.data() + vds::kPreambleBytes + vds::kChunkHeadBytes, head_len, valid[4], valid[5], &h) !=
      vds::Status::ok)
    abort();
  vds::enc::StreamWriter w(h);
  const uint32_t types[] = {vds::chunk::kTerrainParams, vds::chunk::kTerrainFlight, vds::chunk::kTerrainElevation,
                            vds::chunk::kTerrainTexture, vds::chunk::kTerrainFrame};
  size_t at = 0;
  while (at + 2 <= size) {
    const uint8_t pick = data[at];
    const size_t len = data[at + 1] % 64;
    at += 2;
    const size_t n = len < size - at ? len : size - at;
    w.add_chunk(types[pick % 5], std::vector<uint8_t>(data + at, data + at + n));
    at += n;
  }
  return w.finish();
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 2) return 0;
  const uint8_t kind = data[0] % 8;
  const bool rgb888 = (data[0] / 8) & 1;
  const bool predict = (data[0] / 16) & 1;
  const uint8_t piece = static_cast<uint8_t>(data[1] | 1);
  data += 2;
  size -= 2;
  const std::vector<uint8_t> stream =
      kind == 0 ? container(vds::StreamMode::images, data, size)
      : kind == 1 ? container(vds::StreamMode::model, data, size)
      : kind == 2 ? std::vector<uint8_t>(data, data + size)
      : kind == 3 ? flipped(valid_images(), data, size)
      : kind == 4 ? flipped(valid_jpeg_images(), data, size)
      : kind == 5 ? flipped(valid_model(), data, size)
      : kind == 6 ? flipped(valid_terrain(), data, size)
                  : container_terrain(data, size);
  static std::vector<uint8_t> ws(256 * 1024);
  vds::Arena arena(ws.data(), ws.size());
  Watch watch;
  vds::PlayerCallbacks cb;
  cb.ctx = &watch;
  cb.begin_frame = [](void* ctx, uint16_t w, uint16_t h) {
    auto& v = *static_cast<Watch*>(ctx);
    if (v.open) abort();
    v = Watch{w, h, true};
    return true;
  };
  cb.band = [](void* ctx, const vds::PixelRect& r) {
    const auto& v = *static_cast<Watch*>(ctx);
    if (!v.open || r.x != 0 || r.w != v.w || r.h == 0 || r.y + r.h > v.h ||
        r.h > vds::kClientPlayerConfig.band_rows)
      abort();
    return true;
  };
  cb.end_frame = [](void* ctx, uint32_t) {
    auto& v = *static_cast<Watch*>(ctx);
    if (!v.open) abort();
    v.open = false;
    return true;
  };
  // The viewer's controls, always moving it: a terrain stream's client
  // steers and clamps its own pose after every frame, whatever it drew.
  cb.steer = [](void*, vds::terrain::SteerInput* in) {
    in->forward = 1;
    in->up = -1;
    in->turn = 900;
    in->fast = true;
    return true;
  };
  if (predict) {
    // Mid-grey, bounds checked against the frame.
    cb.predict = [](void* ctx, uint16_t x, uint16_t y, uint16_t w, uint16_t h, uint8_t* yo, ptrdiff_t ys, uint8_t* cb_out,
                    uint8_t* cr_out, ptrdiff_t cs) {
      const auto& v = *static_cast<Watch*>(ctx);
      if (!v.open || w == 0 || h == 0 || x + w > v.w || y + h > v.h) abort();
      for (int r = 0; r < h; ++r) std::memset(yo + r * ys, 128, w);
      if (cb_out != nullptr)
        for (int r = 0; r < (h + 1) / 2; ++r) {
          std::memset(cb_out + r * cs, 128, (w + 1) / 2);
          std::memset(cr_out + r * cs, 128, (w + 1) / 2);
        }
      return true;
    };
  }
  vds::PlayerConfig config = vds::kClientPlayerConfig;
  if (rgb888) config.format = vds::PixelFormat::rgb888;
  vds::Player player;
  if (player.init(arena, config, cb) != vds::Status::ok) abort();
  vds::Status s = vds::Status::more_input;
  for (size_t at = 0; at < stream.size() && s == vds::Status::more_input; at += piece) {
    const size_t n = piece < stream.size() - at ? piece : stream.size() - at;
    s = player.feed(stream.data() + at, n);
    player.view_input();  // a model the viewer turns is drawn between the stream's frames
  }
  if (s == vds::Status::more_input) s = player.finish();
  if (s != vds::Status::ok && !vds::is_error(s)) abort();
  player.view_input();  // and after them
  if (arena.high_water() > ws.size()) abort();
  return 0;
}
