// Standalone checks of the layered kernel (plugin/core/layered.*).
// Build and run (about 10-20 s on one core):
//   g++ -O2 -std=c++17 -Iplugin/core plugin/core/kernel.cc \
//       plugin/core/layered.cc tests/cpp/test_layered.cc -o /tmp/test_layered
//   /tmp/test_layered            # PASS/FAIL lines, exit status 1 on failure
//   /tmp/test_layered --dump F   # also writes disc/transfer values as JSON
//                                # for tests/layered_oracle.py to compare
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "kernel.h"
#include "layered.h"

using namespace mjtouch;

namespace {

int g_failures = 0;

void Report(bool ok, const char* name, const std::string& detail) {
  std::printf("%s %s: %s\n", ok ? "PASS" : "FAIL", name, detail.c_str());
  if (!ok) ++g_failures;
}

std::string F(const char* fmt, double a = 0, double b = 0, double c = 0,
              double d = 0) {
  char buf[512];
  std::snprintf(buf, sizeof(buf), fmt, a, b, c, d);
  return buf;
}

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0)
      .count();
}

std::unique_ptr<LayeredSubstrate> Make(const std::vector<ElasticLayer>& layers,
                                       const LayeredBase& base) {
  std::string err;
  auto s = LayeredSubstrate::Create(layers, base, InterfaceSide::kUpper, &err);
  if (!s) {
    std::printf("FAIL create: %s\n", err.c_str());
    ++g_failures;
  }
  return s;
}

const std::array<bool, kNumStress> kAll = {true, true, true, true, true, true};

float TableAt(const std::vector<float>& t, int n, int load, int comp, int di,
              int dj) {
  const int L = 2 * n - 1;
  return t[(static_cast<size_t>(load * kNumStress + comp) * L + (dj + n - 1)) *
               L + (di + n - 1)];
}

// Max |a - b| over a lattice table, relative to max |b| per field, and the
// worst entry-wise relative error among entries with |b| > 1e-3 max |b|.
struct TableErr {
  double norm_rel = 0, entry_rel = 0;
};
TableErr CompareTables(const std::vector<float>& a, const std::vector<float>& b,
                       int n) {
  const int L = 2 * n - 1;
  TableErr e;
  for (int f = 0; f < kNumLoads * kNumStress; ++f) {
    double bmax = 0;
    for (int i = 0; i < L * L; ++i)
      bmax = std::max(bmax, std::abs(double(b[f * L * L + i])));
    if (bmax == 0) continue;
    for (int i = 0; i < L * L; ++i) {
      const double d = std::abs(double(a[f * L * L + i]) - b[f * L * L + i]);
      e.norm_rel = std::max(e.norm_rel, d / bmax);
      if (std::abs(b[f * L * L + i]) > 1e-3 * bmax)
        e.entry_rel = std::max(e.entry_rel, d / std::abs(b[f * L * L + i]));
    }
  }
  return e;
}

// ---------------------------------------------------------------------------

// Transfer functions of identical layers equal the half-space's closed form,
// at k h up to 1e4 and nu = 0.5 (no overflow, no cancellation).
void TestTransferIdentical() {
  double worst = 0;
  bool finite = true;
  for (double nu : {0.3, 0.48, 0.5}) {
    const double E = 50e3;
    auto s = Make({{0.1e-3, E, nu}, {0.6e-3, E, nu}, {20e-3, E, nu}},
                  LayeredBase{false, E, nu});
    for (double z : {0.05e-3, 0.1e-3, 0.3e-3, 0.7e-3, 2e-3, 25e-3}) {
      for (double kh : {0.0, 1e-6, 1e-2, 1.0, 10.0, 100.0, 1e3, 1e4}) {
        const double k = kh / 1e-3;  // k h with h = 1 mm
        for (InterfaceSide side : {InterfaceSide::kUpper, InterfaceSide::kLower}) {
          const LayerTransfer t = s->TransferAt(k, z, side);
          const double kz = k * z, e = std::exp(-kz);
          const double ref[10] = {-(1 - kz) * e, -2 * nu * e, -(1 + kz) * e,
                                  kz * e,        (2 - kz) * e, 2 * nu * e,
                                  kz * e,        (1 - kz) * e, -e, e};
          const double* got = &t.p_xixi;
          for (int i = 0; i < 10; ++i) {
            if (!std::isfinite(got[i])) finite = false;
            // Error relative to the load (1) scaled by the decay at depth.
            worst = std::max(worst, std::abs(got[i] - ref[i]) /
                                        std::max(e * (1 + kz), 1e-300));
          }
        }
      }
    }
  }
  Report(finite && worst < 1e-10, "transfer identical layers = half-space",
         F("max rel err %.2e over nu {0.3,0.48,0.5}, k h in [0, 1e4]", worst));
}

// Thickness up to 20 mm and z up to 25 mm, k h = 1e4 -> k z ~ 2.5e5: the
// compliance of a very thick layer tends to 2 (1 - nu^2) / (E k).
void TestLargeKh() {
  double worst = 0;
  for (double nu : {0.3, 0.48, 0.5}) {
    for (bool rigid : {true, false}) {
      const double E = 80e3, h = 0.7e-3;
      auto s = Make({{h, E, nu}, {0.8e-3, 20e3, 0.45}},
                    LayeredBase{rigid, 30e3, 0.4});
      for (double kh : {1e2, 1e3, 1e4}) {
        const double k = kh / h;
        const double c = s->SurfaceCompliance(k);
        const double ref = 2 * (1 - nu * nu) / (E * k);
        worst = std::max(worst, std::abs(c / ref - 1));
        const LayerTransfer t = s->TransferAt(k, 0.3e-3, InterfaceSide::kUpper);
        const double* p = &t.p_xixi;
        for (int i = 0; i < 10; ++i)
          if (!std::isfinite(p[i])) worst = 1;
      }
    }
  }
  Report(worst < 1e-10, "k h -> inf: compliance = 2(1-nu^2)/(E k)",
         F("max rel err %.2e at k h = 1e2..1e4", worst));
}

// One layer bonded to a rigid base: Fourier compliance in closed form
// (e.g. Carbone & Mangialardi 2008; Johnson 1985 for nu = 0.5):
// C = 2(1-nu^2)/(E k) [(3-4nu) sinh 2kh - 2kh] /
//     [(3-4nu) cosh 2kh + 2 (kh)^2 + 5 - 12 nu + 8 nu^2],
// C(0) = h (1+nu)(1-2nu) / (E (1-nu)).
void TestRigidLayerCompliance() {
  double worst = 0;
  for (double nu : {0.0, 0.3, 0.48, 0.5}) {
    const double E = 50e3, h = 1.5e-3;
    auto s = Make({{h, E, nu}}, LayeredBase{});
    for (double kh : {0.0, 1e-5, 1e-3, 0.1, 0.5, 1.0, 2.0, 5.0, 15.0, 40.0}) {
      const double k = kh / h;
      double ref;
      if (kh == 0) {
        ref = h * (1 + nu) * (1 - 2 * nu) / (E * (1 - nu));
      } else {
        const double k3 = 3 - 4 * nu;
        // Divide numerator and denominator by cosh(2kh) to stay finite.
        const double th = std::tanh(2 * kh), sech = 1 / std::cosh(2 * kh);
        ref = 2 * (1 - nu * nu) / (E * k) * (k3 * th - 2 * kh * sech) /
              (k3 + (2 * kh * kh + 5 - 12 * nu + 8 * nu * nu) * sech);
      }
      const double c = s->SurfaceCompliance(k);
      const double scale = std::max(std::abs(ref), 1e-9 * h / E);
      if (std::abs(c - ref) / scale > 1e-8)
        std::printf("  nu %g kh %g: %.12g vs %.12g\n", nu, kh, c, ref);
      worst = std::max(worst, std::abs(c - ref) / scale);
    }
  }
  Report(worst < 1e-8, "layer on rigid base: closed-form compliance",
         F("max rel err %.2e (nu 0..0.5, k h 0..40)", worst));
}

// The analytic k -> 0 finite part of the compliance matches the solver at
// small k, for layered stacks over a half-space and over bone.
void TestComplianceLimit() {
  double worst = 0;
  for (bool rigid : {true, false}) {
    auto s = Make({{0.7e-3, 80e3, 0.48}, {0.8e-3, 50e3, 0.48}, {1e-3, 24e3, 0.4}},
                  LayeredBase{rigid, 10e3, 0.45});
    const double C0 = s->SurfaceCompliance(0.0);
    const double Cb = rigid ? 0 : 2 * (1 - 0.45 * 0.45) / 10e3;
    for (double k : {1e-3, 1e-2, 1e-1}) {
      const double c = s->SurfaceCompliance(k) - Cb / k;
      worst = std::max(worst, std::abs(c - C0) / std::abs(C0) / (k * 3e-3) );
    }
  }
  // The difference is O(k H): report it per unit k H.
  Report(worst < 10, "k -> 0 compliance limit (closed form) = solver",
         F("|C(k) - C0| / |C0| <= %.2f k H", worst));
}

// Identical layers reproduce HalfSpace::CellStress on the whole lattice.
void TestLatticeIdentical() {
  for (double nu : {0.3, 0.48, 0.5}) {
    const double E = 50e3, h = 0.1e-3;
    const int n = 32;
    auto s = Make({{0.3e-3, E, nu}, {0.6e-3, E, nu}, {1.1e-3, E, nu}},
                  LayeredBase{false, E, nu});
    HalfSpace hs(nu);
    for (double z : {0.05e-3, 0.3e-3, 0.6e-3, 1.2e-3, 2e-3, 3e-3}) {
      std::vector<float> a, b;
      s->LatticeTable(z, h, n, kAll, &a);
      hs.Substrate::LatticeTable(z, h, n, kAll, &b);
      const TableErr e = CompareTables(a, b, n);
      Report(e.norm_rel < 1e-5, "lattice identical layers = HalfSpace",
             F("nu %.2f z %.2f mm: max err %.2e of peak (entries > 1e-3 peak: "
               "%.2e)", nu, z * 1e3, e.norm_rel, e.entry_rel));
    }
  }
}

// The FFT route at k h up to 1e4: a 20 mm layer under a 0.05 mm one, receptor
// just inside the thick layer (so the full field, not a remainder, is
// transformed; aliases up to k z = 50).
void TestLatticeHugeKh() {
  const double nu = 0.5, E = 50e3, h = 0.1e-3, z = 0.06e-3;
  const int n = 16;
  auto s = Make({{0.05e-3, E, nu}, {20e-3, E, nu}}, LayeredBase{false, E, nu});
  HalfSpace hs(nu);
  std::vector<float> a, b;
  const auto t0 = std::chrono::steady_clock::now();
  s->LatticeTable(z, h, n, kAll, &a);
  const double dt = Seconds(t0);
  hs.Substrate::LatticeTable(z, h, n, kAll, &b);
  const TableErr e = CompareTables(a, b, n);
  Report(e.norm_rel < 1e-4, "lattice at k h = 1.7e4 (nu 0.5, z 0.06 mm)",
         F("max err %.2e of peak, entries %.2e (%.2f s)", e.norm_rel,
           e.entry_rel, dt));
}

// Radial (Hankel) route vs the half-space closed forms.
void TestRadialIdentical() {
  double worst = 0;
  for (double nu : {0.3, 0.5}) {
    const double E = 50e3;
    auto s = Make({{0.3e-3, E, nu}, {0.6e-3, E, nu}}, LayeredBase{false, E, nu});
    HalfSpace hs(nu);
    for (double z : {0.2e-3, 0.9e-3, 2e-3}) {  // top layer, interface, base
      for (const auto& xy : std::vector<std::pair<double, double>>{
               {0, 0}, {0.3e-3, 0}, {0.25e-3, -0.4e-3}, {3e-3, 1e-3}}) {
        for (int load = 0; load < kNumLoads; ++load) {
          const auto L = static_cast<SurfaceLoad>(load);
          const Stress6 p = s->PointStress(L, xy.first, xy.second, z,
                                           InterfaceSide::kLower);
          const Stress6 q = load == 0 ? hs.Boussinesq(xy.first, xy.second, z)
                            : load == 1 ? hs.CerrutiX(xy.first, xy.second, z)
                                        : hs.CerrutiY(xy.first, xy.second, z);
          const Stress6 c = s->CellStress(L, xy.first, xy.second, z, 0.2e-3,
                                          InterfaceSide::kLower);
          const Stress6 d = hs.CellStress(L, xy.first, xy.second, z, 0.2e-3);
          double pm = 1 / (2 * M_PI * z * z), cm = 0.04 * pm * 0.2e-3 * 0.2e-3;
          for (int i = 0; i < 6; ++i) {
            pm = std::max(pm, std::abs(q[i]));
            cm = std::max(cm, std::abs(d[i]));
          }
          for (int i = 0; i < 6; ++i) {
            worst = std::max(worst, std::abs(p[i] - q[i]) / pm);
            worst = std::max(worst, std::abs(c[i] - d[i]) / cm);
          }
        }
      }
    }
  }
  Report(worst < 1e-6, "radial route identical layers = Boussinesq/Cerruti",
         F("max err %.2e of the largest component (point and cell)", worst));
}

}  // namespace

int main(int argc, char** argv) {
  const auto t0 = std::chrono::steady_clock::now();
  TestTransferIdentical();
  TestLargeKh();
  TestRigidLayerCompliance();
  TestComplianceLimit();
  TestRadialIdentical();
  TestLatticeIdentical();
  TestLatticeHugeKh();
  (void)argc;
  (void)argv;
  std::printf("%s: %d failure(s), %.1f s\n", g_failures ? "FAIL" : "PASS",
              g_failures, Seconds(t0));
  return g_failures ? 1 : 0;
}
