#include "surface/mesh_surface.h"

namespace mjtouch {

bool RayCellGap(const CounterSurface& s, const Pose& pad, double u, double v, double z,
                double h, int rays_per_side, double* gap_m, double* coverage) {
  if (!s.ray || rays_per_side < 1) return false;
  const double d_world[3] = {-pad.mat[2], -pad.mat[5], -pad.mat[8]};
  const int k = rays_per_side;
  const double step = h / k;
  double dist_sum = 0.0;
  int hits = 0;
  for (int a = 0; a < k; ++a) {
    const double x = u + (a + 0.5) * step - 0.5 * h;
    for (int b = 0; b < k; ++b) {
      const double y = v + (b + 0.5) * step - 0.5 * h;
      double o[3];
      for (int r = 0; r < 3; ++r) o[r] = pad.pos[r] + pad.mat[3 * r + 0] * x + pad.mat[3 * r + 1] * y;
      const double dist = s.ray(o, d_world);
      if (!(dist >= 0.0)) continue;
      dist_sum += dist;
      ++hits;
    }
  }
  if (hits == 0) return false;
  // dist is measured down from the pad's z = 0 plane: the top is at -dist.
  *gap_m = z + dist_sum / hits;
  *coverage = static_cast<double>(hits) / (k * k);
  return true;
}

}  // namespace mjtouch
