// LayeredSubstrate: construction, depth bookkeeping, the per-k solve of the
// layer stack, transfer functions and their log-k tabulation, strain. The
// real-space routes (Hankel transforms, lattice tables) are in
// layered_radial.cc.
#include "substrate/layered.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

#include "substrate/layered_internal.h"

namespace mjtouch {
using namespace layered_internal;

namespace {

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
void InplaneBasis(double nu, double r, double k, double zeta, double h, double out[4][kNumComp]) {
  const double t = k * zeta, e = std::exp(-t);
  double* a = out[0];
  a[kCSxx] = -e;
  a[kCSyy] = 0;
  a[kCSzz] = e;
  a[kCSxz] = -e;
  a[kCUx] = r * e;
  a[kCUz] = -r * e;
  double* c = out[2];
  c[kCSxx] = (2 * nu - t) * e;
  c[kCSyy] = 2 * nu * e;
  c[kCSzz] = (2 - 2 * nu + t) * e;
  c[kCSxz] = -(1 - 2 * nu + t) * e;
  c[kCUx] = r * t * e;
  c[kCUz] = -r * (3 - 4 * nu + t) * e;
  double* b = out[1];
  double* d = out[3];
  if (h < 0) {
    for (int i = 0; i < kNumComp; ++i) b[i] = d[i] = 0;
    return;
  }
  const double tp = k * (zeta - h), ep = std::exp(tp);  // tp <= 0
  b[kCSxx] = -ep;
  b[kCSyy] = 0;
  b[kCSzz] = ep;
  b[kCSxz] = ep;
  b[kCUx] = r * ep;
  b[kCUz] = r * ep;
  d[kCSxx] = -(2 * nu + tp) * ep;
  d[kCSyy] = -2 * nu * ep;
  d[kCSzz] = (tp - 2 + 2 * nu) * ep;
  d[kCSxz] = (tp - 1 + 2 * nu) * ep;
  d[kCUx] = r * tp * ep;
  d[kCUz] = r * (tp - 3 + 4 * nu) * ep;
}

// Antiplane basis: u_eta = (f e + g e') / (mu k). out[col][comp]: col f, g;
// comp V (= mu_ref k u_eta), s_etaz, s_xieta^ (= -i s_xieta).
void AntiplaneBasis(double r, double k, double zeta, double h, double out[2][3]) {
  const double e = std::exp(-k * zeta);
  out[0][0] = r * e;
  out[0][1] = -e;
  out[0][2] = e;
  if (h < 0) {
    out[1][0] = out[1][1] = out[1][2] = 0;
    return;
  }
  const double ep = std::exp(k * (zeta - h));
  out[1][0] = r * ep;
  out[1][1] = ep;
  out[1][2] = ep;
}

// Homogeneous half-space transfer functions (REFERENCE.md sec. 3).
void HalfSpaceTransfer(double k, double z, double nu, double* t) {
  const double kz = k * z, e = std::exp(-kz);
  t[kPxx] = -(1 - kz) * e;
  t[kPyy] = -2 * nu * e;
  t[kPzz] = -(1 + kz) * e;
  t[kPxz] = kz * e;
  t[kQxx] = (2 - kz) * e;
  t[kQyy] = 2 * nu * e;
  t[kQzz] = kz * e;
  t[kQxz] = (1 - kz) * e;
  t[kAyz] = -e;
  t[kAxy] = e;
}

void ToArray(const LayerTransfer& lt, double* t) {
  t[kPxx] = lt.p_xixi;
  t[kPyy] = lt.p_etaeta;
  t[kPzz] = lt.p_zz;
  t[kPxz] = lt.p_xiz;
  t[kQxx] = lt.q_xixi;
  t[kQyy] = lt.q_etaeta;
  t[kQzz] = lt.q_zz;
  t[kQxz] = lt.q_xiz;
  t[kAyz] = lt.a_etaz;
  t[kAxy] = lt.a_xieta;
}

std::string Fmt(const char* f, double a, double b = 0, double c = 0) {
  char buf[256];
  std::snprintf(buf, sizeof(buf), f, a, b, c);
  return buf;
}

}  // namespace

// ---------------------------------------------------------------------------
// Construction.

LayeredSubstrate::LayeredSubstrate(std::vector<ElasticLayer> layers, LayeredBase base,
                                   InterfaceSide side)
    : layers_(std::move(layers)), base_(base), side_(side) {
  double z = 0;
  for (const ElasticLayer& l : layers_) {
    z += l.thickness_m;
    interfaces_m_.push_back(z);
    mu_pa_.push_back(l.young_pa / (2 * (1 + l.poisson)));
  }
  mu_pa_.push_back(base_.rigid ? 0.0 : base_.young_pa / (2 * (1 + base_.poisson)));
  top_halfspace_ = std::make_unique<HalfSpace>(layers_[0].poisson);
}

std::unique_ptr<LayeredSubstrate> LayeredSubstrate::Create(const std::vector<ElasticLayer>& layers,
                                                           const LayeredBase& base,
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
      return fail(Fmt("layer %g thickness: must be > 0 m (got %g)", i1, l.thickness_m));
    if (!(l.young_pa > 0) || !std::isfinite(l.young_pa))
      return fail(Fmt("layer %g young: must be > 0 Pa (got %g)", i1, l.young_pa));
    if (bad_nu(l.poisson))
      return fail(Fmt("layer %g poisson: must be in (-1, 0.5] (got %g)", i1, l.poisson));
  }
  if (!base.rigid) {
    if (!(base.young_pa > 0) || !std::isfinite(base.young_pa))
      return fail(Fmt("base young: must be > 0 Pa (got %g)", base.young_pa));
    if (bad_nu(base.poisson))
      return fail(Fmt("base poisson: must be in (-1, 0.5] (got %g)", base.poisson));
  }
  if (side != InterfaceSide::kUpper && side != InterfaceSide::kLower)
    return fail("interface side: must be upper or lower");
  if (error) error->clear();
  return std::unique_ptr<LayeredSubstrate>(new LayeredSubstrate(layers, base, side));
}

std::vector<ElasticLayer> LayeredSubstrate::ShaoFingertipLayers() {
  return {{0.7e-3, 80e3, 0.48}, {0.8e-3, 50e3, 0.48}, {2.5e-3, 24e3, 0.4}};
}

LayeredBase LayeredSubstrate::ShaoFingertipBase() { return LayeredBase{}; }

std::string LayeredSubstrate::Describe() const {
  std::string s = "layered:";
  for (const ElasticLayer& l : layers_)
    s += Fmt(" [%.4g mm, E=%.4g kPa, nu=%.4g]", l.thickness_m * 1e3, l.young_pa * 1e-3, l.poisson);
  if (base_.rigid)
    s += Fmt(" over rigid base at %.4g mm", interfaces_m_.back() * 1e3);
  else
    s += Fmt(" over half-space E=%.4g kPa nu=%.4g", base_.young_pa * 1e-3, base_.poisson);
  s += side_ == InterfaceSide::kUpper ? "; interfaces: upper side" : "; interfaces: lower side";
  return s;
}

// ---------------------------------------------------------------------------
// Depth bookkeeping.

int LayeredSubstrate::Locate(double z, InterfaceSide side, double* local) const {
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
  if (!(z > 0) || !std::isfinite(z)) return Fmt("receptor depth must be > 0 m (got %g)", z);
  if (Locate(z, side, &local) < 0)
    return Fmt("receptor depth %g m is at or inside the rigid base (%g m)", z,
               interfaces_m_.back());
  return "";
}

Material LayeredSubstrate::MaterialAt(double z, bool upper_side) const {
  double local;
  const int j = Locate(z, upper_side ? InterfaceSide::kUpper : InterfaceSide::kLower, &local);
  if (j < 0) {
    if (z <= 0 && !layers_.empty()) return {layers_[0].young_pa, layers_[0].poisson};
    return {0, 0};
  }
  if (j == static_cast<int>(layers_.size())) return {base_.young_pa, base_.poisson};
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
      for (int c = 0; c < 4; ++c) A[(row + q) * n + 4 * j + c] = bb[c][comps[q]];
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
        for (int c = 0; c < 2; ++c) A[(row + q) * n + 4 * M + c] = -bt[cols[c]][comps[q]];
      for (int q = 0; q < 2; ++q) Aa[(rowa + q) * na + 2 * M] = -at[0][q];
    } else {
      for (int q = 0; q < 4; ++q)
        for (int c = 0; c < 4; ++c) A[(row + q) * n + 4 * (j + 1) + c] = -bt[c][comps[q]];
      for (int q = 0; q < 2; ++q)
        for (int c = 0; c < 2; ++c) Aa[(rowa + q) * na + 2 * (j + 1) + c] = -at[c][q];
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

LayerTransfer LayeredSubstrate::Evaluate(const Solution& sol, double k, int layer,
                                         double local) const {
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

LayerTransfer LayeredSubstrate::TransferAt(double k, double z, InterfaceSide side) const {
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

void LayeredSubstrate::TabulateTransfer(int layer, double local, double z, bool subtract,
                                        double k_lo, double k_hi, Tab* tab) const {
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
    double* dst = i < 0 ? tab->v0.data() : tab->v.data() + static_cast<size_t>(i) * kNumTransfer;
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

double LayeredSubstrate::LowK(double z) const { return 1e-4 / std::max(interfaces_m_.back(), z); }

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