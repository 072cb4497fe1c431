// `vds encode-model IN -o OUT.vds [--quality Q | --bytes N]`: a textured
// model (glTF, OBJ+MTL, 3DS, Collada, IQM, MD3) as one model-mode stream:
// its progressive mesh, then its colour as mesh colors, coarsest MIP level
// first (vds/enc/model_stream.h). Prints where the bytes go and what a
// client needs.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>

#include "anchors.h"
#include "commands.h"
#include "vds/enc/model_stream.h"
#include "vds/enc/stream_writer.h"

namespace vds::cli {
namespace {

struct EncodeModelOptions {
  std::string input;
  std::string output;
  double quality = 1;
  size_t bytes = 0;
  double psnr = 0;
  int bits = enc::ModelStreamOptions{}.mesh.bits;
  int max_res = 8;
  double density = 0;
  std::string up = "+y";
  bool paper = false;
  ColourChoiceArgs colour;
  uint32_t max_chunk = 4096;
  bool quiet = false;
  std::string timeline;
  int views = 8;
  std::string anchors;
  double tail = -1;
  uint32_t orbit = 64;
  std::string dump_obj;
  std::string timeline_images;
  double samples_per_pixel = enc::ModelStreamOptions{}.samples_per_pixel;
};

// The stream as it arrives (enc::model_timeline) and, with anchors, each
// anchor's texture on the whole model: CSV rows
// kind,parameter,bytes,vertices,colour_level,psnr.
void write_timeline(const EncodeModelOptions& o, const enc::TexturedModel& model, const enc::ModelStreamResult& r) {
  enc::TimelineOptions t;
  t.views = o.views;
  t.images_dir = o.timeline_images;
  if (!t.images_dir.empty()) std::filesystem::create_directories(t.images_dir);
  std::vector<Anchor> anchors;
  if (!o.anchors.empty()) anchors = read_anchors(o.anchors, model.textures.size());
  std::FILE* f = std::fopen(o.timeline.c_str(), "w");
  if (f == nullptr) throw Failure(kExitBadInput, o.timeline + ": cannot write");
  std::fprintf(f, "kind,parameter,bytes,vertices,colour_level,psnr\n");
  for (const enc::TimelinePoint& p : enc::model_timeline(model, r, t)) {
    std::fprintf(f, "vds,%.4g,%zu,%u,%d,%.3f\n", r.quality, p.bytes, p.vertices, p.colour_level, p.psnr);
    if (!o.quiet)
      std::printf("  at %7zu bytes: %5u vertices, colour level %2d: %.2f dB\n", p.bytes, p.vertices, p.colour_level, p.psnr);
  }
  for (const Anchor& a : anchors) {
    t.label = a.codec;
    const double psnr = enc::model_views_psnr(model, a.textures, r, t);
    std::fprintf(f, "%s,%s,%zu,%zu,-1,%.3f\n", a.codec.c_str(), a.param.c_str(), a.bytes, model.positions.size(), psnr);
    if (!o.quiet) std::printf("  %s %s: %zu bytes of texture: %.2f dB\n", a.codec.c_str(), a.param.c_str(), a.bytes, psnr);
  }
  std::fclose(f);
}

// The model as an OBJ with its texture coordinates (for other encoders:
// the benchmark's Draco anchor), positions and corners as imported.
void write_obj(const std::string& path, const enc::TexturedModel& m) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) throw Failure(kExitBadInput, path + ": cannot write");
  for (const auto& p : m.positions) std::fprintf(f, "v %.9g %.9g %.9g\n", p[0], p[1], p[2]);
  for (const auto& face : m.uv)
    for (const auto& t : face) std::fprintf(f, "vt %.9g %.9g\n", t[0], t[1]);
  for (size_t i = 0; i < m.triangles.size(); ++i) {
    const auto& t = m.triangles[i];
    std::fprintf(f, "f %u/%zu %u/%zu %u/%zu\n", t[0] + 1, 3 * i + 1, t[1] + 1, 3 * i + 2, t[2] + 1, 3 * i + 3);
  }
  if (std::fclose(f) != 0) throw Failure(kExitBadInput, path + ": cannot write");
}

void run_encode_model(const EncodeModelOptions& o) {
  if (o.bytes > 0 && o.psnr > 0) throw Failure(kExitUsage, "--bytes and --psnr exclude each other");
  enc::ModelStreamOptions e;
  e.quality = o.quality;
  e.max_bytes = o.bytes;
  e.min_psnr = o.psnr;
  e.mesh.bits = o.bits;
  e.mesh.max_chunk_payload = o.max_chunk;
  if (o.tail >= 0) e.mesh.tail_fraction = o.tail;
  e.samples_per_pixel = o.samples_per_pixel;
  e.orbit_frames = o.orbit;
  if (!enc::mesh_up_from_name(o.up, &e.mesh.up))
    throw Failure(kExitUsage, "--up must be +y, +z, +x, -y, -z or -x (or y, z, x), not '" + o.up + "'");
  e.colors.max_res_log2 = o.max_res;
  if (o.density > 0) {
    e.colors.density = o.density;
    e.fixed_density = true;
  }
  e.codec.paper = o.paper;
  e.measure_colours = o.colour.look();
  e.codec.chroma_half = o.colour.chroma_half();
  e.coarser_faces = o.colour.coarser_faces();
  enc::TexturedModel model;
  try {
    model = enc::load_textured_model(o.input);
  } catch (const std::runtime_error& err) {
    throw Failure(kExitBadInput, err.what());
  }
  if (!o.dump_obj.empty()) write_obj(o.dump_obj, model);
  enc::ModelStreamResult r;
  try {
    r = enc::encode_model_stream(model, e);
  } catch (const std::invalid_argument& err) {
    throw Failure(kExitBadInput, o.input + ": " + err.what());
  }
  enc::write_file(o.output, r.stream);
  if (!o.timeline.empty()) write_timeline(o, model, r);
  if (o.quiet) return;
  if (r.repair.repaired()) std::printf("%s", r.repair.summary().c_str());
  const uint32_t faces = static_cast<uint32_t>(r.colors.face_res.size());
  std::printf("%s: %zu bytes: %u vertices, %u faces, quality %.3g, %s codec\n", o.output.c_str(), r.stream.size(),
              static_cast<unsigned>(r.decoded.positions.size()), faces, r.quality, o.paper ? "paper" : "vds");
  std::printf("  geometry %zu bytes (%zu levels), vertex colours with them %zu bytes (%zu chunks), colour header %zu bytes\n",
              r.parts.geometry, r.mesh.levels.size(), r.parts.vertex_colours, r.parts.vertex_chunks,
              r.parts.colors_header);
  for (size_t m = r.parts.level_bytes.size(); m-- > 0;) {
    const double psnr = m < r.level_psnr.size() ? r.level_psnr[m] : 0;
    if (r.sent[m])
      std::printf("  colour level %zu: %u samples, %zu bytes in %zu chunks", m, r.colors.samples(static_cast<int>(m)),
                  r.parts.level_bytes[m], r.coded.levels[m].size());
    else
      std::printf("  colour level %zu: %u samples, not sent (%zu bytes, no better than a coarser one)", m,
                  r.colors.samples(static_cast<int>(m)), r.coded.level_bytes(static_cast<int>(m)));
    if (psnr > 0) std::printf(" (%.2f dB as the client shows it)", psnr);
    std::printf("\n");
  }
  std::printf("client: %u B workspace + %u B chunk buffer\n", r.header.workspace_bytes, r.header.max_chunk_payload);
}

}  // namespace

void add_encode_model(CLI::App& app) {
  auto o = std::make_shared<EncodeModelOptions>();
  CLI::App* sub = app.add_subcommand(
      "encode-model", "Encode a textured model as a model stream: progressive mesh, then mesh colors coarse to fine");
  sub->add_option("IN", o->input, "Model file: glTF 2.0, OBJ+MTL, 3DS, Collada, IQM, MD2, MD3 or MS3D, textures beside it; or a Quake III player's folder (ARCHIVE.pk3:FOLDER inside an archive)")
      ->required();
  sub->add_option("-o,--output", o->output, "Stream to write")->required();
  auto* q = sub->add_option("--quality", o->quality, "Colour quality factor (the JPEG tables' multiplier; lower is finer)")
                ->capture_default_str()
                ->check(CLI::Range(1.0 / 256, 255.0));
  sub->add_option("--bytes", o->bytes, "Instead of --quality: the finest quality whose whole stream fits this many bytes")
      ->check(CLI::Range(size_t{1}, size_t{1} << 32))
      ->excludes(q);
  sub->add_option("--psnr", o->psnr,
                  "Instead of --quality: the coarsest quality whose finest picture, as the client shows it (the rate "
                  "schedule's measure), reaches this PSNR")
      ->check(CLI::Range(1.0, 99.0))
      ->excludes(q);
  sub->add_option("--bits", o->bits, "Geometry quantisation bits per axis")->capture_default_str()->check(CLI::Range(2, 16));
  sub->add_option("--max-res", o->max_res, "Largest face resolution exponent (R = 2^r)")
      ->capture_default_str()
      ->check(CLI::Range(1, 10));
  sub->add_option("--density", o->density, "Samples per texel side (default: follows the quality)")
      ->check(CLI::Range(0.01, 16.0));
  sub->add_option("--up", o->up, "The model's up axis for viewers: +y (glTF), +z, +x, -y, -z or -x")
      ->capture_default_str();
  sub->add_option("--tail", o->tail,
                  "Send the whole mesh single-rate after the split levels that reach this fraction of the vertices "
                  "(0: splits all the way; default 0.3)")
      ->check(CLI::Range(0.0, 1.0));
  sub->add_option("--samples-per-pixel", o->samples_per_pixel,
                  "Cap each face's resolution at this many samples per client pixel along its longest edge, seen as "
                  "near as the client's model view sees it (0: no cap)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 64.0));
  sub->add_option("--orbit", o->orbit, "At the end, a turn of the finished model in this many frames (0: none)")
      ->capture_default_str()
      ->check(CLI::Range(0u, 4096u));
  sub->add_flag("--paper", o->paper, "Code the colours as the thesis does (for comparison)");
  add_colour_choice_options(sub, &o->colour);
  sub->add_option("--max-chunk", o->max_chunk, "Largest chunk payload, bytes (the client's chunk buffer)")
      ->capture_default_str()
      ->check(CLI::Range(512u, 1u << 24));
  sub->add_option("--timeline", o->timeline,
                  "Write the stream as it arrives as CSV: after each chunk that completes a client frame, the client's "
                  "picture from --views orbit angles against the model with its own texture (PSNR)");
  sub->add_option("--views", o->views, "Orbit angles of --timeline")->capture_default_str()->check(CLI::Range(1, 64));
  sub->add_option("--anchors", o->anchors,
                  "With --timeline: the model's textures coded by other codecs (CSV codec,parameter,bytes,files), "
                  "each measured on the whole model at the same cameras");
  sub->add_option("--timeline-images", o->timeline_images,
                  "With --timeline: write each view's reference and the client's last picture (and each anchor's) "
                  "as PNG into this directory");
  sub->add_option("--dump-obj", o->dump_obj, "Also write the model as imported as an OBJ with its texture coordinates");
  sub->add_flag("-q,--quiet", o->quiet, "Print nothing");
  sub->callback([o] { run_encode_model(*o); });
}

}  // namespace vds::cli
