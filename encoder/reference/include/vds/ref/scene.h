// Host scene description shared by tests and benchmarks: geometry, textures
// and cameras in double precision, the three standard scenes (a textured
// cube, a textured terrain grid, a room), a scene drawn from a stored view
// (the walkthrough mode's projective mapping), and the conversion to the
// client's fixed-point structures (vds/render.h). The reference renderer
// (vds/enc/ref_render.h) draws a Scene; the client renderer draws its
// ClientScene. Textures are generated in code, so nothing depends on data
// packages.
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "vds/io/image.h"
#include "vds/render.h"

namespace vds::ref {

using io::Image;

struct Vec2d {
  double x = 0, y = 0;
};
struct Vec3d {
  double x = 0, y = 0, z = 0;
};
inline Vec3d operator+(Vec3d a, Vec3d b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3d operator-(Vec3d a, Vec3d b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3d operator*(Vec3d a, double s) { return {a.x * s, a.y * s, a.z * s}; }
inline double dot(Vec3d a, Vec3d b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3d cross(Vec3d a, Vec3d b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
Vec3d normalize(Vec3d a);

struct Mat3d {
  double m[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
};
Mat3d operator*(const Mat3d& a, const Mat3d& b);
Vec3d operator*(const Mat3d& a, Vec3d v);
Mat3d transpose(const Mat3d& a);

// The camera of vds/render_camera.h in double: camera space is x right,
// y down, z forward; rows of `rotation` are the camera axes in world space.
struct CameraD {
  Mat3d rotation;
  Vec3d position;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  double near_z = 0.1, far_z = 100;

  // A camera at `eye` looking at `target` with `up` (world) pointing up on
  // screen; square pixels, principal point at the image centre.
  static CameraD look_at(Vec3d eye, Vec3d target, Vec3d up, int width, int height, double fov_y_deg,
                         double near_z, double far_z);
  Vec3d to_camera(Vec3d world) const { return rotation * (world - position); }
  // The same view at `s` times the resolution (supersampling).
  CameraD scaled(double s) const;
};

// A texture as the renderers sample it: 8-bit R'G'B' texels, or 8-bit
// Y'CbCr 4:2:0 planes (then `image` keeps the R'G'B' source).
struct TextureD {
  std::string name;
  Image image;  // RGB, 3 channels
  vds::TexAddress address = vds::TexAddress::repeat;
  bool ycbcr = false;
  Image y, cb, cr;  // ycbcr: 1 channel each, chroma at half size rounded up
};

struct MeshD {
  std::vector<uint32_t> indices;  // 3 per triangle, into Scene::positions
  vds::Shading shading = vds::Shading::flat;
  vds::Filter filter = vds::Filter::bilinear;
  vds::Cull cull = vds::Cull::back;
  uint32_t color = 0x808080;  // flat, 0x00RRGGBB
  int texture = -1;           // texture / view_mapped: index into Scene::textures
  int lightmap = -1;          // reference renderer only: modulating texture at Scene::lightmap_uvs
  CameraD view_camera;        // view_mapped: the camera the stored view was rendered with
};

struct Scene {
  std::string name;
  int width = 240, height = 180;
  std::vector<Vec3d> positions;
  std::vector<Vec2d> uvs;           // per vertex, texels
  std::vector<uint32_t> colors;     // per vertex, 0x00RRGGBB
  std::vector<Vec2d> lightmap_uvs;  // per vertex, lightmap texels
  std::vector<TextureD> textures;
  std::vector<MeshD> meshes;
  CameraD camera;
  uint32_t clear_color = 0;

  // Appends a vertex with all attributes and returns its index.
  uint32_t add_vertex(Vec3d p, Vec2d uv = {}, uint32_t color = 0, Vec2d lightmap_uv = {});
  // Appends the quad p0..p3 (in order around its edge) to `mesh` as two
  // triangles wound so that they face `outward`, with texel coordinates
  // uv0..uv3 and per-vertex colours.
  void add_quad(MeshD& mesh, const Vec3d p[4], const Vec2d uv[4], Vec3d outward, const uint32_t colors[4] = nullptr,
                const Vec2d lightmap_uv[4] = nullptr);
};

// The standard scenes at width x height (cameras keep their field of view).
Scene make_cube_scene(int width = 240, int height = 180);
Scene make_terrain_scene(int width = 240, int height = 180);
Scene make_room_scene(int width = 240, int height = 180);
std::vector<Scene> shared_scenes(int width = 240, int height = 180);

// A 240x180 scene built with +, -, * and / on exactly chosen values only (no
// transcendental functions), with integer-pattern textures: every platform
// produces the same client data, so its frame checksums are golden values
// for comparing the host and Cortex-M builds (tests/unit/render_test.cpp).
Scene make_golden_scene();

// The walkthrough mode: the faces of `base` (meshes `mesh_indices`, each
// planar) drawn from `view`, an image of the scene rendered with
// `view_camera`, by the projective map of each face. Faces keep their
// filters; the view is clamped at its borders.
Scene make_view_mapped_scene(const Scene& base, const std::vector<int>& mesh_indices, const Image& view,
                             const CameraD& view_camera);

// Procedural textures (deterministic, size x size, RGB).
Image make_checker_texture(int size, int cells, uint32_t a, uint32_t b);
Image make_brick_texture(int size);
Image make_tile_texture(int size);
Image make_noise_texture(int size, uint32_t seed, uint32_t dark, uint32_t light);
Image make_face_texture(int size, int face);  // cube face `face` (0..5): a distinct hue and pattern

// ---------------------------------------------------------------------------
// The client side
// ---------------------------------------------------------------------------
vds::Camera to_client(const CameraD& cam);

// The scene with every texture replaced by what the client samples in
// `format`: rgb565 channels rounded to 5/6/5 bits and widened back by bit
// replication; ycbcr420 planes as the client gets them (JFIF, chroma as the
// rounded mean of each 2x2 block).
Scene client_textures(const Scene& scene, vds::TexFormat format);

// JFIF full-range conversion with 2x2 chroma averaging (rounded).
void rgb_to_ycbcr420(const Image& rgb, Image& y, Image& cb, Image& cr);
// JFIF full-range Y'CbCr -> R'G'B' of one colour, unrounded and unclamped.
inline std::array<double, 3> ycbcr_to_rgb(double y, double cb, double cr) {
  cb -= 128;
  cr -= 128;
  return {y + 1.402 * cr, y - 0.344136 * cb - 0.714136 * cr, y + 1.772 * cb};
}

// The fixed-point copy of a Scene: owns every array the DrawList points to.
// View-mapped meshes get their homography from vds::plane_homography
// (fixed point), from the client cameras. With `apron`, rgb565 and xrgb8888
// textures get the one-texel apron of vds::Texture::apron.
class ClientScene {
 public:
  ClientScene(const Scene& scene, vds::TexFormat format, bool apron = true);
  ClientScene(const ClientScene&) = delete;
  ClientScene& operator=(const ClientScene&) = delete;

  const vds::DrawList& list() const { return list_; }
  const vds::Camera& camera() const { return camera_; }
  uint32_t clear_color() const { return clear_color_; }

 private:
  std::vector<vds::Vec3<vds::Q16_16>> positions_;
  std::vector<vds::TexCoord> uvs_;
  std::vector<uint32_t> colors_;
  std::vector<std::vector<uint16_t>> indices_;
  std::vector<std::vector<uint16_t>> texels16_;
  std::vector<std::vector<uint32_t>> texels32_;
  std::vector<std::vector<uint8_t>> planes_;
  std::vector<vds::Texture> textures_;
  std::vector<vds::Mesh> meshes_;
  vds::DrawList list_;
  vds::Camera camera_{};
  uint32_t clear_color_ = 0;
};

// Settings of one client render (vds::RenderConfig without the buffers).
struct ClientRenderSettings {
  vds::PixelFormat format = vds::PixelFormat::rgb888;
  vds::DepthFormat depth = vds::DepthFormat::d32;
  int band_height = 16;
  uint32_t vertex_cache = 65536;
  uint32_t triangle_cache = 65536;
  uint32_t setup_cache = 16;
};

struct ClientFrame {
  vds::Status status = vds::Status::ok;
  Image image;                 // RGB (rgb565 output widened by bit replication)
  std::vector<uint8_t> bytes;  // the frame exactly as the renderer wrote it
  vds::RenderStats stats;
  size_t workspace = 0;        // bytes of workspace used
};

// Renders `scene` with vds::Renderer at its width x height through a band sink.
ClientFrame render_client(const ClientScene& scene, int width, int height, const ClientRenderSettings& settings);
ClientFrame render_client(const ClientScene& scene, const vds::Camera& camera, int width, int height,
                          const ClientRenderSettings& settings);

}  // namespace vds::ref
