// Stream container: writer → client parser round trips with every split of
// the input, prefix sweeps, corruption, version and budget refusals, the
// pull interface with an I/O failure at every offset, and the golden v1.0
// stream kept forever.
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "golden_hash.h"
#include "vds/container.h"
#include "vds/crc32c.h"
#include "vds/enc/stream_writer.h"

namespace {

using vds::ChunkResult;
using vds::Status;
using vds::StreamHeader;
using vds::StreamMode;
using vds::StreamParser;

constexpr uint32_t kData = vds::fourcc('D', 'A', 'T', 'A');
constexpr uint32_t kUnknown = vds::fourcc('z', 'z', 'z', 'z');

StreamHeader sample_header() {
  StreamHeader h = vds::enc::default_header(StreamMode::walkthrough, 240, 180);
  h.flags = vds::kHeaderFlagInteractive;
  h.frame_period_us = 50000;
  h.frame_count = 600;
  h.focal_x_q16 = 200 << 16;
  h.focal_y_q16 = 200 << 16;
  h.center_x_q16 = 120 << 16;
  h.center_y_q16 = 90 << 16;
  h.near_q16 = 1 << 14;
  h.far_q16 = 1000 << 16;
  h.max_chunk_payload = 300;
  h.workspace_bytes = 1000;
  h.max_vertices = 5000;
  h.max_triangles = 9000;
  return h;
}

std::vector<uint8_t> sample_stream() {
  vds::enc::StreamWriter w(sample_header());
  w.add_meta("title", "container test");
  std::vector<uint8_t> a(37), b(300), c;
  for (size_t i = 0; i < a.size(); ++i) a[i] = static_cast<uint8_t>(i * 13);
  for (size_t i = 0; i < b.size(); ++i) b[i] = static_cast<uint8_t>(255 - i);
  w.add_chunk(kData, a);
  w.add_chunk(kUnknown, b);
  w.add_chunk(kData, c);
  return w.finish();
}

// What a parser reported, for comparing runs.
struct Events {
  bool header = false;
  StreamHeader h{};
  std::vector<std::pair<uint32_t, std::vector<uint8_t>>> chunks;
  bool abort_on_data = false;
};

vds::ChunkSink sink_for(Events* ev) {
  vds::ChunkSink s;
  s.ctx = ev;
  s.on_header = [](void* ctx, const StreamHeader& h) {
    auto* e = static_cast<Events*>(ctx);
    e->header = true;
    e->h = h;
    return true;
  };
  s.on_chunk = [](void* ctx, uint32_t type, const uint8_t* p, uint32_t n) {
    auto* e = static_cast<Events*>(ctx);
    e->chunks.emplace_back(type, std::vector<uint8_t>(p, p + n));
    if (type == kData && e->abort_on_data) return ChunkResult::abort;
    return type == kData || type == vds::chunk::kMeta ? ChunkResult::consumed : ChunkResult::unknown;
  };
  return s;
}

struct Harness {
  std::vector<uint8_t> ws = std::vector<uint8_t>(4096);
  vds::Arena arena{ws.data(), ws.size()};
  StreamParser parser;
  Events ev;
  explicit Harness(uint32_t capacity = 512, size_t workspace = 4096) {
    ws.assign(workspace, 0);
    arena = vds::Arena(ws.data(), ws.size());
    EXPECT_EQ(parser.init(arena, capacity, sink_for(&ev)), Status::ok);
  }
  Status feed_all(const std::vector<uint8_t>& s) {
    Status r = parser.feed(s.data(), s.size());
    return r == Status::more_input ? parser.finish() : r;
  }
};

void expect_same_events(const Events& a, const Events& b) {
  ASSERT_EQ(a.header, b.header);
  EXPECT_EQ(memcmp(&a.h, &b.h, sizeof a.h), 0);
  ASSERT_EQ(a.chunks.size(), b.chunks.size());
  for (size_t i = 0; i < a.chunks.size(); ++i) {
    EXPECT_EQ(a.chunks[i].first, b.chunks[i].first);
    EXPECT_EQ(a.chunks[i].second, b.chunks[i].second);
  }
}

TEST(Container, RoundTripReportsHeaderAndChunks) {
  const auto s = sample_stream();
  Harness h;
  ASSERT_EQ(h.feed_all(s), Status::ok);
  EXPECT_TRUE(h.parser.done());
  EXPECT_EQ(h.parser.chunks(), 6u);
  EXPECT_EQ(h.parser.chunks_skipped(), 1u);
  EXPECT_EQ(h.parser.bytes_consumed(), s.size());
  const StreamHeader want = sample_header();
  EXPECT_EQ(h.ev.h.width, 240);
  EXPECT_EQ(h.ev.h.height, 180);
  EXPECT_EQ(h.ev.h.mode, StreamMode::walkthrough);
  EXPECT_EQ(h.ev.h.flags, vds::kHeaderFlagInteractive);
  EXPECT_EQ(h.ev.h.frame_period_us, want.frame_period_us);
  EXPECT_EQ(h.ev.h.frame_count, want.frame_count);
  EXPECT_EQ(h.ev.h.focal_x_q16, want.focal_x_q16);
  EXPECT_EQ(h.ev.h.center_y_q16, want.center_y_q16);
  EXPECT_EQ(h.ev.h.near_q16, want.near_q16);
  EXPECT_EQ(h.ev.h.far_q16, want.far_q16);
  EXPECT_EQ(h.ev.h.max_chunk_payload, 300u);
  EXPECT_EQ(h.ev.h.workspace_bytes, 1000u);
  EXPECT_EQ(h.ev.h.max_vertices, 5000u);
  EXPECT_EQ(h.ev.h.max_triangles, 9000u);
  ASSERT_EQ(h.ev.chunks.size(), 4u);
  EXPECT_EQ(h.ev.chunks[0].first, vds::chunk::kMeta);
  EXPECT_EQ(std::string(h.ev.chunks[0].second.begin(), h.ev.chunks[0].second.end()), "title=container test\n");
  EXPECT_EQ(h.ev.chunks[1].second.size(), 37u);
  EXPECT_EQ(h.ev.chunks[2].first, kUnknown);
  EXPECT_EQ(h.ev.chunks[3].second.size(), 0u);
}

TEST(Container, EveryTwoWaySplitGivesTheSameEvents) {
  const auto s = sample_stream();
  Harness ref;
  ASSERT_EQ(ref.feed_all(s), Status::ok);
  for (size_t cut = 0; cut <= s.size(); ++cut) {
    Harness h;
    Status r = h.parser.feed(s.data(), cut);
    ASSERT_EQ(r, cut == s.size() ? Status::ok : Status::more_input) << "cut " << cut;
    r = h.parser.feed(s.data() + cut, s.size() - cut);
    ASSERT_EQ(r, Status::ok) << "cut " << cut;
    expect_same_events(ref.ev, h.ev);
  }
}

TEST(Container, EveryThreeWaySplitGivesTheSameEvents) {
  const auto s = sample_stream();
  Harness ref;
  ASSERT_EQ(ref.feed_all(s), Status::ok);
  for (size_t a = 0; a <= s.size(); a += 3) {
    for (size_t b = a; b <= s.size(); b += 5) {
      Harness h;
      ASSERT_EQ(h.parser.feed(s.data(), a), a == s.size() ? Status::ok : Status::more_input);
      ASSERT_EQ(h.parser.feed(s.data() + a, b - a), b == s.size() ? Status::ok : Status::more_input);
      ASSERT_EQ(h.parser.feed(s.data() + b, s.size() - b), Status::ok) << a << "," << b;
      expect_same_events(ref.ev, h.ev);
    }
  }
}

TEST(Container, FixedPieceSizes) {
  const auto s = sample_stream();
  Harness ref;
  ASSERT_EQ(ref.feed_all(s), Status::ok);
  for (size_t piece = 1; piece <= 64; ++piece) {
    Harness h;
    Status r = Status::more_input;
    for (size_t at = 0; at < s.size(); at += piece) {
      // Exact-size copies so ASan catches any read past a piece.
      std::vector<uint8_t> chunk(s.begin() + static_cast<long>(at),
                                 s.begin() + static_cast<long>(std::min(s.size(), at + piece)));
      r = h.parser.feed(chunk.data(), chunk.size());
      ASSERT_FALSE(vds::is_error(r));
    }
    EXPECT_EQ(r, Status::ok);
    expect_same_events(ref.ev, h.ev);
  }
}

TEST(Container, EveryStrictPrefixIsTruncated) {
  const auto s = sample_stream();
  for (size_t n = 0; n < s.size(); ++n) {
    std::vector<uint8_t> prefix(s.begin(), s.begin() + static_cast<long>(n));
    Harness h;
    EXPECT_EQ(h.parser.feed(prefix.data(), prefix.size()), Status::more_input) << n;
    EXPECT_EQ(h.parser.finish(), Status::truncated) << n;
  }
}

TEST(Container, TrailingByteIsMalformed) {
  auto s = sample_stream();
  s.push_back(0);
  Harness h;
  EXPECT_EQ(h.feed_all(s), Status::malformed);
  EXPECT_EQ(h.parser.error_offset(), s.size() - 1);
}

TEST(Container, EverySingleBitFlipIsRefused) {
  const auto s = sample_stream();
  for (size_t bit = 0; bit < s.size() * 8; ++bit) {
    auto c = s;
    c[bit / 8] ^= static_cast<uint8_t>(1u << (bit % 8));
    Harness h;
    EXPECT_NE(h.feed_all(c), Status::ok) << "bit " << bit;
  }
}

TEST(Container, CorruptHeaderByteIsBadCrc) {
  auto s = sample_stream();
  s[vds::kPreambleBytes + vds::kChunkHeadBytes + 2] ^= 0x40;  // inside the width field
  Harness h;
  EXPECT_EQ(h.feed_all(s), Status::bad_crc);
  EXPECT_FALSE(h.ev.header);
}

TEST(Container, VersionRules) {
  auto s = sample_stream();
  {
    auto c = s;
    c[4] = vds::kStreamVersionMajor + 1;
    Harness h;
    EXPECT_EQ(h.feed_all(c), Status::unsupported_version);
  }
  {
    auto c = s;
    c[4] = 0;
    Harness h;
    EXPECT_EQ(h.feed_all(c), Status::unsupported_version);
  }
  {
    auto c = s;  // a newer minor version is read (HEAD's CRC covers the preamble)
    c[5] = vds::kStreamVersionMinor + 1;
    const size_t crc_at = vds::kPreambleBytes + vds::kChunkHeadBytes + vds::kHeaderPayloadV1;
    const uint32_t crc = vds::crc32c(c.data(), crc_at);
    for (int i = 0; i < 4; ++i) c[crc_at + i] = static_cast<uint8_t>(crc >> (8 * i));
    Harness h;
    EXPECT_EQ(h.feed_all(c), Status::ok);
    EXPECT_EQ(h.ev.h.version_minor, vds::kStreamVersionMinor + 1);
  }
  {
    auto c = s;
    c[7] = 1;
    Harness h;
    EXPECT_EQ(h.feed_all(c), Status::unsupported_feature);
  }
  {
    auto c = s;  // a damaged minor version is caught by HEAD's CRC
    c[5] ^= 0x01;
    Harness h;
    EXPECT_EQ(h.feed_all(c), Status::bad_crc);
  }
  {
    auto c = s;
    c[0] = 'X';
    Harness h;
    EXPECT_EQ(h.feed_all(c), Status::malformed);
  }
}

TEST(Container, BudgetsAreCheckedBeforeAnyChunk) {
  const auto s = sample_stream();
  {
    Harness h(/*capacity=*/299);  // below the declared max_chunk_payload of 300
    EXPECT_EQ(h.feed_all(s), Status::workspace_too_small);
    EXPECT_FALSE(h.ev.header);
    EXPECT_TRUE(h.ev.chunks.empty());
  }
  {
    Harness h(/*capacity=*/300, /*workspace=*/300 + 999);  // one byte short of workspace_bytes
    EXPECT_EQ(h.feed_all(s), Status::workspace_too_small);
    EXPECT_TRUE(h.ev.chunks.empty());
  }
  {
    Harness h(/*capacity=*/300, /*workspace=*/300 + 1000);  // exactly enough
    EXPECT_EQ(h.feed_all(s), Status::ok);
  }
}

TEST(Container, InitRefusesTooSmallWorkspace) {
  std::vector<uint8_t> ws(255);
  vds::Arena arena(ws.data(), ws.size());
  StreamParser p;
  EXPECT_EQ(p.init(arena, 256, {}), Status::workspace_too_small);
  EXPECT_EQ(p.init(arena, 100, {}), Status::invalid_argument);
}

TEST(Container, OversizedChunkIsMalformedBeforeItsPayload) {
  auto s = sample_stream();
  // The first chunk after HEAD is META: claim a payload above the limit.
  const size_t meta = vds::kPreambleBytes + vds::kChunkHeadBytes + vds::kHeaderPayloadV1 + vds::kChunkTailBytes;
  s[meta + 4] = 0x2D;
  s[meta + 5] = 0x01;  // 301 bytes
  Harness h;
  std::vector<uint8_t> head(s.begin(), s.begin() + static_cast<long>(meta + 8));
  EXPECT_EQ(h.parser.feed(head.data(), head.size()), Status::malformed);
  EXPECT_EQ(h.parser.error_offset(), meta);
}

TEST(Container, ChunkBeforeHeaderAndSecondHeaderAreMalformed) {
  const auto s = sample_stream();
  const size_t head_end = vds::kPreambleBytes + vds::kChunkHeadBytes + vds::kHeaderPayloadV1 + vds::kChunkTailBytes;
  {
    // Preamble directly followed by the META chunk.
    std::vector<uint8_t> c(s.begin(), s.begin() + vds::kPreambleBytes);
    c.insert(c.end(), s.begin() + static_cast<long>(head_end), s.end());
    Harness h;
    EXPECT_EQ(h.feed_all(c), Status::malformed);
  }
  {
    std::vector<uint8_t> c(s.begin(), s.begin() + static_cast<long>(head_end));
    c.insert(c.end(), s.begin() + vds::kPreambleBytes, s.end());
    Harness h;
    EXPECT_EQ(h.feed_all(c), Status::malformed);
  }
}

TEST(Container, CallbackAbort) {
  const auto s = sample_stream();
  Harness h;
  h.ev.abort_on_data = true;
  EXPECT_EQ(h.feed_all(s), Status::aborted);
  EXPECT_EQ(h.parser.feed(s.data(), 1), Status::aborted) << "the first error stays latched";
}

struct Reader {
  const std::vector<uint8_t>* data;
  size_t pos = 0;
  size_t fail_at = SIZE_MAX;
  uint32_t step = 7;
};

int32_t read_cb(void* ctx, uint8_t* buf, uint32_t max) {
  auto* r = static_cast<Reader*>(ctx);
  if (r->pos >= r->fail_at) return -1;
  size_t n = std::min<size_t>({max, r->step, r->data->size() - r->pos, r->fail_at - r->pos});
  memcpy(buf, r->data->data() + r->pos, n);
  r->pos += n;
  return static_cast<int32_t>(n);
}

TEST(Container, PumpWithAnIoFailureAtEveryOffset) {
  const auto s = sample_stream();
  uint8_t scratch[16];
  {
    Harness h;
    Reader r{&s};
    EXPECT_EQ(h.parser.pump(read_cb, &r, scratch, sizeof scratch), Status::ok);
  }
  for (size_t at = 0; at < s.size(); ++at) {
    Harness h;
    Reader r{&s, 0, at};
    EXPECT_EQ(h.parser.pump(read_cb, &r, scratch, sizeof scratch), Status::io_error) << at;
  }
}

TEST(Container, WriterRefusesWhatAClientWouldRefuse) {
  StreamHeader h = sample_header();
  h.width = 0;
  EXPECT_THROW(vds::enc::StreamWriter{h}, std::invalid_argument);
  h = sample_header();
  h.near_q16 = h.far_q16;
  EXPECT_THROW(vds::enc::StreamWriter{h}, std::invalid_argument);
  vds::enc::StreamWriter w(sample_header());
  std::vector<uint8_t> big(301);
  EXPECT_THROW(w.add_chunk(kData, big), std::invalid_argument);
  EXPECT_THROW(w.add_chunk(vds::chunk::kEnd, {}), std::invalid_argument);
}

// Golden stream of container v1.0: kept forever; regenerated only when
// VDS_REGENERATE_GOLDEN=1 is set (and then reviewed like code).
TEST(Container, GoldenV1_0) {
  const std::string path = std::string(VDS_SOURCE_DIR) + "/tests/golden/container-v1.0.vds";
  const auto s = sample_stream();
  if (const char* regen = std::getenv("VDS_REGENERATE_GOLDEN"); regen && std::string(regen) == "1") {
    vds::enc::write_file(path, s);
  }
  const std::vector<uint8_t> golden = vds::enc::read_file(path);
  EXPECT_EQ(golden, s) << "the writer's output changed: container v1.0 must stay byte-identical";
  Harness h;
  ASSERT_EQ(h.feed_all(golden), Status::ok);
  // Pinned so that a regeneration cannot pass unnoticed.
  EXPECT_EQ(golden.size(), 496u);
  EXPECT_EQ(vds::test::golden_hash(golden), 0x766f9779e670c66bull);
}

}  // namespace
