// Baseline JPEG, client side: marker and segment parsing (ITU-T T.81 Annex
// B: SOI, SOF0/SOF1, DHT, DQT, DRI, SOS, EOI; APPn/COM skipped), resumable
// at any byte, and refusal of the processes this decoder leaves out.
#include <cstring>

#include "image_output.h"
#include "vds/config.h"
#include "vds/jpeg.h"

namespace vds {

namespace {

// Marker codes (the byte after 0xFF), T.81 table B.1.
constexpr uint8_t kSof0 = 0xC0, kSof1 = 0xC1, kDht = 0xC4, kJpgExt = 0xC8, kDac = 0xCC;
constexpr uint8_t kRst0 = 0xD0, kRst7 = 0xD7, kSoi = 0xD8, kEoi = 0xD9, kSos = 0xDA, kDqt = 0xDB, kDnl = 0xDC,
                  kDri = 0xDD, kDhp = 0xDE, kExp = 0xDF, kApp0 = 0xE0, kApp15 = 0xEF, kJpg0 = 0xF0,
                  kJpg13 = 0xFD, kCom = 0xFE, kTem = 0x01;

constexpr bool is_sof(uint8_t m) { return m >= 0xC0 && m <= 0xCF && m != kDht && m != kJpgExt && m != kDac; }
constexpr bool is_progressive(uint8_t m) { return m == 0xC2 || m == 0xC6 || m == 0xCA || m == 0xCE; }
constexpr bool is_arithmetic(uint8_t m) { return m >= 0xC9 && m <= 0xCF && m != kDac; }

uint16_t be16(const uint8_t* p) { return static_cast<uint16_t>((p[0] << 8) | p[1]); }

// Why a frame header is refused, or nullptr if this decoder takes it.
const char* refusal(uint8_t m) {
  if (is_progressive(m))
    return is_arithmetic(m) ? VDS_DETAIL("progressive arithmetic-coded JPEG is not supported")
                            : VDS_DETAIL("progressive JPEG is not supported");
  if (is_arithmetic(m)) return VDS_DETAIL("arithmetic-coded JPEG is not supported");
  if (m == 0xC3 || m == 0xC7 || m == 0xCB || m == 0xCF) return VDS_DETAIL("lossless JPEG is not supported");
  if (m == 0xC5 || m == 0xC6 || m == 0xC7) return VDS_DETAIL("hierarchical JPEG is not supported");
  return nullptr;
}

// Checks a frame header's fields (shared by the decoder and jpeg_peek_info).
Status parse_frame(const uint8_t* s, uint32_t n, JpegInfo* info, uint8_t ids[3], uint8_t hv[3], uint8_t tq[3],
                   const char** why) {
  if (n < 6) {
    *why = VDS_DETAIL("frame header too short");
    return Status::malformed;
  }
  const int nf = s[5];
  if (n != 6u + 3u * nf) {
    *why = VDS_DETAIL("frame header length does not match its component count");
    return Status::malformed;
  }
  if (s[0] != 8) {
    *why = VDS_DETAIL("only 8-bit samples are supported");
    return Status::unsupported_feature;
  }
  const uint16_t height = be16(s + 1), width = be16(s + 3);
  if (width == 0) {
    *why = VDS_DETAIL("frame width is zero");
    return Status::malformed;
  }
  if (height == 0) {
    *why = VDS_DETAIL("height defined by DNL is not supported");
    return Status::unsupported_feature;
  }
  if (nf != 1 && nf != 3) {
    *why = VDS_DETAIL("only 1- and 3-component JPEG is supported");
    return Status::unsupported_feature;
  }
  for (int i = 0; i < nf; ++i) {
    const uint8_t* c = s + 6 + 3 * i;
    const int h = c[1] >> 4, v = c[1] & 15;
    if (h < 1 || h > 4 || v < 1 || v > 4 || c[2] > 3) {
      *why = VDS_DETAIL("bad sampling factor or quantisation table in the frame header");
      return Status::malformed;
    }
    ids[i] = c[0];
    hv[i] = c[1];
    tq[i] = c[2];
  }
  info->width = width;
  info->height = height;
  info->components = static_cast<uint8_t>(nf);
  info->sub_x = info->sub_y = 0;
  if (nf == 3) {
    const int h0 = hv[0] >> 4, v0 = hv[0] & 15;
    if (h0 > 2 || v0 > 2 || hv[1] != 0x11 || hv[2] != 0x11) {
      *why = VDS_DETAIL("sampling factors other than 4:4:4, 4:2:2, 4:4:0 and 4:2:0 are not supported");
      return Status::unsupported_feature;
    }
    if ((ids[0] == 'R' && ids[1] == 'G' && ids[2] == 'B')) {
      *why = VDS_DETAIL("RGB-coded JPEG is not supported");
      return Status::unsupported_feature;
    }
    info->sub_x = static_cast<uint8_t>(h0 - 1);
    info->sub_y = static_cast<uint8_t>(v0 - 1);
  }
  return Status::ok;
}

}  // namespace

Status jpeg_peek_info(const uint8_t* data, size_t size, JpegInfo* info, const char** detail) {
  const char* why = "";
  if (detail != nullptr) *detail = why;
  if (info == nullptr || (data == nullptr && size != 0)) return Status::invalid_argument;
  if (size < 2) return Status::truncated;
  if (data[0] != 0xFF || data[1] != kSoi) {
    if (detail != nullptr) *detail = VDS_DETAIL("not a JPEG file (no SOI marker)");
    return Status::malformed;
  }
  JpegInfo out;
  bool have_frame = false;
  size_t i = 2;
  for (;;) {
    if (i + 2 > size) break;
    if (data[i] != 0xFF) {
      if (detail != nullptr) *detail = VDS_DETAIL("data between markers");
      return Status::malformed;
    }
    const uint8_t m = data[i + 1];
    if (m == 0xFF) {  // fill byte
      ++i;
      continue;
    }
    i += 2;
    if (m == kTem || (m >= kRst0 && m <= kRst7)) continue;
    if (m == kEoi || m == kSoi) {
      if (detail != nullptr) *detail = VDS_DETAIL("no frame header before EOI");
      return Status::malformed;
    }
    if (i + 2 > size) break;
    const uint16_t len = be16(data + i);
    if (len < 2) {
      if (detail != nullptr) *detail = VDS_DETAIL("marker segment length below 2");
      return Status::malformed;
    }
    if (m == kDac) {
      if (detail != nullptr) *detail = VDS_DETAIL("arithmetic-coded JPEG is not supported");
      return Status::unsupported_feature;
    }
    if (is_sof(m)) {
      if (const char* r = refusal(m)) {
        if (detail != nullptr) *detail = r;
        return Status::unsupported_feature;
      }
      if (i + len > size) return Status::truncated;
      uint8_t ids[3], hv[3], tq[3];
      const Status s = parse_frame(data + i + 2, len - 2u, &out, ids, hv, tq, &why);
      if (s != Status::ok) {
        if (detail != nullptr) *detail = why;
        return s;
      }
      have_frame = true;
    } else if (m == kDri && i + 4 <= size && len == 4) {
      out.restart_interval = be16(data + i + 2);
    } else if (m == kSos) {
      break;
    }
    i += len;
  }
  if (!have_frame) return Status::truncated;
  *info = out;
  return Status::ok;
}

Status JpegDecoder::init(Arena& arena) {
  const size_t mark = arena.mark();
  Status s = Status::ok;
  for (int t = 0; t < kTables && s == Status::ok; ++t) {
    s = dc_[t].reserve(arena, kDcSymbols);
    if (s == Status::ok) s = ac_[t].reserve(arena, kAcSymbols);
    if (s == Status::ok) {
      fast_[t] = arena.alloc_array<uint16_t>(size_t{1} << kFastBits);
      if (fast_[t] == nullptr) s = Status::workspace_too_small;
    }
  }
  if (s == Status::ok) {
    quant_ = arena.alloc_array<uint16_t>(kQuantTables * 64);
    coef_ = arena.alloc_array<int16_t>(64);
    seg_ = arena.alloc_array<uint8_t>(kSegmentBytes);
    mcu_pix_ = arena.alloc_array<uint8_t>(kMcuSampleBytes);
    packed_ = arena.alloc_array<uint8_t>(kPackedBytes);
    if (quant_ == nullptr || coef_ == nullptr || seg_ == nullptr || mcu_pix_ == nullptr || packed_ == nullptr)
      s = Status::workspace_too_small;
  }
  started_ = false;
  if (s != Status::ok) {
    arena.rewind(mark);
    quant_ = nullptr;
    status_ = s;
    return s;
  }
  status_ = Status::ok;
  return s;
}

Status JpegDecoder::fail(Status s, const char* detail) {
  status_ = s;
  detail_ = detail;
  state_ = State::failed;
  return s;
}

Status JpegDecoder::start(const ImageTarget& target) {
  if (quant_ == nullptr) return status_ = Status::invalid_argument;
  target_ = target;
  info_ = JpegInfo{};
  ncomp_ = 0;
  hmax_ = vmax_ = 1;
  quant_defined_ = dc_defined_ = ac_defined_ = 0;
  have_frame_ = have_scan_ = false;
  state_ = State::soi;
  status_ = Status::ok;
  detail_ = "";
  marker_ = 0;
  ff_seen_ = 0;
  seg_left_ = need_ = have_ = 0;
  part_ = 0;
  len_have_ = 0;
  restart_interval_ = 0;
  acc_ = 0;
  bits_ = zeros_ = 0;
  marker_hit_ = pending_ff_ = false;
  mcu_ = mcus_x_ = mcu_total_ = 0;
  blk_ = k_ = pending_s_ = 0;
  pending_dc_ = any_ac_ = false;
  std::memset(coef_, 0, 64 * sizeof(int16_t));
  started_ = true;
  return Status::ok;
}

Status JpegDecoder::decode(const uint8_t* data, size_t size, const ImageTarget& target) {
  Status s = start(target);
  if (s != Status::ok) return s;
  s = feed(data, size);
  if (s == Status::more_input) return fail(Status::truncated, VDS_DETAIL("the file ends before EOI"));
  return s;
}

Status JpegDecoder::feed(const uint8_t* data, size_t size) {
  if (!started_) return Status::invalid_argument;
  if (state_ == State::failed) return status_;
  if (state_ == State::done) return Status::ok;
  if (data == nullptr && size != 0) return fail(Status::invalid_argument, "");
  const uint8_t* p = data;
  const uint8_t* const end = data + size;
  for (;;) {
    Status s;
    if (state_ == State::scan)
      s = scan(p, end);
    else if (state_ == State::restart)
      s = restart(p, end);
    else if (state_ == State::done)
      return Status::ok;
    else
      s = consume_markers(p, end);
    if (s != Status::ok) return s;
  }
}

// Reads markers and segments until the state changes to scan/done, the
// piece ends (more_input) or an error.
Status JpegDecoder::consume_markers(const uint8_t*& p, const uint8_t* end) {
  for (;;) {
    if (state_ == State::segment) {
      const Status s = segment_bytes(p, end);
      if (s != Status::ok || state_ != State::marker) return s;
      continue;
    }
    if (p == end) return Status::more_input;
    if (state_ == State::length) {
      len_bytes_[len_have_++] = *p++;
      if (len_have_ < 2) continue;
      const uint16_t len = be16(len_bytes_);
      if (len < 2) return fail(Status::malformed, VDS_DETAIL("marker segment length below 2"));
      seg_left_ = static_cast<uint16_t>(len - 2);
      have_ = 0;
      part_ = 0;
      switch (marker_) {
        case kSof0:
        case kSof1:
        case kSos:
        case kDri:
          if (seg_left_ > kSegmentBytes) return fail(Status::malformed, VDS_DETAIL("marker segment too long"));
          need_ = seg_left_;
          break;
        case kDqt:
          need_ = 1;
          break;
        case kDht:
          need_ = 17;
          break;
        default:
          need_ = 0;  // skipped
      }
      state_ = State::segment;
      continue;
    }
    // state soi or marker: 0xFF, fill bytes, then the code.
    const uint8_t b = *p++;
    if (!ff_seen_) {
      if (b != 0xFF)
        return fail(Status::malformed, state_ == State::soi ? VDS_DETAIL("not a JPEG file (no SOI marker)")
                                                            : VDS_DETAIL("data between markers"));
      ff_seen_ = 1;
      continue;
    }
    if (b == 0xFF) continue;  // fill byte
    ff_seen_ = 0;
    marker_ = b;
    if (state_ == State::soi) {
      if (b != kSoi) return fail(Status::malformed, VDS_DETAIL("not a JPEG file (no SOI marker)"));
      state_ = State::marker;
      continue;
    }
    if (b == kTem) continue;
    if (b == kEoi) {
      if (!have_scan_ || mcu_ != mcu_total_)
        return fail(Status::malformed, VDS_DETAIL("EOI before the image data is complete"));
      state_ = State::done;
      return Status::ok;
    }
    if (b == kSoi || b == 0x00 || (b >= kRst0 && b <= kRst7))
      return fail(Status::malformed, VDS_DETAIL("unexpected marker"));
    if (b == kDac) return fail(Status::unsupported_feature, VDS_DETAIL("arithmetic-coded JPEG is not supported"));
    if (is_sof(b)) {
      if (const char* r = refusal(b)) return fail(Status::unsupported_feature, r);
    }
    if (b == kDnl) return fail(Status::unsupported_feature, VDS_DETAIL("DNL marker is not supported"));
    if (b == kDhp || b == kExp)
      return fail(Status::unsupported_feature, VDS_DETAIL("hierarchical JPEG is not supported"));
    if (b == kJpgExt) return fail(Status::unsupported_feature, VDS_DETAIL("JPEG extension marker"));
    if (b == kSos && have_scan_)
      return fail(Status::unsupported_feature, VDS_DETAIL("more than one scan is not supported"));
    const bool known = b == kSof0 || b == kSof1 || b == kDht || b == kDqt || b == kDri || b == kSos ||
                       (b >= kApp0 && b <= kApp15) || b == kCom || (b >= kJpg0 && b <= kJpg13);
    if (!known) return fail(Status::malformed, VDS_DETAIL("unknown marker"));
    len_have_ = 0;
    state_ = State::length;
  }
}

// Bytes of a marker segment: skipped, or gathered into seg_ piece by piece.
Status JpegDecoder::segment_bytes(const uint8_t*& p, const uint8_t* end) {
  for (;;) {
    if (need_ == 0) {  // skipping
      const size_t avail = static_cast<size_t>(end - p);
      const size_t n = avail < seg_left_ ? avail : seg_left_;
      p += n;
      seg_left_ = static_cast<uint16_t>(seg_left_ - n);
      if (seg_left_ != 0) return Status::more_input;
      state_ = State::marker;
      return Status::ok;
    }
    if (need_ - have_ > seg_left_) return fail(Status::malformed, VDS_DETAIL("marker segment too short"));
    while (have_ < need_) {
      if (p == end) return Status::more_input;
      seg_[have_++] = *p++;
      --seg_left_;
    }
    Status s = Status::ok;
    switch (marker_) {
      case kSof0:
      case kSof1:
        s = on_sof(seg_, have_);
        break;
      case kSos:
        s = on_sos(seg_, have_);
        if (s == Status::ok) return Status::ok;  // state is scan
        break;
      case kDri:
        if (have_ != 2) return fail(Status::malformed, VDS_DETAIL("DRI segment length is not 4"));
        restart_interval_ = be16(seg_);
        if (!have_scan_) info_.restart_interval = restart_interval_;
        break;
      case kDqt:
        if (part_ == 0) {
          const int pq = seg_[0] >> 4;
          if (pq > 1) return fail(Status::malformed, VDS_DETAIL("DQT precision above 16 bits"));
          if ((seg_[0] & 15) >= kQuantTables) return fail(Status::malformed, VDS_DETAIL("DQT table index above 3"));
          part_ = 1;
          need_ = static_cast<uint16_t>(1 + (pq ? 128 : 64));
          continue;
        }
        s = on_dqt_table(seg_);
        if (s == Status::ok && seg_left_ > 0) {
          part_ = 0;
          have_ = 0;
          need_ = 1;
          continue;
        }
        break;
      case kDht:
        if (part_ == 0) {
          uint32_t total = 0;
          for (int i = 0; i < 16; ++i) total += seg_[1 + i];
          if (total > kAcSymbols) return fail(Status::malformed, VDS_DETAIL("DHT with more than 256 codes"));
          part_ = 1;
          need_ = static_cast<uint16_t>(17 + total);
          continue;
        }
        s = on_dht_table(seg_);
        if (s == Status::ok && seg_left_ > 0) {
          part_ = 0;
          have_ = 0;
          need_ = 17;
          continue;
        }
        break;
      default:
        break;
    }
    if (s != Status::ok) return s;
    if (seg_left_ != 0) return fail(Status::malformed, VDS_DETAIL("marker segment longer than its content"));
    state_ = State::marker;
    return Status::ok;
  }
}

Status JpegDecoder::on_sof(const uint8_t* s, uint32_t n) {
  if (have_frame_) return fail(Status::malformed, VDS_DETAIL("second frame header"));
  uint8_t ids[3], hv[3], tq[3];
  const char* why = "";
  JpegInfo info = info_;
  const Status st = parse_frame(s, n, &info, ids, hv, tq, &why);
  if (st != Status::ok) return fail(st, why);
  info_ = info;
  ncomp_ = info.components;
  hmax_ = vmax_ = 1;
  for (int i = 0; i < ncomp_; ++i) {
    comp_[i] = Component{ids[i], static_cast<uint8_t>(hv[i] >> 4), static_cast<uint8_t>(hv[i] & 15), tq[i], 0, 0, 0};
    if (ncomp_ == 1) comp_[i].h = comp_[i].v = 1;  // a single-component scan codes one block per MCU
  }
  if (ncomp_ == 3) {
    hmax_ = comp_[0].h;
    vmax_ = comp_[0].v;
  }
  const detail::OutputGeometry g{info_.width, info_.height, 8 * hmax_, 8 * vmax_, ncomp_, info_.sub_x, info_.sub_y};
  if (detail::check_target(target_, g, false) != Status::ok)
    return fail(Status::invalid_argument, VDS_DETAIL("the target does not suit the image"));
  mcus_x_ = (info_.width + 8u * hmax_ - 1) / (8u * hmax_);
  mcu_total_ = mcus_x_ * ((info_.height + 8u * vmax_ - 1) / (8u * vmax_));
  have_frame_ = true;
  return Status::ok;
}

Status JpegDecoder::on_sos(const uint8_t* s, uint32_t n) {
  if (!have_frame_) return fail(Status::malformed, VDS_DETAIL("scan before the frame header"));
  const int ns = n > 0 ? s[0] : 0;
  if (ns < 1 || n != 1u + 2u * ns + 3u) return fail(Status::malformed, VDS_DETAIL("bad scan header length"));
  if (ns != ncomp_)
    return fail(Status::unsupported_feature, VDS_DETAIL("non-interleaved scans are not supported"));
  for (int i = 0; i < ns; ++i) {
    const uint8_t id = s[1 + 2 * i], tables = s[2 + 2 * i];
    if (id != comp_[i].id) return fail(Status::malformed, VDS_DETAIL("scan component not in frame order"));
    const int td = tables >> 4, ta = tables & 15;
    if (td > 3 || ta > 3) return fail(Status::malformed, VDS_DETAIL("bad Huffman table selector"));
    if (td >= kTables || ta >= kTables)
      return fail(Status::unsupported_feature, VDS_DETAIL("Huffman tables 2 and 3 are not supported"));
    if (!(dc_defined_ & (1u << td)) || !(ac_defined_ & (1u << ta)))
      return fail(Status::malformed, VDS_DETAIL("scan uses an undefined Huffman table"));
    if (!(quant_defined_ & (1u << comp_[i].tq)))
      return fail(Status::malformed, VDS_DETAIL("component uses an undefined quantisation table"));
    comp_[i].td = static_cast<uint8_t>(td);
    comp_[i].ta = static_cast<uint8_t>(ta);
    comp_[i].pred = 0;
  }
  const uint8_t* t = s + 1 + 2 * ns;
  if (t[0] != 0 || t[1] != 63 || t[2] != 0)
    return fail(Status::malformed, VDS_DETAIL("spectral selection or approximation in a sequential scan"));
  have_scan_ = true;
  acc_ = 0;
  bits_ = zeros_ = 0;
  marker_hit_ = pending_ff_ = false;
  mcu_ = 0;
  blk_ = k_ = pending_s_ = 0;
  pending_dc_ = any_ac_ = false;
  restarts_left_ = restart_interval_;
  next_rst_ = 0;
  state_ = State::scan;
  return Status::ok;
}

Status JpegDecoder::on_dqt_table(const uint8_t* s) {
  const int pq = s[0] >> 4, tq = s[0] & 15;
  uint16_t* q = quant_ + 64 * tq;
  for (int k = 0; k < 64; ++k) q[k] = pq ? be16(s + 1 + 2 * k) : s[1 + k];
  quant_defined_ = static_cast<uint8_t>(quant_defined_ | (1u << tq));
  return Status::ok;
}

Status JpegDecoder::on_dht_table(const uint8_t* s) {
  const int tc = s[0] >> 4, th = s[0] & 15;
  if (tc > 1 || th > 3) return fail(Status::malformed, VDS_DETAIL("bad DHT table class or index"));
  if (th >= kTables) return fail(Status::unsupported_feature, VDS_DETAIL("Huffman tables 2 and 3 are not supported"));
  const uint8_t* counts = s + 1;
  const uint8_t* symbols = s + 17;
  size_t total = 0;
  for (int i = 0; i < 16; ++i) total += counts[i];
  if (tc == 0) {
    if (total > kDcSymbols) return fail(Status::malformed, VDS_DETAIL("DC table with more than 16 codes"));
    if (dc_[th].build_from_counts(counts, symbols, total) != Status::ok)
      return fail(Status::malformed, VDS_DETAIL("bad Huffman table"));
    dc_defined_ = static_cast<uint8_t>(dc_defined_ | (1u << th));
  } else {
    if (ac_[th].build_from_counts(counts, symbols, total) != Status::ok)
      return fail(Status::malformed, VDS_DETAIL("bad Huffman table"));
    build_fast(th, counts, symbols);
    ac_defined_ = static_cast<uint8_t>(ac_defined_ | (1u << th));
  }
  return Status::ok;
}

// The fast AC table: every kFastBits-bit window whose leading bits are a
// code of length len and, for a coefficient, its s extra bits (len + s <=
// kFastBits, |value| < 128) resolves to value << 8 | run << 4 | (len + s).
// EOB (run 0) and ZRL (run 15) carry value 0. Codes are assigned
// canonically (T.81 Annex C).
void JpegDecoder::build_fast(int t, const uint8_t* counts, const uint8_t* symbols) {
  uint16_t* fast = fast_[t];
  std::memset(fast, 0, (size_t{1} << kFastBits) * sizeof(uint16_t));
  uint32_t code = 0;
  size_t idx = 0;
  for (int len = 1; len <= 16; ++len) {
    for (int i = 0; i < counts[len - 1]; ++i, ++idx, ++code) {
      if (len > kFastBits) continue;
      const int sym = symbols[idx];
      const int run = sym >> 4, s = sym & 15;
      const int spare = kFastBits - len;
      if (s == 0) {
        if (run != 0 && run != 15) continue;
        const uint16_t e = static_cast<uint16_t>(run << 4 | len);
        for (uint32_t j = 0; j < (1u << spare); ++j) fast[(code << spare) | j] = e;
        continue;
      }
      if (len + s > kFastBits || s > 7) continue;
      for (uint32_t extra = 0; extra < (1u << s); ++extra) {
        // T.81 F.2.2.1 EXTEND: values below 2^(s-1) are negative.
        const int v = extra < (1u << (s - 1)) ? static_cast<int>(extra) - (1 << s) + 1 : static_cast<int>(extra);
        const uint16_t e = static_cast<uint16_t>((static_cast<uint32_t>(v) & 0xFFu) << 8 | run << 4 | (len + s));
        const int rest = spare - s;
        const uint32_t base = (code << spare) | (extra << rest);
        for (uint32_t j = 0; j < (1u << rest); ++j) fast[base | j] = e;
      }
    }
    code <<= 1;
  }
}

}  // namespace vds
