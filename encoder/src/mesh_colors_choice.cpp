// vds encoder: the measured choice of chroma lattice and face resolutions
// for a model's mesh colors (vds/enc/model_render.h, choose_colours).
#include <cmath>
#include <stdexcept>

#include "vds/enc/model_render.h"

namespace vds::enc {

ColourChoice choose_colours(const TexturedModel& model, const MeshColorsOptions& mo, double quality, const MccOptions& o,
                            const ModelViews& views, const std::vector<ModelFrame>& reference) {
  if (reference.size() != views.cameras.size()) throw std::invalid_argument("choose_colours: a reference per view");
  const MeshColorsModel fine = to_mesh_colors(model, mo);
  const MeshColorsModel coarser = to_mesh_colors_rd(model, mo, fine, quality, o);
  ColourChoice best;
  double best_score = -1e300;
  for (const bool coarser_faces : {false, true})
    for (const bool half : {false, true}) {
      const MeshColorsModel& mc = coarser_faces ? coarser : fine;
      MccOptions co = o;
      co.chroma_half = half;
      MccEncoded coded = encode_mesh_colors(mc, quality, co);
      const auto planes = decode_mesh_colors_level(mc, coded, 0);
      double mse = 0;
      for (size_t i = 0; i < views.cameras.size(); ++i)
        mse += masked_mse(reference[i], render_mesh_colors(mc, planes, 0, views.cameras[i], views));
      const double psnr = psnr_of_mse(mse / static_cast<double>(views.cameras.size()));
      const size_t bytes = coded.header.size() + coded.level_bytes(0);
      const double score = psnr - kChoiceDbPerDoubling * std::log2(static_cast<double>(bytes > 0 ? bytes : 1));
      if (score > best_score) {
        best_score = score;
        best.mc = mc;
        best.coded = std::move(coded);
        best.chroma_half = half;
        best.coarser_faces = coarser_faces;
        best.psnr = psnr;
        best.bytes = bytes;
      }
    }
  return best;
}

}  // namespace vds::enc
