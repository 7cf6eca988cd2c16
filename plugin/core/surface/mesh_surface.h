// Stage 1: counter-surfaces known only through a ray query (MuJoCo meshes),
// averaged over a taxel cell like the analytic bodies, so a mesh sliding
// under the grid varies smoothly instead of jumping cell by cell.
#ifndef MJTOUCH_SURFACE_MESH_SURFACE_H_
#define MJTOUCH_SURFACE_MESH_SURFACE_H_

#include <memory>
#include <vector>

#include "surface/surface.h"

namespace mjtouch {

// A triangle mesh in its own frame with a bounding-volume hierarchy, for
// the kRay queries of mesh counter-surfaces: a ray visits O(log n) boxes
// instead of every triangle (MuJoCo 4.0's mj_rayMesh tests every
// triangle: 16 rays per cell on a 20k-triangle sphere took ~0.5 s a step).
class MeshRayCaster {
 public:
  // vertices: 3 * nvert (x, y, z); faces: 3 * nface vertex indices.
  MeshRayCaster(const float* vertices, int nvert, const int* faces, int nface);
  // Distance along d (unit) from o to the first triangle hit, either side
  // (as mj_rayMesh), or -1 for none. Thread-compatible (const).
  double Cast(const double o[3], const double d[3]) const;
  int triangles() const { return static_cast<int>(tri_.size() / 9); }

 private:
  struct Node {
    float lo[3], hi[3];
    int first = 0, count = 0;  // leaf: triangles [first, first + count)
    int left = -1, right = -1;
  };
  int Build(int first, int count);
  std::vector<double> tri_;  // 9 per triangle, in BVH order
  std::vector<Node> nodes_;
};

// A pad mesh from vertices (3 * nvert, geom frame) and triangles (3 * nface
// indices, each in [0, nvert)), with its ray caster and cache key.
std::shared_ptr<const PadMesh> MakePadMesh(const float* vertices, int nvert, const int* faces,
                                           int nface);

// Rays per cell side: 4 x 4 sub-cell midpoints. The midpoint rule's error on
// a smooth top is h^2 / (24 * 16) |curvature| (16x smaller than one ray's
// h^2 / 24), and a cell on the body's rim is covered in steps of 1/16
// instead of 0 or 1.
constexpr int kRayCellSide = 4;

// Gap (m) and covered fraction of one taxel cell (pad frame centre u, v,
// side h_m, skin height z_m) to the ray-queried surface s: rays from the
// pad's centre plane down its -z axis through the midpoints of
// rays_per_side^2 sub-cells; the gap is z minus the mean top height of the
// rays that hit, the coverage the fraction that hit. False if none hits.
bool RayCellGap(const CounterSurface& s, const Pose& pad, double u_m, double v_m, double z_m,
                double h_m, int rays_per_side, double* gap_m, double* coverage);

}  // namespace mjtouch

#endif  // MJTOUCH_SURFACE_MESH_SURFACE_H_
