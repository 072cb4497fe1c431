// Host reference renderer in double precision: the yardstick of the client
// renderer (vds/render.h) and the offline renderer of ground-truth frames.
//
// With default options it draws exactly the client's primitives and rules
// (docs/renderer.md): the same camera model and clipping planes, the
// top-left fill rule evaluated on double-precision edge functions,
// perspective-correct texture coordinates and Gouraud colours (from the
// ray-plane intersection of each pixel centre), nearest or bilinear sampling
// with the same addressing, a 1/z depth test (strictly nearer wins), and
// each channel rounded to nearest once at the end. For ground truth it adds
// trilinear mip-mapping, lightmap modulation and supersampling, at any
// resolution, and can report the triangle seen at each pixel (an ID buffer).
//
// Also here: the double-precision plane homography and texture quality
// factor of the walkthrough mode (the host side of vds/homography.h).
#pragma once
#include <cstdint>
#include <vector>

#include "vds/io/image.h"
#include "vds/ref/scene.h"

namespace vds::ref {

struct RefOptions {
  bool mipmap = false;          // trilinear mip-mapping of power-of-two RGB textures
  bool lightmaps = false;       // multiply by MeshD::lightmap (lightmap texel / 255 * lightmap_scale)
  double lightmap_scale = 1.0;
  int supersample = 1;          // n x n samples per pixel, box-filtered
  bool want_ids = false;        // fill RefFrame::ids (supersample == 1 only)
};

struct RefFrame {
  Image image;                   // RGB
  std::vector<double> inv_depth;  // 1/z of the visible surface, 0 for the background (supersample == 1)
  std::vector<int32_t> ids;       // visible triangle (running index over meshes), -1 for none
};

RefFrame ref_render(const Scene& scene, const CameraD& camera, int width, int height, const RefOptions& options = {});
inline RefFrame ref_render(const Scene& scene, const RefOptions& options = {}) {
  return ref_render(scene, scene.camera, scene.width, scene.height, options);
}

// Projection of a world point to pixel coordinates; false behind the camera.
bool project(const CameraD& cam, Vec3d world, double* x, double* y);

// The homography from pixel positions of `from` to pixel positions of `to`
// for the plane through plane[0..2] (paper eqs. 6-8), scaled so that its
// largest |entry| is 1 and W > 0 where `to` sees the plane in front of it.
Mat3d plane_homography(const CameraD& from, const CameraD& to, const Vec3d plane[3]);
// Maps (x, y); false when W <= 0.
bool homography_apply(const Mat3d& h, double x, double y, double* ox, double* oy);
// 2-norm of the Jacobian of h at (x, y) (eqs. 9 and 5); +infinity when W = 0.
double homography_scale(const Mat3d& h, double x, double y);
// Texture quality factor of `view` for a planar polygon: the largest scale of
// the view -> screen map at the vertices seen in the view; +infinity when a
// vertex is behind the view camera.
double texture_quality(const CameraD& screen, const CameraD& view, const std::vector<Vec3d>& polygon);

}  // namespace vds::ref
