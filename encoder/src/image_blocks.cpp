// vds encoder: the block syntax of the vds image codec, coded with the
// context-adaptive range encoder; the mirror of decoder/src/image_decoder.cpp.
#include <cstring>
#include <stdexcept>

#include "image_coder.h"

namespace vds::enc::detail {

namespace m = image_model;

namespace {
int blocks_w(const ImageHeader& h, int c) { return (c == 0 && h.chroma == ChromaFormat::yuv420) ? 2 : 1; }
constexpr uint8_t kAvail = ImageDecoder::kInfoAvailable;
constexpr uint8_t kCoded = ImageDecoder::kInfoCoded;
constexpr uint8_t kDcRes = ImageDecoder::kInfoDcResidual;
}  // namespace

void CoderState::reset(int quant_luma, int quant_chroma) {
  m::init_contexts(ctx, quant_luma, quant_chroma);
  std::memset(cur, 0, sizeof cur);
  std::memset(left, 0, sizeof left);
  std::memset(row_start, 0, sizeof row_start);
  std::memset(last_dc, 0, sizeof last_dc);
  std::memset(last_nz, 0, sizeof last_nz);
  prev_coded = 1;
  counts = nullptr;
}

BlockEnv block_env(const CoderState& s, const ImageHeader& h, int comp, int bx, int by, bool first_col) {
  const int bw = blocks_w(h, comp);
  const Info none{0, 0, 0};
  const Info& l = bx > 0 ? s.cur[comp][by * bw + bx - 1] : s.left[comp][by];
  const Info& a = by > 0 ? s.cur[comp][(by - 1) * bw + bx] : (first_col ? s.row_start[comp][bx] : none);
  const bool has_l = (l.flags & kAvail) != 0, has_a = (a.flags & kAvail) != 0;
  BlockEnv e{};
  e.cls = comp == 0 ? 0 : 1;
  if (has_l && has_a) {
    e.pred_dc = (l.dc + a.dc) >> 1;
    e.pred_nz = (static_cast<uint32_t>(l.nz) + a.nz + 1) >> 1;
    e.cbf_ctx = ((l.flags & kCoded) != 0) + ((a.flags & kCoded) != 0);
    e.dz_ctx = ((l.flags & kDcRes) != 0) + ((a.flags & kDcRes) != 0);
  } else if (has_l || has_a) {
    const Info& n = has_l ? l : a;
    e.pred_dc = n.dc;
    e.pred_nz = n.nz;
    e.cbf_ctx = (n.flags & kCoded) != 0 ? 2 : 0;
    e.dz_ctx = (n.flags & kDcRes) != 0 ? 2 : 0;
  } else {
    e.pred_dc = s.last_dc[comp];
    e.pred_nz = s.last_nz[comp];
    e.cbf_ctx = 1;
    e.dz_ctx = 1;
  }
  if ((h.flags & kImageFlagDcPred) == 0) e.pred_dc = 0;
  return e;
}

void encode_block(ArithEncoder& ae, CoderState& s, const ImageHeader& h, const BlockEnv& env, int comp, int bx,
                  int by, const int32_t levels[64]) {
  m::ClassContexts& cc = s.ctx.cls[env.cls];
  const int32_t dc = levels[0];
  if (dc < m::kDcLevelMin || dc > m::kDcLevelMax) throw std::logic_error("encode_block: DC level out of range");
  const int32_t res = dc - env.pred_dc;
  uint32_t nz = 0;
  for (int k = 1; k < 64; ++k) nz += levels[k] != 0;
  const bool cbf = res != 0 || nz != 0;
  uint8_t flags = kAvail;
  code_bin(ae, s, cc.cbf[env.cbf_ctx], cbf ? 1 : 0);
  if (cbf) {
    flags |= kCoded;
    code_bin(ae, s, cc.dc_zero[env.dz_ctx], res != 0 ? 1 : 0);
    if (res != 0) {
      flags |= kDcRes;
      const uint32_t mag = static_cast<uint32_t>(res < 0 ? -res : res);
      code_bin(ae, s, cc.dc_gt1[env.dz_ctx], mag > 1);
      if (mag > 1) {
        code_bin(ae, s, cc.dc_gt2, mag > 2);
        if (mag > 2) ae.encode_exp_golomb(nullptr, 0, mag - 3, m::kDcRestOrder);
      }
      ae.encode_bypass(res < 0 ? 1 : 0);
    }
    // nz
    ArithContext* pre = cc.nz_prefix[m::kNzBucketOf[env.pred_nz]];
    const int len = m::nz_length(nz);
    if (res != 0) code_bin(ae, s, pre[0], len > 0 ? 1 : 0);
    if (len > 0) {
      for (int i = 1; i < m::kNzPrefixBins && i <= len; ++i) code_bin(ae, s, pre[i], len > i ? 1 : 0);
    }
    if (len >= 2) {
      code_bin(ae, s, cc.nz_suffix[len], static_cast<int>((nz >> (len - 2)) & 1u));
      for (int i = len - 3; i >= 0; --i) ae.encode_bypass(static_cast<int>((nz >> i) & 1u));
    }
    // Levels.
    uint32_t left = nz;
    int order = 0;
    for (int k = 1; left != 0; ++k) {
      const int32_t v = levels[k];
      if (static_cast<uint32_t>(64 - k) > left) code_bin(ae, s, cc.sig[m::kSigLeftOf[left]][m::kSigPosOf[k]], v != 0);
      if (v == 0) continue;
      const uint32_t mag = static_cast<uint32_t>(v < 0 ? -v : v);
      if (mag > m::kMaxLevel) throw std::logic_error("encode_block: level out of range");
      const int lp = m::kLevelPosOf[k], lb = m::kLevelLeftOf[left];
      code_bin(ae, s, cc.gt1[lp][lb], mag > 1);
      if (mag > 1) {
        code_bin(ae, s, cc.gt2[lp][lb], mag > 2);
        if (mag > 2) {
          const uint32_t u = mag - 3;
          ae.encode_exp_golomb(nullptr, 0, u, order);
          if (u > (m::kRestRaise << order) && order < m::kRestMaxOrder) ++order;
        }
      }
      ae.encode_bypass(v < 0 ? 1 : 0);
      --left;
    }
  }
  const int bw = blocks_w(h, comp);
  Info& me = s.cur[comp][by * bw + bx];
  me.dc = static_cast<int16_t>(dc);
  me.nz = static_cast<uint8_t>(nz);
  me.flags = flags;
  s.last_dc[comp] = static_cast<int16_t>(dc);
  s.last_nz[comp] = static_cast<uint8_t>(nz);
}

void end_mcu(CoderState& s, const ImageHeader& h, int mx) {
  for (int c = 0; c < h.components(); ++c) {
    const int bw = blocks_w(h, c);
    for (int r = 0; r < bw; ++r) s.left[c][r] = s.cur[c][r * bw + bw - 1];
    if (mx == 0)
      for (int b = 0; b < bw; ++b) s.row_start[c][b] = s.cur[c][(bw - 1) * bw + b];
  }
}

void skip_mcu(CoderState& s, int mx) {
  std::memset(s.left, 0, sizeof s.left);
  if (mx == 0) std::memset(s.row_start, 0, sizeof s.row_start);
}

}  // namespace vds::enc::detail
