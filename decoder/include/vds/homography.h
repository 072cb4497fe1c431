// vds client library: the projective map of a planar polygon between two
// cameras and its texture quality factor, in fixed point. Follows Cohen-Or,
// Mann, Fleishman, "Deep compression for streaming texture intensive
// animations", section 4: eqs. 6-8 (the homography) and eqs. 5, 9 (the 2-norm
// of its Jacobian, the per-polygon texture quality factor).
//
// In the walkthrough mode the client draws each visible polygon by mapping it
// from a stored view, an image rendered with another camera: the renderer
// takes the screen -> view homography of the polygon (Mesh::view_map in
// vds/render.h). The quality factor of the view -> screen map says how much
// the view's pixels are magnified on screen; the client and the encoder
// compute it the same way to agree on which view serves each polygon.
// The host computes the same in double (vds/enc/ref_render.h); the tests
// bound the difference (tests/unit/homography_test.cpp, docs/renderer.md).
#pragma once
#include <cstddef>
#include <cstdint>

#include "vds/fixed.h"
#include "vds/render_camera.h"
#include "vds/status.h"

namespace vds {

// A 3x3 projective map of continuous pixel coordinates (x, y) of a source
// image to (X/W, Y/W) of a target image (the paper's eq. 8 with
// m = [[a, b, c], [d, e, f], [g, h, i]]):
//   X/W = (a x + b y + c) / (g x + h y + i), Y/W = (d x + e y + f) / (g x + h y + i)
// The fixed-point matrix works on coordinates in units of 256 pixels: a
// pixel position (x, y) enters as (x/256, y/256, 1) and leaves as
// 256 (X/W, Y/W), i.e. m = S^-1 H S with S = diag(256, 256, 1) for the pixel
// map H. This conditioning balances the columns (translations of hundreds of
// pixels against unit slopes), so that every entry of a map between images up
// to a few thousand pixels keeps about 29 significant bits.
// The matrix is scale-free: the functions here return it normalised so that
// the largest |entry| lies in [2^29, 2^30), with the sign chosen so that
// W > 0 exactly where the target camera sees the plane in front of it (for
// source pixels whose ray meets the plane in front of the source camera).
struct Homography {
  int32_t m[3][3];
};

// The homography that maps pixel positions of camera `from` to pixel
// positions of camera `to` for points of the plane through the three world
// points plane[0..2] (paper eqs. 6-8: H = K_to R_to (d I + (C_from - C_to) n^T) R_from^T K_from^-1
// with n the plane normal and d = n . (P0 - C_from)), in the scaled form above.
// invalid_argument: a camera fails validate_camera(), the three points are
// collinear, or the plane passes through the centre of `from` (seen edge-on).
Status plane_homography(const Camera& from, const Camera& to, const Vec3<Q16_16> plane[3], Homography* out);

// What plane_homography() computes of the two cameras alone, for the many
// planes drawn between the same two cameras. With L = (S^-1 K_to) R_to and
// R = R_from^T (K_from^-1 S), the homography is a rank-one update of one
// matrix: H = L (d I + c n^T) R = d (L R) + (L c)(n^T R), c = C_from - C_to;
// so a plane costs a 3-vector n^T R and an outer product, not three
// matrix products. plane_homography(pair, plane) gives
// plane_homography(from, to, plane) bit for bit.
struct HomographyCameras {
  struct BlockMatrix {
    int64_t m[3][3];
    int e;  // value = m * 2^e
  };
  struct BlockVector {
    int64_t v[3];
    int e;  // value = v * 2^e
  };
  BlockMatrix lr;        // L R
  BlockMatrix r;         // R_from^T K_from^-1 S (scale-free)
  BlockVector lc;        // L (C_from - C_to); zero for a pure rotation
  Vec3<Q16_16> from_position;
};
// invalid_argument: a camera fails validate_camera().
Status homography_cameras(const Camera& from, const Camera& to, HomographyCameras* out);
Status plane_homography(const HomographyCameras& cams, const Vec3<Q16_16> plane[3], Homography* out);

// (x, y) in Q24.8 pixels mapped by h, into Q24.8. false (outputs untouched)
// when W <= 0 at (x, y) or the result leaves the Q24.8 range.
bool homography_apply(const Homography& h, int32_t x_q8, int32_t y_q8, int32_t* out_x_q8, int32_t* out_y_q8);

// The local scale factor of h at source point (x, y) (Q24.8 pixels): the
// 2-norm of the Jacobian of (x, y) -> (X/W, Y/W) there (paper eq. 9,
// J = (1/W) [[a - x1 g, b - x1 h], [d - y1 g, e - y1 h]] with (x1, y1) the
// mapped point), from the closed form of eq. 5:
//   ||J||_2 = sqrt(S + sqrt(S^2 - det^2)),  S = (J11^2 + J12^2 + J21^2 + J22^2) / 2
// evaluated as S + sqrt((S - det)(S + det)) with both factors formed as sums
// of squares, so it has no cancellation. Jacobian entries are saturated to
// +-2047; the result saturates at Q16_16::max(), also returned when W <= 0.
// Error against the exact value: see docs/renderer.md (tested <= 2^-14
// relative + 2 ulp for scale factors in [1/64, 64]).
Q16_16 homography_scale(const Homography& h, int32_t x_q8, int32_t y_q8);

// The texture quality factor of a stored view for a planar convex polygon
// (world vertices poly[0..n), n >= 3, the plane taken from the first three):
// the largest homography_scale() of the view -> screen map at the polygon's
// vertices as seen in the view (the paper samples the gradient at the
// vertices). <= 1 means the view is at least as sharp as the screen needs;
// the paper switches views above about 1.3-1.4. A vertex behind the view
// camera gives Q16_16::max(). Errors as plane_homography().
Status texture_quality(const Camera& screen, const Camera& view, const Vec3<Q16_16>* poly, size_t n, Q16_16* quality);

}  // namespace vds
