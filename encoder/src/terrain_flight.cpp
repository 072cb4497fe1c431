// Flights over a terrain (vds/enc/terrain_flight.h).
#include "vds/enc/terrain_flight.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <vector>

#include "vds/enc/scene_render.h"
#include "vds/ref/scene.h"
#include "vds/status.h"

namespace vds::enc {

namespace {

// Keeps every frame at least `clearance` metres above the ground around
// it and ahead of it (a pilot clears the next ridge before reaching it),
// smoothly: the floor is spread over a second either way before it lifts
// the path.
void keep_above_ground(const TerrainCoding& t, CameraPath* p, double clearance) {
  const size_t n = p->frames.size();
  std::vector<double> floor(n);
  const double step = t.cell_m, radius = std::max(3 * t.cell_m, 60.0), ahead = std::max(10 * t.cell_m, 300.0);
  for (size_t f = 0; f < n; ++f) {
    const CameraPose& c = p->frames[f];
    const double yaw = c.yaw_deg * 3.14159265358979323846 / 180;
    double g = terrain_height(t, c.x, c.y);
    for (double dx = -radius; dx <= radius; dx += step)
      for (double dy = -radius; dy <= radius; dy += step) g = std::max(g, terrain_height(t, c.x + dx, c.y + dy));
    for (double a = 0; a <= ahead; a += step)
      g = std::max(g, terrain_height(t, c.x + a * std::cos(yaw), c.y + a * std::sin(yaw)));
    floor[f] = g + clearance;
  }
  const size_t half = static_cast<size_t>(std::max(1.0, p->fps));
  std::vector<double> spread(n), smooth(n);
  for (size_t f = 0; f < n; ++f) {
    double m = floor[f];
    for (size_t k = f >= half ? f - half : 0; k <= std::min(n - 1, f + half); ++k) m = std::max(m, floor[k]);
    spread[f] = std::max(p->frames[f].z, m);
  }
  for (size_t f = 0; f < n; ++f) {
    double s = 0;
    size_t c = 0;
    for (size_t k = f >= half ? f - half : 0; k <= std::min(n - 1, f + half); ++k, ++c) s += spread[k];
    smooth[f] = s / static_cast<double>(c);
  }
  for (size_t f = 0; f < n; ++f) p->frames[f].z = std::max({p->frames[f].z, smooth[f], floor[f]});
}

// The grid's cells as two triangles each, into points in raster order.
std::vector<uint32_t> cell_triangles(const TerrainCoding& t) {
  std::vector<uint32_t> indices;
  const uint32_t px = static_cast<uint32_t>(t.points_x());
  for (uint32_t j = 0; j < t.grid.cells_y; ++j)
    for (uint32_t i = 0; i < t.grid.cells_x; ++i) {
      const uint32_t a = j * px + i, b = a + 1, c = a + px, e = c + 1;
      indices.insert(indices.end(), {a, c, b, b, c, e});
    }
  return indices;
}

}  // namespace

CameraPath terrain_flyover(const TerrainCoding& t, int frames, double fps, double hfov_deg) {
  if (frames < 2 || !(fps > 0)) throw std::invalid_argument("terrain_flyover: at least 2 frames at a positive rate");
  const double w = t.grid.cells_x * t.cell_m, d = t.grid.cells_y * t.cell_m;
  const double high = std::max(w, d) / 3;
  // Time (fraction of the flight), position (fractions of the map), height
  // above the ground, heading and pitch.
  struct Key {
    double s, x, y, agl, yaw, pitch;
  };
  const Key keys[] = {
      {0.00, 0.08, 0.15, 15, 45, -8},      // in low over the south-west
      {0.20, 0.35, 0.40, 25, 45, -10},     // low, across the map
      {0.40, 0.50, 0.55, high, 60, -35},   // climb high
      {0.55, 0.62, 0.72, high, 150, -40},  // a wide turn
      {0.70, 0.42, 0.78, high * 0.75, 240, -55},
      {0.82, 0.30, 0.60, 20, 260, -25},    // the dive
      {1.00, 0.18, 0.32, 12, 250, -6},     // out low
  };
  CameraKeys k;
  k.hfov_deg = hfov_deg;
  k.fps = fps;
  const double duration = (frames - 1) / fps;
  for (const Key& e : keys) {
    CameraKey c;
    c.time_s = e.s * duration;
    c.pose.x = e.x * w;
    c.pose.y = e.y * d;
    c.pose.z = terrain_height(t, c.pose.x, c.pose.y) + e.agl;
    c.pose.yaw_deg = e.yaw;
    c.pose.pitch_deg = e.pitch;
    k.keys.push_back(c);
  }
  CameraPath p = interpolate_keyframes(k);
  p.frames.resize(static_cast<size_t>(frames), p.frames.back());
  keep_above_ground(t, &p, 8);
  return p;
}

CameraPath read_flight(const std::string& text, const std::string& name, const TerrainCoding& t) {
  CameraPath p = interpolate_keyframes(read_camera_keys(text, name));
  keep_above_ground(t, &p, 2);
  return p;
}

Scene terrain_scene(const TerrainCoding& t) {
  Scene s;
  s.name = "terrain";
  s.kind = "terrain";
  s.metres_per_unit = 1;
  s.overbright = false;
  const int px = t.points_x(), py = t.points_y();
  const double tw = t.grid.cells_x * 8.0, th = t.grid.cells_y * 8.0;
  for (int j = 0; j < py; ++j)
    for (int i = 0; i < px; ++i) {
      SceneVertex v;
      const auto p = t.point(i, j);
      v.pos = {static_cast<float>(p[0]), static_cast<float>(p[1]), static_cast<float>(p[2])};
      v.uv = {static_cast<float>(8 * i / tw), static_cast<float>(8 * j / th)};
      v.color = {255, 255, 255, 255};
      s.vertices.push_back(v);
    }
  s.indices = cell_triangles(t);
  SceneSurface surf;
  surf.texture = 0;
  surf.index_count = static_cast<uint32_t>(s.indices.size());
  s.surfaces.push_back(surf);
  SceneTexture tex;
  tex.name = "terrain";
  s.textures.push_back(tex);
  for (const SceneVertex& v : s.vertices)
    for (int k = 0; k < 3; ++k) {
      s.min[static_cast<size_t>(k)] = std::min(s.min[static_cast<size_t>(k)], v.pos[static_cast<size_t>(k)]);
      s.max[static_cast<size_t>(k)] = std::max(s.max[static_cast<size_t>(k)], v.pos[static_cast<size_t>(k)]);
    }
  return s;
}

namespace {

// vds: the terrain server, and the texture its mirror of the client holds.
class ServerSource : public FlightSource {
 public:
  ServerSource(const TerrainCoding& t, const FlightOptions& o)
      : t_(t), o_(o), server_(t, o.capacity), shown_(t.grid.blocks(), 0), texture_(reconstruct_texture(t, shown_)) {}
  size_t answer(const std::vector<SceneCamera>& cameras, uint32_t pose, size_t budget, FlightFrame* ff) override {
    return server_.update(cameras, pose, budget, o_.pose, &ff->update).size();
  }
  uint32_t held() const override { return server_.used(); }
  bool changed() const override { return server_.held() != shown_; }
  io::Image texture() override {
    update_texture(t_, shown_, server_.held(), &texture_);
    shown_ = server_.held();
    return planes_to_rgb(texture_);
  }

 private:
  const TerrainCoding& t_;
  const FlightOptions& o_;
  TerrainServer server_;
  std::vector<terrain::Mask> shown_;
  Planes texture_;
};

// The terrain as the client library's renderer draws it: one mesh, the
// whole colour map as a Y'CbCr 4:2:0 texture, bilinear, no culling.
ref::Scene client_terrain(const TerrainCoding& t, int width, int height) {
  ref::Scene s;
  s.name = "terrain";
  s.width = width;
  s.height = height;
  ref::TextureD tex;
  tex.name = "terrain";
  tex.image = t.colour;
  tex.address = vds::TexAddress::clamp;
  s.textures.push_back(tex);
  ref::MeshD mesh;
  mesh.shading = vds::Shading::texture;
  mesh.filter = vds::Filter::bilinear;
  mesh.cull = vds::Cull::none;
  mesh.texture = 0;
  for (int j = 0; j < t.points_y(); ++j)
    for (int i = 0; i < t.points_x(); ++i) {
      const auto p = t.point(i, j);
      s.add_vertex({p[0], p[1], p[2]}, {8.0 * i, 8.0 * j});
    }
  mesh.indices = cell_triangles(t);
  s.meshes.push_back(mesh);
  return s;
}

ref::CameraD client_camera(const SceneCamera& c, double near_m, double far_m) {
  ref::CameraD d;
  for (int k = 0; k < 3; ++k) {
    d.rotation.m[0][k] = c.right[static_cast<size_t>(k)];
    d.rotation.m[1][k] = c.down[static_cast<size_t>(k)];
    d.rotation.m[2][k] = c.forward[static_cast<size_t>(k)];
  }
  d.position = {c.position[0], c.position[1], c.position[2]};
  d.fx = d.fy = c.focal;
  d.cx = c.cx;
  d.cy = c.cy;
  d.near_z = near_m;
  d.far_z = far_m;
  return d;
}

io::Image with_alpha(const io::Image& rgb) {
  io::Image out(rgb.width, rgb.height, 4);
  for (size_t i = 0, n = static_cast<size_t>(rgb.width) * rgb.height; i < n; ++i) {
    for (size_t c = 0; c < 3; ++c) out.pixels[4 * i + c] = rgb.pixels[3 * i + c];
    out.pixels[4 * i + 3] = 255;
  }
  return out;
}

}  // namespace

TerrainTruth::TerrainTruth(const TerrainCoding& t, int width, int height, int supersample, double near_m) {
  RenderOptions ro;
  ro.width = width;
  ro.height = height;
  ro.supersample = supersample;
  ro.near_m = near_m;
  renderer_ = std::make_unique<SceneRenderer>(terrain_scene(t), std::vector<io::Image>{with_alpha(t.colour)}, ro);
}

TerrainTruth::~TerrainTruth() = default;

io::Image TerrainTruth::render(const CameraPose& pose, double hfov_deg) const { return renderer_->render(pose, hfov_deg).rgb; }

CameraPose extrapolate(const CameraPose& a, const CameraPose& b, double steps) {
  CameraPose p;
  p.x = b.x + (b.x - a.x) * steps;
  p.y = b.y + (b.y - a.y) * steps;
  p.z = b.z + (b.z - a.z) * steps;
  double dyaw = std::fmod(b.yaw_deg - a.yaw_deg + 540.0, 360.0) - 180.0;
  p.yaw_deg = std::fmod(b.yaw_deg + dyaw * steps + 720.0, 360.0);
  p.pitch_deg = std::clamp(b.pitch_deg + (b.pitch_deg - a.pitch_deg) * steps, -89.0, 89.0);
  return p;
}


FlightResult fly_source(const TerrainCoding& t, const CameraPath& path, const FlightOptions& o, FlightSource& source) {
  FlightResult r;
  r.coarse_elevation_bytes =
      encode_elevation(t.heights.data(), t.points_x(), t.points_y(), terrain::ElevationPass::coarse).size();
  const size_t fine_bytes =
      encode_elevation(t.heights.data(), t.points_x(), t.points_y(), terrain::ElevationPass::fine).size();
  r.elevation_bytes = r.coarse_elevation_bytes + fine_bytes;
  const Scene scene = terrain_scene(t);
  // The ground the client draws until the fine pass is whole (a scene needs
  // the grid and its heights only).
  TerrainCoding rough;
  rough.grid = t.grid;
  rough.cell_m = t.cell_m;
  rough.metres_per_unit = t.metres_per_unit;
  rough.heights = t.heights;
  terrain::fill_from_coarse(t.points_x(), t.points_y(), rough.heights.data());
  const Scene coarse_scene = terrain_scene(rough);
  double fine_left = static_cast<double>(fine_bytes);
  RenderOptions ro;
  ro.width = o.width;
  ro.height = o.height;
  ro.supersample = o.supersample;
  ro.near_m = o.pose.near_m;
  const SceneRenderer truth(scene, {with_alpha(t.colour)}, ro);
  // The client library's renderer with the whole texture: rendering loss alone.
  std::unique_ptr<ref::ClientScene> full;
  const double far_m = std::hypot(t.grid.cells_x * t.cell_m, t.grid.cells_y * t.cell_m) * 1.5 + 1000;
  // The client's depth range is at most 4096 near distances (vds/render_camera.h).
  const double near_m = std::max(o.pose.near_m, far_m / 4000);
  if (o.client_renderer) full = std::make_unique<ref::ClientScene>(client_terrain(t, o.width, o.height), vds::TexFormat::ycbcr420);
  std::unique_ptr<SceneRenderer> client;
  io::Image texture;
  const bool unlimited = !(o.link.rate_bytes_per_s > 0);
  const double per_frame = unlimited ? 0 : o.link.rate_bytes_per_s / path.fps;
  double credit = -static_cast<double>(r.coarse_elevation_bytes);
  const int pose_every = std::max(1, static_cast<int>(std::lround(path.fps / std::max(1, o.link.poses_per_s))));
  bool first_done = false;
  for (size_t f = 0; f < path.frames.size(); ++f) {
    FlightFrame ff;
    if (f % static_cast<size_t>(pose_every) == 0) ff.up_bytes = o.link.pose_bytes;
    credit = unlimited ? 1e12 : credit + per_frame;
    // The fine elevation shares the link with the texture, half and half,
    // once the coarse pass is through.
    bool ground_changed = false;
    if (fine_left > 0 && credit > 0) {
      const double share = unlimited ? fine_left : std::min(fine_left, std::min(credit, per_frame / 2));
      fine_left -= share;
      credit -= share;
      ff.elevation_bytes = static_cast<size_t>(std::lround(share));
      if (fine_left <= 0) {
        r.elevation_frame = static_cast<uint32_t>(f);
        ground_changed = true;
      }
    }
    // The newest pose the server has: sent at a multiple of pose_every, at
    // least latency_frames ago.
    const long lag = static_cast<long>(f) - o.link.latency_frames;
    // An update waits until the link has carried min_update_bytes for it
    // (its 8-byte header and the arithmetic coder's flush are paid per update).
    if (lag >= 0 && credit >= std::max(1.0, static_cast<double>(o.link.min_update_bytes))) {
      const size_t pose = static_cast<size_t>(lag) - static_cast<size_t>(lag) % static_cast<size_t>(pose_every);
      std::vector<SceneCamera> cams = {scene_camera(path.frames[pose], path.hfov_deg, o.width, o.height)};
      if (o.link.predict && pose >= static_cast<size_t>(pose_every) && f > pose)
        cams.push_back(scene_camera(extrapolate(path.frames[pose - static_cast<size_t>(pose_every)], path.frames[pose],
                                                static_cast<double>(f - pose) / pose_every),
                                    path.hfov_deg, o.width, o.height));
      const size_t sent = source.answer(cams, static_cast<uint32_t>(pose), static_cast<size_t>(credit), &ff);
      ff.down_bytes = sent;
      credit -= static_cast<double>(sent);
      // A link with nothing to send carries nothing: no credit is saved up.
      if (ff.update.wanted == 0 || sent == 0) credit = std::min(credit, per_frame);
      if (!first_done) {
        r.first_update_bytes += sent;
        if (ff.update.wanted == 0) {
          first_done = r.first_update_done = true;
          r.first_update_frames = static_cast<uint32_t>(f);
        }
      }
    }
    ff.held = source.held();
    const bool texture_changed = source.changed() || !client;
    if (texture_changed || ground_changed) {
      if (texture_changed) texture = with_alpha(source.texture());
      client = std::make_unique<SceneRenderer>(fine_left > 0 ? coarse_scene : scene, std::vector<io::Image>{texture}, ro);
    }
    const CameraPose& pose = path.frames[f];
    const SceneFrame a = truth.render(pose, path.hfov_deg);
    const SceneFrame b = client->render(pose, path.hfov_deg);
    ff.psnr = io::psnr(a.rgb, b.rgb);
    if (full) {
      const ref::ClientFrame c = ref::render_client(
          *full, ref::to_client(client_camera(scene_camera(pose, path.hfov_deg, o.width, o.height), near_m, far_m)),
          o.width, o.height, ref::ClientRenderSettings{});
      if (c.status != vds::Status::ok)
        throw std::runtime_error(std::string("terrain: the client renderer refused the frame: ") + vds::status_name(c.status));
      ff.psnr_client_renderer = io::psnr(a.rgb, c.image);
    }
    if (o.frame_sink) o.frame_sink(f, a.rgb, b.rgb);
    r.frames.push_back(ff);
    if (o.progress) o.progress(f + 1);
  }
  return r;
}

FlightResult fly(const TerrainCoding& t, const CameraPath& path, const FlightOptions& o) {
  ServerSource s(t, o);
  return fly_source(t, path, o, s);
}

}  // namespace vds::enc
