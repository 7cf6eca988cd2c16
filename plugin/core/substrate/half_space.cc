#include "substrate/substrate.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

namespace mjtouch {
namespace {

constexpr double kPi = 3.14159265358979323846;

// 4-point Gauss-Legendre on [-1, 1].
constexpr double kGaussX[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                               0.8611363115940526};
constexpr double kGaussW[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461,
                               0.3478548451374538};

// Antiderivative of 1/r: d^2 Phi / dX dY = 1 / sqrt(X^2 + Y^2).
double Phi(double X, double Y) {
  double out = 0.0;
  if (X != 0.0) out += X * std::asinh(Y / std::abs(X));
  if (Y != 0.0) out += Y * std::asinh(X / std::abs(Y));
  return out;
}

}  // namespace

// Boussinesq: normal point force P = 1 N into the solid at the origin, the
// polar solution of Johnson, Contact Mechanics (1985), eq. 3.21, rotated to
// Cartesian axes (s_xy = (s_rr - s_tt) cos sin). (1 - z/rho) / r^2 is written 1 / (rho (rho + z)),
// which is exact and has no cancellation on the axis.
Stress6 HalfSpace::Boussinesq(double x, double y, double z) const {
  const double r2 = x * x + y * y;
  const double rho2 = r2 + z * z;
  const double rho = std::sqrt(rho2);
  const double rho3 = rho2 * rho, rho5 = rho3 * rho2;
  const double c = 1.0 / (2.0 * kPi);
  const double a = 1.0 / (rho * (rho + z));  // (1 - z/rho) / r^2
  const double b = 1.0 - 2.0 * nu_;
  // The (1 - 2 nu) brackets are ratios O(r^2) / r^2, bounded as r -> 0;
  // exactly on the axis use their limit s_xx = s_yy = (1 - 2 nu) / (4 pi z^2).
  Stress6 s{};
  if (r2 > 0.0) {
    const double inv_r2 = 1.0 / r2;
    s[kSxx] = c * (b * inv_r2 * (a * (x * x - y * y) + z * y * y / rho3) - 3.0 * z * x * x / rho5);
    s[kSyy] = c * (b * inv_r2 * (a * (y * y - x * x) + z * x * x / rho3) - 3.0 * z * y * y / rho5);
    s[kSxy] = c * (b * inv_r2 * (2.0 * a * x * y - x * y * z / rho3) - 3.0 * x * y * z / rho5);
  } else {
    s[kSxx] = s[kSyy] = b / (4.0 * kPi * z * z);
  }
  s[kSzz] = -3.0 * c * z * z * z / rho5;
  s[kSxz] = -3.0 * c * x * z * z / rho5;
  s[kSyz] = -3.0 * c * y * z * z / rho5;
  return s;
}

// Johnson (1985), eq. 3.87a: tangential point force Q = 1 N along +x.
Stress6 HalfSpace::CerrutiX(double x, double y, double z) const {
  const double rho2 = x * x + y * y + z * z;
  const double rho = std::sqrt(rho2);
  const double rho3 = rho2 * rho, rho5 = rho3 * rho2;
  const double c = 1.0 / (2.0 * kPi);
  const double b = 1.0 - 2.0 * nu_;
  const double rz = rho + z;
  const double rz2 = rz * rz;
  Stress6 s{};
  s[kSxx] =
      c * x / rho3 * (-3.0 * x * x / rho2 + b / rz2 * (rho2 - y * y - 2.0 * rho * y * y / rz));
  s[kSyy] = c * x / rho3 *
            (-3.0 * y * y / rho2 + b / rz2 * (3.0 * rho2 - x * x - 2.0 * rho * x * x / rz));
  s[kSxy] =
      c * y / rho3 * (-3.0 * x * x / rho2 + b / rz2 * (-rho2 + x * x + 2.0 * rho * x * x / rz));
  s[kSzz] = -3.0 * c * x * z * z / rho5;
  s[kSxz] = -3.0 * c * x * x * z / rho5;
  s[kSyz] = -3.0 * c * x * y * z / rho5;
  return s;
}

// Force along +y: rotate the +x solution by 90 degrees (x -> y, y -> -x).
Stress6 HalfSpace::CerrutiY(double x, double y, double z) const {
  // Evaluate the +x solution at the rotated point (x', y') = (y, -x), then
  // rotate the tensor back: s_xx <- s'_yy, s_yy <- s'_xx, s_xy <- -s'_xy,
  // s_xz <- -s'_yz, s_yz <- s'_xz.
  const Stress6 p = CerrutiX(y, -x, z);
  Stress6 s{};
  s[kSxx] = p[kSyy];
  s[kSyy] = p[kSxx];
  s[kSzz] = p[kSzz];
  s[kSxy] = -p[kSxy];
  s[kSxz] = -p[kSyz];
  s[kSyz] = p[kSxz];
  return s;
}

Stress6 HalfSpace::CellStress(SurfaceLoad load, double x, double y, double z, double h) const {
  // Composite Gauss: split the cell so that every sub-cell is at most a third
  // of its distance to the receptor; 4x4 points per sub-cell then converge
  // to ~1e-7 relative.
  const double dx = std::max(0.0, std::abs(x) - 0.5 * h);
  const double dy = std::max(0.0, std::abs(y) - 0.5 * h);
  const double dmin = std::sqrt(dx * dx + dy * dy + z * z);
  const int m = std::clamp(static_cast<int>(std::ceil(3.0 * h / dmin)), 1, 64);
  const double hs = h / m;
  Stress6 acc{};
  for (int a = 0; a < m; ++a) {
    for (int b = 0; b < m; ++b) {
      const double cx = -0.5 * h + (a + 0.5) * hs;
      const double cy = -0.5 * h + (b + 0.5) * hs;
      for (int ga = 0; ga < 4; ++ga) {
        for (int gb = 0; gb < 4; ++gb) {
          // Source point (sx, sy) inside the cell; receptor relative to it.
          const double sx = cx + 0.5 * hs * kGaussX[ga];
          const double sy = cy + 0.5 * hs * kGaussX[gb];
          const double w = kGaussW[ga] * kGaussW[gb] * 0.25 * hs * hs;
          Stress6 p;
          switch (load) {
            case kLoadPressure: p = Boussinesq(x - sx, y - sy, z); break;
            case kLoadShearX: p = CerrutiX(x - sx, y - sy, z); break;
            default: p = CerrutiY(x - sx, y - sy, z); break;
          }
          for (int k = 0; k < kNumStress; ++k) acc[k] += w * p[k];
        }
      }
    }
  }
  return acc;
}

std::string HalfSpace::Describe() const {
  char buf[96];
  std::snprintf(buf, sizeof(buf), "homogeneous half-space (nu=%.4g)", nu_);
  return buf;
}

void Substrate::LatticeTable(double z, double h, int n, const std::array<bool, kNumStress>& want,
                             std::vector<float>* table) const {
  const int L = 2 * n - 1;
  table->assign(static_cast<size_t>(kNumLoads) * kNumStress * L * L, 0.0f);
  for (int dj = -(n - 1); dj <= n - 1; ++dj) {
    for (int di = -(n - 1); di <= n - 1; ++di) {
      // Source at (+di, +dj) cells from the receptor: the receptor sits at
      // (-di h, -dj h) relative to the source cell's centre.
      for (int load = 0; load < kNumLoads; ++load) {
        const Stress6 s = CellStress(static_cast<SurfaceLoad>(load), -di * h, -dj * h, z, h);
        for (int c = 0; c < kNumStress; ++c) {
          if (!want[c]) continue;
          (*table)[(static_cast<size_t>(load * kNumStress + c) * L + (dj + n - 1)) * L +
                   (di + n - 1)] = static_cast<float>(s[c]);
        }
      }
    }
  }
}

// ---------------------------------------------------------------------------
// Surface compliance (the half-space's surface Green's function per cell).

void HalfSpaceSurfaceComplianceTable(double young_pa, double poisson, double h, int n,
                                     std::vector<float>* table) {
  const int L = 2 * n - 1;
  table->assign(static_cast<size_t>(L) * L, 0.0f);
  const double e_star = young_pa / (1.0 - poisson * poisson);
  const double scale = 1.0 / (kPi * e_star);
  const double a = 0.5 * h;
  for (int dj = 0; dj < n; ++dj) {
    for (int di = 0; di < n; ++di) {
      // Field point at (x, y) = offset of the receptor cell from the loaded
      // one: minus (di, dj) h; the response is even in both.
      const double x = di * h, y = dj * h;
      const double v =
          scale * (Phi(x + a, y + a) - Phi(x + a, y - a) - Phi(x - a, y + a) + Phi(x - a, y - a));
      const float f = static_cast<float>(v);
      for (int sj : {-1, 1})
        for (int si : {-1, 1})
          (*table)[static_cast<size_t>(sj * dj + n - 1) * L + (si * di + n - 1)] = f;
    }
  }
}

}  // namespace mjtouch
