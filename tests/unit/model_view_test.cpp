// The model mode's picture: the golden mesh stream replayed through the
// client's display path (container parser, mesh decoder, model view) gives
// one frame after the base and one per level, with pinned checksums; the
// model fills a sensible part of the frame and is centred; bad
// configurations and meshes are refused with a status.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "mesh_test_meshes.h"
#include "vds/enc/frames.h"
#include "vds/enc/mesh_encoder.h"
#include "vds/container.h"
#include "vds/crc32c.h"
#include "vds/enc/stream_writer.h"
#include "vds/mesh.h"
#include "vds/model_view.h"
#include "vds/player.h"

namespace {

using vds::Status;

std::vector<uint8_t> golden_mesh_stream() {
  return vds::enc::read_file(std::string(VDS_SOURCE_DIR) + "/tests/golden/mesh-v1.vds");
}

// Pixels that differ from the background, and their bounding box.
struct Coverage {
  int pixels = 0;
  int x0 = 1 << 30, y0 = 1 << 30, x1 = -1, y1 = -1;
};

Coverage coverage(const vds::enc::Image& im) {
  Coverage c;
  const uint8_t bg[3] = {im.at(0, 0, 0), im.at(0, 0, 1), im.at(0, 0, 2)};
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x) {
      if (im.at(x, y, 0) == bg[0] && im.at(x, y, 1) == bg[1] && im.at(x, y, 2) == bg[2]) continue;
      ++c.pixels;
      c.x0 = std::min(c.x0, x);
      c.y0 = std::min(c.y0, y);
      c.x1 = std::max(c.x1, x);
      c.y1 = std::max(c.y1, y);
    }
  return c;
}

TEST(ModelView, GoldenStreamOneFramePerLevel) {
  std::vector<vds::enc::Image> frames;
  const std::vector<uint32_t> crcs = vds::enc::client_frame_crcs(golden_mesh_stream(), &frames);
  // 13 levels after the base: 14 frames.
  ASSERT_EQ(crcs.size(), 14u);
  ASSERT_EQ(frames.size(), 14u);
  for (size_t i = 0; i < frames.size(); ++i) {
    const Coverage c = coverage(frames[i]);
    // A sphere of radius ~1 at 3.2 units with a focal length of one frame
    // height covers roughly a disc of 0.3 frame heights' radius.
    EXPECT_GT(c.pixels, 240 * 180 / 12) << "frame " << i;
    EXPECT_LT(c.pixels, 240 * 180 / 2) << "frame " << i;
    EXPECT_NEAR((c.x0 + c.x1) / 2.0, 120, 12) << "frame " << i;
    EXPECT_NEAR((c.y0 + c.y1) / 2.0, 90, 12) << "frame " << i;
    if (i > 0) EXPECT_NE(crcs[i], crcs[i - 1]) << "level " << i << " drew the same picture";
  }
  // Pinned: the client's picture is integer arithmetic, the same on every
  // target (the end-to-end test compares the boards against these replays).
  EXPECT_EQ(crcs.front(), 0x154289D2u) << std::hex << crcs.front();
  EXPECT_EQ(crcs.back(), 0xDA449086u) << std::hex << crcs.back();
}

// A client with `bytes` of workspace for the model (the chunk buffer apart),
// playing the stream through the client's player as the firmware does.
struct SmallClient {
  std::vector<uint8_t> ws;
  size_t parser_bytes = 0;  // what the player's parser carves first
  vds::Arena arena;
  vds::Player player;
  vds::PlayerPlan cap;  // the plan made at MSHH
  std::vector<uint32_t> crcs, vertices;
  uint32_t base_needs = 0;  // from a model_base_too_big notice

  explicit SmallClient(size_t bytes) : ws(bytes + (1u << 16)), arena(ws.data(), ws.size()) {
    vds::Arena probe(ws.data(), ws.size());
    vds::Player p;
    if (p.init(probe, config(), {}) == Status::ok) parser_bytes = probe.used();
    arena = vds::Arena(ws.data(), parser_bytes + bytes);
  }
  static vds::PlayerConfig config() {
    vds::PlayerConfig c = vds::kClientPlayerConfig;
    c.max_chunk_bytes = 1u << 15;
    return c;
  }
  size_t model_high_water() const { return arena.high_water() - parser_bytes; }

  Status play(const std::vector<uint8_t>& s) {
    vds::PlayerCallbacks cb;
    cb.ctx = this;
    cb.frame_shown = [](void* ctx, const vds::PlayedFrame& f) {
      auto* c = static_cast<SmallClient*>(ctx);
      c->crcs.push_back(f.crc);
      c->vertices.push_back(c->player.mesh.mesh().vertex_count());
    };
    cb.notice = [](void* ctx, vds::PlayerNotice n, uint32_t a, uint32_t, uint32_t) {
      if (n == vds::PlayerNotice::model_base_too_big) static_cast<SmallClient*>(ctx)->base_needs = a;
    };
    if (player.init(arena, config(), cb) != Status::ok) return Status::invalid_argument;
    Status st = player.feed(s.data(), s.size());
    if (st == Status::more_input) st = player.finish();
    cap = player.plan();
    return st;
  }
};

TEST(ModelView, ASmallClientShowsTheLevelsThatFit) {
  const std::vector<uint8_t> s = golden_mesh_stream();
  const std::vector<uint32_t> full_crcs = vds::enc::client_frame_crcs(s);
  SmallClient full(8u << 20);
  ASSERT_EQ(full.play(s), Status::ok);
  ASSERT_EQ(full.crcs, full_crcs) << "the same frames as the host replay";
  ASSERT_TRUE(full.player.mesh.complete());
  const vds::MeshHeader h = full.player.mesh.header();
  ASSERT_EQ(full.cap.vertices, h.vertices);
  const size_t base_bytes = [&] {
    vds::ModelCapacity c;
    vds::ModelViewConfig vc;
    vc.width = 240;
    vc.height = 180;
    EXPECT_EQ(vds::plan_model_capacity(h, vc, 0, &c), Status::workspace_too_small);
    return c.bytes;
  }();
  ASSERT_GT(base_bytes, 0u);
  ASSERT_LT(base_bytes, full.cap.bytes);

  // Budgets from the base's need up to the full model's: each client shows
  // the full replay's first frames, one per level that fits, and stops only
  // where the next level's vertices exceed what it planned for.
  size_t sizes_seen = 0;
  for (size_t bytes = base_bytes; bytes < full.cap.bytes + 64; bytes += (full.cap.bytes - base_bytes) / 23 + 1) {
    SmallClient c(bytes);
    ASSERT_EQ(c.play(s), Status::ok) << bytes << " bytes";
    EXPECT_LE(c.cap.bytes, bytes);
    EXPECT_LE(c.model_high_water(), bytes);
    const uint32_t levels = c.player.mesh.levels_done();
    ASSERT_EQ(c.crcs.size(), levels + 1u) << bytes << " bytes";
    for (size_t i = 0; i < c.crcs.size(); ++i) EXPECT_EQ(c.crcs[i], full_crcs[i]) << bytes << " bytes, frame " << i;
    EXPECT_EQ(c.player.mesh.capacity_reached(), levels < h.levels);
    EXPECT_EQ(c.player.workspace_full(), levels < h.levels);
    if (levels < h.levels) EXPECT_GT(full.vertices[levels + 1], c.cap.vertices) << bytes << " bytes";
    if (c.crcs.size() != full_crcs.size()) ++sizes_seen;
  }
  EXPECT_GE(sizes_seen, 10u) << "the sweep should cover many partial clients";

  // Below the base: refused at MSHH with what the base needs.
  SmallClient none(base_bytes - 1);
  EXPECT_EQ(none.play(s), Status::workspace_too_small);
  EXPECT_EQ(none.cap.bytes, base_bytes);
  EXPECT_EQ(none.base_needs, base_bytes);
  EXPECT_TRUE(none.crcs.empty());
}

// A version-2 stream (split levels, then the single-rate tail of a mesh
// with holes): a client plans for the whole tail when it fits, dummies,
// contexts and border included, and shows it; a little less, and it shows
// every split level and stops before the tail.
TEST(ModelView, ATailStreamPlaysWholeOrStopsBeforeTheTail) {
  vds::enc::MeshEncodeOptions o;
  o.tail_fraction = 0.3;
  o.tail_min_levels = 2;
  const vds::enc::MeshEncodeResult r =
      vds::enc::encode_mesh(vds::test::with_hole(vds::test::grid_mesh(12, 10, 0.3), 0.5, 0.5, 0.25), o);
  ASSERT_TRUE(r.tail);
  ASSERT_GT(r.tail_counts.dummy_vertices, 0u);
  const std::vector<uint32_t> want = vds::enc::client_frame_crcs(r.stream);
  ASSERT_EQ(want.size(), r.levels.size());
  SmallClient full(8u << 20);
  ASSERT_EQ(full.play(r.stream), Status::ok);
  EXPECT_EQ(full.crcs, want);
  ASSERT_TRUE(full.player.mesh.complete());
  EXPECT_EQ(full.cap.vertices, r.mesh_header.vertices + r.tail_counts.dummy_vertices);
  EXPECT_EQ(full.cap.triangles, r.mesh_header.triangles + r.tail_counts.dummy_triangles);
  for (size_t less : {size_t{1}, size_t{64}, size_t{2048}}) {
    SmallClient part(full.cap.bytes - less);
    ASSERT_EQ(part.play(r.stream), Status::ok) << less;
    EXPECT_LE(part.model_high_water(), full.cap.bytes - less);
    EXPECT_TRUE(part.player.mesh.capacity_reached()) << less;
    EXPECT_EQ(part.player.mesh.levels_done(), r.levels.size() - 2) << less;
    EXPECT_EQ(part.crcs, std::vector<uint32_t>(want.begin(), want.end() - 1)) << less;
  }
}

// The golden mesh, and the same mesh turned so that its +y is the grid's
// +z (grid (x, y, z) -> (x, K - z, y), exact in integers), each in a
// MeshState of its own.
struct TurnedMeshes {
  std::vector<uint8_t> ws = std::vector<uint8_t>(4u << 20);
  vds::Arena arena{ws.data(), ws.size()};
  vds::MeshState upright, turned;
};

void build_turned(TurnedMeshes& t) {
  SmallClient c(4u << 20);
  ASSERT_EQ(c.play(golden_mesh_stream()), Status::ok);
  const vds::MeshState& m = c.player.mesh.mesh();
  const int k = (1 << m.bits()) - 1;
  for (vds::MeshState* s : {&t.upright, &t.turned}) {
    ASSERT_EQ(s->init(t.arena, m.vertex_count(), m.triangle_count()), Status::ok);
    s->clear(m.bits());
    for (uint32_t v = 0; v < m.vertex_count(); ++v) {
      const uint16_t* p = m.positions() + 3 * v;
      const int32_t q[3] = {p[0], p[1], p[2]};
      const int32_t r[3] = {p[0], k - p[2], p[1]};
      ASSERT_EQ(s->add_vertex(s == &t.upright ? q : r), Status::ok);
    }
    for (uint32_t f = 0; f < m.triangle_count(); ++f) {
      ASSERT_EQ(s->add_triangle(m.corner_vertex(3 * f), m.corner_vertex(3 * f + 1), m.corner_vertex(3 * f + 2)),
                Status::ok);
    }
    ASSERT_EQ(s->finish_base(t.arena, 64), Status::ok);
  }
}

std::vector<uint16_t> frame_pixels(vds::ModelView& view, const vds::MeshState& m, uint16_t angle) {
  std::vector<uint16_t> px;
  auto band = [](void* ctx, const vds::Band& b) {
    auto* out = static_cast<std::vector<uint16_t>*>(ctx);
    for (uint16_t y = 0; y < b.height; ++y) {
      const auto* row = reinterpret_cast<const uint16_t*>(reinterpret_cast<const uint8_t*>(b.pixels) + y * b.stride);
      out->insert(out->end(), row, row + b.width);
    }
    return true;
  };
  EXPECT_EQ(view.draw(m, angle, band, &px), Status::ok);
  return px;
}

// Fraction of pixels that differ.
double differ(const std::vector<uint16_t>& a, const std::vector<uint16_t>& b) {
  EXPECT_EQ(a.size(), b.size());
  size_t n = 0;
  for (size_t i = 0; i < a.size() && i < b.size(); ++i) n += a[i] != b[i];
  return a.empty() ? 1.0 : double(n) / double(a.size());
}

TEST(ModelView, TheStreamsUpAxisIsShownUp) {
  TurnedMeshes t;
  build_turned(t);
  vds::ModelViewConfig cfg;
  cfg.width = 240;
  cfg.height = 180;
  std::vector<uint8_t> ws(vds::ModelView::workspace_bytes(cfg, t.upright.vertex_count(), t.upright.triangle_count()));
  vds::Arena arena(ws.data(), ws.size());
  vds::ModelView view;
  ASSERT_EQ(view.init(cfg, arena, t.upright.vertex_count(), t.upright.triangle_count()), Status::ok);
  for (uint16_t angle : {0, 5000, 40000}) {
    view.set_up(vds::MeshUp::y_plus);
    const std::vector<uint16_t> upright = frame_pixels(view, t.upright, angle);
    EXPECT_GT(differ(frame_pixels(view, t.turned, angle), upright), 0.05) << "the turned mesh shown +y up";
    // Shown +z up it is the upright picture, up to the rounding of
    // arithmetic shifts of negated coordinates (a pixel here and there).
    view.set_up(vds::MeshUp::z_plus);
    EXPECT_LT(differ(frame_pixels(view, t.turned, angle), upright), 0.002) << "angle " << angle;
    // Every other axis gives a picture of its own.
    for (vds::MeshUp u : {vds::MeshUp::x_plus, vds::MeshUp::y_minus, vds::MeshUp::z_minus, vds::MeshUp::x_minus}) {
      view.set_up(u);
      EXPECT_GT(differ(frame_pixels(view, t.turned, angle), upright), 0.05) << static_cast<int>(u);
    }
  }
}

TEST(ModelView, RefusesWhatItCannotDraw) {
  vds::ModelViewConfig cfg;
  cfg.width = 64;
  cfg.height = 48;
  EXPECT_EQ(vds::ModelView::workspace_bytes(cfg, 0, 10), 0u);
  EXPECT_EQ(vds::ModelView::workspace_bytes(cfg, 65536, 10), 0u);
  EXPECT_GT(vds::ModelView::workspace_bytes(cfg, 65535, 10), 0u);
  vds::ModelViewConfig bad = cfg;
  bad.width = 0;
  EXPECT_EQ(vds::ModelView::workspace_bytes(bad, 100, 100), 0u);

  std::vector<uint8_t> ws(vds::ModelView::workspace_bytes(cfg, 162, 320));
  ASSERT_GT(ws.size(), 0u);
  vds::ModelView view;
  {
    vds::Arena small(ws.data(), ws.size() / 2);
    EXPECT_EQ(view.init(cfg, small, 162, 320), Status::workspace_too_small);
  }
  vds::Arena bad_arena(ws.data(), ws.size());
  EXPECT_EQ(view.init(bad, bad_arena, 162, 320), Status::invalid_argument);

  // A decoded mesh larger than the view was sized for.
  std::vector<uint8_t> mesh_ws(vds::MeshDecoder::workspace_bytes(162, 320, 320, vds::MeshCoder::arith) + 4096);
  vds::Arena mesh_arena(mesh_ws.data(), mesh_ws.size());
  vds::MeshState mesh;
  ASSERT_EQ(mesh.init(mesh_arena, 162, 320), Status::ok);
  mesh.clear(10);
  const int32_t p[3][3] = {{0, 0, 0}, {1023, 0, 0}, {0, 1023, 0}};
  for (const auto& q : p) ASSERT_EQ(mesh.add_vertex(q), Status::ok);
  ASSERT_EQ(mesh.add_triangle(0, 1, 2), Status::ok);
  ASSERT_EQ(mesh.finish_base(mesh_arena, 12), Status::ok);
  auto sink = [](void*, const vds::Band&) { return true; };
  EXPECT_EQ(view.draw(mesh, 0, sink, nullptr), Status::invalid_argument) << "not initialised";
  vds::Arena one(ws.data(), ws.size());
  vds::ModelView tiny;
  ASSERT_EQ(tiny.init(cfg, one, 2, 1), Status::ok);
  EXPECT_EQ(tiny.draw(mesh, 0, sink, nullptr), Status::invalid_argument) << "3 vertices in a view for 2";

  // A mesh whose corner table is 32-bit (sized for more than 65,535
  // vertices) has no 16-bit triangles to draw from.
  {
    std::vector<uint8_t> wide_ws(vds::MeshState::workspace_bytes(70000, 10));
    vds::Arena wide_arena(wide_ws.data(), wide_ws.size());
    vds::MeshState wide;
    ASSERT_EQ(wide.init(wide_arena, 70000, 10), Status::ok);
    wide.clear(10);
    for (const auto& q : p) ASSERT_EQ(wide.add_vertex(q), Status::ok);
    ASSERT_EQ(wide.add_triangle(0, 1, 2), Status::ok);
    std::vector<uint8_t> scratch(64);
    vds::Arena scratch_arena(scratch.data(), scratch.size());
    ASSERT_EQ(wide.finish_base(scratch_arena, 12), Status::ok);
    EXPECT_EQ(wide.triangles16(), nullptr);
    vds::Arena fits(ws.data(), ws.size());
    ASSERT_EQ(view.init(cfg, fits, 162, 320), Status::ok);
    EXPECT_EQ(view.draw(wide, 0, sink, nullptr), Status::invalid_argument);
    ASSERT_NE(mesh.triangles16(), nullptr);
  }

  // The single triangle draws, and a sink that stops the frame is obeyed.
  vds::Arena fits(ws.data(), ws.size());
  ASSERT_EQ(view.init(cfg, fits, 162, 320), Status::ok);
  int bands = 0;
  auto count = [](void* ctx, const vds::Band&) {
    ++*static_cast<int*>(ctx);
    return true;
  };
  EXPECT_EQ(view.draw(mesh, 0, count, &bands), Status::ok);
  EXPECT_EQ(bands, 3);  // 48 rows in bands of 16
  auto stop = [](void*, const vds::Band&) { return false; };
  EXPECT_EQ(view.draw(mesh, 0, stop, nullptr), Status::aborted);
}

// The golden stream's full mesh copied into a MeshState of its own, on a
// grid `extra` bits finer (positions times 2^extra); with `hole`, without
// vertex 0 and its faces, which opens a hole whose rim vertices' fans end
// at the boundary.
void build_copy(vds::MeshState& s, vds::Arena& arena, int extra, bool hole) {
  SmallClient c(4u << 20);
  ASSERT_EQ(c.play(golden_mesh_stream()), Status::ok);
  const vds::MeshState& m = c.player.mesh.mesh();
  ASSERT_LE(m.bits() + extra, 16);
  ASSERT_EQ(s.init(arena, m.vertex_count(), m.triangle_count()), Status::ok);
  s.clear(m.bits() + extra);
  const uint32_t skip = hole ? 1 : 0;
  for (uint32_t v = skip; v < m.vertex_count(); ++v) {
    const uint16_t* p = m.positions() + 3 * v;
    const int32_t q[3] = {p[0] << extra, p[1] << extra, p[2] << extra};
    ASSERT_EQ(s.add_vertex(q), Status::ok);
  }
  uint32_t dropped = 0;
  for (uint32_t f = 0; f < m.triangle_count(); ++f) {
    const uint32_t a = m.corner_vertex(3 * f), b = m.corner_vertex(3 * f + 1), d = m.corner_vertex(3 * f + 2);
    if (hole && (a == 0 || b == 0 || d == 0)) {
      ++dropped;
      continue;
    }
    ASSERT_EQ(s.add_triangle(a - skip, b - skip, d - skip), Status::ok);
  }
  if (hole) ASSERT_GE(dropped, 3u);
  ASSERT_EQ(s.finish_base(arena, 64), Status::ok);
}

// Vertex normals are summed over each vertex's fan in the corner table.
// The picture is the same at every grid size: positions scaled by 2^s
// give the same world positions and, after the shift by 2 (bits - 10), the
// same normals, whether the cross products are taken in 32 bits (up to 15
// bits) or 64 (16 bits). With a hole (fans that end at a boundary) the
// frame is the one pinned below, drawn when
// each face's normal was added to its three vertices' sums.
TEST(ModelView, ShadingFromFansAtEveryGridSize) {
  vds::ModelViewConfig cfg;
  cfg.width = 240;
  cfg.height = 180;
  for (bool hole : {false, true}) {
    std::vector<uint16_t> first;
    for (int extra : {0, 2, 5, 6}) {
      std::vector<uint8_t> mesh_ws(4u << 20);
      vds::Arena mesh_arena(mesh_ws.data(), mesh_ws.size());
      vds::MeshState m;
      build_copy(m, mesh_arena, extra, hole);
      if (HasFatalFailure()) return;
      std::vector<uint8_t> ws(vds::ModelView::workspace_bytes(cfg, m.vertex_count(), m.triangle_count()));
      vds::Arena arena(ws.data(), ws.size());
      vds::ModelView view;
      ASSERT_EQ(view.init(cfg, arena, m.vertex_count(), m.triangle_count()), Status::ok);
      const std::vector<uint16_t> px = frame_pixels(view, m, 9000);
      if (first.empty()) {
        first = px;
        if (hole) {
          const uint32_t crc = vds::crc32c(reinterpret_cast<const uint8_t*>(px.data()), px.size() * 2);
          EXPECT_EQ(crc, 0x5DAB34E2u) << std::hex << crc;
        }
      } else {
        EXPECT_EQ(px, first) << "grid " << m.bits() << " bits" << (hole ? ", with a hole" : "");
      }
    }
  }
}

}  // namespace
