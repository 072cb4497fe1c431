// Cortex-M4 side of bench/run_texture.sh: decodes the texture cases that
// `bench_texture m4-case` writes (a vds stream through the stream parser and
// vds::ImageDecoder, or a baseline JPEG through vds::JpegDecoder) and prints
// instructions per decode and a CRC-32C of the decoded output, to compare
// with the host's decode of the same file.
//
// Reads texture_case0.bin, texture_case1.bin, ... from the board's host
// (QEMU's working directory) until one is missing. Case file: "VTX1",
// u8 kind (0 = vds stream, 1 = JPEG file), u8 reps, u16 width, u16 height,
// u16 target (0 = RGB565 frame, 1 = Y'CbCr planes), u32 size, then the bytes.
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "print.h"
#include "vds/arena.h"
#include "vds/board.h"
#include "vds/container.h"
#include "vds/crc32c.h"
#include "vds/image.h"
#include "vds/jpeg.h"
#include "vds/bytes.h"

#ifndef VDS_WORKSPACE_BYTES
#error "VDS_WORKSPACE_BYTES (the client's workspace budget) must be set by the build"
#endif

namespace {

using vds::fw::Line;

constexpr uint32_t kCaseHeaderBytes = 16;
constexpr uint32_t kCaseMagic = 0x31585456;  // "VTX1" read little-endian
// The stream parser's chunk buffer: at least the max_chunk_payload of the
// streams bench_texture writes (4096 by default).
constexpr uint32_t kChunkCapacity = 16384;
// Output: an RGB565 frame (or the three planes) of up to this many pixels.
constexpr uint32_t kMaxPixels = 48 * 1024;

// The case's bytes, the parser's chunk buffer and the decoders' workspaces
// come from this arena, which the board's workspace budget bounds.
alignas(8) uint8_t g_workspace[VDS_WORKSPACE_BYTES];
alignas(4) uint16_t g_frame[kMaxPixels];

struct Case {
  uint8_t kind, reps;
  uint16_t width, height;
  bool planar;
  uint32_t size;
};


vds::ImageTarget target_for(const Case& c) {
  uint8_t* const base = reinterpret_cast<uint8_t*>(g_frame);
  if (c.planar) {
    const int cw = (c.width + 1) / 2;
    const uint32_t luma = static_cast<uint32_t>(c.width) * c.height;
    const uint32_t chroma = static_cast<uint32_t>(cw) * ((c.height + 1) / 2);
    return vds::ImageTarget::planes(base, c.width, base + luma, cw, base + luma + chroma, cw);
  }
  return vds::ImageTarget::frame(vds::PixelFormat::rgb565, base, c.width * 2);
}

uint32_t output_bytes(const Case& c) {
  const uint32_t luma = static_cast<uint32_t>(c.width) * c.height;
  if (!c.planar) return 2 * luma;
  return luma + 2 * static_cast<uint32_t>((c.width + 1) / 2) * ((c.height + 1) / 2);
}

struct VdsCtx {
  vds::ImageDecoder* dec;
  vds::Arena* arena;
  vds::ImageTarget target;
  vds::Status status;
};

bool on_header(void* ctx, const vds::StreamHeader&) {
  VdsCtx& c = *static_cast<VdsCtx*>(ctx);
  return c.dec->init(*c.arena) == vds::Status::ok;
}

vds::ChunkResult on_chunk(void* ctx, uint32_t type, const uint8_t* p, uint32_t size) {
  VdsCtx& c = *static_cast<VdsCtx*>(ctx);
  const vds::Status s = c.dec->on_chunk(type, p, size, c.target);
  if (vds::is_error(s)) {
    c.status = s;
    return vds::ChunkResult::abort;
  }
  return vds::ChunkResult::consumed;
}

// One decode of a vds stream as the client runs it: the stream parser
// (chunk CRC-32C checks included) feeding the image decoder.
vds::Status decode_vds(vds::Arena& arena, const uint8_t* data, const Case& c) {
  vds::ImageDecoder dec;
  VdsCtx ctx{&dec, &arena, target_for(c), vds::Status::ok};
  vds::ChunkSink sink;
  sink.ctx = &ctx;
  sink.on_header = on_header;
  sink.on_chunk = on_chunk;
  vds::StreamParser parser;
  vds::Status s = parser.init(arena, kChunkCapacity, sink);
  if (s != vds::Status::ok) return s;
  s = parser.feed(data, c.size);
  if (ctx.status != vds::Status::ok) return ctx.status;
  if (s != vds::Status::ok) return s;
  return dec.done() ? vds::Status::ok : vds::Status::truncated;
}

vds::Status decode_jpeg(vds::Arena& arena, const uint8_t* data, const Case& c) {
  vds::JpegDecoder dec;
  const vds::Status s = dec.init(arena);
  if (s != vds::Status::ok) return s;
  return dec.decode(data, c.size, target_for(c));
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
  c.planar = vds::load_le16(head + 10) == 1;
  c.size = vds::load_le32(head + 12);
  vds::Arena arena(g_workspace, sizeof g_workspace);
  uint8_t* const data = c.size > 0 ? static_cast<uint8_t*>(arena.alloc(c.size)) : nullptr;
  if (data == nullptr || c.kind > 1 || c.reps == 0 || c.width == 0 || c.height == 0 ||
      output_bytes(c) > sizeof g_frame) {
    vds::board::log(Line().str("m4 error: case does not fit this board: ").str(name.c_str()).str("\n").c_str());
    return 1;
  }
  if (vds::board::host_file_read(name.c_str(), kCaseHeaderBytes, data, c.size) != static_cast<int32_t>(c.size)) {
    vds::board::log(Line().str("m4 error: short case file ").str(name.c_str()).str("\n").c_str());
    return 1;
  }
  const size_t mark = arena.mark();
  uint64_t spent = 0;
  size_t high_water = 0;
  vds::Status s = vds::Status::ok;
  for (uint32_t r = 0; r < c.reps && s == vds::Status::ok; ++r) {
    std::memset(g_frame, 0, sizeof g_frame);
    arena.rewind(mark);
    const uint64_t t0 = vds::board::instructions();
    s = c.kind == 0 ? decode_vds(arena, data, c) : decode_jpeg(arena, data, c);
    spent += vds::board::instructions() - t0;
    high_water = arena.high_water();
  }
  if (s != vds::Status::ok) {
    vds::board::log(Line().str("m4 error: ").str(name.c_str()).str(" status ").str(vds::status_name(s)).str("\n").c_str());
    return 1;
  }
  const uint32_t crc = vds::crc32c(reinterpret_cast<const uint8_t*>(g_frame), output_bytes(c));
  Line l;
  l.str("m4 case=").dec(index).str(c.kind == 0 ? " kind=vds" : " kind=jpeg");
  l.str(c.planar ? " target=planes" : " target=rgb565").str(" bytes=").dec(c.size);
  l.str(" instr=").dec(spent / c.reps).str(" workspace=").dec(high_water).str(" crc=").hex32(crc).str("\n");
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
