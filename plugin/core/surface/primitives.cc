// Stage 1's counter-surface primitives: height fields' cell means
// (HeightFieldRowPrefix, HeightFieldBoxMean) and the bounding radius of a
// surface (BoundRadius).
#include <algorithm>
#include <cmath>
#include <vector>

#include "surface/aligned_face.h"
#include "surface/surface.h"

namespace mjtouch {

using namespace surface_detail;

namespace {

// Integral of the unit hat max(0, 1 - |t|) from -inf to t.
double HatCdf(double t) {
  if (t <= -1.0) return 0.0;
  if (t < 0.0) return 0.5 * (t + 1.0) * (t + 1.0);
  if (t < 1.0) return 1.0 - 0.5 * (1.0 - t) * (1.0 - t);
  return 1.0;
}

// The piecewise-linear interpolant's mean over [s0, s1] (grid units,
// clipped to [0, count - 1]) is sum_c w_c f_c over the samples c in
// [first, last]; HatSpan gives the range and HatWeight each weight. Computed
// on the fly: a cell may span any number of samples.
struct HatSpan {
  int first = 0, last = -1;  // sample range
  double s0 = 0, s1 = 0, inv = 0;
  bool point = false;  // degenerate interval: linear interpolation at s0
};

HatSpan MakeHatSpan(double s0, double s1, int count) {
  HatSpan h;
  const double top = count - 1;
  h.s0 = std::clamp(s0, 0.0, top);
  h.s1 = std::clamp(s1, 0.0, top);
  if (h.s1 - h.s0 < 1e-9) {
    h.point = true;
    h.first = std::max(0, std::min(static_cast<int>(h.s0), count - 2));
    h.last = h.first + 1;
    return h;
  }
  h.first = std::max(0, static_cast<int>(std::floor(h.s0)));
  h.last = std::min(count - 1, static_cast<int>(std::ceil(h.s1)));
  h.inv = 1.0 / (h.s1 - h.s0);
  return h;
}

double HatWeight(const HatSpan& h, int c) {
  if (h.point) {
    const double f = h.s0 - h.first;
    return c == h.first ? 1.0 - f : f;
  }
  return (HatCdf(h.s1 - c) - HatCdf(h.s0 - c)) * h.inv;
}

}  // namespace

std::vector<double> HeightFieldRowPrefix(int nrow, int ncol, const float* samples) {
  std::vector<double> prefix(static_cast<size_t>(nrow) * ncol, 0.0);
  for (int r = 0; r < nrow; ++r) {
    const float* h = samples + static_cast<size_t>(r) * ncol;
    double* P = prefix.data() + static_cast<size_t>(r) * ncol;
    for (int c = 1; c < ncol; ++c) P[c] = P[c - 1] + 0.5 * (double(h[c - 1]) + h[c]);
  }
  return prefix;
}

double HeightFieldBoxMean(const CounterSurface& s, double x0, double x1, double y0, double y1) {
  const double scx = (s.ncol - 1) / (2.0 * s.half_x_m);
  const double scy = (s.nrow - 1) / (2.0 * s.half_y_m);
  const double sx0 = std::clamp((x0 + s.half_x_m) * scx, 0.0, s.ncol - 1.0);
  const double sx1 = std::clamp((x1 + s.half_x_m) * scx, 0.0, s.ncol - 1.0);
  // Identical rows: the row weights sum to one, so the mean is row 0's.
  if (s.rows_identical && s.row_prefix && sx1 - sx0 > 1e-6)
    return s.elevation_m * (RowIntegral(s, 0, sx1) - RowIntegral(s, 0, sx0)) / (sx1 - sx0);
  const HatSpan hy = MakeHatSpan((y0 + s.half_y_m) * scy, (y1 + s.half_y_m) * scy, s.nrow);
  double mean = 0.0;
  if (s.row_prefix && sx1 - sx0 > 1e-6) {
    const double inv = 1.0 / (sx1 - sx0);
    for (int r = hy.first; r <= hy.last; ++r) {
      const double wy = HatWeight(hy, r);
      if (wy == 0.0) continue;
      mean += wy * (RowIntegral(s, r, sx1) - RowIntegral(s, r, sx0)) * inv;
    }
    return s.elevation_m * mean;
  }
  const HatSpan hx = MakeHatSpan(sx0, sx1, s.ncol);
  for (int r = hy.first; r <= hy.last; ++r) {
    const double wy = HatWeight(hy, r);
    if (wy == 0.0) continue;
    const float* row = s.samples + static_cast<size_t>(r) * s.ncol;
    double acc = 0.0;
    for (int c = hx.first; c <= hx.last; ++c) acc += HatWeight(hx, c) * row[c];
    mean += wy * acc;
  }
  return s.elevation_m * mean;
}

double BoundRadius(const CounterSurface& s) {
  using T = CounterSurface::Type;
  switch (s.type) {
    case T::kSphere: return s.size_m[0];
    case T::kEllipsoid: return std::max({s.size_m[0], s.size_m[1], s.size_m[2]});
    case T::kCapsule: return s.size_m[0] + s.size_m[1];
    case T::kCylinder: return std::hypot(s.size_m[0], s.size_m[1]);
    case T::kBox:
      return std::sqrt(s.size_m[0] * s.size_m[0] + s.size_m[1] * s.size_m[1] +
                       s.size_m[2] * s.size_m[2]);
    default: return s.bound_radius_m;
  }
}

}  // namespace mjtouch
