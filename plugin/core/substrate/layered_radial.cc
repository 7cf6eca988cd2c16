// LayeredSubstrate in real space: radial (Hankel) transforms of the tabulated
// transfer functions for point, disc and cell loads, and the lattice tables
// (stress and surface compliance) integrated over each source cell.
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "substrate/layered.h"
#include "substrate/layered_internal.h"

namespace mjtouch {
using namespace layered_internal;

namespace {

// 8-point Gauss-Legendre on [-1, 1].
constexpr double kGl8X[8] = {-0.9602898564975363, -0.7966664774136267, -0.5255324099163290,
                             -0.1834346424956498, 0.1834346424956498,  0.5255324099163290,
                             0.7966664774136267,  0.9602898564975363};
constexpr double kGl8W[8] = {0.1012285362903763, 0.2223810344533745, 0.3137066458778873,
                             0.3626837833783620, 0.3626837833783620, 0.3137066458778873,
                             0.2223810344533745, 0.1012285362903763};
// 4-point Gauss-Legendre on [-1, 1] (cell quadrature).
constexpr double kGl4X[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                             0.8611363115940526};
constexpr double kGl4W[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461,
                             0.3478548451374538};

// Parity of each (load, component) field in x and in y (1 = odd).
constexpr int kOddX[kNumLoads][kNumStress] = {
    {0, 0, 0, 1, 1, 0}, {1, 1, 1, 0, 0, 1}, {0, 0, 0, 1, 1, 0}};
constexpr int kOddY[kNumLoads][kNumStress] = {
    {0, 0, 0, 1, 0, 1}, {0, 0, 0, 1, 0, 1}, {1, 1, 1, 0, 1, 0}};

// Bessel J0..J3. glibc's j0/j1 (POSIX) are accurate to a few ulp and much
// cheaper than std::cyl_bessel_j. Upward recurrence is stable for x > n;
// below that the power series converges fast.
void BesselJ0123(double x, double* j) {
  j[0] = ::j0(x);
  j[1] = ::j1(x);
  if (x > 4.0) {
    j[2] = 2.0 / x * j[1] - j[0];
    j[3] = 4.0 / x * j[2] - j[1];
    return;
  }
  const double h = 0.5 * x, h2 = h * h;
  for (int n = 2; n <= 3; ++n) {
    double term = 1.0;
    for (int i = 1; i <= n; ++i) term *= h / i;  // (x/2)^n / n!
    double sum = term;
    for (int m = 1; m < 20; ++m) {
      term *= -h2 / (m * (m + n));
      sum += term;
      if (std::abs(term) < 1e-18 * std::abs(sum)) break;
    }
    j[n] = sum;
  }
}

// Rotate a +x shear solution evaluated at (y, -x) into the +y solution at
// (x, y) (as HalfSpace::CerrutiY).
Stress6 RotateShearXToY(const Stress6& p) {
  Stress6 s{};
  s[kSxx] = p[kSyy];
  s[kSyy] = p[kSxx];
  s[kSzz] = p[kSzz];
  s[kSxy] = -p[kSxy];
  s[kSxz] = -p[kSyz];
  s[kSyz] = p[kSxz];
  return s;
}

Stress6 NaNStress() {
  Stress6 s;
  s.fill(kNaN);
  return s;
}

// Integral of 1 / sqrt(X^2 + Y^2 + b^2) over a square cell of side h centred
// at the origin, seen from (x, y): corner sum of the antiderivative
// X ln(Y + rho) + Y ln(X + rho) - b atan(X Y / (b rho)).
double LogPlus(double u, double v, double b, double rho) {
  // ln(u + rho), rho = sqrt(u^2 + v^2 + b^2), without cancellation for u < 0.
  if (u >= 0) return std::log(u + rho);
  return std::log((v * v + b * b) / (rho - u));
}
double CellPotentialCorner(double X, double Y, double b) {
  const double rho = std::sqrt(X * X + Y * Y + b * b);
  double f = 0;
  if (X != 0) f += X * LogPlus(Y, X, b, rho);
  if (Y != 0) f += Y * LogPlus(X, Y, b, rho);
  if (b != 0) f -= b * std::atan(X * Y / (b * rho));
  return f;
}
double CellPotential(double x, double y, double h, double b) {
  const double x2 = x + 0.5 * h, x1 = x - 0.5 * h;
  const double y2 = y + 0.5 * h, y1 = y - 0.5 * h;
  return CellPotentialCorner(x2, y2, b) - CellPotentialCorner(x1, y2, b) -
         CellPotentialCorner(x2, y1, b) + CellPotentialCorner(x1, y1, b);
}

}  // namespace

// ---------------------------------------------------------------------------
// Radial (Hankel) route: point force or uniform disc.

namespace {

// The 11 radial integrals I_i = int_0^inf F_i(k) W(k) J_n(k r) k dk, with
// W = 1 (point force) or 2 pi R J1(k R) / k (unit traction on a disc).
enum {
  kIPzz = 0,
  kIPsum,
  kIPdif,
  kIPxz,  // pressure
  kIX1a,
  kIX1b,
  kIX1c,
  kIXzz,
  kIX3,
  kIXz0,
  kIXz2,  // shear x
  kNumRadial
};

// single: the table holds one function (compliance), integrated with J0
// into I[0].
template <typename TabT>
void RadialIntegrals(const TabT& tab, double r, double radius, double decay, bool pressure,
                     bool shear, double* I, bool single = false) {
  for (int i = 0; i < kNumRadial; ++i) I[i] = 0;
  const double k_end = tab.k_hi;
  const double osc = r + radius;
  double k0 = 0;
  double T[kNumTransfer], J[4];
  while (k0 < k_end) {
    double w = std::max(0.25 * k0, tab.k_lo);
    w = std::min(w, 1.0 / decay);
    if (osc > 0) w = std::min(w, kPi / osc);
    const double k1 = std::min(k0 + w, k_end);
    const double half = 0.5 * (k1 - k0), mid = 0.5 * (k1 + k0);
    for (int g = 0; g < 8; ++g) {
      const double k = mid + half * kGl8X[g];
      double wk = half * kGl8W[g] * k;
      if (radius > 0) wk *= 2 * kPi * radius * ::j1(k * radius) / k;
      tab.At(k, T);
      if (single) {
        I[0] += wk * T[0] * ::j0(k * r);
        continue;
      }
      BesselJ0123(k * r, J);
      if (pressure) {
        I[kIPzz] += wk * T[kPzz] * J[0];
        I[kIPsum] += wk * (T[kPxx] + T[kPyy]) * J[0];
        I[kIPdif] += wk * (T[kPxx] - T[kPyy]) * J[2];
        I[kIPxz] += wk * T[kPxz] * J[1];
      }
      if (shear) {
        const double qx = T[kQxx], qy = T[kQyy], ax = T[kAxy];
        I[kIX1a] += wk * 0.25 * (3 * qx + qy + 2 * ax) * J[1];
        I[kIX1b] += wk * 0.25 * (qx + 3 * qy - 2 * ax) * J[1];
        I[kIX1c] += wk * 0.25 * (qx - qy + 2 * ax) * J[1];
        I[kIXzz] += wk * T[kQzz] * J[1];
        I[kIX3] += wk * 0.25 * (qx - qy - 2 * ax) * J[3];
        I[kIXz0] += wk * 0.5 * (T[kAyz] - T[kQxz]) * J[0];
        I[kIXz2] += wk * 0.5 * (T[kQxz] + T[kAyz]) * J[2];
      }
    }
    k0 = k1;
  }
}

// Stress at (x, y) from the radial integrals (inverse 2D Fourier transform:
// cos(n phi) F(k) -> i^n cos(n theta) H_n[F] / (2 pi)).
Stress6 AssembleRadial(SurfaceLoad load, double x, double y, const double* I) {
  const double r = std::hypot(x, y);
  const double c1 = r > 0 ? x / r : 1.0, s1 = r > 0 ? y / r : 0.0;
  const double c2 = c1 * c1 - s1 * s1, s2 = 2 * s1 * c1;
  const double c3 = c1 * c2 - s1 * s2, s3 = s1 * c2 + c1 * s2;
  const double f = 1.0 / (2 * kPi);
  Stress6 s{};
  if (load == kLoadPressure) {
    s[kSzz] = f * I[kIPzz];
    s[kSxx] = f * (0.5 * I[kIPsum] - 0.5 * c2 * I[kIPdif]);
    s[kSyy] = f * (0.5 * I[kIPsum] + 0.5 * c2 * I[kIPdif]);
    s[kSxy] = -f * 0.5 * s2 * I[kIPdif];
    s[kSxz] = -f * c1 * I[kIPxz];
    s[kSyz] = -f * s1 * I[kIPxz];
  } else {
    s[kSxx] = f * (-c1 * I[kIX1a] + c3 * I[kIX3]);
    s[kSyy] = f * (-c1 * I[kIX1b] - c3 * I[kIX3]);
    s[kSxy] = f * (-s1 * I[kIX1c] + s3 * I[kIX3]);
    s[kSzz] = -f * c1 * I[kIXzz];
    s[kSxz] = f * (I[kIXz0] + c2 * I[kIXz2]);
    s[kSyz] = f * s2 * I[kIXz2];
  }
  return s;
}

template <typename TabT>
Stress6 RadialStress(const TabT& tab, SurfaceLoad load, double x, double y, double radius,
                     double decay) {
  double I[kNumRadial];
  if (load == kLoadShearY) {
    // +y solution at (x, y) = rotated +x solution at (y, -x).
    RadialIntegrals(tab, std::hypot(x, y), radius, decay, false, true, I);
    return RotateShearXToY(AssembleRadial(kLoadShearX, y, -x, I));
  }
  RadialIntegrals(tab, std::hypot(x, y), radius, decay, load == kLoadPressure,
                  load != kLoadPressure, I);
  return AssembleRadial(load, x, y, I);
}

}  // namespace

Stress6 LayeredSubstrate::PointStress(SurfaceLoad load, double x, double y, double z,
                                      InterfaceSide side) const {
  double local;
  const int j = Locate(z, side, &local);
  if (j < 0) return NaNStress();
  const bool subtract = (j == 0);
  const double a = DecayLength(j, z);
  Tab tab;
  TabulateTransfer(j, local, z, subtract, LowK(z), kDecayCut / a, &tab);
  Stress6 s = RadialStress(tab, load, x, y, 0.0, a);
  if (subtract) {
    Stress6 h;
    switch (load) {
      case kLoadPressure: h = top_halfspace_->Boussinesq(x, y, z); break;
      case kLoadShearX: h = top_halfspace_->CerrutiX(x, y, z); break;
      default: h = top_halfspace_->CerrutiY(x, y, z); break;
    }
    for (int c = 0; c < kNumStress; ++c) s[c] += h[c];
  }
  return s;
}

Stress6 LayeredSubstrate::DiscStress(SurfaceLoad load, double x, double y, double z, double radius,
                                     InterfaceSide side) const {
  double local;
  const int j = Locate(z, side, &local);
  if (j < 0 || !(radius > 0)) return NaNStress();
  Tab tab;
  TabulateTransfer(j, local, z, false, LowK(z), kDecayCut / z, &tab);
  return RadialStress(tab, load, x, y, radius, z);
}

Stress6 LayeredSubstrate::CellStress(SurfaceLoad load, double x, double y, double z,
                                     double h) const {
  return CellStress(load, x, y, z, h, side_);
}

Stress6 LayeredSubstrate::CellStress(SurfaceLoad load, double x, double y, double z, double h,
                                     InterfaceSide side) const {
  double local;
  const int j = Locate(z, side, &local);
  if (j < 0 || !(h > 0)) return NaNStress();
  const bool subtract = (j == 0);
  const double a = DecayLength(j, z);
  Tab tab;
  TabulateTransfer(j, local, z, subtract, LowK(z), kDecayCut / a, &tab);
  // Sub-cells no larger than the scale on which the integrand varies: a for
  // the smooth top-layer remainder, the distance to the cell otherwise.
  const double dx = std::max(0.0, std::abs(x) - 0.5 * h);
  const double dy = std::max(0.0, std::abs(y) - 0.5 * h);
  const double dmin = std::sqrt(dx * dx + dy * dy + z * z);
  const double scale = subtract ? a : dmin;
  const int m = std::clamp(static_cast<int>(std::ceil(4.0 * h / scale)), 1, 64);
  const double hs = h / m;
  Stress6 acc{};
  for (int ia = 0; ia < m; ++ia) {
    for (int ib = 0; ib < m; ++ib) {
      const double cx = -0.5 * h + (ia + 0.5) * hs;
      const double cy = -0.5 * h + (ib + 0.5) * hs;
      for (int ga = 0; ga < 4; ++ga) {
        for (int gb = 0; gb < 4; ++gb) {
          const double sx = cx + 0.5 * hs * kGl4X[ga];
          const double sy = cy + 0.5 * hs * kGl4X[gb];
          const double w = kGl4W[ga] * kGl4W[gb] * 0.25 * hs * hs;
          const Stress6 p = RadialStress(tab, load, x - sx, y - sy, 0.0, a);
          for (int c = 0; c < kNumStress; ++c) acc[c] += w * p[c];
        }
      }
    }
  }
  if (subtract) {
    const Stress6 hsv = top_halfspace_->CellStress(load, x, y, z, h);
    for (int c = 0; c < kNumStress; ++c) acc[c] += hsv[c];
  }
  return acc;
}

// ---------------------------------------------------------------------------
// Lattice route: radial tables (Hankel transforms on a stretched r grid), then
// Gauss quadrature over each source cell. Real space, so the slowly decaying
// in-plane tails (1/r^2, 1/r^3) have no periodic images.

namespace {

// Radial integrals on r = c (exp(u) - 1), u uniform: spacing 0.03 c near the
// axis, 3 % of r far away, where the functions vary on the scale of r.
struct RadialTable {
  double c = 0, inv_du = 0;
  int nr = 0;
  std::vector<double> g;  // nr x kNumRadial
  static constexpr double kDu = 0.03;
  template <typename TabT>
  void Build(const TabT& tab, double decay, double r_max, int nfunc) {
    c = 0.5 * decay;
    inv_du = 1.0 / kDu;
    nr = static_cast<int>(std::ceil(std::log1p(r_max / c) * inv_du)) + 6;
    g.assign(static_cast<size_t>(nr) * kNumRadial, 0.0);
    for (int i = 0; i < nr; ++i) {
      const double r = c * std::expm1(i * kDu);
      double* out = g.data() + static_cast<size_t>(i) * kNumRadial;
      if (nfunc == 1) {
        RadialIntegrals(tab, r, 0.0, decay, true, false, out, true);
      } else {
        RadialIntegrals(tab, r, 0.0, decay, true, true, out, false);
      }
    }
  }
  // Quintic (6-point) Lagrange in u.
  void At(double r, double* out) const {
    const double u = std::log1p(r / c) * inv_du;
    const int i = std::clamp(static_cast<int>(u) - 2, 0, nr - 6);
    const double s = u - i;
    double w[6];
    for (int a = 0; a < 6; ++a) {
      double num = 1, den = 1;
      for (int b = 0; b < 6; ++b) {
        if (b == a) continue;
        num *= s - b;
        den *= a - b;
      }
      w[a] = num / den;
    }
    const double* p = g.data() + static_cast<size_t>(i) * kNumRadial;
    for (int f = 0; f < kNumRadial; ++f) {
      double v = 0;
      for (int a = 0; a < 6; ++a) v += w[a] * p[a * kNumRadial + f];
      out[f] = v;
    }
  }
};

// Quadrature over a source cell of side h centred at the origin, receptor at
// (x, y), for an integrand that varies on the length `scale`: 2x2 Gauss points
// when h < scale / 30, 3x3 when h < scale / 10, else 4x4 on sub-cells no
// wider than scale / 4 (each keeps the error below ~1e-7 of the integrand;
// scale / 2 left 2e-5 next to a stiff-over-soft interface).
template <typename Fn>
void CellQuadrature(double x, double y, double h, double scale, Fn&& fn) {
  static constexpr double kG2X[2] = {-0.5773502691896258, 0.5773502691896258};
  static constexpr double kG2W[2] = {1.0, 1.0};
  static constexpr double kG3X[3] = {-0.7745966692414834, 0.0, 0.7745966692414834};
  static constexpr double kG3W[3] = {0.5555555555555556, 0.8888888888888888, 0.5555555555555556};
  if (h <= 0.1 * scale) {
    const bool two = h <= scale / 30;
    const int np = two ? 2 : 3;
    const double* gx = two ? kG2X : kG3X;
    const double* gw = two ? kG2W : kG3W;
    for (int a = 0; a < np; ++a)
      for (int b = 0; b < np; ++b)
        fn(x - 0.5 * h * gx[a], y - 0.5 * h * gx[b], 0.25 * h * h * gw[a] * gw[b]);
    return;
  }
  const int m = std::clamp(static_cast<int>(std::ceil(4.0 * h / scale)), 1, 64);
  const double hs = h / m;
  for (int ia = 0; ia < m; ++ia)
    for (int ib = 0; ib < m; ++ib) {
      const double cx = -0.5 * h + (ia + 0.5) * hs;
      const double cy = -0.5 * h + (ib + 0.5) * hs;
      for (int ga = 0; ga < 4; ++ga)
        for (int gb = 0; gb < 4; ++gb) {
          const double sx = cx + 0.5 * hs * kGl4X[ga];
          const double sy = cy + 0.5 * hs * kGl4X[gb];
          fn(x - sx, y - sy, kGl4W[ga] * kGl4W[gb] * 0.25 * hs * hs);
        }
    }
}

}  // namespace

void LayeredSubstrate::LatticeTable(double z, double h, int n,
                                    const std::array<bool, kNumStress>& want,
                                    std::vector<float>* table) const {
  LatticeTable(z, h, n, want, side_, table);
}

void LayeredSubstrate::LatticeTable(double z, double h, int n,
                                    const std::array<bool, kNumStress>& want, InterfaceSide side,
                                    std::vector<float>* table) const {
  const int L = 2 * n - 1;
  table->assign(static_cast<size_t>(kNumLoads) * kNumStress * L * L, 0.0f);
  double local;
  const int j = Locate(z, side, &local);
  if (j < 0 || !(h > 0) || n < 1) {
    std::fill(table->begin(), table->end(), std::numeric_limits<float>::quiet_NaN());
    return;
  }
  const bool subtract = (j == 0);
  const double a = DecayLength(j, z);
  Tab tab;
  TabulateTransfer(j, local, z, subtract, LowK(z), kDecayCut / a, &tab);
  RadialTable rt;
  rt.Build(tab, a, std::sqrt(2.0) * (n - 0.5) * h + h, kNumRadial);

  // Quarter (dx, dy >= 0): receptor at (dx h, dy h) from the source cell.
  std::vector<Stress6> quarter(static_cast<size_t>(n) * n * kNumLoads);
  double I[kNumRadial];
  for (int dy = 0; dy < n; ++dy) {
    for (int dx = 0; dx < n; ++dx) {
      const double x = dx * h, y = dy * h;
      const double lx = std::max(0.0, x - 0.5 * h);
      const double ly = std::max(0.0, y - 0.5 * h);
      const double dlat = std::hypot(lx, ly);
      const double scale = subtract ? std::max(a, 0.5 * dlat) : std::hypot(dlat, z);
      Stress6 acc[kNumLoads] = {};
      CellQuadrature(x, y, h, scale, [&](double px, double py, double w) {
        rt.At(std::hypot(px, py), I);
        const Stress6 sp = AssembleRadial(kLoadPressure, px, py, I);
        const Stress6 sx = AssembleRadial(kLoadShearX, px, py, I);
        const Stress6 sy = RotateShearXToY(AssembleRadial(kLoadShearX, py, -px, I));
        for (int c = 0; c < kNumStress; ++c) {
          acc[0][c] += w * sp[c];
          acc[1][c] += w * sx[c];
          acc[2][c] += w * sy[c];
        }
      });
      if (subtract) {
        for (int load = 0; load < kNumLoads; ++load) {
          const Stress6 hsv =
              top_halfspace_->CellStress(static_cast<SurfaceLoad>(load), x, y, z, h);
          for (int c = 0; c < kNumStress; ++c) acc[load][c] += hsv[c];
        }
      }
      for (int load = 0; load < kNumLoads; ++load)
        quarter[(static_cast<size_t>(dy) * n + dx) * kNumLoads + load] = acc[load];
    }
  }
  // Scatter with parity; table index (di, dj) = (-X, -Y) for receptor offset
  // (X, Y) cells from the source.
  for (int load = 0; load < kNumLoads; ++load)
    for (int comp = 0; comp < kNumStress; ++comp) {
      if (!want[comp]) continue;
      const bool ox = kOddX[load][comp], oy = kOddY[load][comp];
      float* out = table->data() + static_cast<size_t>(load * kNumStress + comp) * L * L;
      for (int dj = -(n - 1); dj <= n - 1; ++dj)
        for (int di = -(n - 1); di <= n - 1; ++di) {
          const int X = -di, Y = -dj;
          double v = quarter[(static_cast<size_t>(std::abs(Y)) * n + std::abs(X)) * kNumLoads +
                             load][comp];
          if (X < 0 && ox) v = -v;
          if (Y < 0 && oy) v = -v;
          out[static_cast<size_t>(dj + n - 1) * L + (di + n - 1)] = static_cast<float>(v);
        }
    }
}

// ---------------------------------------------------------------------------
// Surface compliance lattice.

void LayeredSubstrate::SurfaceComplianceTable(double h, int n, std::vector<float>* table) const {
  const int L = 2 * n - 1;
  table->assign(static_cast<size_t>(L) * L, 0.0f);
  if (!(h > 0) || n < 1) {
    std::fill(table->begin(), table->end(), std::numeric_limits<float>::quiet_NaN());
    return;
  }
  // Reference with the singular parts in closed form (real space):
  // C_ref(k) = [C1 (1 - exp(-k b)) + Cb exp(-k b)] / k, the top layer's
  // half-space at large k and the base's (0 on bone) at small k;
  // 1/k <-> 1/(2 pi r), exp(-k b)/k <-> 1/(2 pi sqrt(r^2 + b^2)). The rest
  // decays like exp(-2 k h1) and goes through the radial route.
  const ElasticLayer& top = layers_[0];
  const double C1 = 2 * (1 - top.poisson * top.poisson) / top.young_pa;
  const double Cb = base_.rigid ? 0.0 : 2 * (1 - base_.poisson * base_.poisson) / base_.young_pa;
  const double b = 2 * top.thickness_m;
  const double a = 2 * top.thickness_m;
  Tab tab;
  tab.Init(1, LowK(0), kDecayCut / a);
  Solution sol;
  tab.v0[0] = SurfaceCompliance(0.0) - (C1 - Cb) * b;
  for (int i = 0; i < kTablePoints; ++i) {
    const double k = tab.KAt(i);
    Solve(k, &sol);
    const double c = sol.surface_uz / (2 * mu_pa_[0] * k);
    const double eb = std::exp(-k * b);
    tab.v[i] = c - (C1 * (1 - eb) + Cb * eb) / k;
  }
  RadialTable rt;
  rt.Build(tab, a, std::sqrt(2.0) * (n - 0.5) * h + h, 1);
  double I[kNumRadial];
  std::vector<double> quarter(static_cast<size_t>(n) * n);
  for (int dy = 0; dy < n; ++dy)
    for (int dx = 0; dx < n; ++dx) {
      const double x = dx * h, y = dy * h;
      const double dlat = std::hypot(std::max(0.0, x - 0.5 * h), std::max(0.0, y - 0.5 * h));
      double acc = 0;
      CellQuadrature(x, y, h, std::max(a, 0.5 * dlat), [&](double px, double py, double w) {
        rt.At(std::hypot(px, py), I);
        acc += w * I[0];
      });
      const double I0 = CellPotential(x, y, h, 0.0);
      const double Ib = CellPotential(x, y, h, b);
      quarter[static_cast<size_t>(dy) * n + dx] =
          acc / (2 * kPi) + (C1 * (I0 - Ib) + Cb * Ib) / (2 * kPi);
    }
  for (int dj = -(n - 1); dj <= n - 1; ++dj)
    for (int di = -(n - 1); di <= n - 1; ++di)
      (*table)[static_cast<size_t>(dj + n - 1) * L + (di + n - 1)] =
          static_cast<float>(quarter[static_cast<size_t>(std::abs(dj)) * n + std::abs(di)]);
}

}  // namespace mjtouch
