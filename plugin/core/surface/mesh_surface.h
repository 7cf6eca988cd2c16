// Stage 1: counter-surfaces known only through a ray query (MuJoCo meshes),
// averaged over a taxel cell like the analytic bodies, so a mesh sliding
// under the grid varies smoothly instead of jumping cell by cell.
#ifndef MJTOUCH_SURFACE_MESH_SURFACE_H_
#define MJTOUCH_SURFACE_MESH_SURFACE_H_

#include "surface/surface.h"

namespace mjtouch {

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
