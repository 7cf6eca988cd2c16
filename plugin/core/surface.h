// Stage 1: surface rendering. The skin's surface (pad shape plus fingerprint
// ridge relief) sampled on the taxel grid, and the gap between each taxel's
// cell and the counter-surfaces it faces. Every sample is an exact average over
// the cell's area (anti-aliased), so a texture sliding under the grid varies
// smoothly and adds no spurious line at V / pitch.
#ifndef MJTOUCH_CORE_SURFACE_H_
#define MJTOUCH_CORE_SURFACE_H_

#include <string>
#include <vector>

#include "grid.h"

namespace mjtouch {

// Pad shape in its own frame; the skin that touches is the -z pole.
enum class PadShape { kSphere, kEllipsoid };

struct PadGeometry {
  PadShape shape = PadShape::kEllipsoid;
  double semi_axes_m[3] = {0, 0, 0};  // x, y, z (sphere: all equal)
};

enum class RidgeProfile { kSine };

struct Ridges {
  bool enabled = true;
  double pitch_m = 0.45e-3;   // ridge period (Shao et al. 2010)
  double height_m = 0.05e-3;  // crest-to-valley relief (Shao et al. 2010)
  double angle_rad = 0.0;     // ridge lines vs pad y axis (0: perpendicular to x)
  RidgeProfile profile = RidgeProfile::kSine;
};

// Cell-averaged skin surface height z (pad frame, m) at every taxel; +inf
// where the cell lies outside the pad's footprint. Ridges protrude towards -z
// around the pad's mean surface.
std::vector<double> SkinSurface(const TaxelGrid& grid, const PadGeometry& pad,
                                const Ridges& ridges);

// Rigid transform, local -> world: world = pos + mat * local (mat row-major).
struct Pose {
  double pos[3] = {0, 0, 0};
  double mat[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
};

// A counter-surface described in its own frame, whose local +z is the outward
// normal of the face that the skin touches.
struct CounterSurface {
  enum class Type { kPlane, kRectangle, kHeightField };
  Type type = Type::kPlane;
  Pose pose;
  // kRectangle: half sizes of the face (x, y); kPlane ignores them.
  double half_x_m = 0, half_y_m = 0;
  // kHeightField (MuJoCo semantics): nrow x ncol samples in [0, 1], row r at
  // y = -half_y + 2 half_y r / (nrow - 1), column c at x likewise;
  // height = elevation_m * sample.
  int nrow = 0, ncol = 0;
  const float* samples = nullptr;
  double elevation_m = 0;
  // Optional per-row running integrals of the samples (HeightFieldRowPrefix):
  // makes a cell average O(rows) instead of O(rows x columns).
  const double* row_prefix = nullptr;
  double max_height_m = 0;  // highest point above the local z = 0 plane
  int id = -1;  // caller's tag (e.g. MuJoCo geom id)
};

// Gap (m) between each taxel cell of the skin (pad at pose `pad_pose`) and the
// nearest counter-surface, measured along each surface's normal; `coverage`
// is the fraction of the cell over a surface (0: no surface, gap = +inf).
// Cells whose gap is provably above `cull_above_m` (relative to the smallest
// lower bound of any cell) are skipped and left at +inf: pass +inf to render
// all. Returns the absolute cull level used (+inf if none), so a caller whose
// contact reaches above it can render again without culling.
double RenderGap(const TaxelGrid& grid, const std::vector<double>& skin_z,
                 const Pose& pad_pose, const std::vector<CounterSurface>& surfaces,
                 double cull_above_m, std::vector<double>* gap_m,
                 std::vector<double>* coverage);

// Running integrals along x of each row of a height field's samples (grid
// units, trapezoid rule, which is exact for the linear interpolant).
std::vector<double> HeightFieldRowPrefix(int nrow, int ncol, const float* samples);

// Exact average of a bilinear height field over the axis-aligned box
// [x0, x1] x [y0, y1] (surface frame), exposed for tests.
double HeightFieldBoxMean(const CounterSurface& s, double x0, double x1,
                          double y0, double y1);

}  // namespace mjtouch

#endif  // MJTOUCH_CORE_SURFACE_H_
