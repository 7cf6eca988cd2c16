#include "surface.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace mjtouch {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();

double Sinc(double x) { return std::abs(x) < 1e-8 ? 1.0 - x * x / 6.0 : std::sin(x) / x; }

// Integral of the unit hat max(0, 1 - |t|) from -inf to t.
double HatCdf(double t) {
  if (t <= -1.0) return 0.0;
  if (t < 0.0) return 0.5 * (t + 1.0) * (t + 1.0);
  if (t < 1.0) return 1.0 - 0.5 * (1.0 - t) * (1.0 - t);
  return 1.0;
}

// Weights of the piecewise-linear interpolant's samples in its mean over
// [s0, s1] (grid units, clipped to [0, count - 1]); returns the first index.
int HatWeights(double s0, double s1, int count, double* w, int max_w) {
  const double top = count - 1;
  s0 = std::clamp(s0, 0.0, top);
  s1 = std::clamp(s1, 0.0, top);
  if (s1 - s0 < 1e-9) {  // degenerate interval: point value
    int c = std::min(static_cast<int>(s0), count - 2);
    c = std::max(c, 0);
    const double f = s0 - c;
    w[0] = 1.0 - f;
    w[1] = f;
    for (int k = 2; k < max_w; ++k) w[k] = 0.0;
    return c;
  }
  const int c0 = std::max(0, static_cast<int>(std::floor(s0)));
  const int c1 = std::min(count - 1, static_cast<int>(std::ceil(s1)));
  const double inv = 1.0 / (s1 - s0);
  int k = 0;
  for (int c = c0; c <= c1 && k < max_w; ++c, ++k) {
    w[k] = (HatCdf(s1 - c) - HatCdf(s0 - c)) * inv;
  }
  for (; k < max_w; ++k) w[k] = 0.0;
  return c0;
}

double Overlap1D(double a0, double a1, double b0, double b1) {
  return std::max(0.0, std::min(a1, b1) - std::max(a0, b0));
}

}  // namespace

std::vector<double> SkinSurface(const TaxelGrid& grid, const PadGeometry& pad,
                                const Ridges& ridges) {
  std::vector<double> z(grid.Size(), kInf);
  const double a = pad.semi_axes_m[0], b = pad.semi_axes_m[1], c = pad.semi_axes_m[2];
  const double h = grid.pitch_m;
  // Ridge relief -(H/2) cos(k . r) averaged over the cell: the cell mean of
  // cos(k . r) is cos(k . r_c) sinc(kx h / 2) sinc(ky h / 2), exactly.
  const double k = 2.0 * kPi / ridges.pitch_m;
  const double kx = k * std::cos(ridges.angle_rad), ky = k * std::sin(ridges.angle_rad);
  const double cell_gain = Sinc(0.5 * kx * h) * Sinc(0.5 * ky * h);
  // Two-point Gauss per axis for the smooth pad shape.
  const double g = 0.5 * h / std::sqrt(3.0);
  for (int j = 0; j < grid.n; ++j) {
    const double v = grid.Centre(j);
    for (int i = 0; i < grid.n; ++i) {
      const double u = grid.Centre(i);
      double sum = 0.0;
      bool inside = true;
      for (int sa = -1; sa <= 1 && inside; sa += 2) {
        for (int sb = -1; sb <= 1; sb += 2) {
          const double x = u + sa * g, y = v + sb * g;
          const double t = 1.0 - (x * x) / (a * a) - (y * y) / (b * b);
          if (t <= 0.0) { inside = false; break; }
          sum += -c * std::sqrt(t);
        }
      }
      if (!inside) continue;
      double zz = 0.25 * sum;
      if (ridges.enabled) {
        zz -= 0.5 * ridges.height_m * std::cos(kx * u + ky * v) * cell_gain;
      }
      z[static_cast<size_t>(j) * grid.n + i] = zz;
    }
  }
  return z;
}

std::vector<double> HeightFieldRowPrefix(int nrow, int ncol, const float* samples) {
  std::vector<double> prefix(static_cast<size_t>(nrow) * ncol, 0.0);
  for (int r = 0; r < nrow; ++r) {
    const float* h = samples + static_cast<size_t>(r) * ncol;
    double* P = prefix.data() + static_cast<size_t>(r) * ncol;
    for (int c = 1; c < ncol; ++c) P[c] = P[c - 1] + 0.5 * (double(h[c - 1]) + h[c]);
  }
  return prefix;
}

namespace {

// Integral from 0 to s (grid units, 0 <= s <= ncol - 1) of row r's linear
// interpolant, from the running integrals.
double RowIntegral(const CounterSurface& s, int r, double x) {
  const float* h = s.samples + static_cast<size_t>(r) * s.ncol;
  const double* P = s.row_prefix + static_cast<size_t>(r) * s.ncol;
  int c = static_cast<int>(x);
  c = std::clamp(c, 0, s.ncol - 2);
  const double f = x - c;
  return P[c] + f * h[c] + 0.5 * f * f * (double(h[c + 1]) - h[c]);
}

}  // namespace

double HeightFieldBoxMean(const CounterSurface& s, double x0, double x1,
                          double y0, double y1) {
  constexpr int kMaxW = 64;
  double wx[kMaxW], wy[kMaxW];
  const double scx = (s.ncol - 1) / (2.0 * s.half_x_m);
  const double scy = (s.nrow - 1) / (2.0 * s.half_y_m);
  const int r0 = HatWeights((y0 + s.half_y_m) * scy, (y1 + s.half_y_m) * scy,
                            s.nrow, wy, kMaxW);
  double sx0 = std::clamp((x0 + s.half_x_m) * scx, 0.0, s.ncol - 1.0);
  double sx1 = std::clamp((x1 + s.half_x_m) * scx, 0.0, s.ncol - 1.0);
  if (s.row_prefix && sx1 - sx0 > 1e-6) {
    const double inv = 1.0 / (sx1 - sx0);
    double mean = 0.0;
    for (int r = 0; r < kMaxW && r0 + r < s.nrow; ++r) {
      if (wy[r] == 0.0) continue;
      mean += wy[r] * (RowIntegral(s, r0 + r, sx1) - RowIntegral(s, r0 + r, sx0)) * inv;
    }
    return s.elevation_m * mean;
  }
  const int c0 = HatWeights(sx0, sx1, s.ncol, wx, kMaxW);
  double mean = 0.0;
  for (int r = 0; r < kMaxW && r0 + r < s.nrow; ++r) {
    if (wy[r] == 0.0) continue;
    const float* row = s.samples + static_cast<size_t>(r0 + r) * s.ncol + c0;
    double acc = 0.0;
    for (int c = 0; c < kMaxW && c0 + c < s.ncol; ++c) acc += wx[c] * row[c];
    mean += wy[r] * acc;
  }
  return s.elevation_m * mean;
}

double RenderGap(const TaxelGrid& grid, const std::vector<double>& skin_z,
                 const Pose& pad, const std::vector<CounterSurface>& surfaces,
                 double cull_above_m, std::vector<double>* gap_m,
                 std::vector<double>* coverage) {
  const size_t N = grid.Size();
  gap_m->assign(N, kInf);
  coverage->assign(N, 0.0);
  const double h = grid.pitch_m;
  struct Frame {
    double R[9], t[3], hx, hy;
  };
  std::vector<Frame> frames(surfaces.size());
  for (size_t k = 0; k < surfaces.size(); ++k) {
    const CounterSurface& s = surfaces[k];
    Frame& F = frames[k];
    // R = S^T P maps pad-frame vectors into the surface frame.
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        F.R[3 * r + c] = s.pose.mat[0 + r] * pad.mat[0 + c] +
                         s.pose.mat[3 + r] * pad.mat[3 + c] +
                         s.pose.mat[6 + r] * pad.mat[6 + c];
    for (int r = 0; r < 3; ++r) {  // pad origin in the surface frame
      F.t[r] = 0.0;
      for (int c = 0; c < 3; ++c) F.t[r] += s.pose.mat[3 * c + r] * (pad.pos[c] - s.pose.pos[c]);
    }
    // Axis-aligned half extents of a cell's footprint in the surface frame.
    F.hx = 0.5 * h * (std::abs(F.R[0]) + std::abs(F.R[1]));
    F.hy = 0.5 * h * (std::abs(F.R[3]) + std::abs(F.R[4]));
  }
  // Lower bound of every cell's gap (surface's highest point): the cull level
  // is relative to the smallest.
  double cull = kInf;
  if (std::isfinite(cull_above_m)) {
    double lb_min = kInf;
    for (size_t k = 0; k < surfaces.size(); ++k) {
      const Frame& F = frames[k];
      for (int j = 0; j < grid.n; ++j) {
        const double v = grid.Centre(j);
        for (int i = 0; i < grid.n; ++i) {
          const double z = skin_z[static_cast<size_t>(j) * grid.n + i];
          if (!std::isfinite(z)) continue;
          const double qz = F.t[2] + F.R[6] * grid.Centre(i) + F.R[7] * v + F.R[8] * z;
          lb_min = std::min(lb_min, qz - surfaces[k].max_height_m);
        }
      }
    }
    cull = lb_min + cull_above_m;
  }
  for (size_t k = 0; k < surfaces.size(); ++k) {
    const CounterSurface& s = surfaces[k];
    const Frame& F = frames[k];
    const double* R = F.R;
    const double area = 4.0 * F.hx * F.hy;
    for (int j = 0; j < grid.n; ++j) {
      const double v = grid.Centre(j);
      for (int i = 0; i < grid.n; ++i) {
        const size_t idx = static_cast<size_t>(j) * grid.n + i;
        const double z = skin_z[idx];
        if (!std::isfinite(z)) continue;
        const double u = grid.Centre(i);
        const double qz = F.t[2] + R[6] * u + R[7] * v + R[8] * z;
        if (qz - s.max_height_m > cull) continue;
        const double qx = F.t[0] + R[0] * u + R[1] * v + R[2] * z;
        const double qy = F.t[1] + R[3] * u + R[4] * v + R[5] * z;
        double cov = 1.0, gap = qz;
        if (s.type != CounterSurface::Type::kPlane) {
          const double ox = Overlap1D(qx - F.hx, qx + F.hx, -s.half_x_m, s.half_x_m);
          const double oy = Overlap1D(qy - F.hy, qy + F.hy, -s.half_y_m, s.half_y_m);
          cov = area > 0 ? ox * oy / area : 0.0;
          if (cov <= 0.0) continue;
          if (s.type == CounterSurface::Type::kHeightField) {
            const double x0 = std::max(qx - F.hx, -s.half_x_m);
            const double x1 = std::min(qx + F.hx, s.half_x_m);
            const double y0 = std::max(qy - F.hy, -s.half_y_m);
            const double y1 = std::min(qy + F.hy, s.half_y_m);
            gap = qz - HeightFieldBoxMean(s, x0, x1, y0, y1);
          }
        }
        if (gap < (*gap_m)[idx]) {
          (*gap_m)[idx] = gap;
          (*coverage)[idx] = cov;
        }
      }
    }
  }
  return cull;
}

}  // namespace mjtouch
