// The pinhole camera of vds/render_camera.h: validation, world -> camera
// transform and the one projection every vertex of the renderer goes through.
#include "vds/render_camera.h"

namespace vds {

namespace {
constexpr int32_t kQ16One = 1 << 16;
}  // namespace

Status validate_camera(const Camera& cam) {
  const int32_t fmin = kCameraMinFocalPx * kQ16One;
  const int32_t fmax = kCameraMaxFocalPx * kQ16One;
  if (cam.fx.raw() < fmin || cam.fx.raw() > fmax || cam.fy.raw() < fmin || cam.fy.raw() > fmax) {
    return Status::invalid_argument;
  }
  const int32_t cmin = kCameraMinCentrePx * kQ16One;
  const int32_t cmax = kCameraMaxCentrePx * kQ16One;
  if (cam.cx.raw() < cmin || cam.cx.raw() > cmax || cam.cy.raw() < cmin || cam.cy.raw() > cmax) {
    return Status::invalid_argument;
  }
  const int32_t n = cam.near_z.raw();
  const int32_t f = cam.far_z.raw();
  if (n < kCameraMinNearRaw || f <= n) return Status::invalid_argument;
  if ((int64_t{n} << kCameraMaxDepthRatioLog2) < f) return Status::invalid_argument;
  return Status::ok;
}

Vec3<Q16_16> camera_transform(const Camera& cam, const Vec3<Q16_16>& world) {
  // The offset from the camera saturates to Q16.16 so that a product with a
  // Q2.30 entry stays below 2^62; mac64 wraps (defined) if a wild rotation
  // pushes the sum further.
  const int32_t d[3] = {sat_s32(int64_t{world.x.raw()} - cam.position.x.raw()),
                        sat_s32(int64_t{world.y.raw()} - cam.position.y.raw()),
                        sat_s32(int64_t{world.z.raw()} - cam.position.z.raw())};
  int32_t out[3];
  for (int i = 0; i < 3; ++i) {
    const Mat3<Q2_30>& r = cam.rotation;
    int64_t acc = mul32x32_64(r.m[i][0].raw(), d[0]);
    acc = mac64(acc, r.m[i][1].raw(), d[1]);
    acc = mac64(acc, r.m[i][2].raw(), d[2]);
    // Q2.30 x Q16.16 = Q.46 -> Q16.16, rounded to nearest (ties up).
    out[i] = sat_s32(shr_round(acc, 30));
  }
  return {Q16_16::from_raw(out[0]), Q16_16::from_raw(out[1]), Q16_16::from_raw(out[2])};
}

bool camera_project(const Camera& cam, const Vec3<Q16_16>& p, int32_t* x_q8, int32_t* y_q8) {
  const int32_t z = p.z.raw();
  if (z <= 0) return false;
  // x/z in Q8.24 (exact rounding); |x/z| must stay below 127, which the
  // guard band guarantees (4000 / 32).
  constexpr uint32_t kRatioFrac = 24;
  constexpr int32_t kRatioLimit = int32_t{127} << kRatioFrac;
  const int32_t rx = div_shl_round_sat(p.x.raw(), z, kRatioFrac);
  const int32_t ry = div_shl_round_sat(p.y.raw(), z, kRatioFrac);
  if (rx >= kRatioLimit || rx <= -kRatioLimit || ry >= kRatioLimit || ry <= -kRatioLimit) return false;
  // fx (Q16.16) * ratio (Q8.24) = Q.40; the rounded high word is Q.8. The
  // principal point goes from Q16.16 to Q.8 rounded to nearest.
  *x_q8 = shr_round(cam.cx.raw(), 8) + mulhi_round(cam.fx.raw(), rx);
  *y_q8 = shr_round(cam.cy.raw(), 8) + mulhi_round(cam.fy.raw(), ry);
  return true;
}

}  // namespace vds
