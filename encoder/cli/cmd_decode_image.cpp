// `vds decode-image IN.vds -o OUT.png`: the first image of a stream (vds image
// or JPEG chunks), decoded by the client's own stream parser and decoders.
#include <cstdio>
#include <memory>
#include <string>

#include "commands.h"
#include "vds/enc/image_codec.h"
#include "vds/enc/image_io.h"
#include "vds/enc/stream_writer.h"
#include "vds/io/image.h"

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
  // Rows go to the PNG as the client shows them: memory of one band
  // however large the image its header declares; the PNG appears only once
  // the image is whole.
  struct ToPng : enc::ImageRowSink {
    std::string path;
    std::unique_ptr<io::PngRowWriter> png;
    int width = 0, height = 0;
    void begin(int w, int h) override {
      width = w;
      height = h;
      png = std::make_unique<io::PngRowWriter>(path, w, h, 3);
    }
    void rows(int, int count, const uint8_t* pixels, ptrdiff_t stride) override { png->write_rows(pixels, count, stride); }
  } sink;
  sink.path = o.out;
  std::string kind;
  try {
    kind = enc::play_stream_image(stream, pred, sink);
  } catch (const std::runtime_error& e) {
    throw Failure(kExitBadInput, o.in + ": " + e.what());
  }
  sink.png->finish();
  std::printf("%s: %dx%d from a %s image of %zu stream bytes\n", o.out.c_str(), sink.width, sink.height, kind.c_str(),
              stream.size());
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
