// Same results on every architecture (tests/cpp, not run by pytest): prints
// hashes of the bits of (1) the Winkler fast solve on gaps with NaN, +-inf
// and +-0 (ScanCandidates' SSE2 / portable extrema; exits 1 if it differs
// from the reference solve) and (2) 120 pipeline steps (winkler, elastic) of
// a pad pressed into and slid over a plane, (3) ConvolveReal<float / double>
// on the shipped scenes' grids (fft.cc's fused and half-input stages). Two builds (x86-64 with AVX2
// clones, MJTOUCH_PORTABLE_SIMD, aarch64) must print the same lines:
//   bash .ci/portable --aarch64
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "common/fft.h"
#include "contact/pressure.h"
#include "pipeline/config.h"
#include "pipeline/model.h"
#include "pipeline/step.h"

using namespace mjtouch;

static uint64_t Fnv(uint64_t h, const void* p, size_t n) {
  const unsigned char* b = static_cast<const unsigned char*>(p);
  for (size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
  return h;
}

// Winkler fast solve vs reference on gaps with NaN, +-inf, +-0 (ScanCandidates'
// extrema): mismatches and a hash of the fast results and the scan's minimum.
static bool Adversarial() {
  uint64_t rng = 12345, h = 1469598103934665603ull;
  auto uni = [&] {
    rng = rng * 6364136223846793005ull + 1442695040888963407ull;
    return (rng >> 11) * (1.0 / 9007199254740992.0);
  };
  const double inf = std::numeric_limits<double>::infinity(), nan = std::nan("");
  int mismatch = 0, solves = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const int n = 3 + trial % 27;
    const TaxelGrid grid{n, 1e-4};
    std::vector<double> gap(n * n), cov(n * n);
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const double x = (i - (n - 1) / 2.0) * 1e-4, y = (j - (n - 1) / 2.0) * 1e-4;
        double g = (x * x + y * y) / 1e-2 + 2e-6 * (uni() - 0.5), u = uni();
        if (u < 0.05)
          g = inf;
        else if (u < 0.07 && trial % 2)
          g = -inf;
        else if (u < 0.10 && trial % 5 == 1)
          g = nan;
        else if (u < 0.15 && trial % 4 == 0)
          g = (u < 0.125) ? 0.0 : -0.0;
        double w = uni() < 0.2 ? uni() : 1.0;
        if (uni() < 0.1) w = 0.0;
        if (trial % 7 == 3 && uni() < 0.02) w = nan;
        gap[j * n + i] = g;
        cov[j * n + i] = w;
      }
    for (double guess : {nan, 1.0, -1e-6}) {
      TractionField a, b, scan;
      const bool oka = WinklerPressure(grid, gap, cov, CellBox::All(grid), 1e9, 0.3, guess, &a);
      const bool okb =
          WinklerPressureReference(grid, gap, cov, CellBox::All(grid), 1e9, 0.3, guess, &b);
      ++solves;
      mismatch += oka != okb || a.pressure_pa != b.pressure_pa ||
                  std::memcmp(&a.approach_m, &b.approach_m, sizeof(double)) != 0;
      h = Fnv(h, &oka, 1);
      h = Fnv(h, a.pressure_pa.data(), a.pressure_pa.size() * sizeof(double));
      h = Fnv(h, &a.approach_m, sizeof(double));
      const double m = ScanWinklerCandidates(grid, gap, cov, CellBox::All(grid), &scan);
      h = Fnv(h, &m, sizeof(m));
    }
  }
  std::printf("winkler fast vs reference (NaN/inf/+-0 gaps): %d/%d differ, hash %016llx\n",
              mismatch, solves, (unsigned long long)h);
  return mismatch == 0;
}

// ConvolveReal on 160 x 150, 180 x 150 and 160 x 160 (the scenes' grids:
// radix-6 / radix-9 fused stages, the half radix-4 + 8 stage), float and
// double, threads 1: a hash of the outputs' bits.
template <typename T>
static void FftHash() {
  uint64_t rng = 777, h = 1469598103934665603ull;
  auto uni = [&] {
    rng = rng * 6364136223846793005ull + 1442695040888963407ull;
    return (rng >> 11) * (1.0 / 9007199254740992.0);
  };
  const int grids[][2] = {{160, 150}, {180, 150}, {160, 160}};
  for (const auto& g : grids) {
    const Fft2D fft(g[0], g[1]);
    const int bx = g[0] / 2 - 1, by = g[1] / 2 - 1;
    std::vector<T> k_hat(fft.spectrum_size()), sre(k_hat.size()), sim(k_hat.size()), work;
    for (T& v : k_hat) v = static_cast<T>(uni());
    std::vector<double> in(static_cast<size_t>(bx) * by), out(in.size());
    for (double& v : in) v = uni();
    fft.ConvolveReal(in.data(), bx, by, bx, k_hat.data(), by, bx, out.data(), bx, sre.data(),
                     sim.data(), &work, 1);
    h = Fnv(h, out.data(), out.size() * sizeof(double));
  }
  std::printf("fft ConvolveReal<%s> 160x150 180x150 160x160: hash %016llx\n",
              sizeof(T) == 4 ? "float" : "double", (unsigned long long)h);
}

int main() {
  const bool ok = Adversarial();
  FftHash<float>();
  FftHash<double>();
  for (PressureModel pm : {PressureModel::kWinkler, PressureModel::kElastic}) {
    SkinConfig cfg;
    cfg.grid = TaxelGrid{48, 1e-4};
    cfg.pad.shape = PadShape::kSphere;
    cfg.pad.semi_axes_m[0] = cfg.pad.semi_axes_m[1] = cfg.pad.semi_axes_m[2] = 8e-3;
    cfg.pressure_model = pm;
    cfg.layered = false;
    cfg.oversample = 1;
    std::string err;
    if (!FinalizeSkinConfig(&cfg, &err)) {
      std::printf("finalize: %s\n", err.c_str());
      return 1;
    }
    auto model = SkinModel::Build(cfg, &err);
    if (!model) {
      std::printf("build: %s\n", err.c_str());
      return 1;
    }
    std::vector<double> state(model->state_size()), out(model->output_size());
    ResetState(*model, state.data());
    Workspace ws;
    StepInput in;
    in.timestep_s = 1e-3;
    CounterSurface plane;
    plane.type = CounterSurface::Type::kPlane;
    uint64_t h = 1469598103934665603ull;
    int spikes = 0;
    for (int t = 0; t < 120; ++t) {
      const double d = 3e-4 * (t < 60 ? t / 60.0 : 1.0);
      plane.pose.pos[0] = t < 60 ? 0.0 : 2e-5 * (t - 60);
      plane.pose.pos[2] = -8e-3 + d - 2e-5;
      in.surfaces = {plane};
      in.normal_force_n = d > 2e-5 ? 2e3 * (d - 2e-5) : 0.0;
      in.shear_x_n = t < 60 ? 0.0 : 0.2 * in.normal_force_n;
      in.in_contact = in.normal_force_n > 0;
      spikes += Step(*model, in, t * 1e-3, state.data(), &ws, out.data());
      h = Fnv(h, out.data(), out.size() * sizeof(double));
      h = Fnv(h, state.data(), state.size() * sizeof(double));
    }
    std::printf("%s: outputs %zu, spikes %d, hash %016llx\n", PressureModelName(pm), out.size(),
                spikes, (unsigned long long)h);
  }
  return ok ? 0 : 1;
}
