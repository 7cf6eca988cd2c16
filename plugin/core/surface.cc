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

const char* RidgeProfileName(RidgeProfile p) {
  switch (p) {
    case RidgeProfile::kSine: return "sine";
    case RidgeProfile::kTriangle: return "triangle";
    default: return "square";
  }
}

bool ParseRidgeProfile(const std::string& name, RidgeProfile* p) {
  for (RidgeProfile v : {RidgeProfile::kSine, RidgeProfile::kTriangle, RidgeProfile::kSquare}) {
    if (name == RidgeProfileName(v)) {
      *p = v;
      return true;
    }
  }
  return false;
}

double RidgeRelief(const Ridges& r, double s) {
  const double L = r.pitch_m, H = r.height_m;
  const double f = s - L * std::round(s / L);  // in [-L/2, L/2], crest at 0
  switch (r.profile) {
    case RidgeProfile::kSine: return 0.5 * H * std::cos(2.0 * kPi * s / L);
    case RidgeProfile::kTriangle: return 0.5 * H * (1.0 - 4.0 * std::abs(f) / L);
    default: return std::abs(f) < 0.25 * L ? 0.5 * H : -0.5 * H;
  }
}

double RidgeCellMean(const Ridges& r, double sc, double h) {
  // Over a square cell, s = s_c + S1 + S2 with S1, S2 uniform of widths
  // h |cos|, h |sin|: the density of s - s_c is a trapezoid.
  const double w1 = h * std::abs(std::cos(r.angle_rad)), w2 = h * std::abs(std::sin(r.angle_rad));
  const double L = r.pitch_m;
  if (r.profile == RidgeProfile::kSine) {
    const double k = 2.0 * kPi / L;
    return 0.5 * r.height_m * std::cos(k * sc) * Sinc(0.5 * k * w1) * Sinc(0.5 * k * w2);
  }
  const double A = std::max(w1, w2), B = std::min(w1, w2);
  const double W = 0.5 * (A + B), flat = 0.5 * (A - B);
  if (!(A > 0.0)) return RidgeRelief(r, sc);
  auto density = [&](double s) {
    const double as = std::abs(s);
    if (as <= flat || !(B > 1e-15 * A)) return as <= W ? 1.0 / A : 0.0;
    return as < W ? (W - as) / (A * B) : 0.0;
  };
  // Knots: the density's corners and the profile's kinks / jumps.
  double knots[64];
  int nk = 0;
  knots[nk++] = -W;
  knots[nk++] = W;
  if (B > 1e-15 * A) {
    knots[nk++] = -flat;
    knots[nk++] = flat;
  }
  const double step = 0.5 * L;  // triangle: crests and valleys; square: jumps at +-L/4
  const double offset = r.profile == RidgeProfile::kTriangle ? 0.0 : 0.25 * L;
  for (double m = std::ceil((sc - W - offset) / step); nk < 64; m += 1.0) {
    const double s = m * step + offset - sc;
    if (s > W) break;
    if (s > -W) knots[nk++] = s;
  }
  std::sort(knots, knots + nk);
  const double g = 0.5 / std::sqrt(3.0);
  double mean = 0.0;
  for (int k = 0; k + 1 < nk; ++k) {
    const double a = knots[k], b = knots[k + 1], len = b - a;
    if (!(len > 0.0)) continue;
    const double mid = 0.5 * (a + b);
    for (double x : {mid - g * len, mid + g * len})
      mean += 0.5 * len * density(x) * RidgeRelief(r, sc + x);
  }
  return mean;
}

std::vector<double> SkinSurface(const TaxelGrid& grid, const PadGeometry& pad,
                                const Ridges& ridges) {
  std::vector<double> z(grid.Size(), kInf);
  const double* ax = pad.semi_axes_m;
  // Shape of the touching side as a height field z(x, y) <= 0 in the pad
  // frame; false outside its footprint.
  auto shape = [&](double x, double y, double* zz) {
    switch (pad.shape) {
      case PadShape::kBox:
        if (std::abs(x) > ax[0] || std::abs(y) > ax[1]) return false;
        *zz = -ax[2];
        return true;
      case PadShape::kCapsule: {  // -z end cap: hemisphere of radius ax[0]
        const double r = ax[0], t = 1.0 - (x * x + y * y) / (r * r);
        if (t <= 0.0) return false;
        *zz = -(ax[2] - r) - r * std::sqrt(t);
        return true;
      }
      default: {
        const double t = 1.0 - (x * x) / (ax[0] * ax[0]) - (y * y) / (ax[1] * ax[1]);
        if (t <= 0.0) return false;
        *zz = -ax[2] * std::sqrt(t);
        return true;
      }
    }
  };
  const double h = grid.pitch_m;
  const double ca = std::cos(ridges.angle_rad), sa = std::sin(ridges.angle_rad);
  // Two-point Gauss per axis for the smooth pad shape.
  const double g = 0.5 * h / std::sqrt(3.0);
  for (int j = 0; j < grid.n; ++j) {
    const double v = grid.Centre(j);
    for (int i = 0; i < grid.n; ++i) {
      const double u = grid.Centre(i);
      double sum = 0.0;
      bool inside = true;
      for (int sx = -1; sx <= 1 && inside; sx += 2) {
        for (int sy = -1; sy <= 1; sy += 2) {
          double zz;
          if (!shape(u + sx * g, v + sy * g, &zz)) { inside = false; break; }
          sum += zz;
        }
      }
      if (!inside) continue;
      double zz = 0.25 * sum;
      if (ridges.enabled) zz -= RidgeCellMean(ridges, ca * u + sa * v, h);
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

namespace {

bool IsLineType(CounterSurface::Type t) {
  using T = CounterSurface::Type;
  return t == T::kSphere || t == T::kEllipsoid || t == T::kCapsule || t == T::kCylinder ||
         t == T::kRay;
}

// Interval of s where a s^2 + b s + c <= 0 (a > 0).
bool Quadratic(double a, double b, double c, double* lo, double* hi) {
  const double disc = b * b - 4.0 * a * c;
  if (disc < 0.0) return false;
  const double sq = std::sqrt(disc);
  *lo = (-b - sq) / (2.0 * a);
  *hi = (-b + sq) / (2.0 * a);
  return true;
}

bool SphereInterval(const double o[3], const double d[3], double r, double* lo, double* hi) {
  return Quadratic(d[0] * d[0] + d[1] * d[1] + d[2] * d[2],
                   2.0 * (o[0] * d[0] + o[1] * d[1] + o[2] * d[2]),
                   o[0] * o[0] + o[1] * o[1] + o[2] * o[2] - r * r, lo, hi);
}

// Finite cylinder of radius r, axis local z in [-hh, hh].
bool CylinderInterval(const double o[3], const double d[3], double r, double hh, double* lo,
                      double* hi) {
  const double a = d[0] * d[0] + d[1] * d[1];
  const double c = o[0] * o[0] + o[1] * o[1] - r * r;
  double l = -kInf, u = kInf;
  if (a > 1e-24) {
    if (!Quadratic(a, 2.0 * (o[0] * d[0] + o[1] * d[1]), c, &l, &u)) return false;
  } else if (c > 0.0) {
    return false;
  }
  if (std::abs(d[2]) > 1e-12) {
    double z0 = (-hh - o[2]) / d[2], z1 = (hh - o[2]) / d[2];
    if (z0 > z1) std::swap(z0, z1);
    l = std::max(l, z0);
    u = std::min(u, z1);
  } else if (std::abs(o[2]) > hh) {
    return false;
  }
  if (!(l <= u)) return false;
  *lo = l;
  *hi = u;
  return true;
}

// The convex body's extent along the line o + s d (local frame).
bool LineInterval(const CounterSurface& s, const double o[3], const double d[3], double* lo,
                  double* hi) {
  using T = CounterSurface::Type;
  switch (s.type) {
    case T::kSphere: return SphereInterval(o, d, s.size_m[0], lo, hi);
    case T::kEllipsoid: {
      double os[3], ds[3];
      for (int k = 0; k < 3; ++k) {
        os[k] = o[k] / s.size_m[k];
        ds[k] = d[k] / s.size_m[k];
      }
      return SphereInterval(os, ds, 1.0, lo, hi);
    }
    case T::kCylinder: return CylinderInterval(o, d, s.size_m[0], s.size_m[1], lo, hi);
    case T::kCapsule: {
      // Convex: the union of the pieces' intervals is one interval.
      double l = kInf, u = -kInf, a, b;
      if (CylinderInterval(o, d, s.size_m[0], s.size_m[1], &a, &b)) { l = a; u = b; }
      for (double zc : {-s.size_m[1], s.size_m[1]}) {
        const double oc[3] = {o[0], o[1], o[2] - zc};
        if (SphereInterval(oc, d, s.size_m[0], &a, &b)) {
          l = std::min(l, a);
          u = std::max(u, b);
        }
      }
      if (!(l <= u)) return false;
      *lo = l;
      *hi = u;
      return true;
    }
    default: return false;
  }
}

}  // namespace

double BoundRadius(const CounterSurface& s) {
  using T = CounterSurface::Type;
  switch (s.type) {
    case T::kSphere: return s.size_m[0];
    case T::kEllipsoid: return std::max({s.size_m[0], s.size_m[1], s.size_m[2]});
    case T::kCapsule: return s.size_m[0] + s.size_m[1];
    case T::kCylinder: return std::hypot(s.size_m[0], s.size_m[1]);
    default: return s.bound_radius_m;
  }
}

double RenderGap(const TaxelGrid& grid, const std::vector<double>& skin_z,
                 const Pose& pad, const std::vector<CounterSurface>& surfaces,
                 double cull_above_m, std::vector<double>* gap_m,
                 std::vector<double>* coverage, bool area_average) {
  const size_t N = grid.Size();
  gap_m->assign(N, kInf);
  coverage->assign(N, 0.0);
  const double h = grid.pitch_m;
  struct Frame {
    double R[9], t[3], hx, hy;
    double centre_pad[3];  // surface origin in the pad frame (line types)
    double radius;         // bounding sphere (line types)
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
    for (int c = 0; c < 3; ++c) {  // -R^T t
      F.centre_pad[c] = 0.0;
      for (int r = 0; r < 3; ++r) F.centre_pad[c] -= F.R[3 * r + c] * F.t[r];
    }
    F.radius = BoundRadius(s);
    // Axis-aligned half extents of a cell's footprint in the surface frame.
    F.hx = 0.5 * h * (std::abs(F.R[0]) + std::abs(F.R[1]));
    F.hy = 0.5 * h * (std::abs(F.R[3]) + std::abs(F.R[4]));
  }
  // Lower bound of a cell's gap to surface k (+inf: cannot touch). Face
  // types: the surface's highest point; line types: the top of the bounding
  // sphere on the cell's line.
  auto lower_bound = [&](size_t k, double u, double v, double z) {
    const Frame& F = frames[k];
    if (IsLineType(surfaces[k].type)) {
      const double dx = u - F.centre_pad[0], dy = v - F.centre_pad[1];
      const double e = F.radius + h;  // the whole cell, not only its centre
      const double q = e * e - dx * dx - dy * dy;
      if (q < 0.0) return kInf;
      return z - (F.centre_pad[2] + std::sqrt(q));
    }
    const double qz = F.t[2] + F.R[6] * u + F.R[7] * v + F.R[8] * z;
    return qz - surfaces[k].max_height_m;
  };
  // The cull level is relative to the smallest lower bound of any cell.
  double cull = kInf;
  if (std::isfinite(cull_above_m)) {
    double lb_min = kInf;
    for (size_t k = 0; k < surfaces.size(); ++k) {
      for (int j = 0; j < grid.n; ++j) {
        const double v = grid.Centre(j);
        for (int i = 0; i < grid.n; ++i) {
          const double z = skin_z[static_cast<size_t>(j) * grid.n + i];
          if (!std::isfinite(z)) continue;
          lb_min = std::min(lb_min, lower_bound(k, grid.Centre(i), v, z));
        }
      }
    }
    cull = lb_min + cull_above_m;
  }
  const double g = area_average ? 0.5 * h / std::sqrt(3.0) : 0.0;
  for (size_t k = 0; k < surfaces.size(); ++k) {
    const CounterSurface& s = surfaces[k];
    const Frame& F = frames[k];
    const double* R = F.R;
    const double area = 4.0 * F.hx * F.hy;
    const bool line = IsLineType(s.type);
    // The pad's z axis in the surface frame, and in the world (kRay).
    const double d_loc[3] = {R[2], R[5], R[8]};
    const double d_world[3] = {-pad.mat[2], -pad.mat[5], -pad.mat[8]};
    for (int j = 0; j < grid.n; ++j) {
      const double v = grid.Centre(j);
      for (int i = 0; i < grid.n; ++i) {
        const size_t idx = static_cast<size_t>(j) * grid.n + i;
        const double z = skin_z[idx];
        if (!std::isfinite(z)) continue;
        const double u = grid.Centre(i);
        if (lower_bound(k, u, v, z) > cull) continue;
        double cov = 1.0, gap;
        if (line) {
          if (s.type == CounterSurface::Type::kRay) {
            // One ray down the pad's -z axis from the pad's centre plane.
            double o[3];
            for (int r = 0; r < 3; ++r)
              o[r] = pad.pos[r] + pad.mat[3 * r + 0] * u + pad.mat[3 * r + 1] * v;
            const double dist = s.ray ? s.ray(o, d_world) : -1.0;
            if (!(dist >= 0.0)) continue;
            gap = z + dist;
          } else {
            double top_sum = 0.0;
            int hits = 0;
            const int np = area_average ? 2 : 1;
            for (int a = 0; a < np; ++a) {
              for (int b = 0; b < np; ++b) {
                const double x = u + (area_average ? (a ? g : -g) : 0.0);
                const double y = v + (area_average ? (b ? g : -g) : 0.0);
                const double o[3] = {F.t[0] + R[0] * x + R[1] * y, F.t[1] + R[3] * x + R[4] * y,
                                     F.t[2] + R[6] * x + R[7] * y};
                double lo, hi;
                if (LineInterval(s, o, d_loc, &lo, &hi)) {
                  top_sum += hi;
                  ++hits;
                }
              }
            }
            if (hits == 0) continue;
            cov = static_cast<double>(hits) / (np * np);
            gap = z - top_sum / hits;
          }
        } else {
          const double qz = F.t[2] + R[6] * u + R[7] * v + R[8] * z;
          const double qx = F.t[0] + R[0] * u + R[1] * v + R[2] * z;
          const double qy = F.t[1] + R[3] * u + R[4] * v + R[5] * z;
          gap = qz;
          if (s.type != CounterSurface::Type::kPlane) {
            const double hx = area_average ? F.hx : 0.0, hy = area_average ? F.hy : 0.0;
            if (area_average) {
              const double ox = Overlap1D(qx - hx, qx + hx, -s.half_x_m, s.half_x_m);
              const double oy = Overlap1D(qy - hy, qy + hy, -s.half_y_m, s.half_y_m);
              cov = area > 0 ? ox * oy / area : 0.0;
            } else {
              cov = (std::abs(qx) <= s.half_x_m && std::abs(qy) <= s.half_y_m) ? 1.0 : 0.0;
            }
            if (cov <= 0.0) continue;
            if (s.type == CounterSurface::Type::kHeightField) {
              const double x0 = std::max(qx - hx, -s.half_x_m);
              const double x1 = std::min(qx + hx, s.half_x_m);
              const double y0 = std::max(qy - hy, -s.half_y_m);
              const double y1 = std::min(qy + hy, s.half_y_m);
              gap = qz - HeightFieldBoxMean(s, x0, x1, y0, y1);
            }
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
