// Internals shared by layered.cc (per-k solve, tabulated transfer functions)
// and layered_radial.cc (Hankel transforms, lattice tables): the per-k
// solution and the log-k table of transfer functions. Not a public header.
#ifndef MJTOUCH_SUBSTRATE_LAYERED_INTERNAL_H_
#define MJTOUCH_SUBSTRATE_LAYERED_INTERNAL_H_

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "substrate/layered.h"

namespace mjtouch {
namespace layered_internal {

constexpr double kPi = 3.14159265358979323846;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Transfer-function slots in a table row (LayerTransfer order).
enum { kPxx = 0, kPyy, kPzz, kPxz, kQxx, kQyy, kQzz, kQxz, kAyz, kAxy, kNumTransfer };

// Tabulation: points per table, and where a decaying function is dropped
// (exp(-50) times the polynomial growth of a few layers is below 1e-16).
constexpr int kTablePoints = 1024;
constexpr double kDecayCut = 50.0;

}  // namespace layered_internal

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
    i = std::clamp(i, 0, layered_internal::kTablePoints - 4);
    const double s = u - i;  // in [0, 3] for interior points
    const double w0 = -(s - 1) * (s - 2) * (s - 3) / 6.0;
    const double w1 = s * (s - 2) * (s - 3) / 2.0;
    const double w2 = -s * (s - 1) * (s - 3) / 2.0;
    const double w3 = s * (s - 1) * (s - 2) / 6.0;
    const double* p = v.data() + static_cast<size_t>(i) * nf;
    for (int f = 0; f < nf; ++f)
      out[f] = w0 * p[f] + w1 * p[nf + f] + w2 * p[2 * nf + f] + w3 * p[3 * nf + f];
  }
  double KAt(int i) const { return k_lo * std::exp(i / inv_du); }
  void Init(int nfunc, double lo, double hi) {
    nf = nfunc;
    k_lo = lo;
    k_hi = hi;
    inv_du = (layered_internal::kTablePoints - 1) / std::log(hi / lo);
    v.assign(static_cast<size_t>(layered_internal::kTablePoints) * nf, 0.0);
    v0.assign(nf, 0.0);
  }
};

}  // namespace mjtouch

#endif  // MJTOUCH_SUBSTRATE_LAYERED_INTERNAL_H_
