// vds client library: the pinhole camera shared by the renderer and the
// view mapping (vds/homography.h), in fixed point.
//
// Conventions (the same in the host reference renderer, vds/enc/ref_render.h):
// - World space: any right-handed frame; units are arbitrary ("units").
// - Camera space: right-handed, x right, y down, z forward (the direction of
//   view). A world point P maps to camera space as R (P - C): the rows of R
//   are the camera's x, y and z axes written in world coordinates.
// - Screen: pixel (i, j) covers [i, i+1) x [j, j+1), its centre is
//   (i + 1/2, j + 1/2); x grows to the right, y grows downward. A camera-space
//   point (x, y, z) with z > 0 projects to (cx + fx x / z, cy + fy y / z).
#pragma once
#include <cstdint>

#include "vds/fixed.h"
#include "vds/status.h"

namespace vds {

struct Camera {
  Mat3<Q2_30> rotation;   // world -> camera, rows = camera axes (orthonormal)
  Vec3<Q16_16> position;  // the centre of projection, world units
  Q16_16 fx, fy;          // focal lengths in pixels
  Q16_16 cx, cy;          // principal point in pixels (continuous coordinates)
  Q16_16 near_z, far_z;   // clip distances along the camera z axis, world units
};

// Limits checked by validate_camera(). They keep every intermediate of the
// renderer and of the view mapping inside its integer type.
constexpr int32_t kCameraMinFocalPx = 32;      // fx, fy >= 32 px (about 150 degrees across 240 px)
constexpr int32_t kCameraMaxFocalPx = 16384;   // fx, fy <= 16384 px
constexpr int32_t kCameraMinCentrePx = -4096;  // cx, cy in [-4096, 4096] px
constexpr int32_t kCameraMaxCentrePx = 4096;
constexpr int32_t kCameraMinNearRaw = 1 << 8;  // near_z >= 1/256 unit (raw Q16.16)
constexpr int kCameraMaxDepthRatioLog2 = 12;   // far_z <= 4096 near_z (depth and perspective precision)

// ok, or invalid_argument when a field is outside the limits above. The
// rotation is not checked for orthonormality; a non-orthonormal one gives a
// distorted but safe picture.
Status validate_camera(const Camera& cam);

// Camera-space position R (P - C) of a world point: 64-bit sums, rounded to
// nearest, saturated to Q16.16 (wrapping, never undefined, for wild input).
Vec3<Q16_16> camera_transform(const Camera& cam, const Vec3<Q16_16>& world);

// Screen position of a camera-space point in Q24.8 pixels (1/256 pixel):
// x = cx + fx * round_24(x/z) rounded to 1/256, likewise y, where round_24 is
// x/z rounded to 24 fraction bits (vds::div_shl_round_sat). This is the one
// projection the renderer uses for every vertex, so shared vertices land on
// the same sub-pixel position in every triangle. false when z <= 0 or
// |x/z|, |y/z| >= 127; outputs untouched then.
bool camera_project(const Camera& cam, const Vec3<Q16_16>& p, int32_t* x_q8, int32_t* y_q8);

}  // namespace vds
