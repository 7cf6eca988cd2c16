#include "stress/stress_field.h"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace mjtouch {
namespace {

// Cost model, one core (examples/bench_kernel.py measures both paths; these
// are its fitted constants on the reference machine, fixed here so that the
// path taken, and so the output bits, depend on the inputs only).
constexpr double kDirectSecondsPerMac = 0.17e-9;  // per site x load x comp x cell
constexpr double kFftSecondsPerPoint = 0.35e-9;   // per N^2 log2(N^2), one 2D transform
constexpr double kMulSecondsPerPoint = 2.5e-9;    // per N^2 x load, one output pair

int CountWanted(const std::array<bool, kNumStress>& w) {
  int c = 0;
  for (bool b : w) c += b;
  return c;
}

}  // namespace

const char* StressMethodName(StressMethod m) {
  switch (m) {
    case StressMethod::kDirect: return "direct";
    case StressMethod::kFft: return "fft";
    case StressMethod::kTree: return "tree";
    default: return "auto";
  }
}

bool ParseStressMethod(const std::string& s, StressMethod* m) {
  if (s == "tree") {
    *m = StressMethod::kTree;
    return true;
  }
  if (s == "auto") {
    *m = StressMethod::kAuto;
    return true;
  }
  if (s == "direct") {
    *m = StressMethod::kDirect;
    return true;
  }
  if (s == "fft") {
    *m = StressMethod::kFft;
    return true;
  }
  return false;
}

std::vector<std::array<bool, kNumStress>> WantedPerDepth(const KernelTables& kt,
                                                         const std::vector<StressSite>& sites) {
  std::vector<std::array<bool, kNumStress>> want(kt.depths_m.size());
  for (const StressSite& s : sites)
    for (int c = 0; c < kNumStress; ++c)
      want[s.depth_index][c] = want[s.depth_index][c] || (s.want[c] && kt.components[c]);
  return want;
}

double KernelSpectraBytes(const KernelTables& kt, const std::vector<StressSite>& sites) {
  const double N = NextFftSize(2 * kt.n - 1);
  double count = 0;
  for (const auto& w : WantedPerDepth(kt, sites)) count += kNumLoads * CountWanted(w);
  return count * 2.0 * sizeof(float) * N * (static_cast<int>(N) | 1);
}

std::shared_ptr<const KernelSpectra> BuildKernelSpectra(const KernelTables& kt,
                                                        const std::vector<StressSite>& sites) {
  const auto t0 = std::chrono::steady_clock::now();
  auto sp = std::make_shared<KernelSpectra>();
  const int n = kt.n, L = 2 * n - 1;
  const int N = NextFftSize(L);
  sp->n = n;
  sp->fft_n = N;
  sp->fft = std::make_unique<Fft2D>(N, N);
  sp->want = WantedPerDepth(kt, sites);
  const size_t S = sp->fft->spectrum_size();
  const size_t D = kt.depths_m.size();
  sp->re.assign(D, std::vector<std::vector<float>>(kNumLoads * kNumStress));
  sp->im.assign(D, std::vector<std::vector<float>>(kNumLoads * kNumStress));
  std::vector<double> g(static_cast<size_t>(N) * N), sre(S), sim(S), scratch;
  for (size_t d = 0; d < D; ++d)
    for (int load = 0; load < kNumLoads; ++load)
      for (int comp = 0; comp < kNumStress; ++comp) {
        if (!sp->want[d][comp]) continue;
        // Flipped table: g[m] = K[-m] (m = receptor - source), wrapped mod N,
        // so that stress = g (*) traction is a plain convolution.
        const float* K = kt.At(static_cast<int>(d), static_cast<SurfaceLoad>(load),
                               static_cast<StressComponent>(comp));
        std::fill(g.begin(), g.end(), 0.0);
        for (int dj = -(n - 1); dj <= n - 1; ++dj)
          for (int di = -(n - 1); di <= n - 1; ++di)
            g[static_cast<size_t>((N - dj) % N) * N + (N - di) % N] =
                K[static_cast<size_t>(dj + n - 1) * L + (di + n - 1)];
        sp->fft->Forward(g.data(), nullptr, N, N, N, sre.data(), sim.data(), &scratch);
        auto& r = sp->re[d][load * kNumStress + comp];
        auto& i = sp->im[d][load * kNumStress + comp];
        r.assign(sre.begin(), sre.end());
        i.assign(sim.begin(), sim.end());
      }
  sp->build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return sp;
}

StressCost EstimateStressCost(const KernelTables& kt, const std::vector<StressSite>& sites,
                              int active_cells, bool shear, bool folded, bool general) {
  StressCost c;
  const int loads = shear ? kNumLoads : 1;
  double macs = 0;
  for (const StressSite& s : sites) macs += CountWanted(s.want);
  c.direct_s = folded    ? EstimateFoldedSeconds(kt, sites, active_cells)
               : general ? 1.6 * EstimateFoldedSeconds(kt, sites, active_cells)
                         : kDirectSecondsPerMac * macs * loads * active_cells;
  const double N = NextFftSize(2 * kt.n - 1);
  const double points = N * N;
  int pairs = 0;
  for (const auto& w : WantedPerDepth(kt, sites)) pairs += (CountWanted(w) + 1) / 2;
  const int forward = shear ? 2 : 1;
  c.fft_s = kFftSecondsPerPoint * (forward + pairs) * points * std::log2(points) +
            kMulSecondsPerPoint * pairs * loads * points;
  return c;
}

void FindActiveRuns(int n, const float* p, const float* sx, const float* sy, ActiveRuns* runs) {
  runs->Clear();
  for (int j = 0; j < n; ++j) {
    int begin = -1;
    for (int i = 0; i <= n; ++i) {
      bool on = false;
      if (i < n) {
        const size_t k = static_cast<size_t>(j) * n + i;
        on = p[k] != 0.0f || (sx && sx[k] != 0.0f) || (sy && sy[k] != 0.0f);
      }
      if (on && begin < 0) begin = i;
      if (!on && begin >= 0) {
        runs->row.push_back(j);
        runs->begin.push_back(begin);
        runs->end.push_back(i);
        begin = -1;
      }
    }
  }
}

namespace {

// W[k] = sum_l K1_l[k] T_l[k] + i sum_l K2_l[k] T_l[k] (K2 absent: 0), one
// pass over the spectra (W written once).
template <int kLoads, bool kPair>
void PairProducts(const float* const* k1r, const float* const* k1i, const float* const* k2r,
                  const float* const* k2i, const double* const* tr, const double* const* ti,
                  size_t size, double* o_r, double* o_i) {
  for (size_t k = 0; k < size; ++k) {
    double ar = 0, ai = 0, br = 0, bi = 0;
    for (int l = 0; l < kLoads; ++l) {
      const double x = tr[l][k], y = ti[l][k];
      ar += k1r[l][k] * x - k1i[l][k] * y;
      ai += k1r[l][k] * y + k1i[l][k] * x;
      if (kPair) {
        br += k2r[l][k] * x - k2i[l][k] * y;
        bi += k2r[l][k] * y + k2i[l][k] * x;
      }
    }
    o_r[k] = ar - bi;
    o_i[k] = ai + br;
  }
}

void FftStresses(const KernelTables& kt, const KernelSpectra& sp,
                 const std::vector<StressSite>& sites, const float* p, const float* sx,
                 const float* sy, StressScratch* w, Stress6* out) {
  const int n = kt.n, N = sp.fft_n;
  const Fft2D& fft = *sp.fft;
  const size_t S = fft.spectrum_size();
  const int ls = fft.spectrum_stride();
  const bool shear = sx && sy;
  const size_t in_size = static_cast<size_t>(n) * n;
  w->in_re.resize(in_size);
  w->in_im.resize(in_size);
  for (auto& v : w->spec_re) v.resize(S);
  for (auto& v : w->spec_im) v.resize(S);
  w->out_re.resize(std::max(in_size, S));
  w->out_im.resize(std::max(in_size, S));
  // Forward: pressure + i shear_x in one complex transform, shear_y alone.
  std::copy(p, p + in_size, w->in_re.begin());
  if (shear) std::copy(sx, sx + in_size, w->in_im.begin());
  fft.Forward(w->in_re.data(), shear ? w->in_im.data() : nullptr, n, n, n, w->spec_re[0].data(),
              w->spec_im[0].data(), &w->fft);
  if (shear) {
    std::copy(sy, sy + in_size, w->in_re.begin());
    fft.Forward(w->in_re.data(), nullptr, n, n, n, w->spec_re[2].data(), w->spec_im[2].data(),
                &w->fft);
    // Split Z = P + i X (P, X spectra of real fields): P = (Z + conj Z(-k)) / 2,
    // X = (Z - conj Z(-k)) / (2 i).
    const double* zr = w->spec_re[0].data();
    const double* zi = w->spec_im[0].data();
    double* pr = w->out_re.data();
    double* pi = w->out_im.data();
    double* xr = w->spec_re[1].data();
    double* xi = w->spec_im[1].data();
    for (int kx = 0; kx < N; ++kx) {
      const size_t row = static_cast<size_t>(kx) * ls;
      const size_t mrow = static_cast<size_t>((N - kx) % N) * ls;
      for (int ky = 0; ky < N; ++ky) {
        const size_t k = row + ky, m = mrow + (N - ky) % N;
        const double ar = zr[k], ai = zi[k], cr = zr[m], ci = -zi[m];
        pr[k] = 0.5 * (ar + cr);
        pi[k] = 0.5 * (ai + ci);
        xr[k] = 0.5 * (ai - ci);
        xi[k] = -0.5 * (ar - cr);
      }
    }
    std::swap(w->spec_re[0], w->out_re);
    std::swap(w->spec_im[0], w->out_im);
    w->out_re.resize(std::max(in_size, S));
    w->out_im.resize(std::max(in_size, S));
  }
  const int loads = shear ? kNumLoads : 1;
  const double scale = 1.0 / (static_cast<double>(N) * N);
  for (size_t d = 0; d < sp.want.size(); ++d) {
    int comps[kNumStress], nc = 0;
    for (int c = 0; c < kNumStress; ++c)
      if (sp.want[d][c]) comps[nc++] = c;
    int rows = 0, cols = 0;
    bool any = false;
    for (const StressSite& s : sites)
      if (s.depth_index == static_cast<int>(d)) {
        rows = std::max(rows, s.j + 1);
        cols = std::max(cols, s.i + 1);
        any = true;
      }
    if (!any) continue;
    for (int a = 0; a < nc; a += 2) {
      const int c1 = comps[a], c2 = a + 1 < nc ? comps[a + 1] : -1;
      // W = sum_l K(l, c1) T_l + i sum_l K(l, c2) T_l, then one inverse.
      std::vector<double>& Wr = w->out_re;
      std::vector<double>& Wi = w->out_im;
      const float *k1r[kNumLoads], *k1i[kNumLoads], *k2r[kNumLoads], *k2i[kNumLoads];
      const double *tr[kNumLoads], *ti[kNumLoads];
      for (int l = 0; l < loads; ++l) {
        tr[l] = w->spec_re[l].data();
        ti[l] = w->spec_im[l].data();
        k1r[l] = sp.re[d][l * kNumStress + c1].data();
        k1i[l] = sp.im[d][l * kNumStress + c1].data();
        k2r[l] = c2 >= 0 ? sp.re[d][l * kNumStress + c2].data() : nullptr;
        k2i[l] = c2 >= 0 ? sp.im[d][l * kNumStress + c2].data() : nullptr;
      }
      if (shear) {
        if (c2 >= 0)
          PairProducts<kNumLoads, true>(k1r, k1i, k2r, k2i, tr, ti, S, Wr.data(), Wi.data());
        else
          PairProducts<kNumLoads, false>(k1r, k1i, k2r, k2i, tr, ti, S, Wr.data(), Wi.data());
      } else {
        if (c2 >= 0)
          PairProducts<1, true>(k1r, k1i, k2r, k2i, tr, ti, S, Wr.data(), Wi.data());
        else
          PairProducts<1, false>(k1r, k1i, k2r, k2i, tr, ti, S, Wr.data(), Wi.data());
      }
      fft.Inverse(Wr.data(), Wi.data(), rows, cols, w->in_re.data(), w->in_im.data(), n, &w->fft);
      for (size_t s = 0; s < sites.size(); ++s) {
        const StressSite& site = sites[s];
        if (site.depth_index != static_cast<int>(d)) continue;
        const size_t k = static_cast<size_t>(site.j) * n + site.i;
        if (site.want[c1]) out[s][c1] = scale * w->in_re[k];
        if (c2 >= 0 && site.want[c2]) out[s][c2] = scale * w->in_im[k];
      }
    }
  }
}

}  // namespace

StressMethod ResolveStressMethod(const KernelTables& kt, const KernelSpectra* spectra,
                                 const StressTree* tree, StressMethod method,
                                 const std::vector<StressSite>& sites, int active_cells, bool shear,
                                 const StressOptions& opt) {
  if (method == StressMethod::kTree) {
    if (tree) return method;
    method = StressMethod::kAuto;
  }
  if (method == StressMethod::kAuto) {
    if (!spectra) return StressMethod::kDirect;
    const StressCost c =
        EstimateStressCost(kt, sites, active_cells, shear, UsesFoldedPath(kt, shear, opt),
                           UsesGeneralFoldedPath(kt, shear, opt));
    return c.fft_s < c.direct_s ? StressMethod::kFft : StressMethod::kDirect;
  }
  if (method == StressMethod::kFft && !spectra) return StressMethod::kDirect;
  return method;
}

StressMethod ComputeStresses(const KernelTables& kt, const KernelSpectra* spectra,
                             const StressTree* tree, StressMethod method,
                             const std::vector<StressSite>& sites, const ActiveRuns& runs,
                             const float* pressure, const float* shear_x, const float* shear_y,
                             StressScratch* scratch, Stress6* out, const StressOptions& opt) {
  const bool shear = shear_x && shear_y;
  const bool folded = UsesFoldedPath(kt, shear, opt);
  method = ResolveStressMethod(kt, spectra, tree, method, sites, runs.Count(), shear, opt);
  if (method == StressMethod::kTree) {
    tree->Compute(runs, pressure, shear ? shear_x : nullptr, shear ? shear_y : nullptr,
                  &scratch->tree, out);
    return method;
  }
  if (method == StressMethod::kFft) {
    for (size_t s = 0; s < sites.size(); ++s) out[s].fill(0.0);
    FftStresses(kt, *spectra, sites, pressure, shear ? shear_x : nullptr, shear ? shear_y : nullptr,
                scratch, out);
    return method;
  }
  scratch->fold.fold_legacy = opt.fold_legacy;
  if (folded)
    FoldedDirectStresses(kt, sites, runs, pressure, shear, opt.slip_x, opt.slip_y, opt.threads,
                         &scratch->fold, out);
  else if (UsesGeneralFoldedPath(kt, shear, opt))
    FoldedSplitStresses(kt, sites, runs, pressure, shear_x, shear_y, opt.slip_x, opt.slip_y,
                        opt.threads, &scratch->fold, out);
  else
    ReferenceDirectStresses(kt, sites, runs, pressure, shear ? shear_x : nullptr,
                            shear ? shear_y : nullptr, opt.threads, out);
  return method;
}

}  // namespace mjtouch
