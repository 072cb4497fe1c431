// vds encoder: the walkthrough's view schedule (vds/enc/walk_views.h).
#include "vds/enc/walk_views.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <tuple>
#include <unordered_map>

#include "vds/enc/scene_render.h"
#include "vds/homography.h"

namespace vds::enc {

namespace {

Q16_16 q16(double v) {
  const double r = std::round(v * 65536.0);
  if (!(std::fabs(r) < 2147483647.0)) throw std::runtime_error("a value outside the client's Q16.16 range: " + std::to_string(v));
  return Q16_16::from_raw(static_cast<int32_t>(r));
}
Q2_30 q30(double v) { return Q2_30::from_raw(static_cast<int32_t>(std::lround(std::clamp(v, -1.0, 1.0) * 1073741823.0))); }

}  // namespace

double scaled_hfov(double hfov_deg, double ratio) {
  const double deg = 3.14159265358979323846 / 180;
  return 2 * std::atan(ratio * std::tan(hfov_deg * deg / 2)) / deg;
}

vds::Camera client_camera(const CameraPose& pose, double hfov_deg, int width, int height, double near_z, double far_z) {
  const SceneCamera c = scene_camera(pose, hfov_deg, width, height);
  vds::Camera k{};
  const std::array<double, 3>* rows[3] = {&c.right, &c.down, &c.forward};
  for (int r = 0; r < 3; ++r)
    for (int j = 0; j < 3; ++j) k.rotation.m[r][j] = q30((*rows[r])[static_cast<size_t>(j)]);
  k.position = {q16(c.position[0]), q16(c.position[1]), q16(c.position[2])};
  k.fx = k.fy = q16(c.focal);
  k.cx = q16(c.cx);
  k.cy = q16(c.cy);
  k.near_z = q16(near_z);
  k.far_z = q16(far_z);
  return k;
}

WalkViewPlan plan_walk_views(const Scene& s, const CameraPath& path,
                             const std::vector<std::vector<std::pair<uint32_t, uint32_t>>>& visible,
                             const WalkViewOptions& o, const std::vector<std::vector<std::pair<uint32_t, uint32_t>>>* view_visible,
                             const WalkViewBuffers* buffers) {
  const size_t n = path.frames.size();
  if (visible.size() != n) throw std::invalid_argument("plan_walk_views: one visibility list per frame");
  if (o.slots < 1 || o.slots > 127 || o.lookahead < 0 || !(o.threshold > 0))
    throw std::invalid_argument("plan_walk_views: options out of range");
  const double view_hfov = o.view_hfov_deg > 0 ? o.view_hfov_deg : path.hfov_deg;
  if (view_visible != nullptr && view_visible->size() != n) throw std::invalid_argument("plan_walk_views: one view visibility list per frame");
  const int vw = o.view_width > 0 ? o.view_width : o.width, vh = o.view_height > 0 ? o.view_height : o.height;
  if (buffers != nullptr) {
    const WalkViewBuffers& b = *buffers;
    const size_t samples = static_cast<size_t>(b.width) * static_cast<size_t>(b.height);
    bool ok = b.step >= 1 && b.width == (o.width + b.step - 1) / b.step && b.height == (o.height + b.step - 1) / b.step &&
              b.screen_ids.size() == n && b.view_ids.size() == n && b.view_depth.size() == n;
    for (size_t f = 0; ok && f < n; ++f)
      ok = b.screen_ids[f].size() == samples && b.view_ids[f].size() == samples && b.view_depth[f].size() == samples;
    if (!ok) throw std::invalid_argument("plan_walk_views: visibility buffers of another size");
  }
  // Each frame's camera as the screen and as a view: the client's and the scene's.
  if (o.zoom < kWalkZoomUnit || o.zoom > kWalkMaxZoom) throw std::invalid_argument("plan_walk_views: a zoom of 16 to 64");
  // A view's camera is named by an index: frame g at the views' own focal
  // length is g, zoomed (WalkViewOptions::zoom) n + g.
  const int zooms = o.zoom > kWalkZoomUnit ? 2 : 1;
  std::vector<vds::Camera> cams, vcams;
  std::vector<SceneCamera> scams, vscams;
  for (const CameraPose& p : path.frames) {
    cams.push_back(client_camera(p, path.hfov_deg, o.width, o.height, o.near_z, o.far_z));
    vcams.push_back(client_camera(p, view_hfov, vw, vh, o.near_z, o.far_z));
    scams.push_back(scene_camera(p, path.hfov_deg, o.width, o.height));
    vscams.push_back(scene_camera(p, view_hfov, vw, vh));
  }
  if (zooms > 1) {
    const double zoomed_hfov = scaled_hfov(view_hfov, static_cast<double>(kWalkZoomUnit) / o.zoom);
    for (size_t g = 0; g < n; ++g) {
      vds::Camera c = vcams[g];  // the client's: the views' focal length times zoom / 16
      c.fx = c.fy = Q16_16::from_raw(static_cast<int32_t>(static_cast<int64_t>(c.fx.raw()) * o.zoom / kWalkZoomUnit));
      vcams.push_back(c);
      vscams.push_back(scene_camera(path.frames[g], zoomed_hfov, vw, vh));
    }
  }
  // Polygons the view at each frame's camera shows, with the pixels they
  // cover there (at the frame's size), for "does view v show polygon p";
  // the pixels each covers on each frame's screen.
  const auto& vv = view_visible != nullptr ? *view_visible : visible;
  std::vector<std::unordered_map<uint32_t, uint32_t>> shows(n), on_screen(n);
  for (size_t f = 0; f < n; ++f) {
    for (const auto& [id, px] : vv[f]) shows[f][id] = px;
    for (const auto& [id, px] : visible[f]) on_screen[f][id] = px;
  }
  // The cameras the view visibility was drawn with.
  std::vector<SceneCamera> rcams;
  for (const CameraPose& p : path.frames) rcams.push_back(scene_camera(p, view_hfov, o.width, o.height));
  const double inf = std::numeric_limits<double>::infinity();
  // The factor of the view at frame g for polygon id on frame f's screen
  // (+inf if g does not show it): the largest magnification of the
  // view -> screen map (the client's fixed-point homography_scale) at the
  // vertices of the part of the polygon frame f's screen shows, in front of
  // the view's near plane.
  using P3 = std::array<double, 3>;
  const auto comb = [](const P3& u, double su, const P3& w, double sw) {
    return P3{u[0] * su + w[0] * sw, u[1] * su + w[1] * sw, u[2] * su + w[2] * sw};
  };
  struct Plane {
    P3 a, c;
    double b;
  };
  // Clips `poly` against planes a . (P - C) >= b.
  const auto clip = [&](std::vector<P3>& poly, const Plane& pl) {
    std::vector<P3> out;
    const auto dist = [&](const P3& p) {
      return pl.a[0] * (p[0] - pl.c[0]) + pl.a[1] * (p[1] - pl.c[1]) + pl.a[2] * (p[2] - pl.c[2]) - pl.b;
    };
    for (size_t i = 0; i < poly.size(); ++i) {
      const P3& a = poly[i];
      const P3& b = poly[(i + 1) % poly.size()];
      const double da = dist(a), db = dist(b);
      if (da >= 0) out.push_back(a);
      if ((da >= 0) != (db >= 0)) out.push_back(comb(a, db / (db - da), b, -da / (db - da)));
    }
    poly.swap(out);
  };
  // The near plane and the four sides of a camera's frustum (w x h pixels).
  const auto frustum = [&](const SceneCamera& c, int w, int h, std::vector<Plane>* planes) {
    const double l = c.cx / c.focal, r = (w - c.cx) / c.focal, t = c.cy / c.focal, btm = (h - c.cy) / c.focal;
    planes->push_back({c.forward, c.position, o.near_z});
    planes->push_back({comb(c.right, 1, c.forward, l), c.position, 0});
    planes->push_back({comb(c.right, -1, c.forward, r), c.position, 0});
    planes->push_back({comb(c.down, 1, c.forward, t), c.position, 0});
    planes->push_back({comb(c.down, -1, c.forward, btm), c.position, 0});
  };
  // The area in pixels of a polygon (inside camera c's frustum) on c's image.
  const auto area_px = [&](const std::vector<P3>& poly, const SceneCamera& c) {
    double a = 0;
    std::vector<std::array<double, 2>> q;
    for (const P3& p : poly) {
      const P3 d{p[0] - c.position[0], p[1] - c.position[1], p[2] - c.position[2]};
      const double z = d[0] * c.forward[0] + d[1] * c.forward[1] + d[2] * c.forward[2];
      q.push_back({c.focal * (d[0] * c.right[0] + d[1] * c.right[1] + d[2] * c.right[2]) / z,
                   c.focal * (d[0] * c.down[0] + d[1] * c.down[1] + d[2] * c.down[2]) / z});
    }
    for (size_t i = 0; i < q.size(); ++i) a += q[i][0] * q[(i + 1) % q.size()][1] - q[(i + 1) % q.size()][0] * q[i][1];
    return std::fabs(a) / 2;
  };
  const auto corners = [&](uint32_t id) {
    std::vector<P3> poly;
    for (int k = 0; k < 3; ++k) {
      const auto& v = s.vertices[s.indices[3 * static_cast<size_t>(id) + static_cast<size_t>(k)]].pos;
      poly.push_back({v[0], v[1], v[2]});
    }
    return poly;
  };
  // The share of a polygon's area inside camera c's frustum that camera
  // sees (its pixels in the visibility drawn there over that area), -1 if
  // the area is too small to tell.
  const auto seen_share = [&](uint32_t id, const SceneCamera& c, uint32_t px) {
    std::vector<P3> poly = corners(id);
    std::vector<Plane> planes;
    frustum(c, o.width, o.height, &planes);
    for (const Plane& pl : planes) {
      clip(poly, pl);
      if (poly.empty()) return -1.0;
    }
    const double a = area_px(poly, c);
    return a >= 24 ? std::min(1.0, px / a) : -1.0;
  };
  // Per-pixel occlusion (buffers): for the screen of frame f and the view
  // at frame g's camera, per polygon, its samples on the screen that land
  // inside the view and those of them behind something else there: the
  // view's depth at the sample it lands on is nearer than the polygon's
  // plane along that sample's ray (so a neighbour in the same plane hides
  // nothing). Kept for the frames the planner is still looking at.
  struct Hidden {
    uint32_t seen = 0, hidden = 0;
  };
  std::map<std::pair<size_t, size_t>, std::unordered_map<uint32_t, Hidden>> hidden_cache;
  const auto hidden_of = [&](size_t f, size_t g) -> const std::unordered_map<uint32_t, Hidden>& {
    auto [it, fresh] = hidden_cache.try_emplace({f, g});
    if (!fresh) return it->second;
    const WalkViewBuffers& b = *buffers;
    const SceneCamera& sf = scams[f];
    const SceneCamera& vg = rcams[g];
    const auto dot = [](const P3& a, const P3& c) { return a[0] * c[0] + a[1] * c[1] + a[2] * c[2]; };
    const auto ray = [&](const SceneCamera& c, double x, double y) {
      return comb(comb(c.forward, 1, c.right, (x - c.cx) / c.focal), 1, c.down, (y - c.cy) / c.focal);
    };
    // Camera-space z along `dir` (forward component 1) from `from` to the plane (normal m through p0); <= 0: none.
    const auto to_plane = [&](const P3& from, const P3& dir, const P3& m, const P3& p0) {
      const double den = dot(m, dir);
      if (std::fabs(den) < 1e-12) return -1.0;
      return dot(m, P3{p0[0] - from[0], p0[1] - from[1], p0[2] - from[2]}) / den;
    };
    const std::vector<uint32_t>& ids = b.screen_ids[f];
    // The plane of the sample's polygon (normal m through p0), kept while
    // the samples of a row stay on one polygon.
    uint32_t plane_of = kNoTriangle;
    P3 p0{}, m{};
    for (int j = 0; j < b.height; ++j)
      for (int i = 0; i < b.width; ++i) {
        const uint32_t id = ids[static_cast<size_t>(j) * static_cast<size_t>(b.width) + static_cast<size_t>(i)];
        if (id == kNoTriangle || 3 * static_cast<size_t>(id) + 2 >= s.indices.size()) continue;
        if (id != plane_of) {
          const auto& a = s.vertices[s.indices[3 * static_cast<size_t>(id)]].pos;
          const auto& b1 = s.vertices[s.indices[3 * static_cast<size_t>(id) + 1]].pos;
          const auto& c1 = s.vertices[s.indices[3 * static_cast<size_t>(id) + 2]].pos;
          const P3 e1{b1[0] - a[0], b1[1] - a[1], b1[2] - a[2]}, e2{c1[0] - a[0], c1[1] - a[1], c1[2] - a[2]};
          p0 = P3{a[0], a[1], a[2]};
          m = P3{e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
          plane_of = id;
        }
        const P3 d = ray(sf, b.step * i + 0.5, b.step * j + 0.5);
        const double t = to_plane(sf.position, d, m, p0);
        if (!(t > 0)) continue;
        const P3 x = comb(sf.position, 1, d, t);
        const P3 r{x[0] - vg.position[0], x[1] - vg.position[1], x[2] - vg.position[2]};
        const double z = dot(r, vg.forward);
        if (!(z > o.near_z)) continue;
        const double u = vg.cx + vg.focal * dot(r, vg.right) / z, v = vg.cy + vg.focal * dot(r, vg.down) / z;
        if (!(u >= 0 && v >= 0 && u < o.width && v < o.height)) continue;
        Hidden& h = it->second[id];
        ++h.seen;
        // Hidden where the four samples around the point all show
        // something nearer (an edge where the polygon meets a wall in
        // front of its plane's extension hides at most two of them).
        // (Sample i lies at pixel centre step i + 1/2.)
        const int iu = static_cast<int>(std::floor((u - 0.5) / b.step)), iv = static_cast<int>(std::floor((v - 0.5) / b.step));
        bool all = true;
        for (int q = 0; q < 4 && all; ++q) {
          const int su = std::clamp(iu + (q & 1), 0, b.width - 1), sv = std::clamp(iv + (q >> 1), 0, b.height - 1);
          const size_t k = static_cast<size_t>(sv) * static_cast<size_t>(b.width) + static_cast<size_t>(su);
          if (b.view_ids[g][k] == id) {
            all = false;
            break;
          }
          const double zp = to_plane(vg.position, ray(vg, b.step * su + 0.5, b.step * sv + 0.5), m, p0);
          all = zp > 0 && b.view_depth[g][k] < zp * 0.98;
        }
        if (all) ++h.hidden;
      }
    return it->second;
  };
  // The share of polygon id's pixels on frame f's screen that the view at
  // frame g (a camera index, zoomed or not) sees something else in front of.
  const auto hidden_share = [&](size_t f, size_t j, uint32_t id) {
    const size_t g = j % n;
    if (f == g) return 0.0;
    const auto& m = hidden_of(f, g);
    const auto e = m.find(id);
    return e == m.end() || e->second.seen == 0 ? 0.0 : static_cast<double>(e->second.hidden) / e->second.seen;
  };
  // Whether the view at frame g sees a clearly smaller share of the
  // polygon than frame f's screen does: something stands in front of it
  // there, which the view would draw onto it.
  const auto occluded = [&](size_t f, size_t j, uint32_t id) {
    const size_t g = j % n;  // (a zoomed view's visibility: its frame's, cut by its image's bounds)
    if (f == g || !(o.occlusion_margin <= 1)) return false;
    const auto shown = shows[g].find(id);
    const auto sf = on_screen[f].find(id);
    if (shown == shows[g].end() || sf == on_screen[f].end()) return false;
    const double on = seen_share(id, scams[f], sf->second);
    if (on < 0) return false;
    const double in_view = seen_share(id, rcams[g], shown->second);
    return in_view >= 0 && in_view < on - o.occlusion_margin;
  };
  // The part of polygon id frame f's screen shows, in front of the near
  // plane of the view at frame g (empty: none).
  const auto screen_part = [&](size_t f, size_t g, uint32_t id) {
    std::vector<P3> poly = corners(id);
    std::vector<Plane> planes;
    frustum(scams[f], o.width, o.height, &planes);
    planes.push_back({vscams[g].forward, vscams[g].position, o.near_z * 1.01});
    for (const Plane& pl : planes) {
      clip(poly, pl);
      if (poly.empty()) break;
    }
    return poly;
  };
  const auto factor = [&](size_t f, size_t g, uint32_t id) {
    const auto shown = shows[g % n].find(id);
    if (shown == shows[g % n].end()) return inf;
    const std::vector<P3> poly = screen_part(f, g, id);
    if (poly.empty()) return inf;
    Vec3<Q16_16> tri[3];
    for (int k = 0; k < 3; ++k) {
      const auto& v = s.vertices[s.indices[3 * static_cast<size_t>(id) + static_cast<size_t>(k)]].pos;
      tri[k] = {q16(v[0]), q16(v[1]), q16(v[2])};
    }
    vds::Homography vs;
    if (vds::plane_homography(vcams[g], cams[f], tri, &vs) != Status::ok) return inf;
    double worst = 0;
    for (const P3& p : poly) {
      int32_t x, y;
      if (!vds::camera_project(vcams[g], vds::camera_transform(vcams[g], {q16(p[0]), q16(p[1]), q16(p[2])}), &x, &y)) return inf;
      // The view must hold the point: inside its image (half a pixel of slack).
      if (x < -128 || y < -128 || x > vw * 256 + 128 || y > vh * 256 + 128) return inf;
      const Q16_16 sc16 = vds::homography_scale(vs, x, y);
      if (sc16 == Q16_16::max()) return inf;
      worst = std::max(worst, sc16.raw() / 65536.0);
    }
    return worst;
  };
  // The MCUs of a view a polygon's part on a screen reads (Update::mcus):
  // the part frame f's screen shows, in front of the view's near plane,
  // projected into the view at frame g with the client's camera; every
  // MCU its outline, widened by the margin, overlaps.
  const int mw = (vw + 15) / 16, mh = (vh + 15) / 16;
  const auto mark = [&](std::vector<uint8_t>& mcus, size_t f, size_t g, uint32_t id) {
    const std::vector<P3> poly = screen_part(f, g, id);
    if (poly.empty()) return;
    std::vector<std::array<double, 2>> q;
    for (const P3& p : poly) {
      int32_t x, y;
      if (!vds::camera_project(vcams[g], vds::camera_transform(vcams[g], {q16(p[0]), q16(p[1]), q16(p[2])}), &x, &y)) {
        std::fill(mcus.begin(), mcus.end(), uint8_t{1});  // cannot tell: all of it
        return;
      }
      q.push_back({x / 256.0, y / 256.0});
    }
    const double m = o.region_margin;
    double x0 = q[0][0], x1 = q[0][0], y0 = q[0][1], y1 = q[0][1];
    double area2 = 0;
    for (size_t i = 0; i < q.size(); ++i) {
      x0 = std::min(x0, q[i][0]), x1 = std::max(x1, q[i][0]);
      y0 = std::min(y0, q[i][1]), y1 = std::max(y1, q[i][1]);
      const auto& b = q[(i + 1) % q.size()];
      area2 += q[i][0] * b[1] - b[0] * q[i][1];
    }
    const int c0 = std::max(0, static_cast<int>(std::floor((x0 - m) / 16))), c1 = std::min(mw - 1, static_cast<int>(std::floor((x1 + m) / 16)));
    const int r0 = std::max(0, static_cast<int>(std::floor((y0 - m) / 16))), r1 = std::min(mh - 1, static_cast<int>(std::floor((y1 + m) / 16)));
    for (int r = r0; r <= r1; ++r)
      for (int c = c0; c <= c1; ++c) {
        // The MCU's box, widened, against the outline's edges (a box wholly
        // outside one edge misses the convex outline; a flat outline: its box).
        const double bx0 = c * 16 - m, bx1 = (c + 1) * 16 + m, by0 = r * 16 - m, by1 = (r + 1) * 16 + m;
        bool hit = true;
        for (size_t i = 0; i < q.size() && hit && std::fabs(area2) > 1e-9; ++i) {
          const auto& a = q[i];
          const auto& b = q[(i + 1) % q.size()];
          const auto side = [&](double x, double y) { return ((b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0])) * area2; };
          if (side(bx0, by0) < 0 && side(bx1, by0) < 0 && side(bx0, by1) < 0 && side(bx1, by1) < 0) hit = false;
        }
        if (hit) mcus[static_cast<size_t>(r * mw + c)] = 1;
      }
  };
  const double limit = o.threshold;
  WalkViewPlan plan;
  plan.updates.resize(n);
  plan.choice.resize(n);
  std::vector<int64_t> held(static_cast<size_t>(o.slots), -1);  // the camera (index, above) of each slot's view
  std::vector<WalkViewPlan::Update*> holder(static_cast<size_t>(o.slots), nullptr);  // the update that put it there
  // Each polygon's view among views `v`: one not occluded for it before an
  // occluded one; of those not occluded the smallest factor; of occluded
  // ones (with the buffers) the one hiding least, then the smallest
  // factor. With the buffers, views within the threshold come first when
  // one serves the polygon, and a view is occluded when it hides more than
  // occlusion_share of the polygon's pixels. -1: no view shows it.
  struct Pick {
    int k = -1;
    double factor = std::numeric_limits<double>::infinity();
    double hidden = 0;  // the share of its pixels the view hides (with the buffers)
  };
  const auto pick_view = [&](size_t f, const std::vector<int64_t>& v, uint32_t id) {
    Pick best;
    // The order of the rules above, smallest first.
    std::tuple<bool, bool, double, double> best_rank;
    for (size_t k = 0; k < v.size(); ++k) {
      if (v[k] < 0) continue;
      const double fk = factor(f, static_cast<size_t>(v[k]), id);
      if (fk == inf) continue;
      const double hk = buffers != nullptr ? hidden_share(f, static_cast<size_t>(v[k]), id) : 0;
      const bool occ = buffers != nullptr ? hk > o.occlusion_share : occluded(f, static_cast<size_t>(v[k]), id);
      const std::tuple<bool, bool, double, double> rank{buffers != nullptr && fk > limit, occ, occ ? hk : 0, fk};
      if (best.k < 0 || rank < best_rank) best = {static_cast<int>(k), fk, hk}, best_rank = rank;
    }
    return best;
  };
  // Whether the views `v` leave frame f unserved: more than tolerance_px
  // of its pixels with no view within the threshold, or (occlusion_updates)
  // more than occlusion_tolerance_px served only by occluded views. With
  // the buffers, a polygon's occluded pixels are those the view it would
  // be drawn from hides.
  const auto unserved = [&](size_t f, const std::vector<int64_t>& v) {
    size_t px_out = 0;
    double px_occluded = 0;
    for (const auto& entry : visible[f]) {
      const uint32_t id = entry.first;
      if (buffers != nullptr) {
        const Pick p = pick_view(f, v, id);
        if (p.k < 0 || p.factor > limit) px_out += entry.second;
        else if (o.occlusion_updates) px_occluded += entry.second * p.hidden;
        continue;
      }
      bool served = false, clear = false;
      for (const int64_t g : v) {
        if (g < 0 || factor(f, static_cast<size_t>(g), id) > limit) continue;
        served = true;
        if (!o.occlusion_updates || !occluded(f, static_cast<size_t>(g), id)) {
          clear = true;
          break;
        }
      }
      if (!served) {
        px_out += entry.second;
      } else if (!clear) {
        px_occluded += entry.second;
      }
    }
    return px_out > o.tolerance_px || px_occluded > static_cast<double>(o.occlusion_tolerance_px);
  };
  for (size_t f = 0; f < n; ++f) {
    // (The planner looks at frames from f on only.)
    hidden_cache.erase(hidden_cache.begin(), hidden_cache.lower_bound({f, 0}));
    if (unserved(f, held)) {
      // An empty slot is filled first; else the slot whose view serves the
      // fewest of this frame's pixels goes.
      size_t victim = 0, victim_px = std::numeric_limits<size_t>::max();
      for (size_t k = 0; k < held.size(); ++k) {
        if (held[k] < 0) {
          victim = k;
          break;
        }
        size_t px_served = 0;
        for (const auto& [id, px] : visible[f]) px_served += factor(f, static_cast<size_t>(held[k]), id) <= limit ? px : 0;
        if (px_served < victim_px) victim = k, victim_px = px_served;
      }
      // The camera, from this frame up to `lookahead` ahead, with which the
      // views serve the most frames from this one on (the frame itself
      // always serves itself; ties: the later camera).
      // A zoomed view instead when it serves long enough (WalkViewOptions::zoom).
      size_t best[2] = {f, f}, best_run[2] = {0, 0};
      const size_t last = std::min(n - 1, f + static_cast<size_t>(o.lookahead));
      for (int z = 0; z < zooms; ++z)
        for (size_t g = f; g <= last; ++g) {
          std::vector<int64_t> trial = held;
          trial[victim] = static_cast<int64_t>(g + static_cast<size_t>(z) * n);
          if (unserved(f, trial)) continue;
          size_t run = 1;
          while (f + run < n && run <= 2 * static_cast<size_t>(o.lookahead) && !unserved(f + run, trial)) ++run;
          if (run >= best_run[z]) best[z] = g, best_run[z] = run;
        }
      const bool zoomed = zooms > 1 && best_run[1] >= static_cast<size_t>(std::max(1, o.zoom_min_run)) &&
                          static_cast<double>(best_run[1]) >= o.zoom_run * static_cast<double>(best_run[0]);
      held[victim] = static_cast<int64_t>(zoomed ? best[1] + n : best[0]);
      plan.updates[f].push_back({static_cast<uint32_t>(victim), static_cast<uint32_t>(zoomed ? best[1] : best[0]),
                                 zoomed ? static_cast<uint8_t>(o.zoom) : kWalkZoomUnit, std::vector<uint8_t>(static_cast<size_t>(mw * mh), 0)});
    }
    // (Each frame's updates are whole: pointers into them stay valid.)
    for (WalkViewPlan::Update& u : plan.updates[f]) holder[u.slot] = &u;
    // Each polygon's view (pick_view).
    for (const auto& [id, px] : visible[f]) {
      const Pick p = pick_view(f, held, id);
      const int8_t pick = static_cast<int8_t>(p.k);
      const double q = p.factor;
      plan.choice[f].push_back(pick);
      if (pick >= 0) mark(holder[static_cast<size_t>(pick)]->mcus, f, static_cast<size_t>(held[static_cast<size_t>(pick)]), id);
      plan.pixels += px;
      if (pick < 0) plan.pixels_unserved += px;
      if (q <= limit) plan.pixels_within += px;
      if (q <= 1) plan.pixels_sharp += px;
    }
  }
  return plan;
}

}  // namespace vds::enc
