// `vds encode-image IN -o OUT.vds`: one image as an images-mode stream, coded
// with the vds image codec at a quality, to a size or to a PSNR; or a
// baseline JPEG carried as it is (--jpeg).
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "vds/enc/image_codec.h"
#include "vds/enc/image_io.h"
#include "vds/enc/stream_writer.h"
#include "vds/jpeg.h"

namespace vds::cli {
namespace {

struct EncodeImageOptions {
  std::string in;
  std::string out;
  int quality = -1;
  size_t bytes = 0;
  double psnr = 0;
  std::string chroma = "420";
  std::string predict;
  std::string region;
  int slope = -1;
  uint32_t max_chunk = 4096;
  bool jpeg = false;
};

ChromaFormat parse_chroma(const std::string& c) {
  if (c == "420") return ChromaFormat::yuv420;
  if (c == "444") return ChromaFormat::yuv444;
  if (c == "grey" || c == "gray") return ChromaFormat::grey;
  throw Failure(kExitUsage, "--chroma must be 420, 444 or grey, not '" + c + "'");
}

enc::Image load(const std::string& path) {
  try {
    return enc::load_image(path);
  } catch (const std::exception& e) {
    throw Failure(kExitBadInput, e.what());
  }
}

// A JPEG file carried unchanged in JPEG chunks, after the client decoder has
// accepted it (so a progressive or damaged file is refused here, not on the device).
void run_jpeg(const EncodeImageOptions& o) {
  const std::vector<uint8_t> file = enc::read_file(o.in);
  JpegInfo info;
  const char* why = "";
  const Status s = jpeg_peek_info(file.data(), file.size(), &info, &why);
  if (s != Status::ok)
    throw Failure(kExitBadInput, o.in + ": not a JPEG the client decodes: " + status_name(s) + (why[0] ? std::string(" (") + why + ")" : ""));
  StreamHeader h = enc::default_header(StreamMode::images, info.width, info.height);
  h.frame_count = 1;
  h.max_chunk_payload = o.max_chunk;
  h.workspace_bytes = static_cast<uint32_t>(JpegDecoder::kWorkspaceBytes);
  enc::StreamWriter w(h);
  for (size_t at = 0; at < file.size(); at += o.max_chunk)
    w.add_chunk(chunk::kJpeg, std::span(file).subspan(at, std::min<size_t>(o.max_chunk, file.size() - at)));
  const std::vector<uint8_t> stream = w.finish();
  try {
    enc::decode_stream_image(stream);
  } catch (const std::exception& e) {
    throw Failure(kExitBadInput, o.in + ": " + e.what());
  }
  enc::write_file(o.out, stream);
  std::printf("%s: %dx%d baseline JPEG, %zu bytes (%.3f bits/pixel), stream %zu bytes\n", o.out.c_str(), info.width,
              info.height, file.size(), file.size() * 8.0 / (static_cast<double>(info.width) * info.height), stream.size());
}

void run_encode_image(const EncodeImageOptions& o) {
  const int targets = (o.quality >= 0) + (o.bytes > 0) + (o.psnr > 0);
  if (o.jpeg) {
    if (targets != 0 || !o.predict.empty() || !o.region.empty())
      throw Failure(kExitUsage, "--jpeg carries the file as it is: no --quality, --bytes, --psnr, --predict or --region");
    run_jpeg(o);
    return;
  }
  if (targets > 1) throw Failure(kExitUsage, "give one of --quality, --bytes and --psnr");
  enc::ImageEncodeOptions e;
  e.quality = o.quality >= 0 ? o.quality : 75;
  e.target_bytes = o.bytes;
  e.target_psnr = o.psnr;
  e.chroma = parse_chroma(o.chroma);
  e.slope = o.slope;
  e.max_chunk_payload = o.max_chunk;
  const enc::Image img = load(o.in);
  enc::Planes prediction;
  if (!o.predict.empty()) {
    const enc::Image p = load(o.predict);
    if (p.width != img.width || p.height != img.height)
      throw Failure(kExitBadInput, o.predict + ": the prediction is " + std::to_string(p.width) + "x" +
                                       std::to_string(p.height) + ", the image " + std::to_string(img.width) + "x" +
                                       std::to_string(img.height));
    prediction = enc::rgb_to_planes(p, e.chroma);
    e.prediction = &prediction;
    e.mode = enc::ImageMode::residual;
  }
  if (!o.region.empty()) {
    // Any non-zero mask pixel inside an MCU selects that MCU.
    const enc::Image m = load(o.region);
    if (m.width != img.width || m.height != img.height)
      throw Failure(kExitBadInput, o.region + ": the region mask must be " + std::to_string(img.width) + "x" +
                                       std::to_string(img.height));
    const int ms = e.chroma == ChromaFormat::yuv420 ? 16 : 8;
    const int mx = (img.width + ms - 1) / ms, my = (img.height + ms - 1) / ms;
    e.region.assign(static_cast<size_t>(mx) * my, 0);
    for (int y = 0; y < m.height; ++y)
      for (int x = 0; x < m.width; ++x)
        if (m.at(x, y, 0) != 0) e.region[static_cast<size_t>(y / ms) * mx + x / ms] = 1;
    if (e.prediction == nullptr) {
      // Intra blocks over a destination that starts black.
      prediction = enc::Planes(img.width, img.height, e.chroma);
      e.prediction = &prediction;
    }
  }
  enc::EncodedImage enc_img;
  try {
    enc_img = enc::encode_image(img, e);
  } catch (const std::invalid_argument& ex) {
    throw Failure(kExitUsage, o.in + ": " + ex.what());
  }
  if (!enc_img.target_met) {
    if (o.bytes > 0)
      throw Failure(kExitBadInput, o.in + ": cannot fit " + std::to_string(o.bytes) + " bytes; the coarsest quantiser needs " +
                                       std::to_string(enc_img.coded_bytes()));
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.2f", enc_img.psnr);
    throw Failure(kExitBadInput, o.in + ": cannot reach the PSNR; the finest quantiser gives " + std::string(buf) + " dB");
  }
  const std::vector<uint8_t> stream = enc::image_stream(enc_img);
  enc::write_file(o.out, stream);
  const ImageHeader& h = enc_img.header;
  const double pixels = static_cast<double>(h.width) * h.height;
  std::printf("%s: %dx%d %s%s%s, quantiser %d/%d slope %d, %zu bytes coded (%.3f bits/pixel), %zu chunks, RGB PSNR %.2f dB\n",
              o.out.c_str(), h.width, h.height,
              h.chroma == ChromaFormat::yuv420 ? "4:2:0" : h.chroma == ChromaFormat::yuv444 ? "4:4:4" : "grey",
              h.residual() ? " residual" : "", h.region() ? " region" : "", h.quant_luma, h.quant_chroma, h.slope,
              enc_img.coded_bytes(), enc_img.coded_bytes() * 8.0 / pixels, enc_img.imgd.size() + 1, enc_img.psnr);
}

}  // namespace

void add_encode_image(CLI::App& app) {
  auto o = std::make_shared<EncodeImageOptions>();
  CLI::App* sub = app.add_subcommand("encode-image", "Code an image (PNG, JPEG, TGA) as a vds image stream");
  sub->add_option("input", o->in, "Image to code")->required();
  sub->add_option("-o,--output", o->out, "Stream to write")->required();
  sub->add_option("--quality", o->quality, "Quality 0..100 (default 75)")->check(CLI::Range(0, 100));
  sub->add_option("--bytes", o->bytes, "Code to at most this many bytes (best quality that fits)")->check(kPositive);
  sub->add_option("--psnr", o->psnr, "Code to at least this RGB PSNR in dB (fewest bytes)")->check(kPositive);
  sub->add_option("--chroma", o->chroma, "420 | 444 | grey")->capture_default_str();
  sub->add_option("--predict", o->predict, "Residual mode: the prediction the client adds to (an image file)");
  sub->add_option("--region", o->region, "Region mode: a mask image; MCUs with any non-zero mask pixel are coded");
  sub->add_option("--slope", o->slope, "Perceptual slope of the quantisation tables, 0 (flat) .. 16 (T.81 Annex K)")
      ->check(CLI::Range(0, 16));
  sub->add_option("--max-chunk", o->max_chunk, "Largest chunk payload, bytes")
      ->capture_default_str()->check(CLI::Range(256u, 1u << 24));
  sub->add_flag("--jpeg", o->jpeg, "Carry the input, a baseline JPEG, unchanged in JPEG chunks");
  sub->callback([o] { run_encode_image(*o); });
}

}  // namespace vds::cli
