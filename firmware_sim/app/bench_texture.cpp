// Cortex-M4 side of bench/run_texture.sh: plays the texture cases that
// `bench_texture m4-case` writes (an images stream holding one vds image or
// one baseline JPEG) through vds::Player, as the client does, into an
// RGB565 frame, and prints the instructions per image (parse + decode of
// the player's frame record: chunk framing and CRCs, entropy decoding,
// inverse transform and colour conversion; the band copies excluded) and
// the frame's CRC-32C, to compare with the host's play of the same file.
//
// Reads texture_case0.bin, texture_case1.bin, ... from the board's host
// (QEMU's working directory) until one is missing. Case file: "VTX1",
// u8 kind (0 = vds image, 1 = JPEG), u8 reps, u16 width, u16 height,
// u16 0, u32 size, then the stream's bytes.
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "print.h"
#include "vds/arena.h"
#include "vds/board.h"
#include "vds/bytes.h"
#include "vds/crc32c.h"
#include "vds/player.h"

#ifndef VDS_WORKSPACE_BYTES
#error "VDS_WORKSPACE_BYTES (the client's workspace budget) must be set by the build"
#endif

namespace {

using vds::fw::Line;

constexpr uint32_t kCaseHeaderBytes = 16;
constexpr uint32_t kCaseMagic = 0x31585456;  // "VTX1" read little-endian
// The player's chunk buffer: at least the max_chunk_payload of the streams
// bench_texture writes (4096 by default).
constexpr uint32_t kChunkCapacity = 16384;
// Output: an RGB565 frame of up to this many pixels.
constexpr uint32_t kMaxPixels = 48 * 1024;

// The case's bytes, the player's chunk buffer and the decoders' workspaces
// come from this arena, which the board's workspace budget bounds.
alignas(8) uint8_t g_workspace[VDS_WORKSPACE_BYTES];
alignas(4) uint16_t g_frame[kMaxPixels];

struct Case {
  uint8_t kind, reps;
  uint16_t width, height;
  uint32_t size;
};

struct Play {
  uint64_t instructions = 0;  // parse + decode of the frame
  uint32_t frames = 0;
};

uint64_t clock(void*) { return vds::board::instructions(); }

bool to_frame(void*, const vds::PixelRect& r) {
  for (uint16_t row = 0; row < r.h; ++row)
    std::memcpy(g_frame + static_cast<size_t>(r.y + row) * r.w, r.pixels + row * r.stride, static_cast<size_t>(r.w) * 2);
  return true;
}

void shown(void* ctx, const vds::PlayedFrame& f) {
  Play& p = *static_cast<Play*>(ctx);
  p.instructions += f.parse + f.decode;
  ++p.frames;
}

// One play of the case's stream as the client runs it.
vds::Status play(vds::Arena& arena, const uint8_t* data, const Case& c, Play& out) {
  vds::PlayerConfig config = vds::kClientPlayerConfig;
  config.max_chunk_bytes = kChunkCapacity;
  config.decode_stages = false;  // decoding as one stage: no clock reads per block
  vds::PlayerCallbacks cb;
  cb.ctx = &out;
  cb.band = to_frame;
  cb.frame_shown = shown;
  cb.clock = clock;
  vds::Player player;
  vds::Status s = player.init(arena, config, cb);
  if (s != vds::Status::ok) return s;
  s = player.feed(data, c.size);
  if (s == vds::Status::more_input) s = player.finish();
  if (s == vds::Status::ok && out.frames != 1) return vds::Status::truncated;
  return s;
}

// Runs texture_case<index>.bin. Returns 0 when done, 1 on an error, 2 when
// the file does not exist (the end of the list).
int run_case(uint32_t index) {
  Line name;
  name.str("texture_case").dec(index).str(".bin");
  uint8_t head[kCaseHeaderBytes];
  const int32_t got = vds::board::host_file_read(name.c_str(), 0, head, sizeof head);
  if (got < 0) return 2;
  Case c{};
  if (got != static_cast<int32_t>(sizeof head) || vds::load_le32(head) != kCaseMagic) {
    vds::board::log(Line().str("m4 error: bad case file ").str(name.c_str()).str("\n").c_str());
    return 1;
  }
  c.kind = head[4];
  c.reps = head[5];
  c.width = static_cast<uint16_t>(vds::load_le16(head + 6));
  c.height = static_cast<uint16_t>(vds::load_le16(head + 8));
  c.size = vds::load_le32(head + 12);
  vds::Arena arena(g_workspace, sizeof g_workspace);
  uint8_t* const data = c.size > 0 ? static_cast<uint8_t*>(arena.alloc(c.size)) : nullptr;
  if (data == nullptr || c.kind > 1 || c.reps == 0 || c.width == 0 || c.height == 0 ||
      static_cast<uint32_t>(c.width) * c.height > kMaxPixels) {
    vds::board::log(Line().str("m4 error: case does not fit this board: ").str(name.c_str()).str("\n").c_str());
    return 1;
  }
  if (vds::board::host_file_read(name.c_str(), kCaseHeaderBytes, data, c.size) != static_cast<int32_t>(c.size)) {
    vds::board::log(Line().str("m4 error: short case file ").str(name.c_str()).str("\n").c_str());
    return 1;
  }
  const size_t mark = arena.mark();
  Play p;
  size_t high_water = 0;
  vds::Status s = vds::Status::ok;
  for (uint32_t r = 0; r < c.reps && s == vds::Status::ok; ++r) {
    std::memset(g_frame, 0, sizeof g_frame);
    arena.rewind(mark);
    p.frames = 0;
    s = play(arena, data, c, p);
    high_water = arena.high_water() - mark;
  }
  if (s != vds::Status::ok) {
    vds::board::log(Line().str("m4 error: ").str(name.c_str()).str(" status ").str(vds::status_name(s)).str("\n").c_str());
    return 1;
  }
  const uint32_t crc = vds::crc32c(reinterpret_cast<const uint8_t*>(g_frame), static_cast<size_t>(c.width) * c.height * 2);
  Line l;
  l.str("m4 case=").dec(index).str(c.kind == 0 ? " kind=vds" : " kind=jpeg");
  l.str(" target=rgb565 bytes=").dec(c.size);
  l.str(" instr=").dec(p.instructions / c.reps).str(" workspace=").dec(high_water).str(" crc=").hex32(crc).str("\n");
  vds::board::log(l.c_str());
  return 0;
}

}  // namespace

extern "C" int vds_app_main() {
  vds::board::init();
  if (vds::board::instruction_resolution() == 0) {
    vds::board::log("m4 error: this board has no instruction counter\n");
    return 1;
  }
  Line sizes;
  sizes.str("m4 sizes image_workspace=").dec(vds::ImageDecoder::kWorkspaceBytes);
  sizes.str(" image_object=").dec(sizeof(vds::ImageDecoder)).str(" jpeg_workspace=").dec(vds::JpegDecoder::kWorkspaceBytes);
  sizes.str(" jpeg_object=").dec(sizeof(vds::JpegDecoder)).str(" parser_object=").dec(sizeof(vds::StreamParser));
  sizes.str(" player_object=").dec(sizeof(vds::Player));
  vds::board::log(sizes.str("\n").c_str());
  uint32_t n = 0;
  for (;; ++n) {
    const int r = run_case(n);
    if (r == 1) return 1;
    if (r == 2) break;
  }
  if (n == 0) {
    vds::board::log("m4 error: no texture_case0.bin\n");
    return 1;
  }
  vds::board::log(Line().str("m4 done cases=").dec(n).str(" stack=").dec(vds::board::stack_high_water()).str("\n").c_str());
  return 0;
}
