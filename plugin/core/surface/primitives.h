// Internal to the surface stage: the line primitives (sphere, ellipsoid,
// capsule, cylinder, mesh ray) of RenderGap's general path, inline so the
// per-cell loop keeps them inlined.
#ifndef MJTOUCH_SURFACE_PRIMITIVES_H_
#define MJTOUCH_SURFACE_PRIMITIVES_H_

#include <algorithm>
#include <cmath>
#include <limits>

#include "surface/surface.h"

namespace mjtouch {
namespace surface_detail {

constexpr double kInf = std::numeric_limits<double>::infinity();

inline bool IsLineType(CounterSurface::Type t) {
  using T = CounterSurface::Type;
  return t == T::kSphere || t == T::kEllipsoid || t == T::kCapsule || t == T::kCylinder ||
         t == T::kRay || t == T::kBox;
}

// Interval of s where a s^2 + b s + c <= 0 (a > 0).
inline bool Quadratic(double a, double b, double c, double* lo, double* hi) {
  const double disc = b * b - 4.0 * a * c;
  if (disc < 0.0) return false;
  const double sq = std::sqrt(disc);
  *lo = (-b - sq) / (2.0 * a);
  *hi = (-b + sq) / (2.0 * a);
  return true;
}

inline bool SphereInterval(const double o[3], const double d[3], double r, double* lo, double* hi) {
  return Quadratic(d[0] * d[0] + d[1] * d[1] + d[2] * d[2],
                   2.0 * (o[0] * d[0] + o[1] * d[1] + o[2] * d[2]),
                   o[0] * o[0] + o[1] * o[1] + o[2] * o[2] - r * r, lo, hi);
}

// Finite cylinder of radius r, axis local z in [-hh, hh].
inline bool CylinderInterval(const double o[3], const double d[3], double r, double hh, double* lo,
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
inline bool LineInterval(const CounterSurface& s, const double o[3], const double d[3], double* lo,
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
    case T::kBox: {  // the slabs' intersection
      double l = -kInf, u = kInf;
      for (int k = 0; k < 3; ++k) {
        const double e = s.size_m[k];
        if (std::abs(d[k]) < 1e-15) {
          if (std::abs(o[k]) > e) return false;
          continue;
        }
        double t0 = (-e - o[k]) / d[k], t1 = (e - o[k]) / d[k];
        if (t0 > t1) std::swap(t0, t1);
        l = std::max(l, t0);
        u = std::min(u, t1);
      }
      if (!(l <= u)) return false;
      *lo = l;
      *hi = u;
      return true;
    }
    case T::kCapsule: {
      // Convex: the union of the pieces' intervals is one interval.
      double l = kInf, u = -kInf, a, b;
      if (CylinderInterval(o, d, s.size_m[0], s.size_m[1], &a, &b)) {
        l = a;
        u = b;
      }
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

}  // namespace surface_detail
}  // namespace mjtouch

#endif  // MJTOUCH_SURFACE_PRIMITIVES_H_
