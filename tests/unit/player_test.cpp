// vds::Player (vds/player.h), the client's one path from stream bytes to
// display bands: the same frames whatever the piece size; bands inside the
// frame and no taller than configured; a callback's false aborts; a mode
// the client does not play is refused at the header; a model larger than
// the workspace plays the levels that fit, says so, and ends early; the
// viewer turns a model between the stream's frames.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "jpeg_sample_422.h"
#include "mesh_test_meshes.h"
#include "vds/crc32c.h"
#include "vds/container.h"
#include "vds/enc/frames.h"
#include "vds/enc/image_codec.h"
#include "vds/enc/mesh_encoder.h"
#include "vds/enc/model_stream.h"
#include "vds/enc/stream_writer.h"
#include "vds/player.h"
#include "xorshift.h"

namespace {

using vds::Status;

std::vector<uint8_t> image_stream() {
  std::vector<vds::enc::Image> frames;
  for (int f = 0; f < 3; ++f) {
    vds::enc::Image im(64, 48, 3);
    for (int y = 0; y < im.height; ++y)
      for (int x = 0; x < im.width; ++x)
        for (int c = 0; c < 3; ++c) im.at(x, y, c) = static_cast<uint8_t>((x * (c + 1) * 5 + y * 3 + f * 40) & 0xFF);
    frames.push_back(im);
  }
  vds::enc::FrameSequenceOptions o;
  o.width = 64;
  o.height = 48;
  return vds::enc::encode_frames(frames, o).stream;
}

// What a caller sees of a play.
struct Seen {
  std::vector<uint32_t> crcs;
  uint32_t begun = 0, ended = 0, bands = 0;
  bool band_outside = false, band_too_tall = false, band_in_no_frame = false;
  uint16_t width = 0, height = 0;
  uint16_t band_rows = 16;
  int abort_at_band = -1;
  std::vector<std::pair<vds::PlayerNotice, uint32_t>> notices;
};

vds::PlayerCallbacks callbacks(Seen& s) {
  vds::PlayerCallbacks cb;
  cb.ctx = &s;
  cb.begin_frame = [](void* ctx, uint16_t w, uint16_t h) {
    auto& v = *static_cast<Seen*>(ctx);
    ++v.begun;
    v.width = w;
    v.height = h;
    return true;
  };
  cb.band = [](void* ctx, const vds::PixelRect& r) {
    auto& v = *static_cast<Seen*>(ctx);
    if (v.begun == v.ended) v.band_in_no_frame = true;
    if (r.x != 0 || r.w != v.width || r.y + r.h > v.height) v.band_outside = true;
    if (r.h > v.band_rows) v.band_too_tall = true;
    return static_cast<int>(v.bands++) != v.abort_at_band;
  };
  cb.end_frame = [](void* ctx, uint32_t) {
    ++static_cast<Seen*>(ctx)->ended;
    return true;
  };
  cb.frame_shown = [](void* ctx, const vds::PlayedFrame& f) { static_cast<Seen*>(ctx)->crcs.push_back(f.crc); };
  cb.notice = [](void* ctx, vds::PlayerNotice n, uint32_t a, uint32_t, uint32_t) {
    static_cast<Seen*>(ctx)->notices.emplace_back(n, a);
  };
  return cb;
}

// Plays `s` fed in pieces of `piece` bytes (0: random 1..300) through an
// arena of `bytes`.
Status play(const std::vector<uint8_t>& s, Seen& seen, size_t piece, size_t bytes = 1u << 20,
            vds::Player* out = nullptr, const vds::PlayerConfig& config = vds::kClientPlayerConfig,
            const vds::PlayerCallbacks* cbs = nullptr) {
  std::vector<uint8_t> ws(bytes);
  vds::Arena arena(ws.data(), ws.size());
  static vds::Player player;
  vds::Player& p = out != nullptr ? *out : player;
  if (p.init(arena, config, cbs != nullptr ? *cbs : callbacks(seen)) != Status::ok) return Status::invalid_argument;
  vds::test::Xorshift32 rng;
  Status st = Status::more_input;
  for (size_t at = 0; at < s.size() && st == Status::more_input;) {
    const size_t n = std::min(s.size() - at, piece != 0 ? piece : 1 + rng.next() % 300);
    st = p.feed(s.data() + at, n);
    at += n;
  }
  if (st == Status::more_input) st = p.finish();
  return st;
}

TEST(Player, SameFramesWhateverThePieceSize) {
  const std::vector<uint8_t> s = image_stream();
  const std::vector<uint32_t> want = vds::enc::client_frame_crcs(s);
  ASSERT_EQ(want.size(), 3u);
  for (size_t piece : {size_t{0}, size_t{1}, size_t{7}, size_t{256}, s.size()}) {
    Seen seen;
    ASSERT_EQ(play(s, seen, piece), Status::ok) << piece;
    EXPECT_EQ(seen.crcs, want) << piece;
    EXPECT_EQ(seen.begun, 3u);
    EXPECT_EQ(seen.ended, 3u);
    EXPECT_EQ(seen.bands, 3u * 3u) << "48 rows of 4:2:0: three bands of 16 per frame";
    EXPECT_FALSE(seen.band_outside);
    EXPECT_FALSE(seen.band_too_tall);
    EXPECT_FALSE(seen.band_in_no_frame);
  }
}

TEST(Player, ACallbackReturningFalseAborts) {
  const std::vector<uint8_t> s = image_stream();
  for (int at : {0, 4, 8}) {
    Seen seen;
    seen.abort_at_band = at;
    EXPECT_EQ(play(s, seen, 100), Status::aborted) << at;
    EXPECT_EQ(seen.bands, static_cast<uint32_t>(at + 1)) << "nothing drawn after the refusal";
  }
}

TEST(Player, EveryPrefixFailsCleanlyOnlyTheWholeSucceeds) {
  const std::vector<uint8_t> s = image_stream();
  for (size_t n = 0; n < s.size(); n += 37) {
    Seen seen;
    const std::vector<uint8_t> cut(s.begin(), s.begin() + static_cast<std::ptrdiff_t>(n));
    EXPECT_EQ(play(cut, seen, 64), Status::truncated) << n;
  }
}

TEST(Player, AStreamItsModeCannotPlayIsRefusedAtTheHeader) {
  // Walkthrough and terrain streams draw with a camera over a known number
  // of frames: a header without them is refused before anything else.
  for (vds::StreamMode mode : {vds::StreamMode::terrain, vds::StreamMode::walkthrough}) {
    vds::StreamHeader h = vds::enc::default_header(mode, 64, 48);
    vds::enc::StreamWriter w(h);
    const std::vector<uint8_t> s = w.finish();
    Seen seen;
    vds::Player p;
    EXPECT_EQ(play(s, seen, 16, 1u << 20, &p), Status::malformed);
    EXPECT_NE(std::string(p.error_detail()).find("camera"), std::string::npos);
    EXPECT_EQ(seen.begun, 0u);
  }
}

// The image stream's chunks under a HEAD that declares another frame size.
std::vector<uint8_t> resized_head(const std::vector<uint8_t>& s, uint16_t w, uint16_t h) {
  uint32_t head_len = 0;
  std::memcpy(&head_len, s.data() + vds::kPreambleBytes + 4, 4);
  vds::StreamHeader hdr{};
  EXPECT_EQ(vds::header_from_bytes(s.data() + vds::kPreambleBytes + vds::kChunkHeadBytes, head_len, s[4], s[5], &hdr),
            Status::ok);
  hdr.width = w;
  hdr.height = h;
  vds::enc::StreamWriter out(hdr);
  for (size_t at = vds::kPreambleBytes + vds::kChunkHeadBytes + head_len + vds::kChunkTailBytes;
       at + vds::kChunkHeadBytes <= s.size();) {
    uint32_t type = 0, len = 0;
    std::memcpy(&type, s.data() + at, 4);
    std::memcpy(&len, s.data() + at + 4, 4);
    if (type != vds::chunk::kEnd)
      out.add_chunk(type, std::vector<uint8_t>(s.begin() + static_cast<std::ptrdiff_t>(at + 8),
                                               s.begin() + static_cast<std::ptrdiff_t>(at + 8 + len)));
    at += vds::kChunkHeadBytes + len + vds::kChunkTailBytes;
  }
  return out.finish();
}

// The band buffer and the display are the stream's frame size: an image of
// another size (wider, taller or smaller) is refused before any pixel.
TEST(Player, AnImageOfAnotherSizeThanTheStreamIsRefused) {
  const std::vector<uint8_t> s = image_stream();  // 64x48 images
  for (const auto& wh : {std::pair<uint16_t, uint16_t>{48, 48}, {64, 32}, {80, 48}, {64, 64}}) {
    Seen seen;
    vds::Player p;
    // Narrower: the image decoder refuses the band target itself
    // (invalid_argument); otherwise the player's size check (malformed).
    const Status want = wh.first < 64 ? Status::invalid_argument : Status::malformed;
    EXPECT_EQ(play(resized_head(s, wh.first, wh.second), seen, 100, 1u << 20, &p), want)
        << wh.first << "x" << wh.second;
    EXPECT_EQ(seen.bands, 0u);
    EXPECT_EQ(seen.begun, 0u);
  }
  Seen same;
  EXPECT_EQ(play(resized_head(s, 64, 48), same, 100), Status::ok) << "the same size still plays";
  EXPECT_EQ(same.crcs, vds::enc::client_frame_crcs(s));
}

TEST(Player, AModelLargerThanTheWorkspacePlaysWhatFitsAndEndsEarly) {
  vds::enc::MeshEncodeOptions o;
  const vds::enc::MeshEncodeResult r = vds::enc::encode_mesh(vds::test::torus_mesh(40, 20), o);
  const std::vector<uint32_t> want = vds::enc::client_frame_crcs(r.stream);
  ASSERT_GT(want.size(), 3u);
  Seen whole;
  ASSERT_EQ(play(r.stream, whole, 0, 8u << 20), Status::ok);
  ASSERT_EQ(whole.crcs, want);
  // Find a workspace that holds the base but not the whole model.
  bool partial_seen = false;
  for (size_t bytes = 24u << 10; bytes < (4u << 20) && !partial_seen; bytes += bytes / 4) {
    Seen seen;
    vds::Player p;
    const Status st = play(r.stream, seen, 0, bytes, &p);
    if (st != Status::ok) continue;  // not even the base
    if (seen.crcs.size() == want.size()) break;
    partial_seen = true;
    EXPECT_TRUE(p.workspace_full());
    EXPECT_TRUE(p.plan().known);
    EXPECT_LT(p.plan().vertices, p.plan().of_vertices);
    EXPECT_EQ(seen.crcs, std::vector<uint32_t>(want.begin(), want.begin() + static_cast<std::ptrdiff_t>(seen.crcs.size())));
    ASSERT_EQ(seen.notices.size(), 2u);
    EXPECT_EQ(seen.notices[0].first, vds::PlayerNotice::model_partial);
    EXPECT_EQ(seen.notices[1].first, vds::PlayerNotice::model_full);
  }
  EXPECT_TRUE(partial_seen) << "some workspace holds part of the model";
}

// A textured model (glTF's textured box from assimp-testmodels, which make
// test installs): the mesh, then its vertex colours, then every mesh colors
// level, coarsest first; a smaller workspace shows the finest level it
// holds, a tiny one the shaded mesh; never a refusal.
TEST(Player, ATexturedModelShowsEveryColourLevelItsWorkspaceHolds) {
  const char* box = "/usr/share/assimp/models/glTF2/BoxTextured-glTF/BoxTextured.gltf";
  vds::enc::ModelStreamOptions o;
  o.colors.max_res_log2 = 6;
  o.samples_per_pixel = 0;  // every level, each sent
  o.schedule_views = 0;
  o.codec.max_chunk = 1024;
  o.mesh.max_chunk_payload = 1024;
  const vds::enc::ModelStreamResult r = vds::enc::encode_model_stream(vds::enc::load_textured_model(box), o);
  ASSERT_EQ(r.colors.max_res, 6);
  const std::vector<uint32_t> want = vds::enc::client_frame_crcs(r.stream);
  // The base shaded, then in its colours and each level in its own (MCVX);
  // then the vertex samples (MCLH) and 6 levels.
  ASSERT_EQ(r.parts.vertex_chunks, r.mesh.levels.size());
  const size_t geometry = 1 + r.parts.vertex_chunks;
  ASSERT_EQ(want.size(), geometry + 1 + 6);
  for (size_t piece : {size_t{0}, size_t{1}, size_t{4096}}) {
    Seen seen;
    ASSERT_EQ(play(r.stream, seen, piece, 1u << 20), Status::ok) << piece;
    EXPECT_EQ(seen.crcs, want) << piece;
    EXPECT_TRUE(seen.notices.empty());
  }
  // An orbit script: that many more frames of the finished model, turning.
  {
    vds::enc::ModelStreamOptions oo = o;
    oo.orbit_frames = 5;
    const vds::enc::ModelStreamResult ro = vds::enc::encode_model_stream(vds::enc::load_textured_model(box), oo);
    const std::vector<uint32_t> turned = vds::enc::client_frame_crcs(ro.stream);
    ASSERT_EQ(turned.size(), want.size() + 5);
    EXPECT_EQ(std::vector<uint32_t>(turned.begin(), turned.begin() + static_cast<std::ptrdiff_t>(want.size())), want);
    EXPECT_NE(turned[want.size()], turned[want.size() + 1]) << "each frame a further step round";
  }
  // Smaller workspaces: fewer colour levels, then none.
  bool coarser = false, none = false;
  size_t lo = 1024, hi = 1u << 20;  // the least workspace that plays the mesh
  while (lo < hi) {
    const size_t mid = (lo + hi) / 2;
    Seen seen;
    if (play(r.stream, seen, 4096, mid) == Status::ok)
      hi = mid;
    else
      lo = mid + 1;
  }
  for (size_t bytes = lo; bytes < (1u << 20); bytes += 256) {
    Seen seen;
    ASSERT_EQ(play(r.stream, seen, 0, bytes), Status::ok) << bytes;
    if (seen.crcs == want) break;
    ASSERT_FALSE(seen.notices.empty());
    const size_t shown = seen.crcs.size();
    ASSERT_GE(shown, geometry);
    // The geometry's frames are the replay's; then the colours it holds.
    EXPECT_EQ(std::vector<uint32_t>(seen.crcs.begin(), seen.crcs.begin() + static_cast<std::ptrdiff_t>(geometry)),
              std::vector<uint32_t>(want.begin(), want.begin() + static_cast<std::ptrdiff_t>(geometry)));
    if (seen.notices.back().first == vds::PlayerNotice::model_no_colors) {
      none = true;
      EXPECT_EQ(shown, geometry);  // in the colours that came with the vertices
    } else {
      ASSERT_EQ(seen.notices.back().first, vds::PlayerNotice::model_colors_level);
      const uint32_t finest = seen.notices.back().second;
      EXPECT_GT(finest, 0u);
      EXPECT_EQ(shown, geometry + 1 + (6 - finest));
      // Up to its finest level, the same pictures as a client that holds them all.
      EXPECT_EQ(seen.crcs, std::vector<uint32_t>(want.begin(), want.begin() + static_cast<std::ptrdiff_t>(shown)));
      coarser = true;
    }
  }
  EXPECT_TRUE(coarser) << "some workspace holds the mesh and part of its colour";
  EXPECT_TRUE(none) << "some workspace holds the mesh and none of its colour";
  // Every prefix of the stream fails cleanly (truncated) or, past the END, plays.
  for (size_t n = 0; n + 1 < r.stream.size(); n += 97) {
    Seen seen;
    const std::vector<uint8_t> prefix(r.stream.begin(), r.stream.begin() + static_cast<std::ptrdiff_t>(n));
    EXPECT_TRUE(vds::is_error(play(prefix, seen, 0))) << n;
  }
}

// Two JPEG images (the 24x18 sample) in JPEG chunks of `piece` bytes.
std::vector<uint8_t> jpeg_stream(size_t piece) {
  vds::StreamHeader h = vds::enc::default_header(vds::StreamMode::images, 24, 18);
  h.frame_count = 2;
  h.max_chunk_payload = static_cast<uint32_t>(piece);
  h.workspace_bytes = static_cast<uint32_t>(vds::Player::jpeg_workspace_bytes(24, vds::kClientPlayerConfig));
  vds::enc::StreamWriter w(h);
  const std::vector<uint8_t> file(vds::test::kJpeg422, vds::test::kJpeg422 + sizeof vds::test::kJpeg422);
  for (int image = 0; image < 2; ++image)
    for (size_t at = 0; at < file.size(); at += piece)
      w.add_chunk(vds::chunk::kJpeg, std::span(file).subspan(at, std::min(piece, file.size() - at)));
  return w.finish();
}

TEST(Player, JpegImagesAreFramesLikeVdsImages) {
  // The frame the JPEG decoder makes of the file on its own, RGB565.
  std::vector<uint8_t> ws(vds::JpegDecoder::kWorkspaceBytes);
  vds::Arena arena(ws.data(), ws.size());
  vds::JpegDecoder dec;
  ASSERT_EQ(dec.init(arena), Status::ok);
  std::vector<uint8_t> frame(24 * 18 * 2);
  ASSERT_EQ(dec.decode(vds::test::kJpeg422, sizeof vds::test::kJpeg422,
                       vds::ImageTarget::frame(vds::PixelFormat::rgb565, frame.data(), 48)),
            Status::ok);
  const uint32_t want = vds::crc32c(frame.data(), frame.size());
  for (size_t chunk : {size_t{8}, size_t{40}, size_t{4096}}) {
    const std::vector<uint8_t> s = jpeg_stream(chunk);
    for (size_t piece : {size_t{0}, size_t{1}, s.size()}) {
      Seen seen;
      ASSERT_EQ(play(s, seen, piece), Status::ok) << chunk << " " << piece;
      EXPECT_EQ(seen.crcs, std::vector<uint32_t>(2, want));
      EXPECT_EQ(seen.bands, 2u * 3u) << "18 rows of 4:2:2: bands of 8 rows";
      EXPECT_FALSE(seen.band_outside);
      EXPECT_FALSE(seen.band_in_no_frame);
    }
  }
  // A JPEG of another size than the stream's frames is refused before a band is shown.
  for (const auto& [w, h] : {std::pair<uint16_t, uint16_t>{24, 16}, {32, 18}, {16, 18}}) {
    Seen seen;
    EXPECT_EQ(play(resized_head(jpeg_stream(40), w, h), seen, 0), Status::malformed) << w << "x" << h;
    EXPECT_EQ(seen.bands, 0u);
    EXPECT_TRUE(seen.crcs.empty());
  }
}

TEST(Player, AJpegInsideAVdsImageIsRefused) {
  // A vds image's header, a JPEG, then the vds image's data.
  const std::vector<uint8_t> vds_images = image_stream();
  std::vector<std::pair<uint32_t, std::vector<uint8_t>>> chunks;
  uint32_t head_len = 0;
  std::memcpy(&head_len, vds_images.data() + vds::kPreambleBytes + 4, 4);
  for (size_t at = vds::kPreambleBytes + vds::kChunkHeadBytes + head_len + vds::kChunkTailBytes;
       at + vds::kChunkHeadBytes <= vds_images.size();) {
    uint32_t type = 0, len = 0;
    std::memcpy(&type, vds_images.data() + at, 4);
    std::memcpy(&len, vds_images.data() + at + 4, 4);
    chunks.emplace_back(type, std::vector<uint8_t>(vds_images.begin() + static_cast<std::ptrdiff_t>(at + 8),
                                                   vds_images.begin() + static_cast<std::ptrdiff_t>(at + 8 + len)));
    at += vds::kChunkHeadBytes + len + vds::kChunkTailBytes;
  }
  ASSERT_EQ(chunks[0].first, vds::chunk::kImageHeader);
  vds::StreamHeader h = vds::enc::default_header(vds::StreamMode::images, 64, 48);
  h.workspace_bytes = 32768;
  h.max_chunk_payload = 4096;
  vds::enc::StreamWriter w(h);
  w.add_chunk(chunks[0].first, chunks[0].second);
  w.add_chunk(vds::chunk::kJpeg, std::vector<uint8_t>(vds::test::kJpeg422, vds::test::kJpeg422 + sizeof vds::test::kJpeg422));
  Seen seen;
  EXPECT_EQ(play(w.finish(), seen, 0), Status::malformed);
  EXPECT_EQ(seen.ended, 0u);
}

TEST(Player, AnImageHeaderInsideAnImageIsRefused) {
  const std::vector<uint8_t> s = image_stream();
  uint32_t head_len = 0;
  std::memcpy(&head_len, s.data() + vds::kPreambleBytes + 4, 4);
  const size_t at = vds::kPreambleBytes + vds::kChunkHeadBytes + head_len + vds::kChunkTailBytes;
  uint32_t len = 0;
  std::memcpy(&len, s.data() + at + 4, 4);
  const std::vector<uint8_t> imgh(s.begin() + static_cast<std::ptrdiff_t>(at + 8),
                                  s.begin() + static_cast<std::ptrdiff_t>(at + 8 + len));
  vds::StreamHeader h = vds::enc::default_header(vds::StreamMode::images, 64, 48);
  h.workspace_bytes = 32768;
  h.max_chunk_payload = 4096;
  vds::enc::StreamWriter w(h);
  w.add_chunk(vds::chunk::kImageHeader, imgh);
  w.add_chunk(vds::chunk::kImageHeader, imgh);
  Seen seen;
  EXPECT_EQ(play(w.finish(), seen, 0), Status::malformed);
  EXPECT_EQ(seen.ended, 0u);
}

TEST(Player, Rgb888BandsShowTheSamePixelsAndModelsRefuseThem) {
  const std::vector<uint8_t> s = image_stream();
  vds::PlayerConfig c888 = vds::kClientPlayerConfig;
  c888.format = vds::PixelFormat::rgb888;
  struct Frames {
    std::vector<std::vector<uint8_t>> rgb;
    std::vector<uint32_t> crcs;
  } got;
  vds::PlayerCallbacks cb;
  cb.ctx = &got;
  cb.begin_frame = [](void* ctx, uint16_t w, uint16_t h) {
    static_cast<Frames*>(ctx)->rgb.emplace_back(static_cast<size_t>(w) * h * 3);
    return true;
  };
  cb.band = [](void* ctx, const vds::PixelRect& r) {
    std::vector<uint8_t>& f = static_cast<Frames*>(ctx)->rgb.back();
    for (int row = 0; row < r.h; ++row)
      std::memcpy(&f[static_cast<size_t>(r.y + row) * r.w * 3], r.pixels + row * r.stride, static_cast<size_t>(r.w) * 3);
    return true;
  };
  cb.frame_shown = [](void* ctx, const vds::PlayedFrame& f) { static_cast<Frames*>(ctx)->crcs.push_back(f.crc); };
  Seen unused;
  ASSERT_EQ(play(s, unused, 0, 1u << 20, nullptr, c888, &cb), Status::ok);
  ASSERT_EQ(got.rgb.size(), 3u);
  // The first frame as the host tools decode it, and each frame's CRC over its RGB888 rows.
  EXPECT_EQ(got.rgb[0], vds::enc::decode_stream_image(s).rgb.pixels);
  for (size_t f = 0; f < 3; ++f) EXPECT_EQ(got.crcs[f], vds::crc32c(got.rgb[f].data(), got.rgb[f].size()));
  const vds::enc::MeshEncodeResult m = vds::enc::encode_mesh(vds::test::torus_mesh(12, 8), vds::enc::MeshEncodeOptions{});
  EXPECT_EQ(play(m.stream, unused, 0, 8u << 20, nullptr, c888, &cb), Status::unsupported_feature);
  c888.format = static_cast<vds::PixelFormat>(7);
  vds::Player p;
  std::vector<uint8_t> ws(1u << 16);
  vds::Arena arena(ws.data(), ws.size());
  EXPECT_EQ(p.init(arena, c888, cb), Status::invalid_argument);
}

TEST(Player, AModelReportsEveryLevelWithItsDecodeCount) {
  const vds::enc::MeshEncodeResult r = vds::enc::encode_mesh(vds::test::torus_mesh(40, 20), vds::enc::MeshEncodeOptions{});
  struct Levels {
    std::vector<vds::PlayedLevel> seen;
    uint64_t ticks = 0;
  } levels;
  Seen seen;
  vds::PlayerCallbacks cb = callbacks(seen);
  vds::PlayerCallbacks with = cb;
  // A clock that moves one tick per call: every count is > 0 when work was done.
  static Levels* current = nullptr;
  current = &levels;
  with.clock = [](void*) { return ++current->ticks; };
  with.level = [](void*, const vds::PlayedLevel& l) { current->seen.push_back(l); };
  vds::Player p;
  ASSERT_EQ(play(r.stream, seen, 0, 8u << 20, &p, vds::kClientPlayerConfig, &with), Status::ok);
  ASSERT_EQ(levels.seen.size(), static_cast<size_t>(p.mesh.header().levels) + 1);
  for (size_t i = 0; i < levels.seen.size(); ++i) {
    EXPECT_EQ(levels.seen[i].level, i);
    EXPECT_GT(levels.seen[i].decode, 0u);
    if (i > 0) EXPECT_GT(levels.seen[i].vertices, levels.seen[i - 1].vertices);
  }
  EXPECT_EQ(levels.seen.back().vertices, p.mesh.mesh().vertex_count());
  EXPECT_EQ(levels.seen.back().triangles, p.mesh.mesh().triangle_count());
}

// The viewer's frames (Player::view_input): a turn draws the model again
// from the stream's last angle plus the turn, shown but not reported; the
// stream's frames after it are drawn turned the same and marked steered.
TEST(Player, TheViewerTurnsAModelBetweenTheStreamsFrames) {
  const char* box = "/usr/share/assimp/models/glTF2/BoxTextured-glTF/BoxTextured.gltf";
  vds::enc::ModelStreamOptions o;
  o.colors.max_res_log2 = 4;
  o.schedule_views = 0;
  o.orbit_frames = 8;  // angles 0, 1/8, ... 7/8 turn
  const vds::enc::ModelStreamResult r = vds::enc::encode_model_stream(vds::enc::load_textured_model(box), o);
  const std::vector<uint32_t> want = vds::enc::client_frame_crcs(r.stream);
  ASSERT_GT(want.size(), 8u);
  const size_t orbit = want.size() - 8;  // the first orbit frame, at angle 0
  ASSERT_NE(want[orbit], want[orbit + 1]) << "each orbit frame a further step round";

  struct Viewer {
    int16_t turn = 0;
    uint32_t reads = 0;
    std::vector<uint32_t> shown;  // end_frame's CRC of every frame shown
    std::vector<vds::PlayedFrame> reported;
  };
  static Viewer* v = nullptr;
  Seen seen;
  vds::PlayerCallbacks cb = callbacks(seen);
  cb.end_frame = [](void*, uint32_t crc) {
    v->shown.push_back(crc);
    return true;
  };
  cb.frame_shown = [](void*, const vds::PlayedFrame& f) { v->reported.push_back(f); };
  cb.steer = [](void*, vds::terrain::SteerInput* in) {
    ++v->reads;
    *in = vds::terrain::SteerInput{};
    in->turn = v->turn;
    return in->any();
  };
  std::vector<uint8_t> ws(1u << 20);

  // After the stream: an eighth of a turn past the last orbit frame (7/8) is angle 0.
  {
    Viewer viewer;
    v = &viewer;
    vds::Arena arena(ws.data(), ws.size());
    vds::Player p;
    ASSERT_EQ(p.init(arena, vds::kClientPlayerConfig, cb), Status::ok);
    EXPECT_FALSE(p.view_input()) << "nothing to turn before the stream";
    ASSERT_EQ(p.feed(r.stream.data(), r.stream.size()), Status::ok);
    ASSERT_EQ(viewer.reported.size(), want.size());
    for (size_t i = 0; i < want.size(); ++i) {
      EXPECT_EQ(viewer.reported[i].crc, want[i]) << i;
      EXPECT_FALSE(viewer.reported[i].steered) << i;
    }
    EXPECT_FALSE(p.view_input()) << "controls that do not turn draw nothing";
    EXPECT_EQ(viewer.reads, 1u);
    viewer.turn = 8192;
    ASSERT_TRUE(p.view_input());
    ASSERT_EQ(viewer.shown.size(), want.size() + 1);
    EXPECT_EQ(viewer.shown.back(), want[orbit]) << "7/8 + 1/8 turn: the orbit's first angle";
    EXPECT_EQ(viewer.reported.size(), want.size()) << "the viewer's frame is not the stream's";
    EXPECT_EQ(p.frames_shown(), want.size());
    ASSERT_TRUE(p.view_input());
    EXPECT_EQ(viewer.shown.back(), want[orbit + 1]);
  }
  // During the stream: the turn stays, so each orbit frame shows the next angle's picture.
  {
    Viewer viewer;
    v = &viewer;
    vds::Arena arena(ws.data(), ws.size());
    vds::Player p;
    ASSERT_EQ(p.init(arena, vds::kClientPlayerConfig, cb), Status::ok);
    size_t at = 0;
    Status st = Status::more_input;
    while (st == Status::more_input && viewer.reported.size() < orbit) st = p.feed(&r.stream[at++], 1);
    ASSERT_EQ(st, Status::more_input);
    viewer.turn = 8192;
    ASSERT_TRUE(p.view_input());
    viewer.turn = 0;
    ASSERT_EQ(p.feed(r.stream.data() + at, r.stream.size() - at), Status::ok);
    ASSERT_EQ(viewer.reported.size(), want.size());
    for (size_t i = 0; i < orbit; ++i) EXPECT_FALSE(viewer.reported[i].steered) << i;
    for (size_t i = orbit; i < want.size(); ++i) {
      EXPECT_TRUE(viewer.reported[i].steered) << i;
      EXPECT_EQ(viewer.reported[i].index, i);
      if (i + 1 < want.size()) EXPECT_EQ(viewer.reported[i].crc, want[i + 1]) << i;
    }
    EXPECT_EQ(viewer.reported.back().crc, want[orbit]) << "7/8 + 1/8 turn";
  }
  // Turned and turned back between any two pieces of a stream whose levels
  // come in several chunks: a viewer's frame at the stream's own angle is
  // the stream's last frame, never a level half decoded or a mesh whose
  // colours have not come; the stream's frames are the replay's.
  {
    vds::enc::ModelStreamOptions small = o;
    small.codec.max_chunk = 512;
    small.mesh.max_chunk_payload = 512;
    const vds::enc::ModelStreamResult rs = vds::enc::encode_model_stream(vds::enc::load_textured_model(box), small);
    const std::vector<uint32_t> crcs = vds::enc::client_frame_crcs(rs.stream);
    Viewer viewer;
    v = &viewer;
    vds::Arena arena(ws.data(), ws.size());
    vds::Player p;
    ASSERT_EQ(p.init(arena, vds::kClientPlayerConfig, cb), Status::ok);
    Status st = Status::more_input;
    size_t checked = 0;
    for (size_t at = 0; at < rs.stream.size() && st == Status::more_input; at += 16) {
      st = p.feed(rs.stream.data() + at, std::min<size_t>(16, rs.stream.size() - at));
      viewer.turn = 16384;
      p.view_input();
      viewer.turn = -16384;
      if (p.view_input()) {
        ASSERT_FALSE(viewer.reported.empty());
        EXPECT_EQ(viewer.shown.back(), viewer.reported.back().crc) << "at byte " << at;
        ++checked;
      }
    }
    ASSERT_EQ(st, Status::ok);
    ASSERT_EQ(viewer.reported.size(), crcs.size());
    for (size_t i = 0; i < crcs.size(); ++i) EXPECT_EQ(viewer.reported[i].crc, crcs[i]) << i;
    EXPECT_GT(checked, crcs.size());
  }
  // Other modes have no viewer's frames.
  {
    Viewer viewer;
    viewer.turn = 8192;
    v = &viewer;
    vds::Arena arena(ws.data(), ws.size());
    vds::Player p;
    ASSERT_EQ(p.init(arena, vds::kClientPlayerConfig, cb), Status::ok);
    const std::vector<uint8_t> images = image_stream();
    ASSERT_EQ(p.feed(images.data(), images.size()), Status::ok);
    EXPECT_FALSE(p.view_input());
    EXPECT_EQ(viewer.reads, 0u);
  }
}

}  // namespace
