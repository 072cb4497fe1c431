// The model stream as a viewer sees it arrive (vds/enc/model_stream.h).
#include <cmath>
#include <map>
#include <memory>
#include <span>
#include <stdexcept>

#include "host_player.h"
#include "vds/bytes.h"
#include "vds/container.h"
#include "vds/enc/model_render.h"
#include "vds/enc/model_stream.h"
#include "vds/io/image.h"
#include "vds/model_view.h"
#include "vds/player.h"

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

// Draws the client's state with the client library's model view.
struct ClientViews {
  const TexturedModel& model;
  const ModelStreamResult& r;
  TimelineOptions o;
  std::map<std::string, ModelFrame> refs;  // by camera

  ModelViews views() const {
    ModelViews v;
    v.width = r.header.width;
    v.height = r.header.height;
    v.supersample = o.supersample;
    return v;
  }

  ModelFrame reference(const ref::CameraD& cam, const std::vector<Image>& textures, bool cache) {
    char key[256];
    std::snprintf(key, sizeof key, "%.9g %.9g %.9g %.9g %.9g %.9g", cam.position.x, cam.position.y, cam.position.z,
                  cam.rotation.m[0][0], cam.rotation.m[0][2], cam.rotation.m[2][1]);
    if (cache) {
      auto it = refs.find(key);
      if (it != refs.end()) return it->second;
    }
    ModelFrame f = render_textured(model, textures, cam, views());
    f.mask = interior(f.mask);
    if (cache) refs.emplace(key, f);
    return f;
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
    for (int k = 0; k < o.views; ++k) {
      const uint16_t angle = static_cast<uint16_t>((k * 65536 + 32768) / o.views);
      Camera cam;
      uint8_t shift = 0;
      Vec3<Q16_16> origin{};
      if (view.camera(mesh, angle, &cam, &shift, &origin) != Status::ok) throw std::logic_error("model timeline: camera");
      const ref::CameraD mc = model_camera(cam, shift, origin, r.mesh.quantisation);
      se += draw(view, angle, mc);
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
      [](void* ctx, const Band& b) {
        Image& im = *static_cast<Image*>(ctx);
        for (int y = 0; y < b.height; ++y)
          for (int x = 0; x < b.width; ++x)
            io::rgb565_to_rgb888(load_le16(b.pixels + y * b.stride + 2 * x), &im.at(x, b.y + y, 0));
        return true;
      },
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
  size_t at = 0;
  const std::span<const uint8_t> s = r.stream;
  while (at < s.size()) {
    const size_t end = at == 0 ? kPreambleBytes : at + kChunkHeadBytes + load_le32(s.data() + at + 4) + kChunkTailBytes;
    const uint32_t before = frames;
    const Status st = player->feed(s.data() + at, end - at);
    if (is_error(st)) throw std::logic_error(std::string("model timeline: the client refused the stream: ") + status_name(st));
    at = end;
    if (frames == before) continue;
    if (o.colours_only && player->model_colors_level() < 0) continue;
    if (o.colours_only && player->model_colors_level() == Player::kModelVertexColours) continue;
    const MeshState& mesh = player->mesh.mesh();
    const MeshColorsSurface* colours = player->model_colors();
    TimelinePoint p;
    p.bytes = at;
    p.vertices = mesh.vertex_count();
    p.colour_level = player->model_colors_level();
    p.psnr = cv.psnr(mesh, [&](ModelView& view, uint16_t angle, const ref::CameraD& cam) {
      const ModelFrame ref = cv.reference(cam, model.textures, true);
      const ModelFrame test{client_picture(view, r.header.width, r.header.height, mesh, angle, colours), Image()};
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
  return cv.psnr(host.player->mesh.mesh(), [&](ModelView&, uint16_t, const ref::CameraD& cam) {
    const ModelFrame ref = cv.reference(cam, model.textures, true);
    ModelFrame test = render_textured(model, textures, cam, cv.views());
    return masked_mse(ref, test);
  });
}

}  // namespace vds::enc
