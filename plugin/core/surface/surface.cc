// Stage 1's skin surface: the pad's shape plus the fingerprint ridges' relief,
// each taxel cell's height an exact average over the cell (SkinSurface).
#include "surface/surface.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "surface/mesh_surface.h"
#include "surface/primitives.h"

namespace mjtouch {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();

double Sinc(double x) { return std::abs(x) < 1e-8 ? 1.0 - x * x / 6.0 : std::sin(x) / x; }

}  // namespace

const char* RidgeProfileName(RidgeProfile p) {
  switch (p) {
    case RidgeProfile::kSine: return "sine";
    case RidgeProfile::kTriangle: return "triangle";
    default: return "square";
  }
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

void SetPadFacing(const double facing[3], PadGeometry* pad) {
  const double a[3] = {-facing[0], -facing[1], -facing[2]};  // the skin's +z
  double* R = pad->rotation;
  pad->rotated = !(a[0] == 0.0 && a[1] == 0.0 && a[2] == 1.0);
  if (!pad->rotated) {
    const double identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    std::copy(identity, identity + 9, R);
    return;
  }
  if (a[2] < -1.0 + 1e-12) {  // facing +z: a half turn about x
    const double half_turn[9] = {1, 0, 0, 0, -1, 0, 0, 0, -1};
    std::copy(half_turn, half_turn + 9, R);
    return;
  }
  // Rodrigues: R = I + [v]x + [v]x^2 / (1 + c), v = z x a, c = z . a
  const double v[3] = {-a[1], a[0], 0.0}, k = 1.0 / (1.0 + a[2]);
  const double V[9] = {0, -v[2], v[1], v[2], 0, -v[0], -v[1], v[0], 0};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      double vv = 0.0;
      for (int m = 0; m < 3; ++m) vv += V[3 * r + m] * V[3 * m + c];
      R[3 * r + c] = (r == c ? 1.0 : 0.0) + V[3 * r + c] + k * vv;
    }
}

double PadFootprintSemiAxis(const PadGeometry& pad) {
  const double* ax = pad.semi_axes_m;
  if (pad.shape == PadShape::kMesh) {
    if (!pad.mesh) return 0.0;
    // The outline of a convex mesh about the centre: its inradius is the
    // smallest support value over directions in the skin's plane (sampled
    // every 0.5 degrees: at most R (1 - cos 0.25 deg) ~ 1e-5 R too large).
    const double* R = pad.rotation;
    const std::vector<float>& v = pad.mesh->vertices_m;
    double inradius = kInf;
    constexpr int kDirections = 720;
    for (int k = 0; k < kDirections; ++k) {
      const double t = 2.0 * kPi * k / kDirections, c = std::cos(t), s = std::sin(t);
      const double u[3] = {c * R[0] + s * R[1], c * R[3] + s * R[4], c * R[6] + s * R[7]};
      double support = -kInf;
      for (size_t i = 0; i + 2 < v.size(); i += 3)
        support = std::max(support, u[0] * v[i] + u[1] * v[i + 1] + u[2] * v[i + 2]);
      inradius = std::min(inradius, support);
    }
    return std::max(inradius, 0.0);
  }
  if (!pad.rotated) return std::min(ax[0], ax[1]);
  // The shape's half extent along the skin's x and y axes (geom frame u).
  auto extent = [&](int column) {
    const double u[3] = {pad.rotation[column], pad.rotation[3 + column], pad.rotation[6 + column]};
    switch (pad.shape) {
      case PadShape::kBox:
        return std::abs(u[0]) * ax[0] + std::abs(u[1]) * ax[1] + std::abs(u[2]) * ax[2];
      case PadShape::kCapsule: return ax[0] + (ax[2] - ax[0]) * std::abs(u[2]);
      default:
        return std::sqrt(u[0] * u[0] * ax[0] * ax[0] + u[1] * u[1] * ax[1] * ax[1] +
                         u[2] * u[2] * ax[2] * ax[2]);
    }
  };
  return std::min(extent(0), extent(1));
}

namespace {

// The near side (smallest s) of the pad's shape on the line o + s d (geom
// frame): the exact surface of a rotated pad, one line per sample point.
bool PadNearSide(const PadGeometry& pad, const double o[3], const double d[3], double* s_near) {
  const double* ax = pad.semi_axes_m;
  double lo, hi;
  switch (pad.shape) {
    case PadShape::kBox: {
      lo = -kInf;
      hi = kInf;
      for (int k = 0; k < 3; ++k) {
        if (std::abs(d[k]) < 1e-15) {
          if (std::abs(o[k]) > ax[k]) return false;
          continue;
        }
        double t0 = (-ax[k] - o[k]) / d[k], t1 = (ax[k] - o[k]) / d[k];
        if (t0 > t1) std::swap(t0, t1);
        lo = std::max(lo, t0);
        hi = std::min(hi, t1);
      }
      if (!(lo <= hi)) return false;
      break;
    }
    case PadShape::kMesh: {
      // The first hit of the line coming from beyond the mesh along +d.
      if (!pad.mesh || !pad.mesh->caster) return false;
      const double far = 2.0 * pad.mesh->bound_radius_m + 1e-3;
      const double start[3] = {o[0] - far * d[0], o[1] - far * d[1], o[2] - far * d[2]};
      const double t = pad.mesh->caster->Cast(start, d);
      if (!(t >= 0.0)) return false;
      *s_near = t - far;
      return true;
    }
    case PadShape::kCapsule: {
      CounterSurface c;
      c.type = CounterSurface::Type::kCapsule;
      c.size_m[0] = ax[0];
      c.size_m[1] = ax[2] - ax[0];
      if (!surface_detail::LineInterval(c, o, d, &lo, &hi)) return false;
      break;
    }
    default: {  // sphere, ellipsoid
      double os[3], ds[3];
      for (int k = 0; k < 3; ++k) {
        os[k] = o[k] / ax[k];
        ds[k] = d[k] / ax[k];
      }
      if (!surface_detail::SphereInterval(os, ds, 1.0, &lo, &hi)) return false;
    }
  }
  *s_near = lo;
  return true;
}

}  // namespace

std::vector<double> SkinSurface(const TaxelGrid& grid, const PadGeometry& pad,
                                const Ridges& ridges) {
  std::vector<double> z(grid.Size(), kInf);
  const double* ax = pad.semi_axes_m;
  const double* R = pad.rotation;
  // Shape of the touching side as a height field z(x, y) <= 0 in the pad
  // frame; false outside its footprint.
  auto shape = [&](double x, double y, double* zz) {
    if (pad.rotated ||
        pad.shape == PadShape::kMesh) {  // the line (x, y, s) of the skin's frame, in the geom's
      const double o[3] = {R[0] * x + R[1] * y, R[3] * x + R[4] * y, R[6] * x + R[7] * y};
      const double d[3] = {R[2], R[5], R[8]};
      return PadNearSide(pad, o, d, zz);
    }
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
          if (!shape(u + sx * g, v + sy * g, &zz)) {
            inside = false;
            break;
          }
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

}  // namespace mjtouch
