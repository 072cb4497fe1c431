// vds encoder: the rendered views a textured model is measured by
// (docs/model-mode.md, "Figures"): a double-precision rasteriser that draws
// the model unlit — either its texture through its UV map (bilinear, the
// reference) or its mesh colors (the mesh colors paper's linear filter) —
// from cameras on an orbit around it, with n x n supersampling, and the
// PSNR of a render against the reference over the pixels the model covers.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "vds/enc/image_io.h"
#include "vds/enc/mesh_colors.h"
#include "vds/ref/scene.h"

namespace vds::enc {

struct ModelViews {
  int width = 256;
  int height = 256;
  int supersample = 3;
  std::vector<ref::CameraD> cameras;
};

// `count` cameras evenly round the up axis (`up`: 1 for +y, 2 for +z)
// through the centre of the model's bounds, alternately 20 degrees above
// and below the horizon, each framing the bounding sphere with a 40-degree
// field of view.
ModelViews orbit_views(const std::vector<std::array<double, 3>>& positions, int count, int width, int height,
                       int supersample, int up = 1);

// The largest resolution exponent each face can show on a display of
// `px_per_unit` pixels per model unit: R for R^2 / 2 samples over the
// face's area in pixels (facing the camera), times samples_per_pixel, to
// the next power of two (docs/model-mode.md, "No finer than the display").
std::vector<uint8_t> display_face_caps(const std::vector<std::array<double, 3>>& positions,
                                       const std::vector<std::array<uint32_t, 3>>& triangles, double px_per_unit,
                                       double samples_per_pixel);
// Pixels per model unit where an orbit view (orbit_views) of `height`
// pixels comes nearest the model: on its bounding sphere, facing the camera.
double orbit_nearest_px_per_unit(const std::vector<std::array<double, 3>>& positions, int height);

// One view of the model: RGB and a coverage mask (255 where the model is).
struct ModelFrame {
  Image rgb;
  Image mask;
};

// The model through its UV map with `textures` in place of its own (same
// count and sizes; pass model.textures for the reference).
ModelFrame render_textured(const TexturedModel& model, const std::vector<Image>& textures, const ref::CameraD& cam,
                           const ModelViews& v);

// The reference of each camera of `v`: the model through its UV map with its own textures.
std::vector<ModelFrame> render_references(const TexturedModel& model, const ModelViews& v);

// The model's mesh colors at level m, from the planes of that level.
ModelFrame render_mesh_colors(const MeshColorsModel& mc, const std::array<std::vector<uint8_t>, 3>& planes, int m,
                              const ref::CameraD& cam, const ModelViews& v);

// Mean squared error of `test` against `ref` over the pixels ref covers.
double masked_mse(const ModelFrame& ref, const ModelFrame& test);
// 10 log10(255^2 / mse) (99 for 0).
double psnr_of_mse(double mse);

// The vds encoder's measured choices for a model at quality factor q:
// chroma on each level's own lattice or the next level's (kFlagChromaHalf),
// and every face at the resolution its texels give or faces made coarser
// where that costs nothing in their samples (to_mesh_colors_rd). Each of
// the four is converted and coded, its level 0 drawn from `views` against
// `reference` (render_textured of the model, one per camera); the one with
// the most PSNR - kChoiceDbPerDoubling x log2(bytes of the header and level
// 0) is kept: the sample counts say nothing of what a display shows of
// lost detail, coding noise or chroma (the milk truck's thin coloured lines
// lose 2.8 dB to chroma from the next level at quality 4, where the duck
// gains), so the encoder looks.
struct ColourChoice {
  MeshColorsModel mc;
  MccEncoded coded;
  bool chroma_half = false;
  bool coarser_faces = false;
  double psnr = 0;
  size_t bytes = 0;
};
constexpr double kChoiceDbPerDoubling = 4;
ColourChoice choose_colours(const TexturedModel& model, const MeshColorsOptions& mo, double quality, const MccOptions& o,
                            const ModelViews& views, const std::vector<ModelFrame>& reference);

}  // namespace vds::enc
