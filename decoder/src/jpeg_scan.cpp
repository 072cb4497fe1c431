// Baseline JPEG, client side: the entropy-coded scan (ITU-T T.81 F.2.2:
// Huffman decoding of DC differences and AC run/size symbols, byte stuffing,
// restart intervals), dequantisation, the integer IDCT and MCU output.
// Resumable between any two Huffman codes when a piece of input ends.
#include <cstring>

#include "image_output.h"
#include "vds/config.h"
#include "vds/idct.h"
#include "vds/image_model.h"
#include "vds/jpeg.h"

namespace vds {

namespace {

using image_model::kZigzag;

// Bits a Huffman code can need: the longest code.
constexpr int kMaxCodeBits = 16;
// Largest magnitude categories of 8-bit baseline data (T.81 F.1.2.1, F.1.2.2).
constexpr int kMaxDcSize = 11;
constexpr int kMaxAcSize = 10;
// A DC predictor of valid 8-bit data stays far inside this.
constexpr int32_t kMaxDcPred = 2047;

constexpr int kMcuCbOffset = 256;
constexpr int kMcuCrOffset = 320;
constexpr int kChromaStride = 8;

// T.81 F.2.2.1 EXTEND: the s-bit value v as a signed difference.
inline int32_t extend(uint32_t v, int s) {
  return v < (1u << (s - 1)) ? static_cast<int32_t>(v) - (1 << s) + 1 : static_cast<int32_t>(v);
}

// Dequantised coefficient saturated to the IDCT's domain.
inline int16_t dequant(int32_t v, uint32_t q) {
  const int32_t x = v * static_cast<int32_t>(q);
  return static_cast<int16_t>(x < kIdctCoefMin ? kIdctCoefMin : (x > kIdctCoefMax ? kIdctCoefMax : x));
}

// Zeroes a coefficient block with 8-byte stores: the freestanding build
// turns a 128-byte memset into a call, which costs several times more on a
// Cortex-M4.
inline void clear_block(int16_t* coef) {
  const uint64_t zero = 0;
#pragma GCC unroll 16
  for (int i = 0; i < 16; ++i) __builtin_memcpy(coef + 4 * i, &zero, sizeof zero);
}

}  // namespace

// Tops the bit buffer up to more than 24 bits from the piece, undoing byte
// stuffing. At a marker it stops and supplies zero bits (counted in zeros_);
// at the end of the piece it stops short (the caller suspends).
void JpegDecoder::fill(const uint8_t*& p, const uint8_t* end) {
  while (bits_ <= 24) {
    if (marker_hit_) {
      bits_ += 8;
      zeros_ += 8;
      continue;
    }
    uint32_t b;
    if (pending_ff_) {  // the previous piece ended with 0xFF
      if (p == end) return;
      const uint8_t n = *p;
      if (n == 0x00) {
        ++p;
        pending_ff_ = false;
        b = 0xFF;
      } else if (n == 0xFF) {  // fill bytes before a marker
        ++p;
        continue;
      } else {  // a marker whose 0xFF is already consumed
        pending_ff_ = false;
        marker_hit_ = true;
        ff_seen_ = 1;
        continue;
      }
    } else {
      if (p == end) return;
      b = *p;
      if (b == 0xFF) {
        if (p + 1 == end) {
          ++p;
          pending_ff_ = true;
          return;
        }
        const uint8_t n = p[1];
        if (n == 0x00) {
          p += 2;
        } else if (n == 0xFF) {
          ++p;
          continue;
        } else {
          marker_hit_ = true;  // p stays on the marker's 0xFF
          continue;
        }
      } else {
        ++p;
      }
    }
    acc_ |= b << (24 - bits_);
    bits_ += 8;
  }
}

// One block into coef_ (natural order, dequantised). 1 = complete, 0 = the
// piece ended (state kept), -1 = malformed data.
int JpegDecoder::decode_block(const uint8_t*& p, const uint8_t* end, Component& c) {
  uint32_t acc = acc_;
  int32_t bits = bits_;
  int k = k_;
  const uint16_t* q = quant_ + 64 * c.tq;
  int16_t* const coef = coef_;
#define VDS_SYNC() (acc_ = acc, bits_ = bits)
#define VDS_LOAD() (acc = acc_, bits = bits_)
  // Tops the local bit buffer up: bytes other than 0xFF go straight in
  // (most of the data); a 0xFF, the end of the piece or a 0xFF left over
  // from the previous piece are fill()'s business.
  const auto top_up = [&]() __attribute__((always_inline)) {
    if (!pending_ff_) {
      while (bits <= 24 && p != end && *p != 0xFF) {
        acc |= static_cast<uint32_t>(*p++) << (24 - bits);
        bits += 8;
      }
    }
    if (bits < kMaxCodeBits) {
      VDS_SYNC();
      fill(p, end);
      VDS_LOAD();
    }
  };

  if (pending_s_ != 0) {  // a code was read before the last piece ended; its extra bits were not
    const int s = pending_s_;
    if (bits < s) {
      top_up();
      if (bits < s) return 0;
    }
    const int32_t v = extend(acc >> (32 - s), s);
    acc <<= s;
    bits -= s;
    pending_s_ = 0;
    if (pending_dc_) {
      pending_dc_ = false;
      c.pred += v;
      if (c.pred > kMaxDcPred || c.pred < -kMaxDcPred) return -1;
      coef[0] = dequant(c.pred, q[0]);
      k = 1;
    } else {
      coef[kZigzag[k]] = dequant(v, q[k]);
      any_ac_ = true;
      ++k;
    }
  }

  if (k == 0) {
    if (bits < kMaxCodeBits) {
      top_up();
      if (bits < kMaxCodeBits && !marker_hit_) return 0;
    }
    int len = 0;
    const int s = dc_[c.td].decode_window(acc >> 16, len);
    if (s < 0 || s > kMaxDcSize) return -1;
    acc <<= len;
    bits -= len;
    int32_t diff = 0;
    if (s != 0) {
      if (bits < s) {
        top_up();
        if (bits < s) {
          pending_s_ = static_cast<uint8_t>(s);
          pending_dc_ = true;
          k_ = 0;
          VDS_SYNC();
          return 0;
        }
      }
      diff = extend(acc >> (32 - s), s);
      acc <<= s;
      bits -= s;
    }
    c.pred += diff;
    if (c.pred > kMaxDcPred || c.pred < -kMaxDcPred) return -1;
    coef[0] = dequant(c.pred, q[0]);
    k = 1;
  }

  const uint16_t* fast = fast_[c.ta];
  const HuffmanTable& table = ac_[c.ta];
  while (k < 64) {
    if (bits < kMaxCodeBits) {
      top_up();
      if (bits < kMaxCodeBits && !marker_hit_) {
        k_ = static_cast<uint8_t>(k);
        VDS_SYNC();
        return 0;
      }
    }
    const uint32_t e = fast[acc >> (32 - kFastBits)];
    if (e != 0) {
      const int len = static_cast<int>(e & 15u), run = static_cast<int>((e >> 4) & 15u);
      const int32_t v = static_cast<int8_t>(e >> 8);
      acc <<= len;
      bits -= len;
      if (v == 0) {
        if (run == 0) break;  // EOB
        k += 16;              // ZRL
        continue;
      }
      k += run;
      if (k > 63) return -1;
      coef[kZigzag[k]] = dequant(v, q[k]);
      any_ac_ = true;
      ++k;
      continue;
    }
    int len = 0;
    const int sym = table.decode_window(acc >> 16, len);
    if (sym < 0) return -1;
    acc <<= len;
    bits -= len;
    const int run = sym >> 4, s = sym & 15;
    if (s == 0) {
      if (run == 15) {
        k += 16;
        continue;
      }
      if (run != 0) return -1;  // EOBn exists only in progressive scans
      break;
    }
    if (s > kMaxAcSize) return -1;
    k += run;
    if (k > 63) return -1;
    if (bits < s) {
      top_up();
      if (bits < s) {
        pending_s_ = static_cast<uint8_t>(s);
        k_ = static_cast<uint8_t>(k);
        VDS_SYNC();
        return 0;
      }
    }
    const int32_t v = extend(acc >> (32 - s), s);
    acc <<= s;
    bits -= s;
    coef[kZigzag[k]] = dequant(v, q[k]);
    any_ac_ = true;
    ++k;
  }
  VDS_SYNC();
#undef VDS_SYNC
#undef VDS_LOAD
  if (k > 64) return -1;  // a run of zeros past the end of the block
  // Bits taken from the zero padding after a marker: the data ran out.
  if (marker_hit_ && bits_ < zeros_) return -1;
  k_ = 0;
  return 1;
}

Status JpegDecoder::finish_block(int comp, int bx, int by) {
  const int mw = 8 * hmax_, mh = 8 * vmax_;
  const int mx = static_cast<int>(mcu_ % mcus_x_), my = static_cast<int>(mcu_ / mcus_x_);
  const int x0 = mx * mw, y0 = my * mh;
  const bool direct = target_.planar && x0 + mw <= info_.width && y0 + mh <= info_.height;
  uint8_t* dst;
  ptrdiff_t stride;
  if (direct) {
    stride = target_.stride[comp];
    dst = comp == 0 ? target_.data[0] + (y0 + 8 * by) * stride + x0 + 8 * bx
                    : target_.data[comp] + (y0 >> info_.sub_y) * stride + (x0 >> info_.sub_x);
  } else {
    stride = comp == 0 ? mw : kChromaStride;
    dst = comp == 0 ? mcu_pix_ + 8 * by * mw + 8 * bx : mcu_pix_ + (comp == 1 ? kMcuCbOffset : kMcuCrOffset);
  }
  if (any_ac_) {
    idct8x8_put(coef_, dst, stride);
    clear_block(coef_);
  } else {
    idct8x8_put_dc(coef_[0], dst, stride);
    coef_[0] = 0;
  }
  any_ac_ = false;
  return Status::ok;
}

Status JpegDecoder::output_mcu() {
  const int mw = 8 * hmax_, mh = 8 * vmax_;
  const int mx = static_cast<int>(mcu_ % mcus_x_), my = static_cast<int>(mcu_ / mcus_x_);
  const int x0 = mx * mw, y0 = my * mh;
  const bool inside = x0 + mw <= info_.width && y0 + mh <= info_.height;
  if (target_.planar) {
    if (inside) return Status::ok;  // reconstructed in place
    const int w = info_.width - x0 < mw ? info_.width - x0 : mw;
    const int h = info_.height - y0 < mh ? info_.height - y0 : mh;
    for (int r = 0; r < h; ++r) std::memcpy(target_.data[0] + (y0 + r) * target_.stride[0] + x0, mcu_pix_ + r * mw, w);
    if (ncomp_ == 3) {
      const int cx0 = x0 >> info_.sub_x, cy0 = y0 >> info_.sub_y;
      const int cw = ((x0 + w + info_.sub_x) >> info_.sub_x) - cx0;
      const int ch = ((y0 + h + info_.sub_y) >> info_.sub_y) - cy0;
      for (int c = 1; c < 3; ++c) {
        const uint8_t* src = mcu_pix_ + (c == 1 ? kMcuCbOffset : kMcuCrOffset);
        for (int r = 0; r < ch; ++r)
          std::memcpy(target_.data[c] + (cy0 + r) * target_.stride[c] + cx0, src + r * kChromaStride, cw);
      }
    }
    return Status::ok;
  }
  const detail::OutputGeometry g{info_.width, info_.height, mw, mh, ncomp_, info_.sub_x, info_.sub_y};
  const detail::McuSamples s{mcu_pix_, mw, ncomp_ == 3 ? mcu_pix_ + kMcuCbOffset : nullptr,
                             ncomp_ == 3 ? mcu_pix_ + kMcuCrOffset : nullptr, kChromaStride, info_.sub_x,
                             info_.sub_y};
  return detail::deliver_packed(target_, g, s, x0, y0, mx == static_cast<int>(mcus_x_) - 1, packed_);
}

Status JpegDecoder::scan(const uint8_t*& p, const uint8_t* end) {
  const int yblocks = ncomp_ == 3 ? hmax_ * vmax_ : 1;
  const int blocks = ncomp_ == 3 ? yblocks + 2 : 1;
  while (mcu_ < mcu_total_) {
    while (blk_ < blocks) {
      const int comp = blk_ < yblocks ? 0 : blk_ - yblocks + 1;
      const int bx = comp == 0 ? blk_ % hmax_ : 0, by = comp == 0 ? blk_ / hmax_ : 0;
      const int r = decode_block(p, end, comp_[comp]);
      if (r == 0) return Status::more_input;
      if (r < 0) return fail(Status::malformed, VDS_DETAIL("corrupt entropy-coded data"));
      finish_block(comp, bx, by);
      ++blk_;
    }
    const Status s = output_mcu();
    if (s != Status::ok) return fail(s, VDS_DETAIL("output callback aborted"));
    blk_ = 0;
    ++mcu_;
    if (restart_interval_ != 0 && mcu_ < mcu_total_ && --restarts_left_ == 0) {
      return end_segment(State::restart);
    }
  }
  return end_segment(State::marker);
}

Status JpegDecoder::end_segment(State next) {
  // The segment's last byte is padded with 1 bits; what is left in the bit
  // buffer is that padding.
  if (pending_ff_) ff_seen_ = 1;
  acc_ = 0;
  bits_ = zeros_ = 0;
  marker_hit_ = pending_ff_ = false;
  state_ = next;
  return Status::ok;
}

// Expects RSTn (n = next_rst_) after an interval, then restarts the
// predictors (T.81 F.2.1.3.1, E.2.4).
Status JpegDecoder::restart(const uint8_t*& p, const uint8_t* end) {
  for (;;) {
    if (p == end) return Status::more_input;
    const uint8_t b = *p++;
    if (!ff_seen_) {
      if (b != 0xFF) return fail(Status::malformed, VDS_DETAIL("restart marker missing"));
      ff_seen_ = 1;
      continue;
    }
    if (b == 0xFF) continue;
    ff_seen_ = 0;
    if (b != 0xD0 + next_rst_) return fail(Status::malformed, VDS_DETAIL("restart marker missing or out of order"));
    break;
  }
  next_rst_ = static_cast<uint8_t>((next_rst_ + 1) & 7);
  restarts_left_ = restart_interval_;
  for (int i = 0; i < ncomp_; ++i) comp_[i].pred = 0;
  state_ = State::scan;
  return Status::ok;
}

}  // namespace vds
