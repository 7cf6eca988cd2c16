#include "substrate/layered.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

namespace mjtouch {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Transfer-function slots in a table row (LayerTransfer order).
enum {
  kPxx = 0, kPyy, kPzz, kPxz, kQxx, kQyy, kQzz, kQxz, kAyz, kAxy, kNumTransfer
};

// Tabulation: points per table, and where a decaying function is dropped
// (exp(-50) times the polynomial growth of a few layers is below 1e-16).
constexpr int kTablePoints = 1024;
constexpr double kDecayCut = 50.0;

// 8-point Gauss-Legendre on [-1, 1].
constexpr double kGl8X[8] = {-0.9602898564975363, -0.7966664774136267,
                             -0.5255324099163290, -0.1834346424956498,
                             0.1834346424956498,  0.5255324099163290,
                             0.7966664774136267,  0.9602898564975363};
constexpr double kGl8W[8] = {0.1012285362903763, 0.2223810344533745,
                             0.3137066458778873, 0.3626837833783620,
                             0.3626837833783620, 0.3137066458778873,
                             0.2223810344533745, 0.1012285362903763};
// 4-point Gauss-Legendre on [-1, 1] (cell quadrature).
constexpr double kGl4X[4] = {-0.8611363115940526, -0.3399810435848563,
                             0.3399810435848563, 0.8611363115940526};
constexpr double kGl4W[4] = {0.3478548451374538, 0.6521451548625461,
                             0.6521451548625461, 0.3478548451374538};

// Parity of each (load, component) field in x and in y (1 = odd).
constexpr int kOddX[kNumLoads][kNumStress] = {
    {0, 0, 0, 1, 1, 0}, {1, 1, 1, 0, 0, 1}, {0, 0, 0, 1, 1, 0}};
constexpr int kOddY[kNumLoads][kNumStress] = {
    {0, 0, 0, 1, 0, 1}, {0, 0, 0, 1, 0, 1}, {1, 1, 1, 0, 1, 0}};

// Bessel J0..J3. glibc's j0/j1 (POSIX) are ~40 ns and accurate to a few ulp;
// std::cyl_bessel_j is ~100x slower. Upward recurrence is stable for x > n;
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

// Dense Gaussian elimination with partial pivoting: A (n x n, row-major) x = B
// (n x m, row-major); the solution overwrites B.
void SolveDense(int n, int m, double* A, double* B) {
  for (int col = 0; col < n; ++col) {
    int piv = col;
    for (int r = col + 1; r < n; ++r)
      if (std::abs(A[r * n + col]) > std::abs(A[piv * n + col])) piv = r;
    if (piv != col) {
      for (int c = 0; c < n; ++c) std::swap(A[col * n + c], A[piv * n + c]);
      for (int c = 0; c < m; ++c) std::swap(B[col * m + c], B[piv * m + c]);
    }
    const double inv = 1.0 / A[col * n + col];
    for (int r = col + 1; r < n; ++r) {
      const double f = A[r * n + col] * inv;
      if (f == 0.0) continue;
      for (int c = col; c < n; ++c) A[r * n + c] -= f * A[col * n + c];
      for (int c = 0; c < m; ++c) B[r * m + c] -= f * B[col * m + c];
    }
  }
  for (int col = n - 1; col >= 0; --col) {
    for (int c = 0; c < m; ++c) {
      double s = B[col * m + c];
      for (int k = col + 1; k < n; ++k) s -= A[col * n + k] * B[k * m + c];
      B[col * m + c] = s / A[col * n + col];
    }
  }
}

// In-plane basis at local depth zeta of a layer (thickness h; h < 0: a
// half-space, no bottom-face terms). out[col][comp]: col a, b, c, d (a, c
// decay from the top face, b, d from the bottom face); comp s_xixi, s_etaeta,
// s_zz, s_xiz^ (= -i s_xiz), U_xi (= 2 mu_ref k (-i u_xi)), U_z
// (= 2 mu_ref k u_z); r = mu_ref / mu.
enum { kCSxx = 0, kCSyy, kCSzz, kCSxz, kCUx, kCUz, kNumComp };
void InplaneBasis(double nu, double r, double k, double zeta, double h,
                  double out[4][kNumComp]) {
  const double t = k * zeta, e = std::exp(-t);
  double* a = out[0];
  a[kCSxx] = -e; a[kCSyy] = 0; a[kCSzz] = e; a[kCSxz] = -e;
  a[kCUx] = r * e; a[kCUz] = -r * e;
  double* c = out[2];
  c[kCSxx] = (2 * nu - t) * e; c[kCSyy] = 2 * nu * e;
  c[kCSzz] = (2 - 2 * nu + t) * e; c[kCSxz] = -(1 - 2 * nu + t) * e;
  c[kCUx] = r * t * e; c[kCUz] = -r * (3 - 4 * nu + t) * e;
  double* b = out[1];
  double* d = out[3];
  if (h < 0) {
    for (int i = 0; i < kNumComp; ++i) b[i] = d[i] = 0;
    return;
  }
  const double tp = k * (zeta - h), ep = std::exp(tp);  // tp <= 0
  b[kCSxx] = -ep; b[kCSyy] = 0; b[kCSzz] = ep; b[kCSxz] = ep;
  b[kCUx] = r * ep; b[kCUz] = r * ep;
  d[kCSxx] = -(2 * nu + tp) * ep; d[kCSyy] = -2 * nu * ep;
  d[kCSzz] = (tp - 2 + 2 * nu) * ep; d[kCSxz] = (tp - 1 + 2 * nu) * ep;
  d[kCUx] = r * tp * ep; d[kCUz] = r * (tp - 3 + 4 * nu) * ep;
}

// Antiplane basis: u_eta = (f e + g e') / (mu k). out[col][comp]: col f, g;
// comp V (= mu_ref k u_eta), s_etaz, s_xieta^ (= -i s_xieta).
void AntiplaneBasis(double r, double k, double zeta, double h,
                    double out[2][3]) {
  const double e = std::exp(-k * zeta);
  out[0][0] = r * e; out[0][1] = -e; out[0][2] = e;
  if (h < 0) {
    out[1][0] = out[1][1] = out[1][2] = 0;
    return;
  }
  const double ep = std::exp(k * (zeta - h));
  out[1][0] = r * ep; out[1][1] = ep; out[1][2] = ep;
}

// Homogeneous half-space transfer functions (REFERENCE.md sec. 3).
void HalfSpaceTransfer(double k, double z, double nu, double* t) {
  const double kz = k * z, e = std::exp(-kz);
  t[kPxx] = -(1 - kz) * e; t[kPyy] = -2 * nu * e; t[kPzz] = -(1 + kz) * e;
  t[kPxz] = kz * e;
  t[kQxx] = (2 - kz) * e; t[kQyy] = 2 * nu * e; t[kQzz] = kz * e;
  t[kQxz] = (1 - kz) * e;
  t[kAyz] = -e; t[kAxy] = e;
}

void ToArray(const LayerTransfer& lt, double* t) {
  t[kPxx] = lt.p_xixi; t[kPyy] = lt.p_etaeta; t[kPzz] = lt.p_zz;
  t[kPxz] = lt.p_xiz; t[kQxx] = lt.q_xixi; t[kQyy] = lt.q_etaeta;
  t[kQzz] = lt.q_zz; t[kQxz] = lt.q_xiz; t[kAyz] = lt.a_etaz;
  t[kAxy] = lt.a_xieta;
}

// Rotate a +x shear solution evaluated at (y, -x) into the +y solution at
// (x, y) (as HalfSpace::CerrutiY).
Stress6 RotateShearXToY(const Stress6& p) {
  Stress6 s{};
  s[kSxx] = p[kSyy]; s[kSyy] = p[kSxx]; s[kSzz] = p[kSzz];
  s[kSxy] = -p[kSxy]; s[kSxz] = -p[kSyz]; s[kSyz] = p[kSxz];
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

std::string Fmt(const char* f, double a, double b = 0, double c = 0) {
  char buf[256];
  std::snprintf(buf, sizeof(buf), f, a, b, c);
  return buf;
}

}  // namespace

// ---------------------------------------------------------------------------
// Per-k solution of the global system and tabulated transfer functions.

struct LayeredSubstrate::Solution {
  std::vector<double> inplane;    // (4 M [+ 2]) x 2: columns pressure, shear
  std::vector<double> antiplane;  // 2 M [+ 1]
  double surface_uz = 0;          // U_z at the surface, unit pressure
  std::vector<double> A, Aa;      // scratch
};

struct LayeredSubstrate::Tab {
  int nf = 0;
  double k_lo = 0, k_hi = 0, inv_du = 0;
  std::vector<double> v;   // kTablePoints x nf, log-spaced k from k_lo
  std::vector<double> v0;  // k = 0
  // Cubic Lagrange in ln k; linear from k = 0 to k_lo (the functions are
  // analytic in k at 0); 0 beyond k_hi (decayed).
  void At(double k, double* out) const {
    if (k >= k_hi) {
      for (int f = 0; f < nf; ++f) out[f] = 0;
      return;
    }
    if (k < k_lo) {
      const double w = k / k_lo;
      for (int f = 0; f < nf; ++f) out[f] = v0[f] + w * (v[f] - v0[f]);
      return;
    }
    const double u = std::log(k / k_lo) * inv_du;
    int i = static_cast<int>(u) - 1;
    i = std::clamp(i, 0, kTablePoints - 4);
    const double s = u - i;  // in [0, 3] for interior points
    const double w0 = -(s - 1) * (s - 2) * (s - 3) / 6.0;
    const double w1 = s * (s - 2) * (s - 3) / 2.0;
    const double w2 = -s * (s - 1) * (s - 3) / 2.0;
    const double w3 = s * (s - 1) * (s - 2) / 6.0;
    const double* p = v.data() + static_cast<size_t>(i) * nf;
    for (int f = 0; f < nf; ++f)
      out[f] = w0 * p[f] + w1 * p[nf + f] + w2 * p[2 * nf + f] +
               w3 * p[3 * nf + f];
  }
  double KAt(int i) const { return k_lo * std::exp(i / inv_du); }
  void Init(int nfunc, double lo, double hi) {
    nf = nfunc;
    k_lo = lo;
    k_hi = hi;
    inv_du = (kTablePoints - 1) / std::log(hi / lo);
    v.assign(static_cast<size_t>(kTablePoints) * nf, 0.0);
    v0.assign(nf, 0.0);
  }
};

// ---------------------------------------------------------------------------
// Construction.

LayeredSubstrate::LayeredSubstrate(std::vector<ElasticLayer> layers,
                                   LayeredBase base, InterfaceSide side)
    : layers_(std::move(layers)), base_(base), side_(side) {
  double z = 0;
  for (const ElasticLayer& l : layers_) {
    z += l.thickness_m;
    interfaces_m_.push_back(z);
    mu_pa_.push_back(l.young_pa / (2 * (1 + l.poisson)));
  }
  mu_pa_.push_back(base_.rigid ? 0.0
                               : base_.young_pa / (2 * (1 + base_.poisson)));
  top_halfspace_ = std::make_unique<HalfSpace>(layers_[0].poisson);
}

std::unique_ptr<LayeredSubstrate> LayeredSubstrate::Create(
    const std::vector<ElasticLayer>& layers, const LayeredBase& base,
    InterfaceSide side, std::string* error) {
  auto fail = [&](const std::string& msg) {
    if (error) *error = msg;
    return std::unique_ptr<LayeredSubstrate>();
  };
  auto bad_nu = [](double nu) { return !(nu > -1.0 && nu <= 0.5); };
  if (layers.empty()) return fail("layers: at least one layer is required");
  if (layers.size() > 64) return fail("layers: at most 64 layers");
  for (size_t i = 0; i < layers.size(); ++i) {
    const ElasticLayer& l = layers[i];
    const double i1 = static_cast<double>(i);
    if (!(l.thickness_m > 0) || !std::isfinite(l.thickness_m))
      return fail(Fmt("layer %g thickness: must be > 0 m (got %g)", i1,
                      l.thickness_m));
    if (!(l.young_pa > 0) || !std::isfinite(l.young_pa))
      return fail(Fmt("layer %g young: must be > 0 Pa (got %g)", i1,
                      l.young_pa));
    if (bad_nu(l.poisson))
      return fail(Fmt("layer %g poisson: must be in (-1, 0.5] (got %g)", i1,
                      l.poisson));
  }
  if (!base.rigid) {
    if (!(base.young_pa > 0) || !std::isfinite(base.young_pa))
      return fail(Fmt("base young: must be > 0 Pa (got %g)", base.young_pa));
    if (bad_nu(base.poisson))
      return fail(Fmt("base poisson: must be in (-1, 0.5] (got %g)",
                      base.poisson));
  }
  if (side != InterfaceSide::kUpper && side != InterfaceSide::kLower)
    return fail("interface side: must be upper or lower");
  if (error) error->clear();
  return std::unique_ptr<LayeredSubstrate>(
      new LayeredSubstrate(layers, base, side));
}

std::vector<ElasticLayer> LayeredSubstrate::ShaoFingertipLayers() {
  return {{0.7e-3, 80e3, 0.48}, {0.8e-3, 50e3, 0.48}, {2.5e-3, 24e3, 0.4}};
}

LayeredBase LayeredSubstrate::ShaoFingertipBase() { return LayeredBase{}; }

std::string LayeredSubstrate::Describe() const {
  std::string s = "layered:";
  for (const ElasticLayer& l : layers_)
    s += Fmt(" [%.4g mm, E=%.4g kPa, nu=%.4g]", l.thickness_m * 1e3,
             l.young_pa * 1e-3, l.poisson);
  if (base_.rigid)
    s += Fmt(" over rigid base at %.4g mm", interfaces_m_.back() * 1e3);
  else
    s += Fmt(" over half-space E=%.4g kPa nu=%.4g", base_.young_pa * 1e-3,
             base_.poisson);
  s += side_ == InterfaceSide::kUpper ? "; interfaces: upper side"
                                      : "; interfaces: lower side";
  return s;
}

// ---------------------------------------------------------------------------
// Depth bookkeeping.

int LayeredSubstrate::Locate(double z, InterfaceSide side,
                             double* local) const {
  const int M = static_cast<int>(layers_.size());
  const double tol = 1e-9 * interfaces_m_.back();
  if (!(z > 0) || !std::isfinite(z)) return -1;
  double top = 0;
  for (int j = 0; j < M; ++j) {
    const double bot = interfaces_m_[j];
    if (std::abs(z - bot) <= tol) {
      if (side == InterfaceSide::kUpper) {
        *local = layers_[j].thickness_m;
        return j;
      }
      *local = 0;
      if (j + 1 == M && base_.rigid) return -1;
      return j + 1;
    }
    if (z < bot) {
      *local = z - top;
      return j;
    }
    top = bot;
  }
  if (base_.rigid) return -1;
  *local = z - interfaces_m_.back();
  return M;
}

std::string LayeredSubstrate::CheckDepth(double z, InterfaceSide side) const {
  double local;
  if (!(z > 0) || !std::isfinite(z))
    return Fmt("receptor depth must be > 0 m (got %g)", z);
  if (Locate(z, side, &local) < 0)
    return Fmt("receptor depth %g m is at or inside the rigid base (%g m)", z,
               interfaces_m_.back());
  return "";
}

Material LayeredSubstrate::MaterialAt(double z, bool upper_side) const {
  double local;
  const int j = Locate(z, upper_side ? InterfaceSide::kUpper
                                     : InterfaceSide::kLower, &local);
  if (j < 0) {
    if (z <= 0 && !layers_.empty())
      return {layers_[0].young_pa, layers_[0].poisson};
    return {0, 0};
  }
  if (j == static_cast<int>(layers_.size()))
    return {base_.young_pa, base_.poisson};
  return {layers_[j].young_pa, layers_[j].poisson};
}

// ---------------------------------------------------------------------------
// Per-k solve.

void LayeredSubstrate::Solve(double k, Solution* sol) const {
  const int M = static_cast<int>(layers_.size());
  const bool hs = !base_.rigid;
  const int n = 4 * M + (hs ? 2 : 0);
  const int na = 2 * M + (hs ? 1 : 0);
  const double mu_ref = mu_pa_[0];
  sol->A.assign(static_cast<size_t>(n) * n, 0.0);
  sol->inplane.assign(static_cast<size_t>(n) * 2, 0.0);
  sol->Aa.assign(static_cast<size_t>(na) * na, 0.0);
  sol->antiplane.assign(na, 0.0);
  double* A = sol->A.data();
  double* B = sol->inplane.data();
  double* Aa = sol->Aa.data();
  double* Ba = sol->antiplane.data();
  double bt[4][kNumComp], bb[4][kNumComp], at[2][3], ab[2][3];

  // Surface: s_zz = -p, s_xiz^ = q (columns: pressure, shear); s_etaz = -1.
  {
    const ElasticLayer& l = layers_[0];
    InplaneBasis(l.poisson, 1.0, k, 0.0, l.thickness_m, bt);
    for (int c = 0; c < 4; ++c) {
      A[0 * n + c] = bt[c][kCSzz];
      A[1 * n + c] = bt[c][kCSxz];
    }
    B[0 * 2 + 0] = -1.0;
    B[1 * 2 + 1] = 1.0;
    AntiplaneBasis(1.0, k, 0.0, l.thickness_m, at);
    for (int c = 0; c < 2; ++c) Aa[c] = at[c][1];
    Ba[0] = -1.0;
  }
  // Welded interfaces and the bottom condition.
  const int comps[4] = {kCUx, kCUz, kCSzz, kCSxz};
  for (int j = 0; j < M; ++j) {
    const ElasticLayer& l = layers_[j];
    const double r = mu_ref / mu_pa_[j];
    InplaneBasis(l.poisson, r, k, l.thickness_m, l.thickness_m, bb);
    AntiplaneBasis(r, k, l.thickness_m, l.thickness_m, ab);
    const int row = 2 + 4 * j, rowa = 1 + 2 * j;
    if (j + 1 == M && !hs) {  // rigid: U_xi = U_z = 0, V = 0
      for (int c = 0; c < 4; ++c) {
        A[row * n + 4 * j + c] = bb[c][kCUx];
        A[(row + 1) * n + 4 * j + c] = bb[c][kCUz];
      }
      for (int c = 0; c < 2; ++c) Aa[rowa * na + 2 * j + c] = ab[c][0];
      break;
    }
    for (int q = 0; q < 4; ++q)
      for (int c = 0; c < 4; ++c)
        A[(row + q) * n + 4 * j + c] = bb[c][comps[q]];
    for (int q = 0; q < 2; ++q)
      for (int c = 0; c < 2; ++c) Aa[(rowa + q) * na + 2 * j + c] = ab[c][q];
    // Next layer (or the half-space base) at its top face.
    const bool next_is_base = (j + 1 == M);
    const double nu2 = next_is_base ? base_.poisson : layers_[j + 1].poisson;
    const double h2 = next_is_base ? -1.0 : layers_[j + 1].thickness_m;
    const double r2 = mu_ref / mu_pa_[j + 1];
    InplaneBasis(nu2, r2, k, 0.0, h2, bt);
    AntiplaneBasis(r2, k, 0.0, h2, at);
    if (next_is_base) {
      const int cols[2] = {0, 2};  // a, c
      for (int q = 0; q < 4; ++q)
        for (int c = 0; c < 2; ++c)
          A[(row + q) * n + 4 * M + c] = -bt[cols[c]][comps[q]];
      for (int q = 0; q < 2; ++q) Aa[(rowa + q) * na + 2 * M] = -at[0][q];
    } else {
      for (int q = 0; q < 4; ++q)
        for (int c = 0; c < 4; ++c)
          A[(row + q) * n + 4 * (j + 1) + c] = -bt[c][comps[q]];
      for (int q = 0; q < 2; ++q)
        for (int c = 0; c < 2; ++c)
          Aa[(rowa + q) * na + 2 * (j + 1) + c] = -at[c][q];
    }
  }
  SolveDense(n, 2, A, B);
  SolveDense(na, 1, Aa, Ba);
  // Surface U_z under unit pressure (layer 0 at zeta = 0, r = 1).
  InplaneBasis(layers_[0].poisson, 1.0, k, 0.0, layers_[0].thickness_m, bt);
  double uz = 0;
  for (int c = 0; c < 4; ++c) uz += B[c * 2 + 0] * bt[c][kCUz];
  sol->surface_uz = uz;
}

LayerTransfer LayeredSubstrate::Evaluate(const Solution& sol, double k,
                                         int layer, double local) const {
  const int M = static_cast<int>(layers_.size());
  const bool in_base = (layer == M);
  const double nu = in_base ? base_.poisson : layers_[layer].poisson;
  const double h = in_base ? -1.0 : layers_[layer].thickness_m;
  double bt[4][kNumComp], at[2][3];
  InplaneBasis(nu, 1.0, k, local, h, bt);
  AntiplaneBasis(1.0, k, local, h, at);
  double coefP[4] = {0, 0, 0, 0}, coefQ[4] = {0, 0, 0, 0}, coefA[2] = {0, 0};
  if (in_base) {
    coefP[0] = sol.inplane[(4 * M) * 2 + 0];
    coefP[2] = sol.inplane[(4 * M + 1) * 2 + 0];
    coefQ[0] = sol.inplane[(4 * M) * 2 + 1];
    coefQ[2] = sol.inplane[(4 * M + 1) * 2 + 1];
    coefA[0] = sol.antiplane[2 * M];
  } else {
    for (int c = 0; c < 4; ++c) {
      coefP[c] = sol.inplane[(4 * layer + c) * 2 + 0];
      coefQ[c] = sol.inplane[(4 * layer + c) * 2 + 1];
    }
    for (int c = 0; c < 2; ++c) coefA[c] = sol.antiplane[2 * layer + c];
  }
  LayerTransfer t;
  for (int c = 0; c < 4; ++c) {
    t.p_xixi += coefP[c] * bt[c][kCSxx];
    t.p_etaeta += coefP[c] * bt[c][kCSyy];
    t.p_zz += coefP[c] * bt[c][kCSzz];
    t.p_xiz += coefP[c] * bt[c][kCSxz];
    t.q_xixi += coefQ[c] * bt[c][kCSxx];
    t.q_etaeta += coefQ[c] * bt[c][kCSyy];
    t.q_zz += coefQ[c] * bt[c][kCSzz];
    t.q_xiz += coefQ[c] * bt[c][kCSxz];
  }
  for (int c = 0; c < 2; ++c) {
    t.a_etaz += coefA[c] * at[c][1];
    t.a_xieta += coefA[c] * at[c][2];
  }
  return t;
}

LayerTransfer LayeredSubstrate::TransferAt(double k, double z,
                                           InterfaceSide side) const {
  double local;
  const int j = Locate(z, side, &local);
  LayerTransfer t;
  if (j < 0 || !(k >= 0)) {
    double* p = &t.p_xixi;
    for (int i = 0; i < kNumTransfer; ++i) p[i] = kNaN;
    return t;
  }
  Solution sol;
  Solve(k, &sol);
  return Evaluate(sol, k, j, local);
}

// Closed-form k -> 0 limit of the finite part of the compliance. Long waves
// see every layer as laterally strained like the base's surface
// (e0 = -(1 - 2 nu_b) / (2 mu_b) per unit pressure, 0 on bone) in plane strain
// under s_zz = -1; the layers' in-plane stress also loads the base with an
// O(k) shear, whose normal displacement (1 - 2 nu_b) S / (2 mu_b) is O(1).
double LayeredSubstrate::SurfaceCompliance(double k) const {
  if (k > 0) {
    Solution sol;
    Solve(k, &sol);
    return sol.surface_uz / (2 * mu_pa_[0] * k);
  }
  const bool hs = !base_.rigid;
  const double e0 = hs ? -(1 - 2 * base_.poisson) / (2 * mu_pa_.back()) : 0;
  double S = 0, uz = 0;
  for (const ElasticLayer& l : layers_) {
    const double E = l.young_pa, nu = l.poisson;
    const double sxx = E * e0 / (1 - nu * nu) - nu / (1 - nu);
    const double ezz = ((1 - nu * nu) * -1.0 - nu * (1 + nu) * sxx) / E;
    uz -= l.thickness_m * ezz;
    S += l.thickness_m * sxx;
  }
  if (hs) uz += (1 - 2 * base_.poisson) * S / (2 * mu_pa_.back());
  return uz;
}

// ---------------------------------------------------------------------------
// Tabulation at one depth.

void LayeredSubstrate::TabulateTransfer(int layer, double local, double z,
                                        bool subtract, double k_lo,
                                        double k_hi, Tab* tab) const {
  tab->Init(kNumTransfer, k_lo, k_hi);
  Solution sol;
  const double nu0 = layers_[0].poisson;
  double t[kNumTransfer], h[kNumTransfer];
  for (int i = -1; i < kTablePoints; ++i) {
    const double k = i < 0 ? 0.0 : tab->KAt(i);
    Solve(k, &sol);
    ToArray(Evaluate(sol, k, layer, local), t);
    if (subtract) {
      HalfSpaceTransfer(k, z, nu0, h);
      for (int f = 0; f < kNumTransfer; ++f) t[f] -= h[f];
    }
    double* dst = i < 0 ? tab->v0.data()
                        : tab->v.data() + static_cast<size_t>(i) * kNumTransfer;
    for (int f = 0; f < kNumTransfer; ++f) dst[f] = t[f];
  }
}

// Decay length of what is transformed at this depth: in the top layer the
// half-space part is subtracted and the rest decays like exp(-k (2 h1 - z));
// deeper, the field decays like exp(-k z).
double LayeredSubstrate::DecayLength(int layer, double z) const {
  if (layer == 0) return 2 * layers_[0].thickness_m - z;
  return z;
}

double LayeredSubstrate::LowK(double z) const {
  return 1e-4 / std::max(interfaces_m_.back(), z);
}

// ---------------------------------------------------------------------------
// Radial (Hankel) route: point force or uniform disc.

namespace {

// The 11 radial integrals I_i = int_0^inf F_i(k) W(k) J_n(k r) k dk, with
// W = 1 (point force) or 2 pi R J1(k R) / k (unit traction on a disc).
enum {
  kIPzz = 0, kIPsum, kIPdif, kIPxz,   // pressure
  kIX1a, kIX1b, kIX1c, kIXzz, kIX3, kIXz0, kIXz2,  // shear x
  kNumRadial
};

// single: the table holds one function (compliance), integrated with J0
// into I[0].
template <typename TabT>
void RadialIntegrals(const TabT& tab, double r, double radius, double decay,
                     bool pressure, bool shear, double* I,
                     bool single = false) {
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
Stress6 RadialStress(const TabT& tab, SurfaceLoad load, double x, double y,
                     double radius, double decay) {
  double I[kNumRadial];
  if (load == kLoadShearY) {
    // +y solution at (x, y) = rotated +x solution at (y, -x).
    RadialIntegrals(tab, std::hypot(x, y), radius, decay, false, true, I);
    return RotateShearXToY(AssembleRadial(kLoadShearX, y, -x, I));
  }
  RadialIntegrals(tab, std::hypot(x, y), radius, decay,
                  load == kLoadPressure, load != kLoadPressure, I);
  return AssembleRadial(load, x, y, I);
}

}  // namespace

Stress6 LayeredSubstrate::PointStress(SurfaceLoad load, double x, double y,
                                      double z, InterfaceSide side) const {
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

Stress6 LayeredSubstrate::DiscStress(SurfaceLoad load, double x, double y,
                                     double z, double radius,
                                     InterfaceSide side) const {
  double local;
  const int j = Locate(z, side, &local);
  if (j < 0 || !(radius > 0)) return NaNStress();
  Tab tab;
  TabulateTransfer(j, local, z, false, LowK(z), kDecayCut / z, &tab);
  return RadialStress(tab, load, x, y, radius, z);
}

Stress6 LayeredSubstrate::CellStress(SurfaceLoad load, double x, double y,
                                     double z, double h) const {
  return CellStress(load, x, y, z, h, side_);
}

Stress6 LayeredSubstrate::CellStress(SurfaceLoad load, double x, double y,
                                     double z, double h,
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
  static constexpr double kG3X[3] = {-0.7745966692414834, 0.0,
                                     0.7745966692414834};
  static constexpr double kG3W[3] = {0.5555555555555556, 0.8888888888888888,
                                     0.5555555555555556};
  if (h <= 0.1 * scale) {
    const bool two = h <= scale / 30;
    const int np = two ? 2 : 3;
    const double* gx = two ? kG2X : kG3X;
    const double* gw = two ? kG2W : kG3W;
    for (int a = 0; a < np; ++a)
      for (int b = 0; b < np; ++b)
        fn(x - 0.5 * h * gx[a], y - 0.5 * h * gx[b],
           0.25 * h * h * gw[a] * gw[b]);
    return;
  }
  const int m =
      std::clamp(static_cast<int>(std::ceil(4.0 * h / scale)), 1, 64);
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
                                    const std::array<bool, kNumStress>& want,
                                    InterfaceSide side,
                                    std::vector<float>* table) const {
  const int L = 2 * n - 1;
  table->assign(static_cast<size_t>(kNumLoads) * kNumStress * L * L, 0.0f);
  double local;
  const int j = Locate(z, side, &local);
  if (j < 0 || !(h > 0) || n < 1) {
    std::fill(table->begin(), table->end(),
              std::numeric_limits<float>::quiet_NaN());
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
      const double scale = subtract ? std::max(a, 0.5 * dlat)
                                    : std::hypot(dlat, z);
      Stress6 acc[kNumLoads] = {};
      CellQuadrature(x, y, h, scale, [&](double px, double py, double w) {
        rt.At(std::hypot(px, py), I);
        const Stress6 sp = AssembleRadial(kLoadPressure, px, py, I);
        const Stress6 sx = AssembleRadial(kLoadShearX, px, py, I);
        const Stress6 sy =
            RotateShearXToY(AssembleRadial(kLoadShearX, py, -px, I));
        for (int c = 0; c < kNumStress; ++c) {
          acc[0][c] += w * sp[c];
          acc[1][c] += w * sx[c];
          acc[2][c] += w * sy[c];
        }
      });
      if (subtract) {
        for (int load = 0; load < kNumLoads; ++load) {
          const Stress6 hsv = top_halfspace_->CellStress(
              static_cast<SurfaceLoad>(load), x, y, z, h);
          for (int c = 0; c < kNumStress; ++c) acc[load][c] += hsv[c];
        }
      }
      for (int load = 0; load < kNumLoads; ++load)
        quarter[(static_cast<size_t>(dy) * n + dx) * kNumLoads + load] =
            acc[load];
    }
  }
  // Scatter with parity; table index (di, dj) = (-X, -Y) for receptor offset
  // (X, Y) cells from the source.
  for (int load = 0; load < kNumLoads; ++load)
    for (int comp = 0; comp < kNumStress; ++comp) {
      if (!want[comp]) continue;
      const bool ox = kOddX[load][comp], oy = kOddY[load][comp];
      float* out = table->data() +
                   static_cast<size_t>(load * kNumStress + comp) * L * L;
      for (int dj = -(n - 1); dj <= n - 1; ++dj)
        for (int di = -(n - 1); di <= n - 1; ++di) {
          const int X = -di, Y = -dj;
          double v = quarter[(static_cast<size_t>(std::abs(Y)) * n +
                              std::abs(X)) * kNumLoads + load][comp];
          if (X < 0 && ox) v = -v;
          if (Y < 0 && oy) v = -v;
          out[static_cast<size_t>(dj + n - 1) * L + (di + n - 1)] =
              static_cast<float>(v);
        }
    }
}

// ---------------------------------------------------------------------------
// Surface compliance lattice.

void LayeredSubstrate::SurfaceComplianceTable(double h, int n,
                                              std::vector<float>* table) const {
  const int L = 2 * n - 1;
  table->assign(static_cast<size_t>(L) * L, 0.0f);
  if (!(h > 0) || n < 1) {
    std::fill(table->begin(), table->end(),
              std::numeric_limits<float>::quiet_NaN());
    return;
  }
  // Reference with the singular parts in closed form (real space):
  // C_ref(k) = [C1 (1 - exp(-k b)) + Cb exp(-k b)] / k, the top layer's
  // half-space at large k and the base's (0 on bone) at small k;
  // 1/k <-> 1/(2 pi r), exp(-k b)/k <-> 1/(2 pi sqrt(r^2 + b^2)). The rest
  // decays like exp(-2 k h1) and goes through the radial route.
  const ElasticLayer& top = layers_[0];
  const double C1 = 2 * (1 - top.poisson * top.poisson) / top.young_pa;
  const double Cb =
      base_.rigid ? 0.0
                  : 2 * (1 - base_.poisson * base_.poisson) / base_.young_pa;
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
      const double dlat = std::hypot(std::max(0.0, x - 0.5 * h),
                                     std::max(0.0, y - 0.5 * h));
      double acc = 0;
      CellQuadrature(x, y, h, std::max(a, 0.5 * dlat),
                     [&](double px, double py, double w) {
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
          static_cast<float>(
              quarter[static_cast<size_t>(std::abs(dj)) * n + std::abs(di)]);
}

// ---------------------------------------------------------------------------
// Strain and strain energy density.

Stress6 StrainFromStress(const Stress6& s, const Material& m) {
  const double E = m.young_pa, nu = m.poisson;
  const double tr = s[kSxx] + s[kSyy] + s[kSzz];
  Stress6 e{};
  for (int c = 0; c < 3; ++c) e[c] = ((1 + nu) * s[c] - nu * tr) / E;
  for (int c = 3; c < kNumStress; ++c) e[c] = (1 + nu) * s[c] / E;
  return e;
}

double StrainEnergyDensity(const Stress6& s, const Material& m) {
  const double E = m.young_pa, nu = m.poisson;
  const double tr = s[kSxx] + s[kSyy] + s[kSzz];
  double ss = 0;
  for (int c = 0; c < 3; ++c) ss += s[c] * s[c];
  for (int c = 3; c < kNumStress; ++c) ss += 2 * s[c] * s[c];
  return ((1 + nu) * ss - nu * tr * tr) / (2 * E);
}

}  // namespace mjtouch
