// The fixed-point plane homography and texture quality factor
// (vds/homography.h) against the double-precision host versions
// (vds/enc/ref_render.h), on random cameras and planes, plus exact cases.
#include "vds/homography.h"

#include <algorithm>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "vds/ref/render.h"
#include "vds/ref/scene.h"

namespace vds {
namespace {

using ref::CameraD;
using ref::Vec3d;

Vec3<Q16_16> fixed(Vec3d p) {
  return {Q16_16::from_raw(static_cast<int32_t>(std::llround(p.x * 65536))),
          Q16_16::from_raw(static_cast<int32_t>(std::llround(p.y * 65536))),
          Q16_16::from_raw(static_cast<int32_t>(std::llround(p.z * 65536)))};
}
Vec3d as_double(const Vec3<Q16_16>& p) { return {p.x.raw() / 65536.0, p.y.raw() / 65536.0, p.z.raw() / 65536.0}; }

// The double camera that the fixed one really is (inputs rounded the same way).
CameraD as_double(const Camera& c) {
  CameraD d;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) d.rotation.m[i][j] = c.rotation.m[i][j].raw() / 1073741824.0;
  d.position = as_double(c.position);
  d.fx = c.fx.raw() / 65536.0;
  d.fy = c.fy.raw() / 65536.0;
  d.cx = c.cx.raw() / 65536.0;
  d.cy = c.cy.raw() / 65536.0;
  d.near_z = c.near_z.raw() / 65536.0;
  d.far_z = c.far_z.raw() / 65536.0;
  return d;
}

struct PlaneCase {
  Camera screen, view;
  Vec3<Q16_16> plane[3];
};

// A random plane patch in front of a random screen camera, and a view camera
// nearby looking at it (as consecutive walkthrough frames are).
PlaneCase random_setup(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  const Vec3d target{10 * u(rng), 2 * u(rng), 10 * u(rng)};
  const Vec3d eye = target + Vec3d{8 * u(rng), 3 + 2 * u(rng), 8 * u(rng) - 9};
  const Vec3d view_eye = eye + Vec3d{2 * u(rng), 0.5 * u(rng), 2 * u(rng)};
  const double fov = 45 + 20 * u(rng);
  PlaneCase s;
  s.screen = ref::to_client(CameraD::look_at(eye, target, {0, 1, 0}, 240, 180, fov, 0.1, 100));
  s.view = ref::to_client(CameraD::look_at(view_eye, target + Vec3d{u(rng), u(rng), u(rng)}, {0, 1, 0}, 240, 180,
                                           fov + 10 * u(rng), 0.1, 100));
  const Vec3d n = ref::normalize({u(rng), 1 + u(rng), u(rng)});
  const Vec3d a = ref::normalize(ref::cross(n, {0.3, 0.1, 1})), b = ref::cross(n, a);
  const double size = 1 + 3 * (u(rng) + 1);
  s.plane[0] = fixed(target);
  s.plane[1] = fixed(target + a * size);
  s.plane[2] = fixed(target + b * size + a * (0.3 * size));
  return s;
}

TEST(Homography, MapsScreenPointsLikeTheDoubleVersion) {
  std::mt19937 rng(2024);
  int checked = 0;
  double worst = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const PlaneCase s = random_setup(rng);
    Homography h;
    ASSERT_EQ(plane_homography(s.screen, s.view, s.plane, &h), Status::ok);
    const CameraD sd = as_double(s.screen), vd = as_double(s.view);
    const Vec3d pl[3] = {as_double(s.plane[0]), as_double(s.plane[1]), as_double(s.plane[2])};
    const ref::Mat3d hd = ref::plane_homography(sd, vd, pl);
    // The normalised largest entry lies in [2^29, 2^30).
    int32_t mx = 0;
    for (auto& row : h.m)
      for (int32_t v : row) mx = std::max(mx, std::abs(v));
    EXPECT_GE(mx, 1 << 29);
    EXPECT_LT(mx, 1 << 30);
    for (int k = 0; k < 20; ++k) {
      const double x = std::uniform_real_distribution<double>(0, 240)(rng);
      const double y = std::uniform_real_distribution<double>(0, 180)(rng);
      double ox, oy;
      if (!ref::homography_apply(hd, x, y, &ox, &oy) || std::fabs(ox) > 2000 || std::fabs(oy) > 2000) continue;
      int32_t fx, fy;
      const int32_t xq = static_cast<int32_t>(std::lround(x * 256)), yq = static_cast<int32_t>(std::lround(y * 256));
      ASSERT_TRUE(homography_apply(h, xq, yq, &fx, &fy)) << trial;
      // Compare at the same (rounded) input point.
      double rx, ry;
      ref::homography_apply(hd, xq / 256.0, yq / 256.0, &rx, &ry);
      const double err = std::hypot(fx / 256.0 - rx, fy / 256.0 - ry);
      worst = std::max(worst, err);
      ASSERT_LT(err, 1.0 / 64) << "trial " << trial << " at " << x << "," << y;
      ++checked;
    }
  }
  EXPECT_GT(checked, 2000);
  RecordProperty("worst_map_error_px", std::to_string(worst));
}

// The cameras' part computed once serves every plane between them: the
// same matrices, bit for bit, and the same refusals.
TEST(Homography, CamerasComputedOnceGiveTheSameHomographyForEveryPlane) {
  std::mt19937 rng(77);
  int compared = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const PlaneCase s = random_setup(rng);
    HomographyCameras pair;
    ASSERT_EQ(homography_cameras(s.screen, s.view, &pair), Status::ok);
    for (int k = 0; k < 20; ++k) {
      PlaneCase other = random_setup(rng);
      if (k == 19) other.plane[2] = other.plane[1];  // collinear: refused by both
      Homography a{}, b{};
      const Status sa = plane_homography(s.screen, s.view, other.plane, &a);
      const Status sb = plane_homography(pair, other.plane, &b);
      ASSERT_EQ(sa, sb);
      if (sa != Status::ok) continue;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) ASSERT_EQ(a.m[i][j], b.m[i][j]) << trial << " " << k;
      ++compared;
    }
  }
  EXPECT_GT(compared, 700);
  Camera bad = random_setup(rng).screen;
  bad.fx = Q16_16::from_int(1);
  HomographyCameras pair;
  EXPECT_EQ(homography_cameras(bad, bad, &pair), Status::invalid_argument);
}

TEST(Homography, ScreenPointsOfThePlaneLandOnTheirViewProjection) {
  // Geometric meaning: a point of the plane seen at screen pixel p is seen at
  // view pixel H p. The screen position is rounded to 1/256 pixel first, an
  // error the map magnifies by its local scale (large for planes seen nearly
  // edge-on), so the tolerance includes that term.
  std::mt19937 rng(7);
  for (int trial = 0; trial < 100; ++trial) {
    const PlaneCase s = random_setup(rng);
    Homography h;
    ASSERT_EQ(plane_homography(s.screen, s.view, s.plane, &h), Status::ok);
    const CameraD sd = as_double(s.screen), vd = as_double(s.view);
    const Vec3d p0 = as_double(s.plane[0]), p1 = as_double(s.plane[1]), p2 = as_double(s.plane[2]);
    const Vec3d pl[3] = {p0, p1, p2};
    const ref::Mat3d hd = ref::plane_homography(sd, vd, pl);
    for (double a : {0.1, 0.4, 0.7})
      for (double b : {0.2, 0.5}) {
        const Vec3d p = p0 + (p1 - p0) * a + (p2 - p0) * (b * (1 - a));
        double sx, sy, vx, vy;
        if (!ref::project(sd, p, &sx, &sy) || !ref::project(vd, p, &vx, &vy)) continue;
        int32_t hx, hy;
        ASSERT_TRUE(homography_apply(h, static_cast<int32_t>(std::lround(sx * 256)), static_cast<int32_t>(std::lround(sy * 256)), &hx, &hy));
        const double tol = 0.01 + ref::homography_scale(hd, sx, sy) * (1.5 / 512);
        EXPECT_NEAR(hx / 256.0, vx, tol) << trial;
        EXPECT_NEAR(hy / 256.0, vy, tol) << trial;
      }
  }
}

TEST(Homography, ScaleFactorMatchesTheDoubleClosedForm) {
  std::mt19937 rng(99);
  int checked = 0;
  double worst = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const PlaneCase s = random_setup(rng);
    Homography vs;
    ASSERT_EQ(plane_homography(s.view, s.screen, s.plane, &vs), Status::ok);
    const Vec3d pl[3] = {as_double(s.plane[0]), as_double(s.plane[1]), as_double(s.plane[2])};
    const ref::Mat3d hd = ref::plane_homography(as_double(s.view), as_double(s.screen), pl);
    for (int k = 0; k < 10; ++k) {
      const int32_t xq = static_cast<int32_t>(rng() % (240 * 256)), yq = static_cast<int32_t>(rng() % (180 * 256));
      const double want = ref::homography_scale(hd, xq / 256.0, yq / 256.0);
      if (!(want > 1.0 / 64 && want < 64)) continue;
      const double got = homography_scale(vs, xq, yq).raw() / 65536.0;
      const double err = std::fabs(got - want);
      worst = std::max(worst, err / want);
      // Stated bound: 2^-14 relative plus 2 ulp of Q16.16.
      ASSERT_LE(err, want * std::ldexp(1.0, -14) + 2.0 / 65536) << "trial " << trial << " want " << want;
      ++checked;
    }
  }
  EXPECT_GT(checked, 1500);
  RecordProperty("worst_scale_relative_error", std::to_string(worst));
}

TEST(Homography, ExactCases) {
  const CameraD base = CameraD::look_at({0, 2, -6}, {0, 0, 0}, {0, 1, 0}, 240, 180, 60, 0.1, 100);
  const Vec3<Q16_16> plane[3] = {fixed({-1, 0, -1}), fixed({1, 0, -1}), fixed({0, 0, 1})};
  // Same camera: the identity (up to scale), scale factor 1.
  const Camera c = ref::to_client(base);
  Homography h;
  ASSERT_EQ(plane_homography(c, c, plane, &h), Status::ok);
  for (int32_t x : {0, 1000, 30000, 61439})
    for (int32_t y : {0, 12345, 46079}) {
      int32_t ox, oy;
      ASSERT_TRUE(homography_apply(h, x, y, &ox, &oy));
      EXPECT_NEAR(ox, x, 1);
      EXPECT_NEAR(oy, y, 1);
      EXPECT_NEAR(homography_scale(h, x, y).raw(), 65536, 2);
    }
  // A view with twice the focal length from the same place: the view is
  // magnified 2x, so mapping it to the screen shrinks by 2 (quality 0.5),
  // and mapping the screen to the view magnifies by 2.
  CameraD zoom = base;
  zoom.fx *= 2;
  zoom.fy *= 2;
  const Camera cz = ref::to_client(zoom);
  Homography vs, sv;
  ASSERT_EQ(plane_homography(cz, c, plane, &vs), Status::ok);
  ASSERT_EQ(plane_homography(c, cz, plane, &sv), Status::ok);
  EXPECT_NEAR(homography_scale(vs, 120 * 256, 90 * 256).raw(), 32768, 2);
  EXPECT_NEAR(homography_scale(sv, 37 * 256, 11 * 256).raw(), 131072, 3);
  Q16_16 q;
  const Vec3<Q16_16> poly[4] = {plane[0], plane[1], plane[2], fixed({-1, 0, 1})};
  ASSERT_EQ(texture_quality(c, cz, poly, 4, &q), Status::ok);
  EXPECT_NEAR(q.raw(), 32768, 2);
  // W > 0 where the view sees the plane, whatever the order of the points.
  const Vec3<Q16_16> reversed[3] = {plane[2], plane[1], plane[0]};
  Homography hr;
  ASSERT_EQ(plane_homography(c, cz, reversed, &hr), Status::ok);
  int32_t ox, oy;
  EXPECT_TRUE(homography_apply(hr, 120 * 256, 150 * 256, &ox, &oy));
}

TEST(Homography, TextureQualityAgreesWithTheHostAndDecidesTheSame) {
  // The host evaluates the same closed form at the same view positions of
  // the vertices (projected by the client's vds::camera_project).
  std::mt19937 rng(5);
  int decided = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const PlaneCase s = random_setup(rng);
    const Vec3<Q16_16> poly[3] = {s.plane[0], s.plane[1], s.plane[2]};
    Q16_16 q;
    ASSERT_EQ(texture_quality(s.screen, s.view, poly, 3, &q), Status::ok);
    const Vec3d pl[3] = {as_double(poly[0]), as_double(poly[1]), as_double(poly[2])};
    const ref::Mat3d vs = ref::plane_homography(as_double(s.view), as_double(s.screen), pl);
    double want = 0;
    bool behind = false;
    for (const Vec3<Q16_16>& p : poly) {
      int32_t x, y;
      if (!camera_project(s.view, camera_transform(s.view, p), &x, &y)) {
        behind = true;
        break;
      }
      want = std::max(want, ref::homography_scale(vs, x / 256.0, y / 256.0));
    }
    if (behind) {
      EXPECT_EQ(q, Q16_16::max());
      continue;
    }
    if (want > 2000) continue;  // saturating
    const double got = q.raw() / 65536.0;
    const double bound = want * std::ldexp(1.0, -14) + 2.0 / 65536;
    ASSERT_LE(std::fabs(got - want), bound) << trial;
    // Client and encoder agree on the paper's update test (threshold 1.3)
    // unless the true value is within the bound of the threshold.
    const double threshold = 1.3;
    if (std::fabs(want - threshold) > bound) {
      EXPECT_EQ(got > threshold, want > threshold);
      ++decided;
    }
  }
  EXPECT_GT(decided, 300);
}

TEST(Homography, RejectsDegenerateInput) {
  const Camera c = ref::to_client(CameraD::look_at({0, 2, -6}, {0, 0, 0}, {0, 1, 0}, 240, 180, 60, 0.1, 100));
  Homography h;
  const Vec3<Q16_16> line[3] = {fixed({0, 0, 0}), fixed({1, 0, 0}), fixed({2, 0, 0})};
  EXPECT_EQ(plane_homography(c, c, line, &h), Status::invalid_argument);
  // A plane through the centre of `from` (seen edge-on).
  const Vec3<Q16_16> edge_on[3] = {fixed({0, 2, -6}), fixed({1, 2, -6}), fixed({0, 2, 0})};
  EXPECT_EQ(plane_homography(c, c, edge_on, &h), Status::invalid_argument);
  Camera bad = c;
  bad.fx = Q16_16::from_raw(0);
  const Vec3<Q16_16> plane[3] = {fixed({-1, 0, -1}), fixed({1, 0, -1}), fixed({0, 0, 1})};
  EXPECT_EQ(plane_homography(bad, c, plane, &h), Status::invalid_argument);
  EXPECT_EQ(plane_homography(c, c, plane, nullptr), Status::invalid_argument);
  Q16_16 q;
  EXPECT_EQ(texture_quality(c, c, plane, 2, &q), Status::invalid_argument);
  // A vertex behind the view camera: the view cannot serve the polygon.
  const Vec3<Q16_16> behind[3] = {fixed({-1, 0, -1}), fixed({1, 0, -1}), fixed({0, 0, -20})};
  ASSERT_EQ(texture_quality(c, c, behind, 3, &q), Status::ok);
  EXPECT_EQ(q, Q16_16::max());
  // W = 0 (a point on the horizon line of the map): maximal scale.
  Homography z{};
  z.m[0][0] = 1 << 29;
  z.m[1][1] = 1 << 29;
  EXPECT_EQ(homography_scale(z, 5, 5), Q16_16::max());
  int32_t ox, oy;
  EXPECT_FALSE(homography_apply(z, 5, 5, &ox, &oy));
}

}  // namespace
}  // namespace vds
