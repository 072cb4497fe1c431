// `vds decode-image IN.vds -o OUT.png`: the first image of a stream (vds image
// or JPEG chunks), decoded by the client's own stream parser and decoders.
#include <cstdio>
#include <memory>
#include <string>

#include "commands.h"
#include "vds/enc/image_codec.h"
#include "vds/enc/image_io.h"
#include "vds/enc/stream_writer.h"

namespace vds::cli {
namespace {

struct DecodeImageOptions {
  std::string in;
  std::string out;
  std::string predict;
  std::string chroma = "420";
};

void run_decode_image(const DecodeImageOptions& o) {
  const std::vector<uint8_t> stream = enc::read_file(o.in);
  enc::Planes prediction;
  const enc::Planes* pred = nullptr;
  if (!o.predict.empty()) {
    enc::Image p;
    try {
      p = enc::load_image(o.predict);
    } catch (const std::exception& e) {
      throw Failure(kExitBadInput, e.what());
    }
    const ChromaFormat c = o.chroma == "444" ? ChromaFormat::yuv444 : o.chroma == "grey" ? ChromaFormat::grey
                                                                                          : ChromaFormat::yuv420;
    prediction = enc::rgb_to_planes(p, c);
    pred = &prediction;
  }
  enc::DecodedImage d;
  try {
    d = enc::decode_stream_image(stream, pred);
  } catch (const std::exception& e) {
    throw Failure(kExitBadInput, o.in + ": " + e.what());
  }
  enc::save_png(o.out, d.rgb);
  std::printf("%s: %dx%d from a %s image of %zu stream bytes\n", o.out.c_str(), d.rgb.width, d.rgb.height,
              d.kind.c_str(), stream.size());
}

}  // namespace

void add_decode_image(CLI::App& app) {
  auto o = std::make_shared<DecodeImageOptions>();
  CLI::App* sub = app.add_subcommand("decode-image", "Decode the image of a stream with the client decoder, to PNG");
  sub->add_option("input", o->in, "Stream to read")->required();
  sub->add_option("-o,--output", o->out, "PNG to write")->required();
  sub->add_option("--predict", o->predict,
                  "Residual/region images: what the client holds before the image (an image file)");
  sub->add_option("--chroma", o->chroma, "Chroma format the prediction is converted to: 420 | 444 | grey")
      ->capture_default_str();
  sub->callback([o] { run_decode_image(*o); });
}

}  // namespace vds::cli
