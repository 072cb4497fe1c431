// vds image codec, client decoder: MCUs of 8x8 DCT blocks, run/level coded
// with the context-adaptive binary range coder (vds/arith.h, decoded by its
// inlined twin image_model::RangeDecoder), inverse transformed by the
// integer IDCT (vds/idct.h). Syntax: vds/image_model.h.
#include <cstddef>
#include <cstring>

#include "image_output.h"
#include "vds/idct.h"
#include "vds/image.h"
#include "vds/bytes.h"

namespace vds {

namespace m = image_model;

namespace {

// Offsets of the planes inside the MCU sample buffer: Y 16x16 (stride 16)
// or 8x8 (stride 8), Cb and Cr 8x8 each (stride 8).
constexpr int kMcuCbOffset = 256;
constexpr int kMcuCrOffset = 320;
constexpr int kChromaStride = 8;

using Info = ImageDecoder::BlockInfo;

// nz_suffix[0] is never coded (the suffix starts at bit length 2), so the
// decoder keeps it at zero: a context whose bins are all ones and cost
// nothing. RangeDecoder::bit() on it finds bound = 0, so the bin is 1, range
// and code stay as they are, and the update leaves the zero in place.
constexpr size_t kAlwaysOneOffset = offsetof(m::PackedClassContexts, nz_suffix);
constexpr m::PackedContext kAlwaysOne = 0;


// Blocks per MCU of component c, across and down.
inline int blocks_w(const ImageHeader& h, int c) { return (c == 0 && h.chroma == ChromaFormat::yuv420) ? 2 : 1; }

detail::OutputGeometry geometry(const ImageHeader& h) {
  const int sub = h.chroma == ChromaFormat::yuv420 ? 1 : 0;
  return {h.width, h.height, h.mcu_size(), h.mcu_size(), h.components(), sub, sub};
}

}  // namespace

Status ImageDecoder::init(Arena& arena) {
  const size_t mark = arena.mark();
  ctx_ = arena.alloc_array<m::PackedContexts>(1);
  coef_ = arena.alloc_array<int16_t>(64);
  mcu_pix_ = arena.alloc_array<uint8_t>(kMcuSampleBytes);
  packed_ = arena.alloc_array<uint8_t>(kPackedBytes);
  started_ = false;
  if (ctx_ == nullptr || coef_ == nullptr || mcu_pix_ == nullptr || packed_ == nullptr) {
    arena.rewind(mark);
    ctx_ = nullptr;
    status_ = Status::workspace_too_small;
    return status_;
  }
  status_ = Status::ok;
  return status_;
}

Status ImageDecoder::start(const uint8_t* imgh, uint32_t size, const ImageTarget& target) {
  started_ = false;
  if (ctx_ == nullptr) return status_ = Status::invalid_argument;
  ImageHeader h;
  Status s = image_header_from_bytes(imgh, size, &h);
  if (s != Status::ok) return status_ = s;
  s = detail::check_target(target, geometry(h), h.residual());
  if (s != Status::ok) return status_ = s;
  header_ = h;
  target_ = target;
  // The tables come in zig-zag order; the level loop wants natural order.
  uint16_t zz[64];
  for (int c = 0; c < 2; ++c) {
    image_quant_table(c == 0 ? h.quant_luma : h.quant_chroma, h.slope, c == 1, zz);
    for (int k = 0; k < 64; ++k) quant_[c][m::kZigzag[k]] = zz[k];
  }
  m::init_contexts(*ctx_, h.quant_luma, h.quant_chroma);
  for (m::PackedClassContexts& cc : ctx_->cls) cc.nz_suffix[0] = kAlwaysOne;
  std::memset(cur_, 0, sizeof cur_);
  std::memset(left_, 0, sizeof left_);
  std::memset(row_start_, 0, sizeof row_start_);
  std::memset(last_dc_, 0, sizeof last_dc_);
  std::memset(last_nz_, 0, sizeof last_nz_);
  std::memset(coef_, 0, kCoefBytes);
  next_mcu_ = 0;
  prev_coded_ = 1;
  started_ = true;
  return status_ = Status::ok;
}

Status ImageDecoder::on_chunk(uint32_t type, const uint8_t* payload, uint32_t size, const ImageTarget& target) {
  if (type == chunk::kImageHeader) {
    const Status s = start(payload, size, target);
    return s == Status::ok ? Status::more_input : s;
  }
  if (type == chunk::kImageData) return feed(payload, size);
  return Status::ok;
}

Status ImageDecoder::feed(const uint8_t* imgd, uint32_t size) {
  if (!started_) return status_ == Status::ok ? Status::invalid_argument : status_;
  if (status_ != Status::ok) return status_;
  if (imgd == nullptr) return status_ = Status::invalid_argument;
  const uint32_t total = header_.mcu_count();
  if (size < kImageDataPrefixBytes) return status_ = Status::malformed;
  const uint32_t first = load_le32(imgd);
  const uint32_t count = static_cast<uint32_t>(imgd[4] | (imgd[5] << 8));
  if (next_mcu_ == total || first != next_mcu_ || count == 0 || count > total - first)
    return status_ = Status::malformed;
  Status s = rd_.init(imgd + kImageDataPrefixBytes, size - kImageDataPrefixBytes);
  for (uint32_t i = 0; i < count && s == Status::ok; ++i) {
    s = decode_mcu(first + i);
    if (s == Status::ok) s = rd_.status;
  }
  if (clock_) clock_->enter(StageClock::idle);
  if (s == Status::ok) s = rd_.finish();
  if (s != Status::ok) return status_ = s;
  next_mcu_ = first + count;
  return next_mcu_ == total ? Status::ok : Status::more_input;
}

namespace {

// Zeroes a coefficient block with 8-byte stores (a memset call costs more
// for 128 bytes on a Cortex-M4); the builtin keeps it free of aliasing
// questions and of calls.
inline void clear_block(int16_t* coef) {
  const uint64_t zero = 0;
#pragma GCC unroll 16
  for (int i = 0; i < 16; ++i) __builtin_memcpy(coef + 4 * i, &zero, sizeof zero);
}

// The level loop walks one table, indexed by the count of levels still to
// code (1..63) and the scan index k (1..63), whose entry holds every byte
// offset that pair selects: the sig context's offset from the start of
// PackedClassContexts, the level contexts' offset within gt1 (and gt2),
// and the natural position times 2 (the byte offset of an int16_t or
// uint16_t element in natural order). The next scan position is the next
// entry; after a level, one row up (one level fewer). 16 KB of constants
// buys a loop that keeps only the walking pointer; the sig offset is a
// halfword of its own so that the hottest load needs no masking.
struct WalkEntry {
  uint16_t sig;
  uint8_t level;
  uint8_t natural2;
};
struct WalkTable {
  WalkEntry e[64][64];
};
constexpr size_t kCtxBytes = sizeof(m::PackedContext);
constexpr WalkTable make_walk_table() {
  WalkTable t{};
  for (int n = 0; n < 64; ++n) {
    for (int k = 0; k < 64; ++k) {
      // Where the remaining positions hold only the remaining levels (no
      // zeros left: k + n == 64), the bin is not coded: the always-one
      // context stands in for it.
      const size_t sig = k + n >= 64 ? kAlwaysOneOffset
                                     : offsetof(m::PackedClassContexts, sig) +
                                           (static_cast<size_t>(m::kSigLeftOf[n]) * m::kSigPos + m::kSigPosOf[k]) *
                                               kCtxBytes;
      const size_t level = (static_cast<size_t>(m::kLevelPosOf[k]) * m::kLevelLeft + m::kLevelLeftOf[n]) * kCtxBytes;
      t.e[n][k] = {static_cast<uint16_t>(sig), static_cast<uint8_t>(level), static_cast<uint8_t>(m::kZigzag[k] * 2)};
    }
  }
  return t;
}
constexpr WalkTable kWalk = make_walk_table();
static_assert(sizeof(m::PackedClassContexts) <= 65536 && sizeof(m::PackedClassContexts::gt1) <= 256,
              "walk table offsets fit their fields");
static_assert(sizeof(WalkEntry) == 4, "one word per walk entry");
constexpr int kWalkRow = 64;

inline __attribute__((always_inline)) m::PackedContext& context_at(uint8_t* base, uint32_t offset) {
  return *reinterpret_cast<m::PackedContext*>(base + offset);
}

// The levels of a block (nz >= 1) in zig-zag order: the sig bins find each
// nonzero position; none is coded where every remaining position must be
// nonzero, i.e. once the zeros the block can still hold (63 - nz at the
// start) run out, which the walk table handles with the always-one context.
// Returns 0, or -1 on a magnitude no encoder writes.
inline __attribute__((always_inline)) int decode_levels(m::RangeDecoder& rd, m::PackedClassContexts& cc, uint32_t nz,
                                                        int16_t* coef, const uint16_t* qnat) {
  uint32_t left = nz;
  int order = 0;
  const WalkEntry* tp = &kWalk.e[nz][1];
  uint8_t* base = reinterpret_cast<uint8_t*>(&cc);
  uint8_t* const out = reinterpret_cast<uint8_t*>(coef);
  const uint8_t* const qn = reinterpret_cast<const uint8_t*>(qnat);
  for (;;) {
    while (!rd.bit(context_at(base, tp->sig))) ++tp;
    uint8_t* const g = base + tp->level;
    uint32_t mag = 1;
    if (rd.bit(context_at(g, offsetof(m::PackedClassContexts, gt1)))) {
      mag = 2;
      if (rd.bit(context_at(g, offsetof(m::PackedClassContexts, gt2)))) {
        const uint32_t u = rd.exp_golomb(order);
        if (u > m::kMaxLevel - 3) return -1;
        if (u > (m::kRestRaise << order) && order < m::kRestMaxOrder) ++order;
        mag = 3 + u;
      }
    }
    // Dequantise (mag <= 2048 and steps <= 2047: no overflow), apply the
    // sign (a bypass bin, RangeDecoder::bypass(), decoded here) and
    // saturate to the IDCT's domain, [-2048, 2047]: one SSAT on a Cortex-M4.
    const uint32_t pos = tp->natural2;
    const int32_t v = static_cast<int32_t>(mag * *reinterpret_cast<const uint16_t*>(qn + pos));
    const uint32_t half = rd.range >> 1;
    int32_t value;
    if (rd.code >= half) {
      rd.code -= half;
      rd.range -= half;
      value = v > -kIdctCoefMin ? kIdctCoefMin : -v;
    } else {
      rd.range = half;
      value = v > kIdctCoefMax ? kIdctCoefMax : v;
    }
    if (rd.range < kArithRangeTop) rd.renormalise();
    *reinterpret_cast<int16_t*>(out + pos) = static_cast<int16_t>(value);
    if (--left == 0) return 0;
    tp += 1 - kWalkRow;
  }
}
static_assert(offsetof(image_model::PackedClassContexts, gt2) ==
                  offsetof(image_model::PackedClassContexts, gt1) + sizeof(image_model::PackedClassContexts::gt1),
              "decode_levels finds gt2 right after gt1");
}  // namespace

// One block: entropy decoding into coef (natural order, all zero on entry
// and on return), neighbour bookkeeping. Returns the count of nonzero AC
// levels, or -1 if the data are malformed. The range decoder is copied into
// a local for the block so that it lives in registers.
int ImageDecoder::decode_block(m::RangeDecoder& rdr, int comp, int bx, int by, bool first_col, int16_t* coef) {
  m::RangeDecoder rd = rdr;
  const int cls = comp == 0 ? 0 : 1;
  m::PackedClassContexts& cc = ctx_->cls[cls];
  const int bw = blocks_w(header_, comp);
  Info& me = cur_[comp][by * bw + bx];

  // Neighbours: left (this MCU or the previous one) and above (this MCU, or
  // for the first MCU of a row the first MCU of the row above).
  const Info none{0, 0, 0};
  const Info& l = bx > 0 ? cur_[comp][by * bw + bx - 1] : left_[comp][by];
  const Info& a = by > 0 ? cur_[comp][(by - 1) * bw + bx] : (first_col ? row_start_[comp][bx] : none);
  const bool has_l = (l.flags & kInfoAvailable) != 0, has_a = (a.flags & kInfoAvailable) != 0;

  int32_t pred_dc;
  uint32_t pred_nz;
  int cbf_ctx, dz_ctx;
  if (has_l && has_a) {
    pred_dc = (l.dc + a.dc) >> 1;
    pred_nz = (static_cast<uint32_t>(l.nz) + a.nz + 1) >> 1;
    cbf_ctx = ((l.flags & kInfoCoded) != 0) + ((a.flags & kInfoCoded) != 0);
    dz_ctx = ((l.flags & kInfoDcResidual) != 0) + ((a.flags & kInfoDcResidual) != 0);
  } else if (has_l || has_a) {
    const Info& n = has_l ? l : a;
    pred_dc = n.dc;
    pred_nz = n.nz;
    cbf_ctx = (n.flags & kInfoCoded) != 0 ? 2 : 0;
    dz_ctx = (n.flags & kInfoDcResidual) != 0 ? 2 : 0;
  } else {
    pred_dc = last_dc_[comp];
    pred_nz = last_nz_[comp];
    cbf_ctx = 1;
    dz_ctx = 1;
  }
  if ((header_.flags & kImageFlagDcPred) == 0) pred_dc = 0;

  const uint16_t* qnat = quant_[cls];  // natural order
  int32_t dc = pred_dc;
  uint32_t nz = 0;
  uint8_t flags = kInfoAvailable;
  int result = 0;
  if (rd.bit(cc.cbf[cbf_ctx])) {
    flags |= kInfoCoded;
    int32_t res = 0;
    if (rd.bit(cc.dc_zero[dz_ctx])) {
      uint32_t mag = 1;
      if (rd.bit(cc.dc_gt1[dz_ctx])) {
        mag = 2;
        if (rd.bit(cc.dc_gt2)) {
          const uint32_t u = rd.exp_golomb(m::kDcRestOrder);
          // |residual| <= 4095 between two DC levels of [-2048, 2047].
          if (u > static_cast<uint32_t>(m::kDcLevelMax - m::kDcLevelMin) - 3) result = -1;
          mag = 3 + u;
        }
      }
      res = rd.bypass() ? -static_cast<int32_t>(mag) : static_cast<int32_t>(mag);
      flags |= kInfoDcResidual;
    }
    dc += res;
    if (dc < m::kDcLevelMin || dc > m::kDcLevelMax) result = -1;

    // nz: prefix of its bit length; the "> 0" bin is implied by a zero DC residual.
    m::PackedContext* pre = cc.nz_prefix[m::kNzBucketOf[pred_nz]];
    int len = res == 0 ? 1 : rd.bit(pre[0]);
    if (len != 0)
      while (len < m::kNzPrefixBins && rd.bit(pre[len])) ++len;
    if (len <= 1) {
      nz = static_cast<uint32_t>(len);
    } else {
      nz = 2u | static_cast<uint32_t>(rd.bit(cc.nz_suffix[len]));
      for (int i = 2; i < len; ++i) nz = (nz << 1) | static_cast<uint32_t>(rd.bypass());
    }

    if (nz != 0 && result == 0) result = decode_levels(rd, cc, nz, coef, qnat);
  }
  rd.check_end();
  rdr = rd;
  if (result < 0) return result;
  const int32_t dcv = dc * qnat[0];
  coef[0] = static_cast<int16_t>(dcv < kIdctCoefMin ? kIdctCoefMin : (dcv > kIdctCoefMax ? kIdctCoefMax : dcv));
  me.dc = static_cast<int16_t>(dc);
  me.nz = static_cast<uint8_t>(nz);
  me.flags = flags;
  last_dc_[comp] = static_cast<int16_t>(dc);
  last_nz_[comp] = static_cast<uint8_t>(nz);
  return static_cast<int>(nz);
}

Status ImageDecoder::decode_mcu(uint32_t mcu) {
  const ImageHeader& h = header_;
  const int mx = static_cast<int>(mcu % static_cast<uint32_t>(h.mcus_x()));
  const int my = static_cast<int>(mcu / static_cast<uint32_t>(h.mcus_x()));
  const int ms = h.mcu_size();
  const int x0 = mx * ms, y0 = my * ms;
  const bool row_end = mx == h.mcus_x() - 1;
  const int ncomp = h.components();
  if (mx == 0) std::memset(left_, 0, sizeof left_);

  if (h.region()) {
    const int coded = rd_.bit(ctx_->region[prev_coded_]);
    rd_.check_end();
    prev_coded_ = static_cast<uint8_t>(coded);
    if (!coded) {
      std::memset(left_, 0, sizeof left_);
      if (mx == 0) std::memset(row_start_, 0, sizeof row_start_);
      // A packed target with a prediction shows the prediction where
      // nothing is coded: a band buffer holds no earlier frame.
      if (target_.planar || target_.predict == nullptr)
        return row_end ? detail::emit_band(target_, geometry(h), y0) : Status::ok;
      if (!fetch_prediction(x0, y0)) return Status::aborted;
      return deliver_mcu(x0, y0, row_end);
    }
  }

  const bool planes = target_.planar;
  const bool inside = x0 + ms <= h.width && y0 + ms <= h.height;
  const bool direct = planes && inside;  // reconstruct straight into the caller's planes
  const int sub = h.chroma == ChromaFormat::yuv420 ? 1 : 0;
  const int y_stride = ms;
  const int cx0 = x0 >> sub, cy0 = y0 >> sub;

  if (h.residual() && !direct && !fetch_prediction(x0, y0)) return Status::aborted;

  for (int c = 0; c < ncomp; ++c) {
    const int bw = blocks_w(h, c);
    for (int by = 0; by < bw; ++by) {
      for (int bx = 0; bx < bw; ++bx) {
        if (clock_) clock_->enter(StageClock::entropy);
        const int nz = decode_block(rd_, c, bx, by, mx == 0, coef_);
        if (clock_) clock_->enter(StageClock::transform);
        if (nz < 0) return Status::malformed;
        if (rd_.status != Status::ok) return rd_.status;
        uint8_t* dst;
        ptrdiff_t stride;
        if (direct) {
          stride = target_.stride[c];
          dst = c == 0 ? target_.data[0] + (y0 + 8 * by) * stride + x0 + 8 * bx
                       : target_.data[c] + cy0 * stride + cx0;
        } else {
          stride = c == 0 ? y_stride : kChromaStride;
          dst = c == 0 ? mcu_pix_ + 8 * by * y_stride + 8 * bx : mcu_pix_ + (c == 1 ? kMcuCbOffset : kMcuCrOffset);
        }
        if (nz == 0) {
          if (h.residual()) {
            if (coef_[0] != 0) idct8x8_add_dc(coef_[0], dst, stride);
          } else {
            idct8x8_put_dc(coef_[0], dst, stride);
          }
          coef_[0] = 0;
        } else {
          if (h.residual())
            idct8x8_add(coef_, dst, stride);
          else
            idct8x8_put(coef_, dst, stride);
          clear_block(coef_);
        }
      }
    }
    // Neighbours for the next MCU (right column) and the next MCU row
    // (bottom row of the first MCU).
    for (int r = 0; r < bw; ++r) left_[c][r] = cur_[c][r * bw + bw - 1];
    if (mx == 0)
      for (int b = 0; b < bw; ++b) row_start_[c][b] = cur_[c][(bw - 1) * bw + b];
  }

  if (clock_) clock_->enter(StageClock::colour);
  if (direct) return Status::ok;
  return deliver_mcu(x0, y0, row_end);
}

// Copies the part of the MCU at (x0, y0) inside the image between the
// sample buffer and a planar target's planes (`to_target`: buffer -> planes).
void ImageDecoder::copy_mcu_planes(int x0, int y0, bool to_target) {
  const ImageHeader& h = header_;
  const int ms = h.mcu_size();
  const int sub = h.chroma == ChromaFormat::yuv420 ? 1 : 0;
  const int w = (h.width - x0) < ms ? (h.width - x0) : ms;
  const int hh = (h.height - y0) < ms ? (h.height - y0) : ms;
  const int cx0 = x0 >> sub, cy0 = y0 >> sub;
  const int cw = ((x0 + w + sub) >> sub) - cx0, ch = ((y0 + hh + sub) >> sub) - cy0;
  for (int c = 0; c < h.components(); ++c) {
    uint8_t* buf = c == 0 ? mcu_pix_ : mcu_pix_ + (c == 1 ? kMcuCbOffset : kMcuCrOffset);
    const int buf_stride = c == 0 ? ms : kChromaStride;
    uint8_t* plane = c == 0 ? target_.data[0] + y0 * target_.stride[0] + x0 : target_.data[c] + cy0 * target_.stride[c] + cx0;
    for (int r = 0; r < (c == 0 ? hh : ch); ++r) {
      uint8_t* p = plane + r * target_.stride[c];
      uint8_t* b = buf + r * buf_stride;
      if (to_target)
        std::memcpy(p, b, c == 0 ? w : cw);
      else
        std::memcpy(b, p, c == 0 ? w : cw);
    }
  }
}

// The prediction of the MCU at (x0, y0) into the sample buffer: from the
// planes a planar target holds, else from the target's predict callback.
// Only pixels inside the image are ever read back, so the rest needs no
// defined value, but it is cleared to keep the output deterministic.
bool ImageDecoder::fetch_prediction(int x0, int y0) {
  const ImageHeader& h = header_;
  const int ms = h.mcu_size();
  std::memset(mcu_pix_, 0, kMcuSampleBytes);
  if (target_.planar) {
    copy_mcu_planes(x0, y0, false);
    return true;
  }
  const bool colour = h.components() == 3;
  const int w = (h.width - x0) < ms ? (h.width - x0) : ms;
  const int hh = (h.height - y0) < ms ? (h.height - y0) : ms;
  return target_.predict(target_.predict_ctx, static_cast<uint16_t>(x0), static_cast<uint16_t>(y0),
                         static_cast<uint16_t>(w), static_cast<uint16_t>(hh), mcu_pix_, ms,
                         colour ? mcu_pix_ + kMcuCbOffset : nullptr, colour ? mcu_pix_ + kMcuCrOffset : nullptr,
                         kChromaStride);
}

// The MCU at (x0, y0), whole in the sample buffer, to a target that is not
// written in place: the planes (a partial MCU on the right or bottom edge:
// what lies inside) or packed pixels.
Status ImageDecoder::deliver_mcu(int x0, int y0, bool row_end) {
  if (target_.planar) {
    copy_mcu_planes(x0, y0, true);
    return Status::ok;
  }
  const ImageHeader& h = header_;
  const int sub = h.chroma == ChromaFormat::yuv420 ? 1 : 0;
  const bool colour = h.components() == 3;
  const detail::McuSamples s{mcu_pix_, h.mcu_size(), colour ? mcu_pix_ + kMcuCbOffset : nullptr,
                             colour ? mcu_pix_ + kMcuCrOffset : nullptr, kChromaStride,
                             static_cast<uint8_t>(sub), static_cast<uint8_t>(sub)};
  return detail::deliver_packed(target_, geometry(h), s, x0, y0, row_end, packed_);
}

}  // namespace vds
