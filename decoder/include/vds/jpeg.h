// vds client library: baseline JPEG decoder (ITU-T T.81 sequential DCT,
// Huffman coding, 8-bit samples; SOF0 and SOF1), using the same integer IDCT
// as the vds image codec and the same pixel targets (vds/image.h).
//
// Supported: 1 component (grey) or 3 components (Y'CbCr, JFIF) with luma
// sampling 1x1, 2x1, 1x2 or 2x2 and chroma 1x1 (4:4:4, 4:2:2, 4:4:0, 4:2:0),
// one interleaved scan, restart intervals, 8- and 16-bit quantisation tables,
// tables redefined between scans' markers. Refused with
// Status::unsupported_feature: progressive (SOF2/SOF6), arithmetic coding
// (SOF9..SOF15 or DAC), lossless and hierarchical processes, 12-bit samples,
// 4 components, non-interleaved or multiple scans, DNL; error_detail() says
// which. Chroma is upsampled by replication (no "fancy" upsampling).
//
// Input is pushed in pieces of any size (successive JPEG chunk payloads of a
// stream): the decoder keeps its place between pieces, down to a Huffman
// code, so no piece need hold a whole marker segment or MCU.
//
// Memory: the JpegDecoder object (about 800 bytes) plus kWorkspaceBytes
// from the caller's Arena, both constants.
#pragma once
#include <cstddef>
#include <cstdint>

#include "vds/arena.h"
#include "vds/container.h"
#include "vds/huffman.h"
#include "vds/image.h"
#include "vds/status.h"

namespace vds {

namespace chunk {
constexpr uint32_t kJpeg = fourcc('J', 'P', 'E', 'G');  // successive bytes of one baseline JPEG file
}  // namespace chunk

struct JpegInfo {
  uint16_t width = 0;
  uint16_t height = 0;
  uint8_t components = 0;  // 1 or 3
  uint8_t sub_x = 0;       // chroma subsampling shifts: 1 = half resolution
  uint8_t sub_y = 0;
  uint16_t restart_interval = 0;  // MCUs per restart interval (0: none); as first defined
  int chroma_width() const { return (width + (1 << sub_x) - 1) >> sub_x; }
  int chroma_height() const { return (height + (1 << sub_y) - 1) >> sub_y; }
};

// Reads the markers of a JPEG held in memory up to its frame header. ok with
// the info; truncated if the buffer ends first; unsupported_feature for
// what the decoder refuses (detail, when non-null, says what).
Status jpeg_peek_info(const uint8_t* data, size_t size, JpegInfo* info, const char** detail = nullptr);

class JpegDecoder {
 public:
  static constexpr int kTables = 2;  // Huffman tables of each class (baseline: 0 and 1)
  static constexpr int kQuantTables = 4;
  static constexpr size_t kDcSymbols = 16;
  static constexpr size_t kAcSymbols = 256;
  // Fast AC lookup: a code and its extra bits resolved together when they
  // fit in kFastBits bits.
  static constexpr int kFastBits = 9;
  static constexpr size_t kSegmentBytes = 17 + 256;  // the largest piece of a segment gathered at once
  static constexpr size_t kMcuSampleBytes = 16 * 16 + 2 * 8 * 8;
  static constexpr size_t kPackedBytes = 16 * 16 * 3;
  static constexpr size_t kWorkspaceBytes =
      kTables * (HuffmanTable::workspace_bytes(kDcSymbols) + HuffmanTable::workspace_bytes(kAcSymbols)) +
      kTables * ((size_t{1} << kFastBits) * sizeof(uint16_t) + alignof(uint16_t)) +
      kQuantTables * 64 * sizeof(uint16_t) + alignof(uint16_t) + 64 * sizeof(int16_t) + alignof(int16_t) +
      kSegmentBytes + kMcuSampleBytes + kPackedBytes;

  // Carves the workspace (workspace_too_small if it does not fit).
  Status init(Arena& arena);
  // Starts a new JPEG; the target is checked against the frame header when
  // it arrives (invalid_argument if it does not suit the image).
  Status start(const ImageTarget& target);
  // Consumes the next piece of the file. more_input until EOI, then ok
  // (bytes after EOI are ignored); errors are latched.
  Status feed(const uint8_t* data, size_t size);
  // start + feed of a whole file; a file without EOI is truncated.
  Status decode(const uint8_t* data, size_t size, const ImageTarget& target);

  bool have_info() const { return have_frame_; }
  const JpegInfo& info() const { return info_; }
  Status status() const { return status_; }
  // What was wrong or unsupported ("" with VDS_CONFIG_STATUS_NAMES == 0).
  const char* error_detail() const { return detail_; }
  uint32_t mcus_decoded() const { return mcu_; }

 private:
  enum class State : uint8_t { soi, marker, length, segment, scan, restart, done, failed };
  struct Component {
    uint8_t id, h, v, tq;
    uint8_t td, ta;  // Huffman table selectors of the scan
    int32_t pred;    // DC predictor
  };

  Status fail(Status s, const char* detail);
  Status consume_markers(const uint8_t*& p, const uint8_t* end);
  Status segment_bytes(const uint8_t*& p, const uint8_t* end);
  Status on_sof(const uint8_t* s, uint32_t n);
  Status on_sos(const uint8_t* s, uint32_t n);
  Status on_dqt_table(const uint8_t* s);
  Status on_dht_table(const uint8_t* s);
  Status scan(const uint8_t*& p, const uint8_t* end);
  Status restart(const uint8_t*& p, const uint8_t* end);
  void fill(const uint8_t*& p, const uint8_t* end);
  int decode_block(const uint8_t*& p, const uint8_t* end, Component& c);
  Status finish_block(int comp, int bx, int by);
  Status output_mcu();
  // Ends an entropy-coded segment: drops the bit buffer (its padding) and goes on in `next`.
  Status end_segment(State next);
  void build_fast(int t, const uint8_t* counts, const uint8_t* symbols);

  // Workspace.
  HuffmanTable dc_[kTables];
  HuffmanTable ac_[kTables];
  uint16_t* fast_[kTables] = {};  // kFastBits lookup: value << 8 | run << 4 | length; 0 = slow path
  uint16_t* quant_ = nullptr;      // kQuantTables x 64, zig-zag order
  int16_t* coef_ = nullptr;
  uint8_t* seg_ = nullptr;
  uint8_t* mcu_pix_ = nullptr;
  uint8_t* packed_ = nullptr;

  ImageTarget target_{};
  JpegInfo info_{};
  Component comp_[3] = {};
  uint8_t ncomp_ = 0;
  uint8_t hmax_ = 1, vmax_ = 1;
  uint8_t quant_defined_ = 0;  // bit per table
  uint8_t dc_defined_ = 0, ac_defined_ = 0;
  bool have_frame_ = false;
  bool have_scan_ = false;
  bool started_ = false;
  State state_ = State::failed;
  Status status_ = Status::invalid_argument;
  const char* detail_ = "";

  // Marker / segment parsing.
  uint8_t marker_ = 0;
  uint8_t ff_seen_ = 0;        // a 0xFF that may start a marker was consumed
  uint16_t seg_left_ = 0;      // bytes of the current segment still to come
  uint16_t need_ = 0;          // bytes to gather into seg_ before the next step
  uint16_t have_ = 0;          // bytes gathered
  uint8_t part_ = 0;           // step within a DQT/DHT segment
  uint8_t len_bytes_[2] = {};
  uint8_t len_have_ = 0;
  uint16_t restart_interval_ = 0;

  // Scan position and entropy decoder state.
  uint32_t acc_ = 0;      // bit buffer, next bit in bit 31
  int32_t bits_ = 0;      // valid bits in acc_
  int32_t zeros_ = 0;     // of which zero padding after a marker
  bool marker_hit_ = false;
  bool pending_ff_ = false;  // a piece ended with 0xFF inside entropy-coded data
  uint32_t mcu_ = 0;
  uint32_t mcus_x_ = 0, mcu_total_ = 0;
  uint16_t restarts_left_ = 0;
  uint8_t next_rst_ = 0;
  uint8_t blk_ = 0;       // block index within the MCU
  uint8_t k_ = 0;         // next coefficient (0 = DC) of a block in progress
  uint8_t pending_s_ = 0; // extra bits still to read for coefficient k_ (0 = none)
  bool pending_dc_ = false;
  bool any_ac_ = false;
};

}  // namespace vds
