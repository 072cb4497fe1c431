// The double-precision reference renderer (vds/enc/ref_render.h): the
// client's primitives and fill rule on edge functions, attributes from the
// exact ray-plane intersection of each pixel centre, plus mip-mapping,
// lightmaps and supersampling for ground-truth frames.
#include "vds/ref/render.h"

#include <stdexcept>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>

namespace vds::ref {

namespace {

using Rgb = std::array<double, 3>;

bool is_pow2(int v) { return v > 0 && (v & (v - 1)) == 0; }

int wrap_or_clamp(int i, int size, bool repeat) {
  if (repeat) return i & (size - 1);
  return std::clamp(i, 0, size - 1);
}

double plane_texel(const Image& img, int x, int y, int c) { return img.at(x, y, c); }

// One level: nearest texel or bilinear blend around (u - 1/2, v - 1/2).
Rgb sample_rgb(const Image& img, double u, double v, Filter f, bool repeat) {
  const int w = img.width, h = img.height;
  if (f == Filter::nearest) {
    const int i = wrap_or_clamp(static_cast<int>(std::floor(u)), w, repeat);
    const int j = wrap_or_clamp(static_cast<int>(std::floor(v)), h, repeat);
    return {plane_texel(img, i, j, 0), plane_texel(img, i, j, 1), plane_texel(img, i, j, 2)};
  }
  const double x = u - 0.5, y = v - 0.5;
  const double fx = std::floor(x), fy = std::floor(y);
  const double a = x - fx, b = y - fy;
  const int i0 = wrap_or_clamp(static_cast<int>(fx), w, repeat), i1 = wrap_or_clamp(static_cast<int>(fx) + 1, w, repeat);
  const int j0 = wrap_or_clamp(static_cast<int>(fy), h, repeat), j1 = wrap_or_clamp(static_cast<int>(fy) + 1, h, repeat);
  Rgb r;
  for (int c = 0; c < 3; ++c) {
    const double top = plane_texel(img, i0, j0, c) * (1 - a) + plane_texel(img, i1, j0, c) * a;
    const double bot = plane_texel(img, i0, j1, c) * (1 - a) + plane_texel(img, i1, j1, c) * a;
    r[static_cast<size_t>(c)] = top * (1 - b) + bot * b;
  }
  return r;
}

double sample_plane(const Image& img, double u, double v, Filter f, bool repeat) {
  const int w = img.width, h = img.height;
  if (f == Filter::nearest) {
    return img.at(wrap_or_clamp(static_cast<int>(std::floor(u)), w, repeat), wrap_or_clamp(static_cast<int>(std::floor(v)), h, repeat), 0);
  }
  const double x = u - 0.5, y = v - 0.5;
  const double fx = std::floor(x), fy = std::floor(y);
  const double a = x - fx, b = y - fy;
  const int i0 = wrap_or_clamp(static_cast<int>(fx), w, repeat), i1 = wrap_or_clamp(static_cast<int>(fx) + 1, w, repeat);
  const int j0 = wrap_or_clamp(static_cast<int>(fy), h, repeat), j1 = wrap_or_clamp(static_cast<int>(fy) + 1, h, repeat);
  const double top = img.at(i0, j0, 0) * (1 - a) + img.at(i1, j0, 0) * a;
  const double bot = img.at(i0, j1, 0) * (1 - a) + img.at(i1, j1, 0) * a;
  return top * (1 - b) + bot * b;
}

struct TextureLevels {
  std::vector<Image> levels;  // level 0 = the texture
};

Image downsample(const Image& a) {
  Image r(std::max(1, a.width / 2), std::max(1, a.height / 2), 3);
  for (int y = 0; y < r.height; ++y)
    for (int x = 0; x < r.width; ++x)
      for (int c = 0; c < 3; ++c) {
        const int x0 = std::min(2 * x, a.width - 1), x1 = std::min(2 * x + 1, a.width - 1);
        const int y0 = std::min(2 * y, a.height - 1), y1 = std::min(2 * y + 1, a.height - 1);
        r.at(x, y, c) = static_cast<uint8_t>((a.at(x0, y0, c) + a.at(x1, y0, c) + a.at(x0, y1, c) + a.at(x1, y1, c) + 2) / 4);
      }
  return r;
}

class Sampler {
 public:
  Sampler(const Scene& s, const RefOptions& o) : scene_(s), opt_(o) {}

  // (u, v) texels of level 0; lod = log2 of the texel footprint of a pixel.
  Rgb sample(int tex, double u, double v, Filter f, double lod) {
    const TextureD& t = scene_.textures.at(static_cast<size_t>(tex));
    const bool repeat = t.address == TexAddress::repeat && is_pow2(t.image.width) && is_pow2(t.image.height);
    if (t.ycbcr) {
      const bool crep = repeat && is_pow2(t.cb.width) && is_pow2(t.cb.height);
      return ycbcr_to_rgb(sample_plane(t.y, u, v, f, repeat), sample_plane(t.cb, u / 2, v / 2, f, crep),
                          sample_plane(t.cr, u / 2, v / 2, f, crep));
    }
    if (!opt_.mipmap || lod <= 0 || !repeat) return sample_rgb(t.image, u, v, f, repeat);
    const TextureLevels& lv = levels(tex);
    const double l = std::min(lod, static_cast<double>(lv.levels.size() - 1));
    const int k = static_cast<int>(std::floor(l));
    const double a = l - k;
    auto at = [&](int level) {
      const double s = std::ldexp(1.0, -level);
      return sample_rgb(lv.levels[static_cast<size_t>(level)], u * s, v * s, Filter::bilinear, true);
    };
    const Rgb c0 = at(k);
    if (a == 0 || k + 1 >= static_cast<int>(lv.levels.size())) return c0;
    const Rgb c1 = at(k + 1);
    return {c0[0] * (1 - a) + c1[0] * a, c0[1] * (1 - a) + c1[1] * a, c0[2] * (1 - a) + c1[2] * a};
  }

 private:
  const TextureLevels& levels(int tex) {
    auto it = cache_.find(tex);
    if (it != cache_.end()) return it->second;
    TextureLevels lv;
    lv.levels.push_back(scene_.textures[static_cast<size_t>(tex)].image);
    while (lv.levels.back().width > 1 || lv.levels.back().height > 1) lv.levels.push_back(downsample(lv.levels.back()));
    return cache_.emplace(tex, std::move(lv)).first->second;
  }
  const Scene& scene_;
  RefOptions opt_;
  std::map<int, TextureLevels> cache_;
};

// Sutherland-Hodgman against near <= z <= far (camera space).
std::vector<Vec3d> clip_depth(const std::vector<Vec3d>& in, double near_z, double far_z) {
  std::vector<Vec3d> poly = in;
  for (int plane = 0; plane < 2; ++plane) {
    auto dist = [&](const Vec3d& p) { return plane == 0 ? p.z - near_z : far_z - p.z; };
    std::vector<Vec3d> out;
    for (size_t i = 0; i < poly.size(); ++i) {
      const Vec3d& a = poly[i];
      const Vec3d& b = poly[(i + 1) % poly.size()];
      const double da = dist(a), db = dist(b);
      if (da >= 0) out.push_back(a);
      if ((da >= 0) != (db >= 0)) {
        // From the inside end, as the client does.
        const Vec3d& in_p = da >= 0 ? a : b;
        const Vec3d& out_p = da >= 0 ? b : a;
        const double din = da >= 0 ? da : db, dout = da >= 0 ? db : da;
        out.push_back(in_p + (out_p - in_p) * (din / (din - dout)));
      }
    }
    poly = std::move(out);
    if (poly.size() < 3) return {};
  }
  return poly;
}

struct SV {
  double x, y;
};

// Top-left rule on a triangle with positive area2 (clockwise on screen).
bool edge_in(const SV& p, const SV& q, double x, double y) {
  const double e = (q.x - p.x) * (y - p.y) - (q.y - p.y) * (x - p.x);
  if (e > 0) return true;
  if (e < 0) return false;
  return q.y < p.y || (q.y == p.y && q.x > p.x);
}

uint8_t round8(double v) { return static_cast<uint8_t>(std::clamp(std::lround(v), 0L, 255L)); }

Mat3d normalised(Mat3d h) {
  double mx = 0;
  for (auto& row : h.m)
    for (double v : row) mx = std::max(mx, std::fabs(v));
  if (mx > 0)
    for (auto& row : h.m)
      for (double& v : row) v /= mx;
  return h;
}

}  // namespace

bool project(const CameraD& cam, Vec3d world, double* x, double* y) {
  const Vec3d c = cam.to_camera(world);
  if (c.z <= 0) return false;
  *x = cam.cx + cam.fx * c.x / c.z;
  *y = cam.cy + cam.fy * c.y / c.z;
  return true;
}

Mat3d plane_homography(const CameraD& from, const CameraD& to, const Vec3d plane[3]) {
  const Vec3d n = cross(plane[1] - plane[0], plane[2] - plane[0]);
  const double delta = dot(n, plane[0] - from.position);
  const Vec3d c = from.position - to.position;
  Mat3d m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const double ci = i == 0 ? c.x : i == 1 ? c.y : c.z;
      const double nj = j == 0 ? n.x : j == 1 ? n.y : n.z;
      m.m[i][j] = ci * nj + (i == j ? delta : 0.0);
    }
  Mat3d kto;
  kto.m[0][0] = to.fx, kto.m[0][2] = to.cx, kto.m[1][1] = to.fy, kto.m[1][2] = to.cy;
  Mat3d kinv;
  kinv.m[0][0] = 1 / from.fx, kinv.m[0][2] = -from.cx / from.fx, kinv.m[1][1] = 1 / from.fy,
  kinv.m[1][2] = -from.cy / from.fy;
  Mat3d h = normalised(kto * to.rotation * m * transpose(from.rotation) * kinv);
  // W = (n . d) z_to along the ray d of a `from` pixel, and n . d has the sign
  // of delta in front of `from`: with delta > 0, W > 0 where `to` sees the point.
  if (delta < 0)
    for (auto& row : h.m)
      for (double& v : row) v = -v;
  return h;
}

bool homography_apply(const Mat3d& h, double x, double y, double* ox, double* oy) {
  const double X = h.m[0][0] * x + h.m[0][1] * y + h.m[0][2];
  const double Y = h.m[1][0] * x + h.m[1][1] * y + h.m[1][2];
  const double W = h.m[2][0] * x + h.m[2][1] * y + h.m[2][2];
  if (W <= 0) return false;
  *ox = X / W;
  *oy = Y / W;
  return true;
}

double homography_scale(const Mat3d& h, double x, double y) {
  const double X = h.m[0][0] * x + h.m[0][1] * y + h.m[0][2];
  const double Y = h.m[1][0] * x + h.m[1][1] * y + h.m[1][2];
  const double W = h.m[2][0] * x + h.m[2][1] * y + h.m[2][2];
  if (W == 0) return std::numeric_limits<double>::infinity();
  const double x1 = X / W, y1 = Y / W;
  // Eq. 9: the Jacobian of (x, y) -> (X/W, Y/W).
  const double j11 = (h.m[0][0] - x1 * h.m[2][0]) / W, j12 = (h.m[0][1] - x1 * h.m[2][1]) / W;
  const double j21 = (h.m[1][0] - y1 * h.m[2][0]) / W, j22 = (h.m[1][1] - y1 * h.m[2][1]) / W;
  // Eq. 5.
  const double s = 0.5 * (j11 * j11 + j12 * j12 + j21 * j21 + j22 * j22);
  const double det = j11 * j22 - j12 * j21;
  const double lambda = s + std::sqrt(std::max(0.0, s * s - det * det));
  return std::sqrt(lambda);
}

double texture_quality(const CameraD& screen, const CameraD& view, const std::vector<Vec3d>& polygon) {
  const Mat3d vs = plane_homography(view, screen, polygon.data());
  double worst = 0;
  for (const Vec3d& p : polygon) {
    double x, y;
    if (!project(view, p, &x, &y)) return std::numeric_limits<double>::infinity();
    worst = std::max(worst, homography_scale(vs, x, y));
  }
  return worst;
}

RefFrame ref_render(const Scene& scene, const CameraD& camera_in, int width, int height, const RefOptions& opt) {
  const int ss = std::max(1, opt.supersample);
  const CameraD cam = camera_in.scaled(ss);
  const int W = width * ss, H = height * ss;
  std::vector<Rgb> color(static_cast<size_t>(W) * H,
                         Rgb{double((scene.clear_color >> 16) & 255), double((scene.clear_color >> 8) & 255),
                             double(scene.clear_color & 255)});
  std::vector<double> zbuf(static_cast<size_t>(W) * H, 0.0);
  std::vector<int32_t> ids;
  if (opt.want_ids) ids.assign(zbuf.size(), -1);
  Sampler sampler(scene, opt);
  int32_t tri_id = 0;

  for (const MeshD& m : scene.meshes) {
    // A scene carries textures, not mesh colors: those are drawn in double
    // by vds::enc::render_mesh_colors (vds/enc/model_render.h).
    if (m.shading == Shading::mesh_colors)
      throw std::invalid_argument("ref_render: mesh colors are drawn by enc::render_mesh_colors");
    Mat3d view_map;
    if (m.shading == Shading::view_mapped && m.indices.size() >= 3) {
      const Vec3d pl[3] = {scene.positions[m.indices[0]], scene.positions[m.indices[1]], scene.positions[m.indices[2]]};
      view_map = plane_homography(camera_in, m.view_camera, pl);
    }
    for (size_t t = 0; t + 2 < m.indices.size(); t += 3, ++tri_id) {
      const uint32_t vi[3] = {m.indices[t], m.indices[t + 1], m.indices[t + 2]};
      const Vec3d c0 = cam.to_camera(scene.positions[vi[0]]);
      const Vec3d c1 = cam.to_camera(scene.positions[vi[1]]);
      const Vec3d c2 = cam.to_camera(scene.positions[vi[2]]);
      const Vec3d n = cross(c1 - c0, c2 - c0);
      const double facing = dot(n, c0);  // < 0: the normal points at the camera (front)
      if (facing == 0) continue;
      if ((m.cull == Cull::back && facing > 0) || (m.cull == Cull::front && facing < 0)) continue;
      const std::vector<Vec3d> poly = clip_depth({c0, c1, c2}, cam.near_z, cam.far_z);
      if (poly.size() < 3) continue;
      std::vector<SV> sv;
      for (const Vec3d& p : poly) sv.push_back({cam.cx + cam.fx * p.x / p.z, cam.cy + cam.fy * p.y / p.z});

      // Barycentric set-up on the original triangle (camera space).
      const Vec3d e0 = c1 - c0, e1 = c2 - c0;
      const double d00 = dot(e0, e0), d01 = dot(e0, e1), d11 = dot(e1, e1);
      const double denom = d00 * d11 - d01 * d01;
      auto bary = [&](Vec3d p, double* b1, double* b2) {
        const Vec3d e2 = p - c0;
        const double d20 = dot(e2, e0), d21 = dot(e2, e1);
        *b1 = (d11 * d20 - d01 * d21) / denom;
        *b2 = (d00 * d21 - d01 * d20) / denom;
      };
      auto point_at = [&](double px, double py, Vec3d* p) {
        const Vec3d r{(px - cam.cx) / cam.fx, (py - cam.cy) / cam.fy, 1.0};
        const double nr = dot(n, r);
        if (nr == 0) return false;
        *p = r * (facing / nr);
        return true;
      };
      auto attr2 = [&](const std::vector<Vec2d>& a, double b1, double b2) {
        const Vec2d a0 = a[vi[0]], a1 = a[vi[1]], a2 = a[vi[2]];
        return Vec2d{a0.x + b1 * (a1.x - a0.x) + b2 * (a2.x - a0.x), a0.y + b1 * (a1.y - a0.y) + b2 * (a2.y - a0.y)};
      };

      for (size_t k = 1; k + 1 < sv.size(); ++k) {
        SV a = sv[0], b = sv[k], c = sv[k + 1];
        const double area = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
        if (area == 0) continue;
        if (area < 0) std::swap(b, c);
        const double minx = std::min({a.x, b.x, c.x}), maxx = std::max({a.x, b.x, c.x});
        const double miny = std::min({a.y, b.y, c.y}), maxy = std::max({a.y, b.y, c.y});
        const int x0 = std::max(0, static_cast<int>(std::ceil(minx - 0.5)));
        const int x1 = std::min(W, static_cast<int>(std::ceil(maxx - 0.5)) + 1);
        const int y0 = std::max(0, static_cast<int>(std::ceil(miny - 0.5)));
        const int y1 = std::min(H, static_cast<int>(std::ceil(maxy - 0.5)) + 1);
        for (int py = y0; py < y1; ++py)
          for (int px = x0; px < x1; ++px) {
            const double xc = px + 0.5, yc = py + 0.5;
            if (!edge_in(a, b, xc, yc) || !edge_in(b, c, xc, yc) || !edge_in(c, a, xc, yc)) continue;
            Vec3d p;
            if (!point_at(xc, yc, &p) || p.z <= 0) continue;
            const double inv = 1.0 / p.z;
            const size_t o = static_cast<size_t>(py) * W + px;
            if (!(inv > zbuf[o])) continue;
            zbuf[o] = inv;
            if (opt.want_ids) ids[o] = tri_id;
            double b1, b2;
            bary(p, &b1, &b2);
            Rgb col{};
            switch (m.shading) {
              case Shading::flat:
                col = {double((m.color >> 16) & 255), double((m.color >> 8) & 255), double(m.color & 255)};
                break;
              case Shading::gouraud: {
                for (int ch = 0; ch < 3; ++ch) {
                  auto chan = [&](uint32_t v) { return double((v >> (16 - 8 * ch)) & 255); };
                  const double v0 = chan(scene.colors[vi[0]]), v1 = chan(scene.colors[vi[1]]), v2 = chan(scene.colors[vi[2]]);
                  col[static_cast<size_t>(ch)] = v0 + b1 * (v1 - v0) + b2 * (v2 - v0);
                }
                break;
              }
              case Shading::texture: {
                const Vec2d uv = attr2(scene.uvs, b1, b2);
                double lod = 0;
                if (opt.mipmap) {
                  Vec3d px1, py1;
                  if (point_at(xc + 1, yc, &px1) && point_at(xc, yc + 1, &py1)) {
                    double u1, u2, w1, w2;
                    bary(px1, &u1, &u2);
                    bary(py1, &w1, &w2);
                    const Vec2d dx = attr2(scene.uvs, u1, u2), dy = attr2(scene.uvs, w1, w2);
                    const double rho = std::max(std::hypot(dx.x - uv.x, dx.y - uv.y), std::hypot(dy.x - uv.x, dy.y - uv.y));
                    lod = rho > 0 ? std::log2(rho) : 0;
                  }
                }
                col = sampler.sample(m.texture, uv.x, uv.y, m.filter, lod);
                break;
              }
              case Shading::mesh_colors: break;  // refused above
              case Shading::view_mapped: {
                // view_map is in pixels of the unscaled camera.
                double u = 0, v = 0;
                homography_apply(view_map, xc / ss, yc / ss, &u, &v);
                col = sampler.sample(m.texture, u, v, m.filter, 0);
                break;
              }
            }
            if (opt.lightmaps && m.lightmap >= 0) {
              const Vec2d luv = attr2(scene.lightmap_uvs, b1, b2);
              const TextureD& lt = scene.textures.at(static_cast<size_t>(m.lightmap));
              const Rgb l = sample_rgb(lt.image, luv.x, luv.y, Filter::bilinear, false);
              for (int ch = 0; ch < 3; ++ch) col[static_cast<size_t>(ch)] *= l[static_cast<size_t>(ch)] / 255.0 * opt.lightmap_scale;
            }
            color[o] = col;
          }
      }
    }
  }

  RefFrame out;
  out.image = Image(width, height, 3);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      Rgb s{};
      for (int j = 0; j < ss; ++j)
        for (int i = 0; i < ss; ++i) {
          const Rgb& c = color[static_cast<size_t>(y * ss + j) * W + (x * ss + i)];
          for (int ch = 0; ch < 3; ++ch) s[static_cast<size_t>(ch)] += c[static_cast<size_t>(ch)];
        }
      for (int ch = 0; ch < 3; ++ch) out.image.at(x, y, ch) = round8(s[static_cast<size_t>(ch)] / (ss * ss));
    }
  if (ss == 1) {
    out.inv_depth = std::move(zbuf);
    out.ids = std::move(ids);
  }
  return out;
}

}  // namespace vds::ref
