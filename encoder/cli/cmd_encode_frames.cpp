// `vds encode-frames IMAGE... -o OUT.vds`: a sequence of images as one
// images-mode stream (each frame an intra vds image), with the per-frame
// CRCs a client will display (host replay of the client's decode path).
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "vds/enc/frames.h"
#include "vds/enc/stream_writer.h"

namespace vds::cli {
namespace {

struct Options {
  std::vector<std::string> inputs;
  std::string out;
  std::string size = "240x180";
  double fps = 20;
  int quality = 75;
  size_t bytes = 0;
  double psnr = 0;
  uint32_t max_chunk = 2048;
  std::string crc_out;
};

void run(const Options& o) {
  unsigned w = 0, h = 0;
  char tail = 0;
  if (std::sscanf(o.size.c_str(), "%ux%u%c", &w, &h, &tail) != 2 || w == 0 || h == 0 || w > 16384 || h > 16384)
    throw Failure(kExitUsage, "--size must be WIDTHxHEIGHT with sides 1..16384, not '" + o.size + "'");
  if ((o.bytes != 0) + (o.psnr != 0) > 1) throw Failure(kExitUsage, "give at most one of --bytes and --psnr");
  enc::FrameSequenceOptions fo;
  fo.width = static_cast<int>(w);
  fo.height = static_cast<int>(h);
  fo.fps = o.fps;
  fo.image.quality = o.quality;
  fo.image.target_bytes = o.bytes;
  fo.image.target_psnr = o.psnr;
  fo.image.max_chunk_payload = o.max_chunk;
  std::vector<enc::Image> frames;
  for (const std::string& path : o.inputs) frames.push_back(enc::fit_image(enc::load_image(path, 3), fo.width, fo.height));
  enc::FrameSequenceResult r;
  try {
    r = enc::encode_frames(frames, fo);
  } catch (const std::invalid_argument& e) {
    throw Failure(kExitUsage, e.what());
  }
  const std::vector<uint32_t> crcs = enc::client_frame_crcs(r.stream);
  enc::write_file(o.out, r.stream);
  std::printf("%s: %zu frames %ux%u, %zu bytes (%.1f kbit/s at %.3g frames/s)\n", o.out.c_str(), frames.size(), w, h,
              r.stream.size(), r.stream.size() * 8.0 * o.fps / frames.size() / 1000.0, o.fps);
  std::printf("  %5s  %8s  %7s  %10s  %s\n", "frame", "bytes", "PSNR", "client CRC", "source");
  for (size_t i = 0; i < frames.size(); ++i)
    std::printf("  %5zu  %8zu  %7.2f  %08x  %s\n", i, r.frame_bytes[i], r.psnr[i], crcs[i], o.inputs[i].c_str());
  if (!o.crc_out.empty()) {
    std::string text;
    for (uint32_t c : crcs) {
      char line[16];
      std::snprintf(line, sizeof line, "%08x\n", c);
      text += line;
    }
    enc::write_file(o.crc_out, std::span(reinterpret_cast<const uint8_t*>(text.data()), text.size()));
  }
}

}  // namespace

void add_encode_frames(CLI::App& app) {
  auto o = std::make_shared<Options>();
  CLI::App* sub = app.add_subcommand("encode-frames", "Encode images as the frames of one stream");
  sub->add_option("IMAGES", o->inputs, "Frames in order (PNG, JPEG, TGA, BMP)")->required()->check(CLI::ExistingFile);
  sub->add_option("-o,--output", o->out, "Stream to write")->required();
  sub->add_option("--size", o->size, "Frame size WIDTHxHEIGHT (inputs are scaled to cover it and centre-cropped)")
      ->capture_default_str();
  sub->add_option("--fps", o->fps, "Frame rate")->capture_default_str()->check(kPositive);
  sub->add_option("--quality", o->quality, "Quality 0..100 per frame")->capture_default_str()->check(CLI::Range(0, 100));
  sub->add_option("--bytes", o->bytes, "Target bytes per frame (rate control)")->check(kPositive);
  sub->add_option("--psnr", o->psnr, "Target PSNR per frame, dB (rate control)")->check(kPositive);
  sub->add_option("--max-chunk", o->max_chunk, "Largest chunk payload, bytes")->capture_default_str()
      ->check(CLI::Range(256u, 1u << 20));
  sub->add_option("--crc-out", o->crc_out, "Write the client CRC of each frame, one hex line per frame");
  sub->callback([o] { run(*o); });
}

}  // namespace vds::cli
