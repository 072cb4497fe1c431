// `vds mesh-colors MODEL`: a textured model as mesh colors and through the
// mesh colors codec: the resolutions chosen, the samples per MIP level and,
// per quality factor, the bytes, the compression ratio against 24-bit
// samples and the PSNR of Y', Cb and Cr of every level as the client
// decodes it (the measure of Taskin's thesis, chapter 3). --csv writes the
// same table as CSV for the benchmark's plots.
//
// With --views N, the rendered-view measure too: the model drawn unlit from
// N cameras round it (vds/enc/model_render.h), its own texture through its
// UV map the reference; per quality the mesh colors (header + level 0, the
// bytes a client needs to show level 0) and every anchor the --anchors file
// lists (the model's texture coded by another codec: CSV lines
// codec,parameter,bytes,decoded-file[;decoded-file...], one decoded image
// per texture, in the order --dump-textures writes them), each as the PSNR
// of all views over the pixels the model covers. --sheet writes view 0 of
// each as a PNG contact sheet.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "anchors.h"
#include "commands.h"
#include "vds/enc/mesh_colors.h"
#include "vds/enc/model_render.h"
#include "vds/mesh_colors.h"

namespace vds::cli {
namespace {

using enc::Image;
using enc::load_image;
using enc::save_png;

struct MeshColorsOptions {
  std::string input;
  std::vector<double> quality{0.25, 0.5, 1, 2, 4};
  double density = 0;  // 0: the vds codec's density follows the quality
  int max_res = 10;
  std::string csv;
  int views = 0;
  int size = 256;
  int supersample = 3;
  std::string anchors;
  std::string dump_textures;
  std::string rendered_csv;
  std::string sheet;
  std::string up = "y";
  std::vector<std::string> codecs{"vds", "paper"};
  double deadzone = enc::MccOptions{}.deadzone;
  bool no_seam_boost = false;
  double samples_per_pixel = 2;  // the vds codec's faces: no finer than a view of --size shows (0: no cap)
  ColourChoiceArgs colour;
};

void write_ppm(const std::string& path, const Image& img) {
  std::ofstream f(path, std::ios::binary);
  f << "P6\n" << img.width << " " << img.height << "\n255\n";
  f.write(reinterpret_cast<const char*>(img.pixels.data()), static_cast<std::streamsize>(img.pixels.size()));
  if (!f) throw Failure(kExitBadInput, path + ": cannot write");
}

double plane_psnr(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b, size_t from) {
  double se = 0;
  for (size_t i = from; i < a.size(); ++i) se += (double(a[i]) - b[i]) * (double(a[i]) - b[i]);
  const size_t n = a.size() - from;
  if (n == 0 || se == 0) return 99;
  return 10 * std::log10(255.0 * 255.0 * n / se);
}

void run(const MeshColorsOptions& o) {
  enc::TexturedModel model;
  try {
    model = enc::load_textured_model(o.input);
  } catch (const std::runtime_error& e) {
    throw Failure(kExitBadInput, e.what());
  }
  std::printf("%s: %zu vertices, %zu faces (%zu dropped), %zu textures", o.input.c_str(), model.positions.size(),
              model.triangles.size(), model.dropped_faces, model.textures.size());
  for (size_t i = 0; i < model.textures.size(); ++i)
    std::printf("%s %dx%d", i == 0 ? ":" : ",", model.textures[i].width, model.textures[i].height);
  std::printf("\n");
  auto options = [&o](const std::string& codec) {
    enc::MccOptions mo;
    mo.paper = codec == "paper";
    mo.deadzone = o.deadzone;
    mo.chroma_half = o.colour.chroma_half();
    return mo;
  };
  // The mesh colors at each sample density used, converted once each.
  // Keyed by density and, for the vds codec's rate-distortion choice of face
  // resolutions, the quality (0: none).
  // The vds codec's faces are no finer than the display shows: what the
  // nearest surface of an orbit view of --size pixels covers (the model
  // stream's rule, docs/model-mode.md); the thesis's keep the texel rule.
  const std::vector<uint8_t> display_caps =
      o.samples_per_pixel > 0
          ? enc::display_face_caps(model.positions, model.triangles,
                                   enc::orbit_nearest_px_per_unit(model.positions, o.size), o.samples_per_pixel)
          : std::vector<uint8_t>{};
  std::map<std::tuple<double, double, bool>, enc::MeshColorsModel> converted;
  auto colors = [&](double density, double rd_quality = 0, bool capped = false) -> const enc::MeshColorsModel& {
    auto it = converted.find({density, rd_quality, capped});
    if (it != converted.end()) return it->second;
    enc::MeshColorsOptions mo;
    mo.density = density;
    mo.max_res_log2 = o.max_res;
    mo.seam_boost = !o.no_seam_boost;
    if (capped) mo.face_max_res = display_caps;
    enc::MeshColorsModel mcm;
    try {
      mcm = rd_quality > 0 ? enc::to_mesh_colors_rd(model, mo, rd_quality, options("vds"))
                           : enc::to_mesh_colors(model, mo);
    } catch (const std::runtime_error& e) {
      throw Failure(kExitBadInput, e.what());
    }
    std::printf("density %g%s%s: resolutions", density, rd_quality > 0 ? (", chosen for quality " + std::to_string(rd_quality)).c_str() : "",
                capped && !display_caps.empty() ? ", no finer than the display" : "");
    std::vector<size_t> hist(mc::kMaxResLog2 + 1, 0);
    for (uint8_t r : mcm.face_res) ++hist[r];
    for (int r = 0; r <= mc::kMaxResLog2; ++r)
      if (hist[r] > 0) std::printf(" R=%d: %zu faces", 1 << r, hist[r]);
    std::printf("; samples per level");
    for (int m = 0; m <= mcm.max_res; ++m) std::printf(" %d: %u", m, mcm.samples(m));
    std::printf("\n");
    return converted.emplace(std::make_tuple(density, rd_quality, capped), std::move(mcm)).first->second;
  };
  // The vds codec's density follows the quality unless --density fixes it;
  // the thesis's codec keeps one sample per texel.
  auto density_of = [&](const std::string& codec, double q) {
    return o.density > 0 ? o.density : (codec == "paper" ? 1.0 : enc::density_for_quality(q));
  };
  // The vds codec's faces made coarser for the quality (--faces coarser).
  auto rd_of = [&](const std::string& codec, double q) { return codec != "paper" && o.colour.coarser_faces() ? q : 0.0; };
  // With --chroma and --faces auto the vds encoder looks: each choice drawn
  // from 5 views of its own at the display's size (--size, --supersample),
  // not the ones measured below.
  const bool look = o.colour.look();
  enc::ModelViews choice_views;
  std::vector<enc::ModelFrame> choice_reference;
  if (look && std::find(o.codecs.begin(), o.codecs.end(), "vds") != o.codecs.end()) {
    choice_views = enc::orbit_views(model.positions, 5, o.size, o.size, o.supersample, o.up == "z" ? 2 : 1);
    choice_reference = enc::render_references(model, choice_views);
  }
  std::ofstream csv;
  if (!o.csv.empty()) {
    csv.open(o.csv);
    if (!csv) throw Failure(kExitBadInput, o.csv + ": cannot write");
    csv << "codec,quality,density,level,samples,bytes,ratio,psnr_y,psnr_cb,psnr_cr\n";
  }
  // Each codec and quality encoded once, for the table and the rendered views.
  struct Coded {
    enc::MeshColorsModel mc;
    enc::MccEncoded e;
  };
  std::map<std::pair<std::string, double>, Coded> encoded;
  std::map<std::pair<std::string, double>, size_t> header_bytes;  // by codec and density
  std::vector<std::string> table;
  for (const std::string& codec : o.codecs)
    for (double q : o.quality) {
      const double density = density_of(codec, q);
      Coded coded;
      if (look && codec == "vds") {
        enc::MeshColorsOptions mo;
        mo.density = density;
        mo.max_res_log2 = o.max_res;
        mo.seam_boost = !o.no_seam_boost;
        mo.face_max_res = display_caps;
        enc::ColourChoice choice = enc::choose_colours(model, mo, q, options(codec), choice_views, choice_reference);
        std::printf("quality %g: chroma %s, faces %s (%.2f dB in %zu bytes on the encoder's views)\n", q,
                    choice.chroma_half ? "from the next level" : "on its own level",
                    choice.coarser_faces ? "made coarser" : "at their texels' resolution", choice.psnr, choice.bytes);
        coded = Coded{std::move(choice.mc), std::move(choice.coded)};
      } else {
        coded.mc = colors(density, rd_of(codec, q), codec == "vds");
        coded.e = enc::encode_mesh_colors(coded.mc, q, options(codec));
      }
      const Coded& entry = encoded.emplace(std::make_pair(codec, q), std::move(coded)).first->second;
      const enc::MeshColorsModel& mcm = entry.mc;
      const enc::MccEncoded& e = entry.e;
      const size_t V = mcm.positions.size();
      header_bytes[{codec, density}] = e.header.size();
      for (int m = 0; m < mcm.max_res; ++m) {
        const auto planes = enc::decode_mesh_colors_level(mcm, e, m);
        const size_t coded = mcm.samples(m) - V;  // the codec's samples: edges and faces
        const size_t bytes = e.level_bytes(m);
        const double ratio = 3.0 * coded / bytes;
        double p[3];
        for (int c = 0; c < 3; ++c) p[c] = plane_psnr(mcm.levels[m][c], planes[c], V);
        char line[160];
        std::snprintf(line, sizeof line, "%s | %.3g | %g | %d | %zu | %.2f | %.2f | %.2f | %.2f", codec.c_str(), q, density,
                      m, bytes, ratio, p[0], p[1], p[2]);
        table.push_back(line);
        if (csv)
          csv << codec << "," << q << "," << density << "," << m << "," << coded << "," << bytes << "," << ratio << ","
              << p[0] << "," << p[1] << "," << p[2] << "\n";
      }
    }
  std::printf("\n codec | quality | density | level | bytes | ratio | PSNR Y' | PSNR Cb | PSNR Cr\n"
              "---|---:|---:|---:|---:|---:|---:|---:|---:\n");
  for (const std::string& line : table) std::printf("%s\n", line.c_str());
  std::printf("\nheader (resolutions, vertex samples), the same at every quality:");
  for (const auto& [key, bytes] : header_bytes) std::printf(" %s at density %g %zu bytes;", key.first.c_str(), key.second, bytes);
  std::printf("\n");

  if (!o.dump_textures.empty())
    for (size_t i = 0; i < model.textures.size(); ++i) {
      const std::string stem = o.dump_textures + "/texture" + std::to_string(i);
      save_png(stem + ".png", model.textures[i]);
      write_ppm(stem + ".ppm", model.textures[i]);
    }
  if (o.views <= 0) return;

  // Rendered views.
  const std::vector<Anchor> anchors = o.anchors.empty() ? std::vector<Anchor>{} : read_anchors(o.anchors, model.textures.size());
  const enc::ModelViews views = enc::orbit_views(model.positions, o.views, o.size, o.size, o.supersample, o.up == "z" ? 2 : 1);
  const std::vector<enc::ModelFrame> reference = enc::render_references(model, views);
  struct Row {
    std::string codec, param;
    size_t bytes;
    double psnr;
    Image view0;
  };
  std::vector<Row> rows;
  auto measure = [&](auto&& render) {
    double mse = 0;
    Image first;
    for (size_t i = 0; i < views.cameras.size(); ++i) {
      const enc::ModelFrame f = render(views.cameras[i]);
      mse += enc::masked_mse(reference[i], f);
      if (i == 0) first = f.rgb;
    }
    return std::make_pair(enc::psnr_of_mse(mse / views.cameras.size()), first);
  };
  {
    const enc::MeshColorsModel& mcm = colors(o.density > 0 ? o.density : 1.0);
    auto [p, img] = measure([&](const ref::CameraD& c) { return enc::render_mesh_colors(mcm, mcm.levels[0], 0, c, views); });
    rows.push_back({"mesh colors", "uncoded", 3 * mcm.samples(0), p, img});
  }
  size_t coded_rows = 0;
  for (const std::string& codec : o.codecs)
    for (double q : o.quality) {
      const enc::MeshColorsModel& mcm = encoded.at({codec, q}).mc;
      const enc::MccEncoded& e = encoded.at({codec, q}).e;
      const auto planes = enc::decode_mesh_colors_level(mcm, e, 0);
      auto [p, img] = measure([&](const ref::CameraD& c) { return enc::render_mesh_colors(mcm, planes, 0, c, views); });
      char param[32];
      std::snprintf(param, sizeof param, "%g", q);
      rows.push_back({"mcc-" + codec, param, e.header.size() + e.level_bytes(0), p, img});
      ++coded_rows;
    }
  for (const Anchor& a : anchors) {
    auto [p, img] = measure([&](const ref::CameraD& c) { return enc::render_textured(model, a.textures, c, views); });
    rows.push_back({a.codec, a.param, a.bytes, p, img});
  }
  std::printf("\nrendered views: %d of %dx%d, %dx%d supersampled, PSNR over the model's pixels\n\n codec | parameter | bytes | PSNR\n---|---:|---:|---:\n",
              o.views, o.size, o.size, o.supersample, o.supersample);
  std::ofstream rcsv;
  if (!o.rendered_csv.empty()) {
    rcsv.open(o.rendered_csv);
    if (!rcsv) throw Failure(kExitBadInput, o.rendered_csv + ": cannot write");
    rcsv << "codec,parameter,bytes,psnr\n";
  }
  for (const Row& r : rows) {
    std::printf("%s | %s | %zu | %.2f\n", r.codec.c_str(), r.param.c_str(), r.bytes, r.psnr);
    if (rcsv) rcsv << r.codec << "," << r.param << "," << r.bytes << "," << r.psnr << "\n";
  }
  if (!o.sheet.empty()) {
    // The reference, the mesh colors rows, and of each anchor codec the row
    // nearest in bytes to the middle mesh colors row.
    std::vector<const Image*> tiles{&reference[0].rgb};
    const size_t coded = coded_rows;
    const size_t middle = coded > 0 ? rows[1 + o.quality.size() / 2].bytes : 0;
    std::vector<std::string> codecs;
    for (size_t i = 0; i < rows.size(); ++i) {
      if (i <= coded) {
        tiles.push_back(&rows[i].view0);
        continue;
      }
      if (std::find(codecs.begin(), codecs.end(), rows[i].codec) != codecs.end()) continue;
      codecs.push_back(rows[i].codec);
      size_t best = i;
      for (size_t j = i; j < rows.size(); ++j)
        if (rows[j].codec == rows[i].codec &&
            std::llabs(static_cast<long long>(rows[j].bytes) - static_cast<long long>(middle)) <
                std::llabs(static_cast<long long>(rows[best].bytes) - static_cast<long long>(middle)))
          best = j;
      tiles.push_back(&rows[best].view0);
    }
    save_png(o.sheet, enc::side_by_side(tiles));
  }
}

}  // namespace

void add_mesh_colors(CLI::App& app) {
  auto o = std::make_shared<MeshColorsOptions>();
  CLI::App* c = app.add_subcommand("mesh-colors", "a textured model as mesh colors, through the mesh colors codec");
  c->add_option("model", o->input, "model file (glTF, OBJ, Collada, IQM, MS3D, 3DS, MD2, MD3), or a Quake III player's folder (ARCHIVE.pk3:FOLDER inside an archive)")->required();
  c->add_option("--quality", o->quality, "quality factors (the JPEG tables' multiplier)")->check(kPositive);
  c->add_option("--codec", o->codecs, "mesh colors codecs: vds (the improved one), paper (the thesis's)")
      ->check(CLI::IsMember({"vds", "paper"}));
  c->add_option("--deadzone", o->deadzone, "vds codec: levels rounded down below 0.5 + this of a step")
      ->check(CLI::Range(0.0, 0.5));
  c->add_option("--samples-per-pixel", o->samples_per_pixel,
                "vds codec: a face's samples per pixel side at most, on the nearest surface of a view of --size (0: no cap)")
      ->check(CLI::Range(0.0, 16.0));
  c->add_flag("--no-seam-boost", o->no_seam_boost, "keep faces on seams whose sides differ at their own resolution");
  add_colour_choice_options(c, &o->colour);
  c->add_option("--density", o->density,
                 "samples per texel side (default: the vds codec's follows the quality, the thesis's is 1)")
      ->check(kPositive);
  c->add_option("--max-res", o->max_res, "largest face resolution exponent (R = 2^r)")->check(CLI::Range(0, 10));
  c->add_option("--csv", o->csv, "also write the table as CSV");
  c->add_option("--views", o->views, "rendered views round the model (0: none)")->check(CLI::Range(0, 360));
  c->add_option("--size", o->size, "rendered view width and height")->check(CLI::Range(16, 2048));
  c->add_option("--supersample", o->supersample, "samples per pixel side")->check(CLI::Range(1, 8));
  c->add_option("--up", o->up, "the model's up axis, for the orbit (y or z)")->check(CLI::IsMember({"y", "z"}));
  c->add_option("--anchors", o->anchors, "CSV of the texture coded by other codecs (codec,parameter,bytes,files)");
  c->add_option("--dump-textures", o->dump_textures, "write the model's textures as DIR/textureN.png and .ppm");
  c->add_option("--rendered-csv", o->rendered_csv, "write the rendered-view table as CSV");
  c->add_option("--sheet", o->sheet,
                "write view 0 side by side (PNG): the reference, the mesh colors rows, each anchor codec nearest the middle quality's bytes");
  c->callback([o] { run(*o); });
}

}  // namespace vds::cli
