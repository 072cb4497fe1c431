// The model stream as a viewer sees it arrive (vds/enc/model_stream.h).
#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <span>
#include <stdexcept>

#include "host_player.h"
#include "stream_chunks.h"
#include "vds/bytes.h"
#include "vds/container.h"
#include "vds/enc/model_render.h"
#include "vds/enc/image_io.h"
#include "vds/enc/model_stream.h"
#include "vds/io/image.h"
#include "vds/model_view.h"
#include "vds/player.h"
#include "vds/render.h"

namespace vds::enc {
namespace {

// The client's camera for its mesh at `angle`, in the model's own units:
// the view puts grid point g at world (g << shift) + origin (Q16.16), and
// g = (p - q.origin) / q.step, so world = s p + t with one scale s for
// every axis; the camera at C sees p as it sees world point s p + t,
// i.e. as a camera at (C - t) / s sees p (projection ignores the scale).
ref::CameraD model_camera(const Camera& c, uint8_t shift, const Vec3<Q16_16>& origin, const Quantisation& q) {
  const double unit = std::ldexp(1.0, shift - 16);  // world units per grid step
  const double s = unit / q.step;
  const double o[3] = {origin.x.raw() / 65536.0, origin.y.raw() / 65536.0, origin.z.raw() / 65536.0};
  const double C[3] = {c.position.x.raw() / 65536.0, c.position.y.raw() / 65536.0, c.position.z.raw() / 65536.0};
  ref::CameraD d;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) d.rotation.m[i][j] = c.rotation.m[i][j].raw() / 1073741824.0;
  double p[3];
  for (int a = 0; a < 3; ++a) p[a] = (C[a] - (o[a] - unit * q.origin[a] / q.step)) / s;
  d.position = {p[0], p[1], p[2]};
  d.fx = c.fx.raw() / 65536.0;
  d.fy = c.fy.raw() / 65536.0;
  d.cx = c.cx.raw() / 65536.0;
  d.cy = c.cy.raw() / 65536.0;
  d.near_z = c.near_z.raw() / 65536.0 / s;
  d.far_z = c.far_z.raw() / 65536.0 / s;
  return d;
}

// Pixels inside the silhouette: covered, and so are their four neighbours.
Image interior(const Image& mask) {
  Image out(mask.width, mask.height, 1);
  for (int y = 1; y + 1 < mask.height; ++y)
    for (int x = 1; x + 1 < mask.width; ++x)
      out.at(x, y, 0) = mask.at(x, y, 0) && mask.at(x - 1, y, 0) && mask.at(x + 1, y, 0) && mask.at(x, y - 1, 0) &&
                                mask.at(x, y + 1, 0)
                            ? 255
                            : 0;
  return out;
}

// A band of RGB565 rows into the Image `ctx` (the frame's size).
bool band_to_image(void* ctx, const Band& b) {
  Image& im = *static_cast<Image*>(ctx);
  for (int y = 0; y < b.height; ++y)
    for (int x = 0; x < b.width; ++x) io::rgb565_to_rgb888(load_le16(b.pixels + y * b.stride + 2 * x), &im.at(x, b.y + y, 0));
  return true;
}

// The model view's camera and grid placement for one angle.
struct ClientCamera {
  Camera cam;
  uint8_t shift;
  Vec3<Q16_16> origin;
};

// The model with `textures` drawn as a client would draw a downloaded
// textured mesh: the client library's renderer (RGB565, 16-bit depth,
// bilinear) from the model view's camera, every face its own three corners
// with their texture coordinates; faces without a texture in their
// material's colour. (Vertex colours and material factors on textures are
// not drawn: the test models have none that change the picture.)
Image client_textured_picture(const TexturedModel& m, const std::vector<Image>& textures, const ClientCamera& c,
                              const Quantisation& q, int width, int height) {
  const size_t corners = 3 * m.triangles.size();
  if (corners > 65535) throw std::invalid_argument("model timeline: too many faces for one draw list");
  const double unit = std::ldexp(1.0, c.shift - 16);
  const double o[3] = {c.origin.x.raw() / 65536.0, c.origin.y.raw() / 65536.0, c.origin.z.raw() / 65536.0};
  std::vector<Vec3<Q16_16>> pos(corners);
  std::vector<TexCoord> uvs(corners);
  std::vector<std::vector<uint16_t>> by_material(m.materials.size());
  for (size_t f = 0; f < m.triangles.size(); ++f) {
    const int mat = m.material[f];
    const int t = m.materials[static_cast<size_t>(mat)].texture;
    for (int k = 0; k < 3; ++k) {
      const size_t i = 3 * f + static_cast<size_t>(k);
      const auto& p = m.positions[m.triangles[f][static_cast<size_t>(k)]];
      int32_t w[3];
      for (int a = 0; a < 3; ++a) w[a] = static_cast<int32_t>(std::lround((unit * (p[a] - q.origin[a]) / q.step + o[a]) * 65536));
      pos[i] = {Q16_16::from_raw(w[0]), Q16_16::from_raw(w[1]), Q16_16::from_raw(w[2])};
      if (t >= 0) {
        const Image& img = textures[static_cast<size_t>(t)];
        const auto& uv = m.uv[f][static_cast<size_t>(k)];
        uvs[i] = {Q16_16::from_raw(static_cast<int32_t>(std::lround(uv[0] * img.width * 65536))),
                  Q16_16::from_raw(static_cast<int32_t>(std::lround((1 - uv[1]) * img.height * 65536)))};
      }
      by_material[static_cast<size_t>(mat)].push_back(static_cast<uint16_t>(i));
    }
  }
  std::vector<std::vector<uint32_t>> texels(textures.size());
  std::vector<Texture> tex(textures.size());
  for (size_t t = 0; t < textures.size(); ++t) {
    const Image& img = textures[t];
    texels[t].resize(static_cast<size_t>(img.width) * img.height);
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x)
        texels[t][static_cast<size_t>(y) * img.width + x] = (uint32_t{img.at(x, y, 0)} << 16) |
                                                            (uint32_t{img.at(x, y, 1)} << 8) | img.at(x, y, 2);
    tex[t].format = TexFormat::xrgb8888;
    tex[t].address = TexAddress::repeat;
    tex[t].width = static_cast<uint16_t>(img.width);
    tex[t].height = static_cast<uint16_t>(img.height);
    tex[t].stride = static_cast<uint32_t>(img.width);
    tex[t].texels = texels[t].data();
  }
  std::vector<vds::Mesh> meshes;
  for (size_t mat = 0; mat < by_material.size(); ++mat) {
    if (by_material[mat].empty()) continue;
    vds::Mesh mesh;
    mesh.indices = by_material[mat].data();
    mesh.num_triangles = static_cast<uint32_t>(by_material[mat].size() / 3);
    mesh.cull = Cull::none;
    const TexturedMaterial& tm = m.materials[mat];
    if (tm.texture >= 0) {
      mesh.shading = Shading::texture;
      mesh.filter = Filter::bilinear;
      mesh.texture = &tex[static_cast<size_t>(tm.texture)];
      mesh.uvs = uvs.data();
    } else {
      const auto ch = [&](int k) { return static_cast<uint32_t>(std::clamp(std::lround(tm.colour[k] * 255), 0L, 255L)); };
      mesh.color = ch(0) << 16 | ch(1) << 8 | ch(2);
    }
    meshes.push_back(mesh);
  }
  DrawList list{pos.data(), static_cast<uint32_t>(corners), meshes.data(), static_cast<uint32_t>(meshes.size())};
  RenderConfig rc;
  rc.width = static_cast<uint16_t>(width);
  rc.height = static_cast<uint16_t>(height);
  rc.band_height = 16;
  rc.vertex_cache = static_cast<uint32_t>(corners);
  std::vector<uint8_t> ws(render_workspace_size(rc));
  Arena arena(ws.data(), ws.size());
  Renderer renderer;
  Image img(width, height, 3);
  if (renderer.init(rc, arena) != Status::ok) throw std::logic_error("model timeline: renderer");
  const Status st = renderer.render(
      c.cam, list, 0x182028,
      band_to_image,
      &img);
  if (st != Status::ok) throw std::runtime_error(std::string("model timeline: the renderer refused the model: ") + status_name(st));
  return img;
}

// Draws the client's state with the client library's model view.
struct ClientViews {
  const TexturedModel& model;
  const ModelStreamResult& r;
  TimelineOptions o;
  std::map<std::string, ModelFrame> refs;  // by camera
  int view_index = 0;                      // the view being measured

  // The pictures of view_index, when asked for.
  void keep(const ModelFrame& ref, const Image& test) const {
    if (o.images_dir.empty()) return;
    const std::string base = o.images_dir + "/view" + std::to_string(view_index);
    save_png(base + "_reference.png", ref.rgb);
    save_png(base + "_" + o.label + ".png", test);
  }

  ModelViews views() const {
    ModelViews v;
    v.width = r.header.width;
    v.height = r.header.height;
    v.supersample = o.supersample;
    return v;
  }

  // The model with its own textures from `cam`, its silhouette eroded;
  // drawn once per camera (the colour levels of one mesh share them).
  const ModelFrame& reference(const ref::CameraD& cam) {
    char key[256];
    std::snprintf(key, sizeof key, "%.9g %.9g %.9g %.9g %.9g %.9g", cam.position.x, cam.position.y, cam.position.z,
                  cam.rotation.m[0][0], cam.rotation.m[0][2], cam.rotation.m[2][1]);
    auto it = refs.find(key);
    if (it == refs.end()) {
      ModelFrame f = render_textured(model, model.textures, cam, views());
      f.mask = interior(f.mask);
      it = refs.emplace(key, std::move(f)).first;
    }
    return it->second;
  }

  // Mean over the views of the squared error of `draw(angle, cam)` against the reference.
  template <class Draw>
  double psnr(const MeshState& mesh, const Draw& draw) {
    ModelViewConfig vc;
    vc.width = r.header.width;
    vc.height = r.header.height;
    vc.up = r.mesh.mesh_header.up;
    std::vector<uint8_t> ws(ModelView::workspace_bytes(vc, mesh.vertex_count(), mesh.triangle_count()) + 64);
    Arena arena(ws.data(), ws.size());
    ModelView view;
    if (view.init(vc, arena, mesh.vertex_count(), mesh.triangle_count()) != Status::ok)
      throw std::logic_error("model timeline: the model view");
    double se = 0;
    view_index = 0;
    for (int k = 0; k < o.views; ++k, ++view_index) {
      const uint16_t angle = static_cast<uint16_t>((k * 65536 + 32768) / o.views);
      Camera cam;
      uint8_t shift = 0;
      Vec3<Q16_16> origin{};
      if (view.camera(mesh, angle, &cam, &shift, &origin) != Status::ok) throw std::logic_error("model timeline: camera");
      const ref::CameraD mc = model_camera(cam, shift, origin, r.mesh.quantisation);
      se += draw(view, angle, mc, ClientCamera{cam, shift, origin});
    }
    return psnr_of_mse(se / o.views);
  }
};

// The client's picture of `mesh` (with `colours`) at `angle`, RGB.
Image client_picture(ModelView& view, int width, int height, const MeshState& mesh, uint16_t angle,
                     const MeshColorsSurface* colours) {
  Image img(width, height, 3);
  const Status s = view.draw(
      mesh, angle,
      band_to_image,
      &img, colours);
  if (s != Status::ok) throw std::logic_error("model timeline: the model view could not draw");
  return img;
}

}  // namespace

std::vector<TimelinePoint> model_timeline(const TexturedModel& model, const ModelStreamResult& r,
                                          const TimelineOptions& o) {
  ClientViews cv{model, r, o, {}};
  PlayerCallbacks cb;
  uint32_t frames = 0;
  cb.ctx = &frames;
  cb.frame_shown = [](void* ctx, const PlayedFrame&) { ++*static_cast<uint32_t*>(ctx); };
  HostPlayer host(cb);
  Player* player = host.player.get();
  std::vector<TimelinePoint> out;
  size_t at = 0;  // fed so far: the preamble with the first chunk, then chunk by chunk
  for (const StreamChunk& c : stream_chunks(r.stream)) {
    const uint32_t before = frames;
    const Status st = player->feed(r.stream.data() + at, c.end - at);
    if (is_error(st)) throw std::logic_error(std::string("model timeline: the client refused the stream: ") + status_name(st));
    at = c.end;
    if (frames == before) continue;
    if (c.type == kModelOrbitChunk) continue;  // the same model, turning
    if (o.colours_only && player->model_colors_level() < 0) continue;
    if (o.colours_only && player->model_colors_level() == Player::kModelVertexColours) continue;
    const MeshState& mesh = player->mesh.mesh();
    const MeshColorsSurface* colours = player->model_colors();
    TimelinePoint p;
    p.bytes = at;
    p.vertices = mesh.vertex_count();
    p.colour_level = player->model_colors_level();
    p.psnr = cv.psnr(mesh, [&](ModelView& view, uint16_t angle, const ref::CameraD& cam, const ClientCamera&) {
      const ModelFrame& ref = cv.reference(cam);
      const ModelFrame test{client_picture(view, r.header.width, r.header.height, mesh, angle, colours), Image()};
      cv.keep(ref, test.rgb);
      return masked_mse(ref, test);
    });
    out.push_back(p);
  }
  return out;
}

double model_views_psnr(const TexturedModel& model, const std::vector<Image>& textures, const ModelStreamResult& r,
                        const TimelineOptions& o) {
  ClientViews cv{model, r, o, {}};
  HostPlayer host;
  if (host.play(r.stream) != Status::ok) throw std::logic_error("model timeline: the client refused the stream");
  return cv.psnr(host.player->mesh.mesh(), [&](ModelView&, uint16_t, const ref::CameraD& cam, const ClientCamera& cc) {
    const ModelFrame& ref = cv.reference(cam);
    const ModelFrame test{client_textured_picture(model, textures, cc, r.mesh.quantisation, r.header.width, r.header.height),
                          Image()};
    cv.keep(ref, test.rgb);
    return masked_mse(ref, test);
  });
}

}  // namespace vds::enc
