// vds client library: the stream container (docs/stream-format.md).
// An incremental parser that accepts bytes in pieces of any size, verifies
// each chunk's CRC-32C before handing it on, skips chunk types nobody
// handles, and refuses a stream whose declared budgets do not fit the
// caller's workspace before any payload is delivered.
#pragma once
#include <cstddef>
#include <cstdint>

#include "vds/arena.h"
#include "vds/status.h"

namespace vds {

// The container version this library writes and reads. A stream with a
// newer major version is refused; a newer minor version is read (minor
// versions only append header fields and add chunk types).
constexpr uint8_t kStreamVersionMajor = 1;
constexpr uint8_t kStreamVersionMinor = 0;

// Stream preamble: 4 magic bytes, major, minor, 2 flag bytes (0 in v1).
constexpr uint8_t kStreamMagic[4] = {'V', 'D', 'S', 0x1A};
constexpr uint32_t kPreambleBytes = 8;
// Chunk framing: type (4) + payload length (4) before, CRC-32C (4) after.
// The CRC covers type, length and payload; HEAD's also covers the preamble.
constexpr uint32_t kChunkHeadBytes = 8;
constexpr uint32_t kChunkTailBytes = 4;
// The header chunk's payload is small and fixed in v1; it may grow in later
// minor versions up to this limit.
constexpr uint32_t kHeaderPayloadMax = 256;
constexpr uint32_t kHeaderPayloadV1 = 54;

// Four ASCII bytes as they appear in the stream, read little-endian.
constexpr uint32_t fourcc(char a, char b, char c, char d) {
  return static_cast<uint32_t>(static_cast<uint8_t>(a)) | static_cast<uint32_t>(static_cast<uint8_t>(b)) << 8 |
         static_cast<uint32_t>(static_cast<uint8_t>(c)) << 16 | static_cast<uint32_t>(static_cast<uint8_t>(d)) << 24;
}

// Chunk types of container v1.0. Codecs add theirs in docs/stream-format.md.
namespace chunk {
constexpr uint32_t kHeader = fourcc('H', 'E', 'A', 'D');  // stream header, first chunk
constexpr uint32_t kEnd = fourcc('E', 'N', 'D', ' ');     // end of stream, last chunk
constexpr uint32_t kMeta = fourcc('M', 'E', 'T', 'A');    // UTF-8 "key=value\n" lines, informative
}  // namespace chunk

enum class StreamMode : uint8_t {
  images = 0,       // a sequence of still images
  walkthrough = 1,  // view-dependent texture streaming along a camera script
  terrain = 2,      // view-dependent DCT terrain, driven by the back-channel
  model = 3,        // progressive mesh with mesh colors
};
constexpr uint8_t kStreamModeCount = 4;

// Header flags (HEAD byte 1).
constexpr uint8_t kHeaderFlagInteractive = 0x01;  // the encoder needs the viewer pose on the back-channel

// The HEAD chunk. All lengths in bytes, fixed point named by Q format.
struct StreamHeader {
  uint8_t version_major;
  uint8_t version_minor;
  StreamMode mode;
  uint8_t flags;
  uint16_t width;            // frame size in pixels
  uint16_t height;
  uint32_t frame_period_us;  // 0: no timing (stills, interactive)
  uint32_t frame_count;      // 0: unknown or unbounded
  int32_t focal_x_q16;       // camera intrinsics, pixels, Q16.16
  int32_t focal_y_q16;
  int32_t center_x_q16;
  int32_t center_y_q16;
  int32_t near_q16;          // clip planes, scene units, Q16.16
  int32_t far_q16;
  // Budgets the client must have before it starts.
  uint32_t max_chunk_payload;  // largest chunk payload that follows
  uint32_t workspace_bytes;    // decoder state beyond the parser's chunk buffer
  uint32_t max_vertices;       // 0 when the mode has no geometry
  uint32_t max_triangles;
};

// Serialises a header into exactly kHeaderPayloadV1 bytes (little-endian).
void header_to_bytes(const StreamHeader& h, uint8_t out[kHeaderPayloadV1]);
// Parses a HEAD payload; checks field ranges (mode, size, budgets).
Status header_from_bytes(const uint8_t* payload, uint32_t size, uint8_t version_major, uint8_t version_minor,
                         StreamHeader* out);

// What a chunk's consumer did with it.
enum class ChunkResult : uint8_t {
  consumed = 0,  // known and used
  unknown = 1,   // not a type this consumer knows: skipped and counted
  abort = 2,     // stop parsing: the parser returns Status::aborted
};

// Where verified chunks go. `ctx` is passed back unchanged.
struct ChunkSink {
  void* ctx = nullptr;
  // After HEAD is verified and the budgets are checked; false aborts.
  bool (*on_header)(void* ctx, const StreamHeader& header) = nullptr;
  // Every verified chunk after HEAD except END. The payload pointer is valid
  // only during the call. A null callback skips every chunk as unknown.
  ChunkResult (*on_chunk)(void* ctx, uint32_t type, const uint8_t* payload, uint32_t size) = nullptr;
  // A model stream is progressive: a client can stop refining where its
  // workspace ends. With this set, a model stream whose HEAD workspace_bytes
  // (its full resolution) exceed what the arena has left is passed on
  // anyway, and the sink decides what it holds (vds/model_view.h,
  // plan_model_capacity). Other streams are refused as always.
  bool model_prefix = false;
};

// Pull-style input for StreamParser::pump: fills up to `max` bytes and
// returns how many (> 0), 0 at the end of input, or < 0 on an I/O failure.
using ReadFn = int32_t (*)(void* ctx, uint8_t* buf, uint32_t max);

class StreamParser {
 public:
  // Carves the chunk buffer (chunk_capacity bytes) from the arena; a stream
  // whose max_chunk_payload exceeds it, or whose workspace_bytes exceed what
  // the arena has left (unless ChunkSink::model_prefix lets a model stream
  // through), is refused with workspace_too_small.
  Status init(Arena& arena, uint32_t chunk_capacity, const ChunkSink& sink);

  // Consumes bytes. Returns more_input while the stream is unfinished, ok
  // once END has been read, or the first error (latched: later calls
  // return it again). Bytes after END are an error (malformed).
  Status feed(const uint8_t* data, size_t size);

  // Reads with `read` through the caller's scratch buffer until END, the
  // end of input, or an error. End of input before END is `truncated`.
  Status pump(ReadFn read, void* ctx, uint8_t* scratch, uint32_t scratch_size);

  // The caller has no more bytes: ok if END was read, else truncated.
  Status finish();

  Status status() const { return status_; }
  bool done() const { return state_ == State::done; }
  bool have_header() const { return have_header_; }
  const StreamHeader& header() const { return header_; }
  // Stream offset of the item that failed, and a short description of what
  // was wrong ("" with VDS_CONFIG_STATUS_NAMES == 0).
  uint64_t error_offset() const { return error_offset_; }
  const char* error_detail() const { return error_detail_; }

  uint64_t bytes_consumed() const { return offset_; }
  uint32_t chunks() const { return chunks_; }
  uint32_t chunks_skipped() const { return skipped_; }

 private:
  enum class State : uint8_t { preamble, chunk_head, payload, crc, done, failed };

  Status fail(Status s, uint64_t at, const char* detail);
  Status on_chunk_head();
  Status on_chunk_complete();

  ChunkSink sink_{};
  Arena* arena_ = nullptr;
  uint8_t* buf_ = nullptr;
  uint32_t capacity_ = 0;
  uint32_t limit_ = kHeaderPayloadMax;  // payload limit in force
  State state_ = State::failed;
  Status status_ = Status::invalid_argument;
  uint8_t small_[kPreambleBytes] = {};  // preamble, chunk head or CRC being gathered
  uint32_t have_ = 0;                   // bytes gathered for the current item
  uint32_t type_ = 0;
  uint32_t length_ = 0;
  uint32_t crc_ = 0;                    // running CRC of type, length and payload
  uint32_t preamble_crc_ = 0;           // HEAD's CRC starts from the preamble's
  uint64_t offset_ = 0;
  uint64_t item_offset_ = 0;
  uint64_t error_offset_ = 0;
  const char* error_detail_ = "";
  uint8_t version_major_ = 0;
  uint8_t version_minor_ = 0;
  bool have_header_ = false;
  StreamHeader header_{};
  uint32_t chunks_ = 0;
  uint32_t skipped_ = 0;
};

}  // namespace vds
