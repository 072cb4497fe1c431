// vds encoder: a scene's shape in fewer triangles, for a client that draws
// pictures of the scene (the walkthrough's views) onto its polygons instead
// of the scene's own textures. Such a client needs the shape, not the
// texture seams: neighbouring triangles in one plane become one polygon,
// drawn in as few triangles as its outline needs.
//
// The rule (docs/walkthrough.md, "Fewer triangles"):
// - vertices are the same where their positions are (to 1/64 unit); a
//   triangle with the same corners the same way round as another is dropped;
// - triangles join a region when they share an edge (the same two
//   vertices, opposite ways round: the same side faces out), lie within
//   ShapeOptions::plane_tolerance of the plane of the region's first
//   triangle and face the same way; only opaque triangles join (not sky,
//   fog, additive, alpha-tested or two-sided ones: those stay as they are);
// - a region whose outline is one loop, or one loop with holes, is drawn as
//   its outline: a corner where the outline runs straight on is dropped
//   unless a triangle outside the region uses it (so that no edge the
//   region shares with a neighbour loses a vertex the neighbour has, which
//   would open cracks), holes are joined to the outline by a cut, and the
//   outline is cut into triangles ear by ear;
// - a region whose outline cannot be cut so (it touches itself at a
//   vertex, or an ear cannot be found) keeps its triangles.
// - then, with ShapeOptions::tolerance above 0, the opaque one-sided
//   triangles of curved patches and models (every face but polygon faces,
//   SceneSurface::face_type 1, which the merge has drawn as outlines) are
//   decimated: edges collapse (a vertex onto a neighbour) while the
//   surface stays near where it was (a quadric error bound of the
//   tolerance: a measure of distance to the planes around a vertex, not a
//   strict bound); a vertex on an open edge of the welded mesh (a
//   model's rim, a T-junction, where a surface meets one that faces the
//   other way round its winding) never moves, so no crack opens.
// The result has the scene's textures and lightmaps; merged regions are
// surfaces of their own, with the first triangle's texture, and vertices of
// their own whose normals are the region's; decimated triangles likewise,
// each with vertices of its own whose normals are its own.
#pragma once
#include <cstddef>

#include "vds/enc/scene.h"

namespace vds::enc {

struct ShapeOptions {
  double plane_tolerance = 1.0 / 16;  // scene units
  double tolerance = 0;               // scene units a decimated surface may move (0: none)
};

struct ShapeStats {
  size_t regions = 0;           // regions of two or more triangles
  size_t merged = 0;            // regions drawn as their outline
  size_t kept = 0;              // regions that keep their triangles
  size_t repeats = 0;           // triangles dropped as repeats of another
  size_t decimated_in = 0, decimated_out = 0;  // triangles the decimation took, and gave back
  size_t triangles_in = 0, triangles_out = 0;
};

Scene simplify_shape(const Scene& s, const ShapeOptions& o = ShapeOptions{}, ShapeStats* stats = nullptr);

}  // namespace vds::enc
