// vds encoder: rays against a scene's solid triangles (every drawn surface
// but fog and additive effects), for camera tours that stay out of walls.
// A bounding volume hierarchy over the triangles; both sides of a triangle
// stop a ray.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "vds/enc/scene.h"

namespace vds::enc {

using Vec3 = std::array<double, 3>;

class SceneRays {
 public:
  explicit SceneRays(const Scene& s);
  // Distance along `dir` (unit length) from `origin` to the first triangle,
  // or `tmax` if none is nearer.
  double cast(const Vec3& origin, const Vec3& dir, double tmax) const;
  // The distance from `p` to the nearest triangle along the 26 directions
  // of a cube's faces, edges and corners, or `limit` if none is nearer;
  // it stops looking once it has found one nearer than `enough`.
  double clearance(const Vec3& p, double limit, double enough = 0) const;
  // True when no triangle lies within `radius` of `p` along those directions.
  bool clear(const Vec3& p, double radius) const;
  // True when the segment a-b and four segments beside it (offset by
  // `radius` left, right, up and down of its direction) cross no triangle,
  // and both ends are clear(radius).
  bool segment_clear(const Vec3& a, const Vec3& b, double radius) const;
  size_t triangles() const { return tris_.size(); }

 private:
  struct Node {
    std::array<float, 3> lo, hi;
    uint32_t first, count;  // leaf: triangles [first, first + count); inner: count 0, children first, first + 1
  };
  struct Tri {
    Vec3 a, e1, e2;
  };
  std::vector<Tri> tris_;
  std::vector<Node> nodes_;
};

}  // namespace vds::enc
