// vds encoder: camera tours (vds/enc/camera_tour.h).
#include "vds/enc/camera_tour.h"

#include <algorithm>
#include <cmath>
#include <queue>
#include <stdexcept>
#include <unordered_map>

namespace vds::enc {

namespace {

constexpr double kPi = 3.14159265358979323846;

Vec3 add(const Vec3& a, const Vec3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
Vec3 sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec3 mul(const Vec3& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
double len(const Vec3& a) { return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }

// The free-space grid, evaluated lazily.
class Grid {
 public:
  Grid(const Scene& s, const SceneRays& rays, const TourOptions& o) : rays_(rays), o_(o) {
    for (int k = 0; k < 3; ++k) {
      lo_[k] = s.min[k] - o.cell;
      n_[k] = std::max(1, static_cast<int>(std::ceil((s.max[k] - s.min[k] + 2 * o.cell) / o.cell)));
    }
    const size_t cells = static_cast<size_t>(n_[0]) * n_[1] * n_[2];
    if (cells > (size_t{1} << 26)) throw std::runtime_error(s.name + ": the scene is too large for a tour grid of " +
                                                            std::to_string(o.cell) + "-unit cells");
    free_.assign(cells, -1);
    floor_.assign(cells, -1.0f);
  }
  size_t size() const { return free_.size(); }
  Vec3 centre(size_t c) const {
    const int x = static_cast<int>(c % n_[0]), y = static_cast<int>((c / n_[0]) % n_[1]), z = static_cast<int>(c / (static_cast<size_t>(n_[0]) * n_[1]));
    return {lo_[0] + (x + 0.5) * o_.cell, lo_[1] + (y + 0.5) * o_.cell, lo_[2] + (z + 0.5) * o_.cell};
  }
  bool index(const Vec3& p, size_t* c) const {
    int i[3];
    for (int k = 0; k < 3; ++k) {
      i[k] = static_cast<int>(std::floor((p[k] - lo_[k]) / o_.cell));
      if (i[k] < 0 || i[k] >= n_[k]) return false;
    }
    *c = (static_cast<size_t>(i[2]) * n_[1] + i[1]) * n_[0] + i[0];
    return true;
  }
  bool neighbour(size_t c, int dx, int dy, int dz, size_t* out) const {
    const int x = static_cast<int>(c % n_[0]) + dx, y = static_cast<int>((c / n_[0]) % n_[1]) + dy,
              z = static_cast<int>(c / (static_cast<size_t>(n_[0]) * n_[1])) + dz;
    if (x < 0 || y < 0 || z < 0 || x >= n_[0] || y >= n_[1] || z >= n_[2]) return false;
    *out = (static_cast<size_t>(z) * n_[1] + y) * n_[0] + x;
    return true;
  }
  bool is_free(size_t c) {
    if (free_[c] < 0) free_[c] = rays_.clear(centre(c), o_.radius) ? 1 : 0;
    return free_[c] == 1;
  }
  // Cost factor of a cell: 1 within walking height of the floor, rising above it.
  double height_cost(size_t c) {
    if (floor_[c] < 0) floor_[c] = static_cast<float>(rays_.cast(centre(c), {0, 0, -1}, 1024));
    const double above = floor_[c] - (o_.eye_height + 24 + o_.cell);
    return 1 + std::max(0.0, above) / 24;
  }

 private:
  const SceneRays& rays_;
  const TourOptions& o_;
  Vec3 lo_{};
  int n_[3]{};
  std::vector<int8_t> free_;
  std::vector<float> floor_;
};

// A* from point a to point b through the grid; empty if no route.
std::vector<Vec3> route(Grid& g, const SceneRays& rays, const Vec3& a, const Vec3& b, double radius) {
  // Cells near each end that the end sees along a clear segment.
  const auto attach = [&](const Vec3& p) {
    std::vector<size_t> out;
    size_t c;
    if (!g.index(p, &c)) return out;
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          size_t nb;
          if (g.neighbour(c, dx, dy, dz, &nb) && g.is_free(nb) && rays.segment_clear(p, g.centre(nb), radius * 0.5))
            out.push_back(nb);
        }
    return out;
  };
  const std::vector<size_t> starts = attach(a), goals = attach(b);
  if (starts.empty() || goals.empty()) return {};
  std::unordered_map<size_t, double> cost;
  std::unordered_map<size_t, size_t> from;
  using Item = std::pair<double, size_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> open;
  for (size_t s : starts) {
    cost[s] = len(sub(g.centre(s), a));
    from[s] = s;
    open.push({cost[s] + len(sub(g.centre(s), b)), s});
  }
  size_t reached = SIZE_MAX;
  size_t expanded = 0;
  while (!open.empty() && expanded < 400000) {
    const auto [f, c] = open.top();
    open.pop();
    const double cc = cost[c];
    if (f > cc + len(sub(g.centre(c), b)) + 1e-9) continue;  // stale
    ++expanded;
    if (std::find(goals.begin(), goals.end(), c) != goals.end()) {
      reached = c;
      break;
    }
    const Vec3 pc = g.centre(c);
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          size_t nb;
          if ((dx | dy | dz) == 0 || !g.neighbour(c, dx, dy, dz, &nb) || !g.is_free(nb)) continue;
          const Vec3 pn = g.centre(nb);
          const Vec3 d = sub(pn, pc);
          const double l = len(d);
          const double nc = cc + l * g.height_cost(nb);
          const auto it = cost.find(nb);
          if (it != cost.end() && it->second <= nc) continue;
          if (rays.cast(pc, mul(d, 1 / l), l) < l) continue;
          cost[nb] = nc;
          from[nb] = c;
          open.push({nc + len(sub(pn, b)), nb});
        }
  }
  if (reached == SIZE_MAX) return {};
  std::vector<Vec3> path{b};
  for (size_t c = reached;; c = from[c]) {
    path.push_back(g.centre(c));
    if (from[c] == c) break;
  }
  path.push_back(a);
  std::reverse(path.begin(), path.end());
  return path;
}

// The fewest straight legs through the route's points whose segments stay clear.
std::vector<Vec3> shorten(const SceneRays& rays, const std::vector<Vec3>& p, double radius) {
  std::vector<Vec3> out{p.front()};
  size_t i = 0;
  while (i + 1 < p.size()) {
    size_t j = i + 1;
    for (size_t k = p.size() - 1; k > i + 1; --k)
      if (rays.segment_clear(p[i], p[k], radius)) {
        j = k;
        break;
      }
    out.push_back(p[j]);
    i = j;
  }
  return out;
}

// Dense points along the legs (every `step` units), corners rounded by a
// quadratic curve where its points stay clear.
std::vector<Vec3> round_corners(const SceneRays& rays, const std::vector<Vec3>& p, double radius, double step) {
  std::vector<Vec3> out{p.front()};
  const auto line_to = [&](const Vec3& b) {
    const Vec3 a = out.back();
    const double l = len(sub(b, a));
    const int n = std::max(1, static_cast<int>(std::ceil(l / step)));
    for (int k = 1; k <= n; ++k) out.push_back(add(a, mul(sub(b, a), static_cast<double>(k) / n)));
  };
  for (size_t i = 1; i + 1 < p.size(); ++i) {
    const Vec3 in = sub(p[i], p[i - 1]), outv = sub(p[i + 1], p[i]);
    const double li = len(in), lo = len(outv);
    const double d = std::min({96.0, 0.45 * li, 0.45 * lo});
    const Vec3 a = sub(p[i], mul(in, d / li)), b = add(p[i], mul(outv, d / lo));
    std::vector<Vec3> curve;
    const int n = std::max(2, static_cast<int>(std::ceil(2 * d / step)));
    bool ok = rays.segment_clear(a, b, radius * 0.5);
    for (int k = 1; k <= n && ok; ++k) {
      const double t = static_cast<double>(k) / n;
      const Vec3 q = add(add(mul(a, (1 - t) * (1 - t)), mul(p[i], 2 * t * (1 - t))), mul(b, t * t));
      ok = rays.clear(q, radius * 0.75);
      curve.push_back(q);
    }
    if (ok) {
      line_to(a);
      for (size_t k = 0; k + 1 < curve.size(); ++k) out.push_back(curve[k]);
      out.push_back(b);
    } else {
      line_to(p[i]);
    }
  }
  line_to(p.back());
  return out;
}

double wrap180(double a) {
  while (a > 180) a -= 360;
  while (a <= -180) a += 360;
  return a;
}

double smoothstep(double t) { return t * t * (3 - 2 * t); }

}  // namespace

CameraPath make_tour(const Scene& s, const SceneRays& rays, const TourOptions& opt, TourReport* report) {
  // Lengths are given in Quake units (1/32 m): scaled to the scene's.
  TourOptions o = opt;
  const double k = (1.0 / 32) / s.metres_per_unit;
  o.speed *= k, o.eye_height *= k, o.radius *= k, o.cell *= k;
  // A scene without spawn points is toured from the centre of its bounds.
  std::vector<SpawnPoint> spawns = s.spawns;
  if (spawns.empty()) {
    SpawnPoint c;
    for (int a = 0; a < 3; ++a) c.origin[a] = (s.min[a] + s.max[a]) / 2;
    c.origin[2] -= static_cast<float>(o.eye_height);
    c.classname = "centre of the bounds";
    spawns.push_back(c);
  }
  TourReport rep;
  CameraPath path;
  path.fps = o.fps;
  path.hfov_deg = o.hfov_deg;
  // Eye positions: a spawn's origin raised by the eye height, lowered or
  // raised a little if that is not clear.
  std::vector<Vec3> eyes;
  std::vector<size_t> ids;
  for (size_t i = 0; i < spawns.size(); ++i) {
    const auto& sp = spawns[i].origin;
    for (double dz : {0.0, -8.0, 8.0, -16.0, 16.0}) {
      const Vec3 e = {sp[0], sp[1], sp[2] + o.eye_height + dz * k};
      if (rays.clear(e, o.radius)) {
        eyes.push_back(e);
        ids.push_back(i);
        break;
      }
    }
  }
  if (eyes.empty()) throw std::runtime_error(s.name + ": no spawn point with room for a camera (a tour starts at one)");
  Grid grid(s, rays, o);
  const size_t frames = o.frames;
  Vec3 pos = eyes[0];
  double yaw = spawns[ids[0]].yaw_deg, pitch = 0;
  const auto emit = [&](const Vec3& p, double y, double pt) {
    if (path.frames.size() >= frames) return false;
    double yy = std::fmod(y, 360.0);
    if (yy < 0) yy += 360;
    path.frames.push_back({p[0], p[1], p[2], yy, pt});
    return true;
  };
  std::vector<bool> visited(eyes.size(), false);
  size_t at = 0;
  visited[0] = true;
  rep.stops.push_back(ids[0]);
  const double dt = 1 / o.fps;
  while (path.frames.size() < frames) {
    // Hold, then pan.
    for (int k = 0; k < static_cast<int>(std::lround(o.hold_s * o.fps)); ++k)
      if (!emit(pos, yaw, pitch)) break;
    // Pan towards the more open side (the longer horizontal sight lines).
    const auto openness = [&](double y) {
      const double r = y * kPi / 180;
      return rays.cast(pos, {std::cos(r), std::sin(r), 0}, 4096);
    };
    const double y0 = yaw;
    const int pan_sign =
        openness(y0 - o.pan_deg) + openness(y0 - o.pan_deg / 2) > openness(y0 + o.pan_deg) + openness(y0 + o.pan_deg / 2) ? -1 : 1;
    const int pan_frames = static_cast<int>(std::lround(o.pan_s * o.fps));
    for (int k = 1; k <= pan_frames; ++k) {
      yaw = y0 + pan_sign * o.pan_deg * smoothstep(static_cast<double>(k) / pan_frames);
      pitch *= 0.9;
      if (!emit(pos, yaw, pitch)) break;
    }
    if (path.frames.size() >= frames) break;
    // The next stop: the nearest unvisited one a route reaches (all visited: start again).
    if (std::all_of(visited.begin(), visited.end(), [](bool v) { return v; })) std::fill(visited.begin(), visited.end(), false), visited[at] = true;
    std::vector<size_t> order;
    for (size_t i = 0; i < eyes.size(); ++i)
      if (!visited[i]) order.push_back(i);
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return len(sub(eyes[a], pos)) < len(sub(eyes[b], pos)); });
    std::vector<Vec3> legs;
    size_t next = SIZE_MAX;
    for (size_t cand : order) {
      const std::vector<Vec3> r = route(grid, rays, pos, eyes[cand], o.radius);
      visited[cand] = true;
      if (r.empty()) {
        if (std::find(rep.unreachable.begin(), rep.unreachable.end(), ids[cand]) == rep.unreachable.end())
          rep.unreachable.push_back(ids[cand]);
        continue;
      }
      legs = round_corners(rays, shorten(rays, r, o.radius), o.radius, 4.0 * k);
      next = cand;
      break;
    }
    if (next == SIZE_MAX) {
      // No stop is reachable from here: look round where the camera is for the rest.
      while (emit(pos, yaw += 45 * dt, pitch)) {
      }
      break;
    }
    // Dolly along the legs: arc length at a trapezoid speed profile.
    std::vector<double> arc{0};
    for (size_t i = 1; i < legs.size(); ++i) arc.push_back(arc.back() + len(sub(legs[i], legs[i - 1])));
    const double total = arc.back();
    const double ramp = std::min(0.75, total / o.speed / 2);  // seconds to full speed
    const double t_total = total / o.speed + ramp;
    const int n = std::max(1, static_cast<int>(std::ceil(t_total * o.fps)));
    const auto at_arc = [&](double a) {
      a = std::clamp(a, 0.0, total);
      const size_t k = static_cast<size_t>(std::upper_bound(arc.begin(), arc.end(), a) - arc.begin());
      if (k >= arc.size()) return legs.back();
      const double seg = arc[k] - arc[k - 1];
      return seg > 0 ? add(legs[k - 1], mul(sub(legs[k], legs[k - 1]), (a - arc[k - 1]) / seg)) : legs[k];
    };
    // Turn to face the way the camera goes before it sets off.
    {
      const Vec3 ahead = sub(at_arc(64 * k), pos);
      const double want = std::atan2(ahead[1], ahead[0]) * 180 / kPi, turn = wrap180(want - yaw), y1 = yaw, p1 = pitch;
      const int turn_frames = static_cast<int>(std::ceil(std::fabs(turn) / 120 * o.fps));
      for (int k = 1; k <= turn_frames; ++k) {
        const double f = smoothstep(static_cast<double>(k) / turn_frames);
        yaw = y1 + turn * f;
        pitch = p1 * (1 - f);
        if (!emit(pos, yaw, pitch)) break;
      }
    }
    for (int k = 1; k <= n; ++k) {
      const double t = std::min(t_total, k * dt);
      // Distance covered: accelerate over `ramp`, cruise, decelerate over `ramp`.
      double a;
      if (t < ramp) a = 0.5 * o.speed / ramp * t * t;
      else if (t > t_total - ramp) a = total - 0.5 * o.speed / ramp * (t_total - t) * (t_total - t);
      else a = 0.5 * o.speed * ramp + o.speed * (t - ramp);
      pos = at_arc(a);
      // Look where the camera goes: a point ahead on the route.
      const Vec3 ahead = sub(at_arc(a + 64 * k), pos);
      const double h = std::hypot(ahead[0], ahead[1]);
      if (h > 1) {
        const double want = std::atan2(ahead[1], ahead[0]) * 180 / kPi;
        const double turn = std::clamp(wrap180(want - yaw), -120 * dt, 120 * dt);
        yaw += turn;
        const double want_pitch = std::clamp(std::atan2(ahead[2], h) * 180 / kPi * 0.5, -20.0, 20.0);
        pitch += std::clamp(want_pitch - pitch, -30 * dt, 30 * dt);
      }
      if (!emit(pos, yaw, pitch)) break;
    }
    at = next;
    rep.stops.push_back(ids[next]);
  }
  for (size_t i = 1; i < path.frames.size(); ++i) {
    const CameraPose& a = path.frames[i - 1];
    const CameraPose& b = path.frames[i];
    rep.length += std::sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) + (a.z - b.z) * (a.z - b.z));
  }
  // The clearance actually kept, frame by frame.
  rep.min_clearance = o.radius * 4;
  for (const CameraPose& f : path.frames) {
    rep.min_clearance = rays.clearance({f.x, f.y, f.z}, rep.min_clearance);
  }
  if (report) *report = rep;
  return path;
}

}  // namespace vds::enc
