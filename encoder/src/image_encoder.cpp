// vds encoder: the vds image codec's MCU loop — forward DCT, RD-optimised
// levels, block coding, reconstruction with the client's integer IDCT, and
// packing whole MCUs into IMGD chunks (docs/texture-codec.md).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

#include "image_coder.h"
#include "vds/enc/dct.h"
#include "vds/enc/image_codec.h"
#include "vds/idct.h"

namespace vds::enc {

namespace m = image_model;
using detail::CoderState;

namespace {

// A plane padded to whole MCUs by replicating its last column and row.
struct Padded {
  int w = 0, h = 0;
  std::vector<uint8_t> px;
  uint8_t* at(int x, int y) { return px.data() + static_cast<size_t>(y) * w + x; }
  const uint8_t* at(int x, int y) const { return px.data() + static_cast<size_t>(y) * w + x; }
};

Padded pad(const Planes& p, int c, int pw, int ph) {
  Padded o;
  o.w = pw;
  o.h = ph;
  o.px.resize(static_cast<size_t>(pw) * ph);
  const int sw = p.plane_width(c), sh = p.plane_height(c);
  for (int y = 0; y < ph; ++y) {
    const uint8_t* src = p.row(c, std::min(y, sh - 1));
    for (int x = 0; x < pw; ++x) o.px[static_cast<size_t>(y) * pw + x] = src[std::min(x, sw - 1)];
  }
  return o;
}

// A quarter of the Annex K shape: the highest frequencies about 2.6x (luma)
// and 2.2x (chroma) coarser than the DC. docs/texture-codec.md weighs the
// slope against PSNR rate and client decoding time.
int default_slope() { return 4; }

// Distortion weights for RGB error: an error e in Cb (Cr) changes R, G, B
// by (0, -0.344, 1.772) e ((1.402, -0.714, 0) e); luma changes all three by
// e. Relative to luma: Cb (0.344^2 + 1.772^2) / 3, Cr (1.402^2 + 0.714^2) / 3,
// times the pixels a 4:2:0 chroma sample covers.
double component_weight(int c, ChromaFormat f) {
  if (c == 0) return 1.0;
  const double area = f == ChromaFormat::yuv420 ? 4.0 : 1.0;
  return area * (c == 1 ? (0.344136 * 0.344136 + 1.772 * 1.772) / 3.0 : (1.402 * 1.402 + 0.714136 * 0.714136) / 3.0);
}

// Lagrange multiplier for a luma quantiser index: lambda = k * step^2 with
// the base step 2^(index/32) (high-rate theory gives 2 ln2 / 12 = 0.1155),
// raised with the perceptual slope: the coarser high frequencies put the
// operating point of the whole table further out (measured on the training
// textures: the best factor is about 1 + slope / 4).
constexpr double kLambdaPerStep2 = 0.12;
double lambda_for(int index, int slope, double scale) {
  const double step = std::exp2(index / 32.0);
  return kLambdaPerStep2 * (1.0 + slope / 4.0) * scale * step * step;
}

void put_u32(std::vector<uint8_t>& v, uint32_t x) {
  for (int i = 0; i < 4; ++i) v.push_back(static_cast<uint8_t>(x >> (8 * i)));
}

}  // namespace

EncodedImage encode_planes_at(const Planes& src, int quant_luma, int quant_chroma, const ImageEncodeOptions& o) {
  if (src.width <= 0 || src.height <= 0 || src.width > kImageMaxSide || src.height > kImageMaxSide)
    throw std::invalid_argument("encode: image size must be 1.." + std::to_string(kImageMaxSide));
  if (src.chroma != o.chroma && !(o.chroma == ChromaFormat::grey && src.chroma == ChromaFormat::grey))
    throw std::invalid_argument("encode: source planes are not in the requested chroma format");
  const bool residual = o.mode == ImageMode::residual;
  const Planes* pred = o.prediction;
  if (residual && pred == nullptr) throw std::invalid_argument("encode: residual mode needs a prediction");
  if (pred != nullptr && (pred->width != src.width || pred->height != src.height || pred->chroma != src.chroma))
    throw std::invalid_argument("encode: prediction differs from the source in size or chroma format");

  ImageHeader h;
  h.chroma = src.chroma;
  h.flags = static_cast<uint8_t>((residual ? kImageFlagResidual : kImageFlagDcPred) |
                                 (o.region.empty() ? 0 : kImageFlagRegion));
  h.quant_luma = static_cast<uint8_t>(std::clamp(quant_luma, 0, kQuantIndexMax));
  h.quant_chroma = static_cast<uint8_t>(std::clamp(quant_chroma, 0, kQuantIndexMax));
  h.slope = static_cast<uint8_t>(std::clamp(o.slope < 0 ? default_slope() : o.slope, 0, kQuantSlopeMax));
  h.width = static_cast<uint16_t>(src.width);
  h.height = static_cast<uint16_t>(src.height);
  const uint32_t mcus = h.mcu_count();
  if (!o.region.empty() && o.region.size() != mcus)
    throw std::invalid_argument("encode: region mask has " + std::to_string(o.region.size()) + " entries, the image has " +
                                std::to_string(mcus) + " MCUs");
  if (o.max_chunk_payload < kImageDataPrefixBytes + 16)
    throw std::invalid_argument("encode: max_chunk_payload too small");

  const int ms = h.mcu_size();
  const int ncomp = h.components();
  const int sub = h.chroma == ChromaFormat::yuv420 ? 1 : 0;
  Padded s_p[3], p_p[3], r_p[3];
  for (int c = 0; c < ncomp; ++c) {
    const int pw = (c == 0 ? h.mcus_x() * ms : (h.mcus_x() * ms) >> sub);
    const int ph = (c == 0 ? h.mcus_y() * ms : (h.mcus_y() * ms) >> sub);
    s_p[c] = pad(src, c, pw, ph);
    if (pred != nullptr) {
      p_p[c] = pad(*pred, c, pw, ph);
    } else {
      p_p[c].w = pw;
      p_p[c].h = ph;
      p_p[c].px.assign(static_cast<size_t>(pw) * ph, 0);
    }
    r_p[c] = p_p[c];
  }

  uint16_t q[2][64];
  image_quant_table(h.quant_luma, h.slope, false, q[0]);
  image_quant_table(h.quant_chroma, h.slope, true, q[1]);
  const double lambda = lambda_for(h.quant_luma, h.slope, o.lambda_scale);

  EncodedImage out;
  out.header = h;
  out.imgh.resize(kImageHeaderBytes);
  image_header_to_bytes(h, out.imgh.data());

  CoderState st;
  st.reset(h.quant_luma, h.quant_chroma);
  if (o.context_counts != nullptr) {
    o.context_counts->resize(image_model::kContextCount);
    st.counts = o.context_counts->data();
  }
  ArithEncoder ae;
  const int mx_count = h.mcus_x();

  const auto code_mcu = [&](uint32_t mcu) {
    const int mx = static_cast<int>(mcu % static_cast<uint32_t>(mx_count));
    const int my = static_cast<int>(mcu / static_cast<uint32_t>(mx_count));
    if (mx == 0) std::memset(st.left, 0, sizeof st.left);
    if (!o.region.empty()) {
      const int coded = o.region[mcu] != 0;
      detail::code_bin(ae, st, st.ctx.region[st.prev_coded], coded);
      st.prev_coded = static_cast<uint8_t>(coded);
      if (!coded) {
        detail::skip_mcu(st, mx);
        return;
      }
    }
    for (int c = 0; c < ncomp; ++c) {
      const int bw = (c == 0 && sub) ? 2 : 1;
      const int cms = c == 0 ? ms : ms >> sub;
      const detail::RdoParams rp{o.rdo, lambda, component_weight(c, h.chroma)};
      for (int by = 0; by < bw; ++by) {
        for (int bx = 0; bx < bw; ++bx) {
          const int px = mx * cms + 8 * bx, py = my * cms + 8 * by;
          double in[64], coef[64], zz[64];
          for (int y = 0; y < 8; ++y)
            for (int x = 0; x < 8; ++x)
              in[8 * y + x] = static_cast<double>(s_p[c].at(px + x, py + y)[0]) -
                              (residual ? static_cast<double>(p_p[c].at(px + x, py + y)[0]) : 128.0);
          fdct8x8_ref(in, coef);
          for (int k = 0; k < 64; ++k) zz[k] = coef[m::kZigzag[k]];
          const detail::BlockEnv env = detail::block_env(st, h, c, bx, by, mx == 0);
          int32_t levels[64];
          const uint16_t* qt = q[c == 0 ? 0 : 1];
          detail::choose_levels(st, env, zz, qt, rp, levels);
          detail::encode_block(ae, st, h, env, c, bx, by, levels);
          // Reconstruct as the decoder does.
          int16_t deq[64] = {};
          int nz = 0;
          for (int k = 1; k < 64; ++k)
            if (levels[k] != 0) {
              deq[m::kZigzag[k]] = detail::dequantise_ac(levels[k], qt[k]);
              ++nz;
            }
          deq[0] = detail::dequantise_dc(levels[0], qt[0]);
          uint8_t* dst = r_p[c].at(px, py);
          const ptrdiff_t stride = r_p[c].w;
          if (nz == 0) {
            if (residual) {
              if (deq[0] != 0) idct8x8_add_dc(deq[0], dst, stride);
            } else {
              idct8x8_put_dc(deq[0], dst, stride);
            }
          } else if (residual) {
            idct8x8_add(deq, dst, stride);
          } else {
            idct8x8_put(deq, dst, stride);
          }
        }
      }
    }
    detail::end_mcu(st, h, mx);
  };

  const uint32_t limit = o.max_chunk_payload - kImageDataPrefixBytes;
  uint32_t chunk_first = 0, chunk_count = 0;
  const auto flush = [&]() {
    std::vector<uint8_t> payload;
    put_u32(payload, chunk_first);
    payload.push_back(static_cast<uint8_t>(chunk_count));
    payload.push_back(static_cast<uint8_t>(chunk_count >> 8));
    const std::vector<uint8_t> bytes = ae.finish();
    payload.insert(payload.end(), bytes.begin(), bytes.end());
    out.imgd.push_back(std::move(payload));
  };
  constexpr uint32_t kMaxMcusPerChunk = 0xFFFF;
  for (uint32_t mcu = 0; mcu < mcus; ++mcu) {
    const CoderState saved = st;
    const ArithEncoder saved_ae = ae;
    code_mcu(mcu);
    if (ae.finished_size() > limit || chunk_count == kMaxMcusPerChunk) {
      if (chunk_count == 0)
        throw std::invalid_argument("encode: one MCU needs more than the chunk limit of " +
                                    std::to_string(o.max_chunk_payload) + " bytes");
      st = saved;
      ae = saved_ae;
      flush();
      chunk_first = mcu;
      chunk_count = 0;
      code_mcu(mcu);
      if (ae.finished_size() > limit)
        throw std::invalid_argument("encode: one MCU needs more than the chunk limit of " +
                                    std::to_string(o.max_chunk_payload) + " bytes");
    }
    ++chunk_count;
  }
  flush();

  out.recon = Planes(src.width, src.height, src.chroma);
  for (int c = 0; c < ncomp; ++c)
    for (int y = 0; y < out.recon.plane_height(c); ++y)
      std::memcpy(out.recon.row(c, y), r_p[c].at(0, y), static_cast<size_t>(out.recon.plane_width(c)));
  out.psnr = planes_psnr(src, out.recon);
  return out;
}

namespace detail {
int default_chroma_delta(ChromaFormat c) { return c == ChromaFormat::yuv420 ? -16 : -8; }
}  // namespace detail

}  // namespace vds::enc
