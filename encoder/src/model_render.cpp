// vds encoder: rendered views of textured models (vds/enc/model_render.h).
#include "vds/enc/model_render.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "vds/mesh_colors.h"

namespace vds::enc {
namespace {

constexpr double kPi = 3.14159265358979323846;

using Rgb = std::array<double, 3>;

// Draws every face with a z-buffer at the supersampled size, then shades
// each sample once: shade(face, perspective-correct barycentric weights).
template <class Face, class Shade>
ModelFrame rasterise(const std::vector<std::array<double, 3>>& positions, size_t faces, Face face_vertices,
                     const ref::CameraD& cam, const ModelViews& v, Shade shade) {
  const int ss = std::max(1, v.supersample);
  const int W = v.width * ss, H = v.height * ss;
  const ref::CameraD c = cam.scaled(ss);
  std::vector<double> depth(static_cast<size_t>(W) * H, 0);
  std::vector<int32_t> id(static_cast<size_t>(W) * H, -1);
  std::vector<Rgb> weights(static_cast<size_t>(W) * H);
  for (size_t f = 0; f < faces; ++f) {
    const std::array<uint32_t, 3> tri = face_vertices(f);
    double sx[3], sy[3], iz[3];
    bool visible = true;
    for (int k = 0; k < 3; ++k) {
      const auto& p = positions[tri[k]];
      const ref::Vec3d q = c.to_camera({p[0], p[1], p[2]});
      if (q.z <= c.near_z) visible = false;
      iz[k] = 1 / q.z;
      sx[k] = c.fx * q.x * iz[k] + c.cx;
      sy[k] = c.fy * q.y * iz[k] + c.cy;
    }
    for (int k = 0; k < 3; ++k)
      if (!(std::fabs(sx[k]) < 1e9 && std::fabs(sy[k]) < 1e9)) visible = false;  // NaN too
    if (!visible) continue;
    const double area = (sx[1] - sx[0]) * (sy[2] - sy[0]) - (sx[2] - sx[0]) * (sy[1] - sy[0]);
    if (std::fabs(area) < 1e-12) continue;
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min({sx[0], sx[1], sx[2]}))));
    const int x1 = std::min(W - 1, static_cast<int>(std::ceil(std::max({sx[0], sx[1], sx[2]}))));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min({sy[0], sy[1], sy[2]}))));
    const int y1 = std::min(H - 1, static_cast<int>(std::ceil(std::max({sy[0], sy[1], sy[2]}))));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const double px = x + 0.5, py = y + 0.5;
        double b[3];
        for (int k = 0; k < 3; ++k) {
          const int i = (k + 1) % 3, j = (k + 2) % 3;
          b[k] = ((sx[j] - sx[i]) * (py - sy[i]) - (px - sx[i]) * (sy[j] - sy[i])) / area;
        }
        if (b[0] < 0 || b[1] < 0 || b[2] < 0) continue;
        const double inv = b[0] * iz[0] + b[1] * iz[1] + b[2] * iz[2];
        const size_t at = static_cast<size_t>(y) * W + x;
        if (inv <= depth[at]) continue;
        depth[at] = inv;
        id[at] = static_cast<int32_t>(f);
        weights[at] = {b[0] * iz[0] / inv, b[1] * iz[1] / inv, b[2] * iz[2] / inv};
      }
  }
  ModelFrame out;
  out.rgb = Image(v.width, v.height, 3);
  out.mask = Image(v.width, v.height, 1);
  for (int y = 0; y < v.height; ++y)
    for (int x = 0; x < v.width; ++x) {
      Rgb sum{0, 0, 0};
      int covered = 0;
      for (int dy = 0; dy < ss; ++dy)
        for (int dx = 0; dx < ss; ++dx) {
          const size_t at = static_cast<size_t>(y * ss + dy) * W + (x * ss + dx);
          if (id[at] < 0) continue;
          const Rgb col = shade(static_cast<size_t>(id[at]), weights[at]);
          for (int k = 0; k < 3; ++k) sum[k] += col[k];
          ++covered;
        }
      for (int k = 0; k < 3; ++k)
        out.rgb.at(x, y, k) = static_cast<uint8_t>(std::lround(std::clamp(sum[k] / (ss * ss), 0.0, 255.0)));
      out.mask.at(x, y, 0) = covered > 0 ? 255 : 0;
    }
  return out;
}

Rgb bilinear(const Image& img, double u, double v) { return io::bilinear_repeat(img, u * img.width, (1 - v) * img.height); }

}  // namespace

namespace {

// The orbit: round the centre of the bounds, framing the bounding sphere.
constexpr double kOrbitFovDegrees = 40;
struct Orbit {
  ref::Vec3d centre;
  double radius, distance;
};
Orbit orbit_of(const std::vector<std::array<double, 3>>& positions) {
  std::array<double, 3> lo = positions[0], hi = positions[0];
  for (const auto& p : positions)
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
  const ref::Vec3d centre{(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2};
  double radius = 0;
  for (const auto& p : positions)
    radius = std::max(radius, std::hypot(p[0] - centre.x, p[1] - centre.y, p[2] - centre.z));
  if (radius <= 0) radius = 1;
  return Orbit{centre, radius, radius / std::sin(kOrbitFovDegrees / 2 * kPi / 180) * 1.05};
}

}  // namespace

std::vector<uint8_t> display_face_caps(const std::vector<std::array<double, 3>>& positions,
                                       const std::vector<std::array<uint32_t, 3>>& triangles, double px_per_unit,
                                       double samples_per_pixel) {
  std::vector<uint8_t> caps(triangles.size());
  for (size_t f = 0; f < triangles.size(); ++f) {
    const auto& a = positions[triangles[f][0]];
    const auto& b = positions[triangles[f][1]];
    const auto& c = positions[triangles[f][2]];
    double e[2][3];
    for (int k = 0; k < 3; ++k) {
      e[0][k] = (b[k] - a[k]) * px_per_unit;
      e[1][k] = (c[k] - a[k]) * px_per_unit;
    }
    const double cx = e[0][1] * e[1][2] - e[0][2] * e[1][1], cy = e[0][2] * e[1][0] - e[0][0] * e[1][2],
                 cz = e[0][0] * e[1][1] - e[0][1] * e[1][0];
    const double area = 0.5 * std::sqrt(cx * cx + cy * cy + cz * cz);
    const double samples = std::max(1.0, samples_per_pixel * std::sqrt(2 * area));
    caps[f] = static_cast<uint8_t>(std::clamp(static_cast<int>(std::ceil(std::log2(samples) - 1e-9)), 0, mc::kMaxResLog2));
  }
  return caps;
}

double orbit_nearest_px_per_unit(const std::vector<std::array<double, 3>>& positions, int height) {
  if (positions.empty() || height < 1) throw std::invalid_argument("orbit_nearest_px_per_unit: no positions or no pixels");
  const Orbit o = orbit_of(positions);
  const double focal = height / 2.0 / std::tan(kOrbitFovDegrees / 2 * kPi / 180);
  return focal / std::max(o.distance - o.radius, o.distance * 0.01);
}

ModelViews orbit_views(const std::vector<std::array<double, 3>>& positions, int count, int width, int height,
                       int supersample, int up) {
  if (positions.empty() || count < 1) throw std::invalid_argument("orbit_views: no positions or no views");
  const Orbit o = orbit_of(positions);
  const ref::Vec3d centre = o.centre;
  const double fov = kOrbitFovDegrees;
  const double distance = o.distance;
  ModelViews v;
  v.width = width;
  v.height = height;
  v.supersample = supersample;
  for (int i = 0; i < count; ++i) {
    const double yaw = 2 * kPi * i / count, pitch = (i % 2 == 0 ? 20 : -20) * kPi / 180;
    // Round +y from +z towards +x; round +z from -y towards +x.
    const ref::Vec3d u = up == 2 ? ref::Vec3d{0, 0, 1} : ref::Vec3d{0, 1, 0};
    const ref::Vec3d front = up == 2 ? ref::Vec3d{0, -1, 0} : ref::Vec3d{0, 0, 1}, side{1, 0, 0};
    const ref::Vec3d eye = centre + (side * std::sin(yaw) + front * std::cos(yaw)) * (distance * std::cos(pitch)) +
                           u * (distance * std::sin(pitch));
    v.cameras.push_back(ref::CameraD::look_at(eye, centre, u, width, height, fov, distance * 0.01, distance * 4));
  }
  return v;
}

ModelFrame render_textured(const TexturedModel& model, const std::vector<Image>& textures, const ref::CameraD& cam,
                           const ModelViews& v) {
  if (textures.size() != model.textures.size()) throw std::invalid_argument("render_textured: texture count differs");
  return rasterise(
      model.positions, model.triangles.size(), [&](size_t f) { return model.triangles[f]; }, cam, v,
      [&](size_t f, const Rgb& w) {
        const TexturedMaterial& mat = model.materials[static_cast<size_t>(model.material[f])];
        Rgb c{255, 255, 255};
        if (mat.texture >= 0) {
          const auto& uv = model.uv[f];
          c = bilinear(textures[static_cast<size_t>(mat.texture)], w[0] * uv[0][0] + w[1] * uv[1][0] + w[2] * uv[2][0],
                       w[0] * uv[0][1] + w[1] * uv[1][1] + w[2] * uv[2][1]);
        }
        for (int k = 0; k < 3; ++k)
          c[k] *= mat.colour[k] *
                  (w[0] * model.colour[f][0][k] + w[1] * model.colour[f][1][k] + w[2] * model.colour[f][2][k]);
        return c;
      });
}

std::vector<ModelFrame> render_references(const TexturedModel& model, const ModelViews& v) {
  std::vector<ModelFrame> out;
  for (const auto& cam : v.cameras) out.push_back(render_textured(model, model.textures, cam, v));
  return out;
}

ModelFrame render_mesh_colors(const MeshColorsModel& mc, const std::array<std::vector<uint8_t>, 3>& planes, int m,
                              const ref::CameraD& cam, const ModelViews& v) {
  const uint32_t F = static_cast<uint32_t>(mc.face_res.size()), V = static_cast<uint32_t>(mc.positions.size());
  std::vector<uint8_t> work(vds::mc::MeshColors::init_bytes(F, V));
  Arena arena(work.data(), work.size());
  vds::mc::MeshColors layout;
  if (layout.init(arena, mc.triangles.data(), F, V) != Status::ok ||
      layout.set(mc.face_res.data(), nullptr, 256) != Status::ok)
    throw std::invalid_argument("render_mesh_colors: not a mesh a client holds");
  if (layout.layout_level(m) != planes[0].size()) throw std::invalid_argument("render_mesh_colors: planes of another level");
  auto sample = [&](uint32_t f, uint32_t i, uint32_t j) {
    const uint32_t s = layout.sample_index(f, m, i, j);
    return ref::ycbcr_to_rgb(planes[0][s], planes[1][s], planes[2][s]);
  };
  return rasterise(
      mc.positions, F,
      [&](size_t f) {
        return std::array<uint32_t, 3>{mc.triangles[3 * f], mc.triangles[3 * f + 1], mc.triangles[3 * f + 2]};
      },
      cam, v,
      [&](size_t f, const Rgb& w) {
        // The linear filter of Yuksel et al.: the lattice triangle holding
        // the point, its three samples weighted barycentrically.
        const uint32_t R = vds::mc::resolution(vds::mc::level_res(mc.face_res[f], m));
        const double a = std::clamp(w[1], 0.0, 1.0) * R, b = std::clamp(w[2], 0.0, 1.0) * R;
        uint32_t i = static_cast<uint32_t>(std::min<double>(std::floor(a), R));
        uint32_t j = static_cast<uint32_t>(std::min<double>(std::floor(b), R - i));
        const double fi = std::clamp(a - i, 0.0, 1.0), fj = std::clamp(b - j, 0.0, 1.0);
        const uint32_t face = static_cast<uint32_t>(f);
        if (i + j >= R) return sample(face, i, R - i);
        if (fi + fj <= 1) {
          const Rgb s0 = sample(face, i, j), s1 = sample(face, i + 1, j), s2 = sample(face, i, j + 1);
          Rgb out;
          for (int k = 0; k < 3; ++k) out[k] = s0[k] * (1 - fi - fj) + s1[k] * fi + s2[k] * fj;
          return out;
        }
        const Rgb s0 = sample(face, i + 1, j + 1), s1 = sample(face, i + 1, j), s2 = sample(face, i, j + 1);
        Rgb out;
        for (int k = 0; k < 3; ++k) out[k] = s0[k] * (fi + fj - 1) + s1[k] * (1 - fj) + s2[k] * (1 - fi);
        return out;
      });
}

double masked_mse(const ModelFrame& ref, const ModelFrame& test) {
  if (ref.rgb.width != test.rgb.width || ref.rgb.height != test.rgb.height)
    throw std::invalid_argument("masked_mse: sizes differ");
  double se = 0;
  size_t n = 0;
  for (int y = 0; y < ref.rgb.height; ++y)
    for (int x = 0; x < ref.rgb.width; ++x) {
      if (ref.mask.at(x, y, 0) == 0) continue;
      for (int k = 0; k < 3; ++k) {
        const double d = static_cast<double>(ref.rgb.at(x, y, k)) - test.rgb.at(x, y, k);
        se += d * d;
      }
      n += 3;
    }
  return n == 0 ? 0 : se / n;
}

double psnr_of_mse(double mse) { return mse <= 0 ? 99 : 10 * std::log10(255.0 * 255.0 / mse); }

}  // namespace vds::enc
