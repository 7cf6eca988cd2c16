// Standalone checks of the layered kernel (plugin/core/substrate/layered.*).
// Build and run (about 10-20 s on one core):
//   g++ -O2 -std=c++17 -Iplugin/core plugin/core/substrate/half_space.cc \
//       plugin/core/substrate/layered.cc plugin/core/substrate/layered_radial.cc \
//       plugin/core/stress/kernel_tables.cc tests/cpp/test_layered.cc -o test_layered
//   ./test_layered            # PASS/FAIL lines, exit status 1 on failure
//   ./test_layered --dump F   # also writes disc/transfer values as JSON
//                                # for tests/layered_oracle.py to compare
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "stress/kernel_tables.h"
#include "substrate/layered.h"
#include "substrate/substrate.h"

using namespace mjtouch;

namespace {

int g_failures = 0;

void Report(bool ok, const char* name, const std::string& detail) {
  std::printf("%s %s: %s\n", ok ? "PASS" : "FAIL", name, detail.c_str());
  if (!ok) ++g_failures;
}

template <typename... Args>
std::string F(const char* fmt, Args... args) {
  char buf[512];
  std::snprintf(buf, sizeof(buf), fmt, args...);
  return buf;
}

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
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

float TableAt(const std::vector<float>& t, int n, int load, int comp, int di, int dj) {
  const int L = 2 * n - 1;
  return t[(static_cast<size_t>(load * kNumStress + comp) * L + (dj + n - 1)) * L + (di + n - 1)];
}

// Max |a - b| over a lattice table, relative to max |b| per field, and the
// worst entry-wise relative error among entries with |b| > 1e-3 max |b|.
struct TableErr {
  double norm_rel = 0, entry_rel = 0;
};
TableErr CompareTables(const std::vector<float>& a, const std::vector<float>& b, int n) {
  const int L = 2 * n - 1;
  TableErr e;
  for (int f = 0; f < kNumLoads * kNumStress; ++f) {
    double bmax = 0;
    for (int i = 0; i < L * L; ++i) bmax = std::max(bmax, std::abs(double(b[f * L * L + i])));
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
    auto s = Make({{0.1e-3, E, nu}, {0.6e-3, E, nu}, {20e-3, E, nu}}, LayeredBase{false, E, nu});
    for (double z : {0.05e-3, 0.1e-3, 0.3e-3, 0.7e-3, 2e-3, 25e-3}) {
      for (double kh : {0.0, 1e-6, 1e-2, 1.0, 10.0, 100.0, 1e3, 1e4}) {
        const double k = kh / 1e-3;  // k h with h = 1 mm
        for (InterfaceSide side : {InterfaceSide::kUpper, InterfaceSide::kLower}) {
          const LayerTransfer t = s->TransferAt(k, z, side);
          const double kz = k * z, e = std::exp(-kz);
          const double ref[10] = {-(1 - kz) * e, -2 * nu * e, -(1 + kz) * e, kz * e, (2 - kz) * e,
                                  2 * nu * e,    kz * e,      (1 - kz) * e,  -e,     e};
          const double* got = &t.p_xixi;
          for (int i = 0; i < 10; ++i) {
            if (!std::isfinite(got[i])) finite = false;
            // Error relative to the load (1) scaled by the decay at depth.
            worst = std::max(worst, std::abs(got[i] - ref[i]) / std::max(e * (1 + kz), 1e-300));
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
      auto s = Make({{h, E, nu}, {0.8e-3, 20e3, 0.45}}, LayeredBase{rigid, 30e3, 0.4});
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
      // Relative error, floored at 1e-6 of the half-space compliance: for
      // nu = 0.5, C ~ (k h)^3 x that as k h -> 0 and the solve's round-off
      // (~1e-16 of the half-space value) dominates below k h ~ 1e-3.
      const double scale =
          std::max(std::abs(ref), kh > 0 ? 1e-6 * 2 * (1 - nu * nu) / (E * k) : 0.0);
      worst = std::max(worst, std::abs(c - ref) / scale);
    }
  }
  Report(worst < 1e-8, "layer on rigid base: closed-form compliance",
         F("max rel err %.2e (nu 0..0.5, k h 0..40)", worst));
}

// Surface compliance lattice: homogeneous half-space centre value equals
// Love's closed form (1 - nu^2) / (pi E) * 4 h ln(1 + sqrt 2); a layer on bone
// sums (uniform pressure) to the k = 0 compliance.
void TestComplianceTable() {
  const double E = 50e3, nu = 0.45, h = 0.1e-3;
  {
    auto s = Make({{0.5e-3, E, nu}, {1e-3, E, nu}}, LayeredBase{false, E, nu});
    std::vector<float> t;
    s->SurfaceComplianceTable(h, 16, &t);
    const double ref = (1 - nu * nu) / (M_PI * E) * 4 * h * std::log(1 + std::sqrt(2.0));
    const double c = t[15 * 31 + 15];
    // Far entry vs the point-force field (1 - nu^2) / (pi E r) h^2.
    const double far = t[15 * 31 + 0];
    const double far_ref = (1 - nu * nu) / (M_PI * E * 15 * h) * h * h;
    Report(std::abs(c / ref - 1) < 1e-6 && std::abs(far / far_ref - 1) < 1e-3,
           "compliance table: half-space = Love",
           F("centre rel err %.2e, 15 cells away %.2e (vs point force)", c / ref - 1,
             far / far_ref - 1));
  }
  for (double nu1 : {0.3, 0.5}) {
    const double H = 1e-3;
    auto s = Make({{H, E, nu1}}, LayeredBase{});
    std::vector<float> t;
    const int n = 256;  // +-25 mm: the bone-clamped field has died out
    const auto t0 = std::chrono::steady_clock::now();
    s->SurfaceComplianceTable(h, n, &t);
    const double dt = Seconds(t0);
    double sum = 0;
    for (float v : t) sum += v;
    const double ref = s->SurfaceCompliance(0.0);
    // nu = 0.5: C(0) = 0, compare with the centre value instead.
    const int L = 2 * n - 1;
    const double scale = nu1 < 0.5 ? std::abs(ref) : std::abs(t[(n - 1) * L + (n - 1)]);
    Report(std::abs(sum - ref) / scale < 1e-4,
           "compliance table: layer on bone, uniform load = C(0)",
           F("nu %.2f: sum %.6e vs %.6e m/Pa (rel %.2e), %.3f s", nu1, sum, ref,
             std::abs(sum - ref) / scale, dt));
  }
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
      worst = std::max(worst, std::abs(c - C0) / std::abs(C0) / (k * 3e-3));
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
    auto s = Make({{0.3e-3, E, nu}, {0.6e-3, E, nu}, {1.1e-3, E, nu}}, LayeredBase{false, E, nu});
    HalfSpace hs(nu);
    for (double z : {0.05e-3, 0.3e-3, 0.6e-3, 1.2e-3, 2e-3, 3e-3}) {
      std::vector<float> a, b;
      s->LatticeTable(z, h, n, kAll, &a);
      hs.Substrate::LatticeTable(z, h, n, kAll, &b);
      const TableErr e = CompareTables(a, b, n);
      Report(e.norm_rel < 1e-5, "lattice identical layers = HalfSpace",
             F("nu %.2f z %.2f mm: max err %.2e of peak (entries > 1e-3 peak: "
               "%.2e)",
               nu, z * 1e3, e.norm_rel, e.entry_rel));
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
         F("max err %.2e of peak, entries %.2e (%.2f s)", e.norm_rel, e.entry_rel, dt));
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
          const Stress6 p = s->PointStress(L, xy.first, xy.second, z, InterfaceSide::kLower);
          const Stress6 q = load == 0   ? hs.Boussinesq(xy.first, xy.second, z)
                            : load == 1 ? hs.CerrutiX(xy.first, xy.second, z)
                                        : hs.CerrutiY(xy.first, xy.second, z);
          const Stress6 c = s->CellStress(L, xy.first, xy.second, z, 0.2e-3, InterfaceSide::kLower);
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

// Shao fingertip: LatticeTable (radial tables) vs CellStress (direct Hankel
// integrals at each quadrature point) at sampled offsets, both interface
// sides, and s_zz / s_xz / s_yz continuous across the interface while s_xx
// jumps.
void TestShaoLatticeVsCell() {
  auto s = Make(LayeredSubstrate::ShaoFingertipLayers(), LayeredSubstrate::ShaoFingertipBase());
  const double h = 0.1e-3;
  const int n = 48;
  const int offsets[][2] = {{0, 0},  {1, 0},     {0, 1},  {2, -3}, {-5, 4},
                            {10, 0}, {-17, -23}, {40, 3}, {47, 47}};
  struct Case {
    double z;
    InterfaceSide side;
    const char* name;
  };
  const Case cases[] = {{0.05e-3, InterfaceSide::kUpper, "0.05 mm"},
                        {0.3e-3, InterfaceSide::kUpper, "0.3 mm"},
                        {0.7e-3, InterfaceSide::kUpper, "0.7 mm upper"},
                        {0.7e-3, InterfaceSide::kLower, "0.7 mm lower"},
                        {2.0e-3, InterfaceSide::kUpper, "2 mm"},
                        {3.5e-3, InterfaceSide::kUpper, "3.5 mm"}};
  std::vector<float> up, low;
  for (const Case& c : cases) {
    std::vector<float> t;
    s->LatticeTable(c.z, h, n, kAll, c.side, &t);
    if (c.z == 0.7e-3) (c.side == InterfaceSide::kUpper ? up : low) = t;
    double peak[kNumLoads] = {0, 0, 0}, worst = 0;
    const size_t LL = static_cast<size_t>(2 * n - 1) * (2 * n - 1);
    for (int load = 0; load < kNumLoads; ++load)
      for (size_t i = 0; i < kNumStress * LL; ++i)
        peak[load] = std::max(peak[load], std::abs(double(t[load * kNumStress * LL + i])));
    for (const auto& o : offsets)
      for (int load = 0; load < kNumLoads; ++load) {
        // Receptor at (-di h, -dj h) from the source.
        const Stress6 ref =
            s->CellStress(static_cast<SurfaceLoad>(load), -o[0] * h, -o[1] * h, c.z, h, c.side);
        for (int comp = 0; comp < kNumStress; ++comp)
          worst = std::max(
              worst, std::abs(TableAt(t, n, load, comp, o[0], o[1]) - ref[comp]) / peak[load]);
      }
    Report(worst < 1e-6, "Shao lattice = direct cell integrals",
           F("z %s: max err %.2e of peak", c.name, worst));
  }
  // Interface: traction components continuous, in-plane stress jumps.
  double cont = 0, jump = 0, peak = 0;
  const int L = 2 * n - 1;
  for (int load = 0; load < kNumLoads; ++load)
    for (int comp = 0; comp < kNumStress; ++comp)
      for (int i = 0; i < L * L; ++i) {
        const size_t k = static_cast<size_t>(load * kNumStress + comp) * L * L + i;
        const double d = std::abs(double(up[k]) - low[k]);
        peak = std::max(peak, std::abs(double(up[k])));
        if (comp == kSzz || comp == kSxz || comp == kSyz)
          cont = std::max(cont, d);
        else
          jump = std::max(jump, d);
      }
  Report(cont < 1e-6 * peak && jump > 1e-2 * peak,
         "interface 0.7 mm: s_zz, s_xz, s_yz continuous, s_xx jumps",
         F("max |traction jump| %.2e, max in-plane jump %.2e (of peak %.2e)", cont / peak,
           jump / peak, peak));
}

// Integral of s_zz over a plane (lattice sum x pitch^2) = -1 x cell area at
// every depth, and of s_xz under shear x. On bone the field dies out
// exponentially (here over ~7 mm: the soft pulp spreads shear widely), so a
// +-100 mm table holds all of it; over a half-space the Boussinesq tail beyond
// the table (fraction ~ (z/R)^3 for s_zz, ~ z/R for s_xz) is missing.
void TestLoadIntegral() {
  {
    const double h = 0.4e-3;
    const int n = 256;
    auto s = Make(LayeredSubstrate::ShaoFingertipLayers(), LayeredSubstrate::ShaoFingertipBase());
    double worst = 0;
    for (double z : {0.05e-3, 0.3e-3, 0.7e-3, 1.0e-3, 1.5e-3, 2.0e-3, 3.0e-3}) {
      std::vector<float> t;
      s->LatticeTable(z, h, n, kAll, &t);
      const int L = 2 * n - 1;
      const int field[3] = {0 * 6 + kSzz, 1 * 6 + kSxz, 2 * 6 + kSyz};
      for (int f = 0; f < 3; ++f) {
        double sum = 0;
        for (int i = 0; i < L * L; ++i) sum += t[field[f] * L * L + i];
        worst = std::max(worst, std::abs(sum + 1));
      }
    }
    Report(worst < 1e-5, "load integral, bone at 4 mm",
           F("max |sum s_zz + 1|, |sum s_xz + 1|, |sum s_yz + 1| = %.2e "
             "(z 0.05..3 mm, table +-100 mm)",
             worst));
  }
  // Over a half-space the tails (s_zz ~ 1/r^5, s_xz ~ 1/r^3) reach past any
  // table; the plane integral is the k = 0 transfer function, which must be
  // exactly the load at every depth (on both sides of each interface).
  double worst = 0;
  for (bool rigid : {true, false}) {
    std::vector<ElasticLayer> layers = LayeredSubstrate::ShaoFingertipLayers();
    auto s = Make(layers, LayeredBase{rigid, 24e3, 0.4});
    for (double z : {0.05e-3, 0.7e-3, 1.5e-3, 3.0e-3, 4.0e-3, 6.0e-3})
      for (InterfaceSide side : {InterfaceSide::kUpper, InterfaceSide::kLower}) {
        if (!s->CheckDepth(z, side).empty()) continue;
        const LayerTransfer t = s->TransferAt(0.0, z, side);
        worst = std::max({worst, std::abs(t.p_zz + 1), std::abs(t.q_xiz - 1),
                          std::abs(t.a_etaz + 1), std::abs(t.p_xiz), std::abs(t.q_zz)});
      }
  }
  Report(worst < 1e-14, "load integral = k -> 0 transfer (any base, depth)",
         F("max deviation %.2e", worst));
}

// A very thin stiff top layer tends to the substrate's own field.
void TestThinTopLayer() {
  const double nu_b = 0.45, E_b = 30e3, h = 0.1e-3, z = 0.5e-3;
  const int n = 24;
  HalfSpace hs(nu_b);
  std::vector<float> ref;
  hs.Substrate::LatticeTable(z, h, n, kAll, &ref);
  double prev = 1e9;
  bool monotone = true;
  std::string detail;
  for (double t_m : {10e-6, 1e-6, 0.1e-6, 0.01e-6}) {
    auto s = Make({{t_m, 5 * E_b, 0.3}, {1e-3, E_b, nu_b}}, LayeredBase{false, E_b, nu_b});
    std::vector<float> tab;
    s->LatticeTable(z, h, n, kAll, &tab);
    const double e = CompareTables(tab, ref, n).norm_rel;
    if (!(e < prev)) monotone = false;
    prev = e;
    detail += F("t %.2g um: %.1e; ", t_m * 1e6, e);
  }
  Report(monotone && prev < 1e-3, "thin top layer -> substrate field", detail);
}

// Build time of the plugin's tables: Shao fingertip, n = 128, pitch 0.1 mm,
// receptor depths 0.3, 0.7, 2.0 mm, all components, one core.
void TestBuildTime() {
  auto s = Make(LayeredSubstrate::ShaoFingertipLayers(), LayeredSubstrate::ShaoFingertipBase());
  const auto kt = BuildKernelTables(*s, 128, 0.1e-3, {0.3e-3, 0.7e-3, 2.0e-3}, kAll);
  bool finite = true;
  for (const auto& t : kt->tables)
    for (float v : t)
      if (!std::isfinite(v)) finite = false;
  // (the build time is reported, not asserted: the machines are shared)
  Report(finite, "tables n=128, 3 depths finite",
         F("built in %.3f s (%s)", kt->build_seconds, s->Describe().c_str()));
  std::vector<float> c;
  const auto t0 = std::chrono::steady_clock::now();
  s->SurfaceComplianceTable(0.1e-3, 128, &c);
  bool positive_centre = c.size() == 255u * 255u && c[127 * 255 + 127] > 0;
  for (float v : c) positive_centre = positive_centre && std::isfinite(v);
  Report(positive_centre, "compliance table n=128 finite, positive at the load",
         F("built in %.3f s", Seconds(t0)));
}

// Input validation names the field and range.
void TestValidation() {
  std::string err;
  bool ok = true;
  auto expect = [&](const std::vector<ElasticLayer>& l, const LayeredBase& b, const char* needle) {
    auto s = LayeredSubstrate::Create(l, b, InterfaceSide::kUpper, &err);
    if (s || err.find(needle) == std::string::npos) {
      ok = false;
      std::printf("  validation: expected '%s', got '%s'\n", needle, err.c_str());
    }
  };
  expect({}, LayeredBase{}, "at least one layer");
  expect({{0, 1e3, 0.3}}, LayeredBase{}, "thickness");
  expect({{1e-3, -1, 0.3}}, LayeredBase{}, "young");
  expect({{1e-3, 1e3, 0.51}}, LayeredBase{}, "(-1, 0.5]");
  expect({{1e-3, 1e3, -1.0}}, LayeredBase{}, "poisson");
  expect({{1e-3, 1e3, 0.3}}, LayeredBase{false, 0, 0.3}, "base young");
  expect({{1e-3, 1e3, 0.3}}, LayeredBase{false, 1e3, 0.7}, "base poisson");
  auto s = Make({{1e-3, 1e3, 0.5}}, LayeredBase{});
  ok = ok && !s->CheckDepth(1e-3, InterfaceSide::kLower).empty() &&
       s->CheckDepth(1e-3, InterfaceSide::kUpper).empty() &&
       !s->CheckDepth(0.0, InterfaceSide::kUpper).empty();
  const Material m1 = s->MaterialAt(0.5e-3, true);
  ok = ok && m1.young_pa == 1e3 && m1.poisson == 0.5;
  // Strain and SED: uniaxial stress 1 Pa, E = 2 Pa, nu = 0.25.
  Stress6 st{};
  st[kSxx] = 1;
  const Stress6 e = StrainFromStress(st, {2.0, 0.25});
  const double sed = StrainEnergyDensity(st, {2.0, 0.25});
  ok = ok && std::abs(e[kSxx] - 0.5) < 1e-15 && std::abs(e[kSyy] + 0.125) < 1e-15 &&
       std::abs(sed - 0.25) < 1e-15;
  st = Stress6{};
  st[kSxy] = 1;  // pure shear: SED = tau^2 / (2 mu), mu = E / (2 (1 + nu))
  ok = ok && std::abs(StrainEnergyDensity(st, {2.0, 0.25}) - 1.25 / 2) < 1e-15;
  Report(ok, "validation, depth checks, material, strain and SED", "last message: " + err);
}

// Values for tests/layered_oracle.py (independent numpy/scipy computation):
// disc loads and transfer functions on two stacks.
void Dump(const char* path) {
  FILE* f = std::fopen(path, "w");
  if (!f) {
    Report(false, "dump", path);
    return;
  }
  struct Stack {
    const char* name;
    std::vector<ElasticLayer> layers;
    LayeredBase base;
  };
  const Stack stacks[] = {
      {"shao_bone", LayeredSubstrate::ShaoFingertipLayers(), LayeredSubstrate::ShaoFingertipBase()},
      {"two_layers_halfspace",
       {{0.4e-3, 100e3, 0.3}, {0.3e-3, 20e3, 0.49}},
       LayeredBase{false, 40e3, 0.35}}};
  const char* load_names[] = {"pressure", "shear_x", "shear_y"};
  std::fprintf(f, "{\"cases\": [\n");
  for (size_t c = 0; c < 2; ++c) {
    const Stack& st = stacks[c];
    auto s = Make(st.layers, st.base);
    std::fprintf(f, "%s{\"name\": \"%s\", \"layers\": [", c ? ",\n" : "", st.name);
    for (size_t i = 0; i < st.layers.size(); ++i)
      std::fprintf(f, "%s[%.17g, %.17g, %.17g]", i ? ", " : "", st.layers[i].thickness_m,
                   st.layers[i].young_pa, st.layers[i].poisson);
    if (st.base.rigid)
      std::fprintf(f, "], \"base\": null,\n \"disc\": [");
    else
      std::fprintf(f, "], \"base\": [%.17g, %.17g],\n \"disc\": [", st.base.young_pa,
                   st.base.poisson);
    const double zi = st.layers[0].thickness_m;
    const struct {
      double z;
      bool upper;
    } depths[] = {{0.2e-3, true}, {zi, true}, {zi, false}, {2.5e-3, true}};
    const double pts[][2] = {{0, 0}, {0.5e-3, 0.3e-3}, {-2e-3, 1e-3}};
    bool first = true;
    for (const auto& d : depths)
      for (const auto& p : pts)
        for (int load = 0; load < kNumLoads; ++load) {
          const Stress6 v = s->DiscStress(static_cast<SurfaceLoad>(load), p[0], p[1], d.z, 1e-3,
                                          d.upper ? InterfaceSide::kUpper : InterfaceSide::kLower);
          std::fprintf(f,
                       "%s\n  {\"load\": \"%s\", \"x\": %.17g, \"y\": %.17g, "
                       "\"z\": %.17g, \"radius\": 1e-3, \"upper\": %s, "
                       "\"stress\": [%.17g, %.17g, %.17g, %.17g, %.17g, %.17g]}",
                       first ? "" : ",", load_names[load], p[0], p[1], d.z,
                       d.upper ? "true" : "false", v[0], v[1], v[2], v[3], v[4], v[5]);
          first = false;
        }
    std::fprintf(f, "],\n \"cell\": [");
    first = true;
    for (const auto& d : depths)
      for (const auto& p : pts)
        for (int load = 0; load < kNumLoads; ++load) {
          // Lattice table entries (pitch 0.2 mm, n = 16) at the receptor
          // offset nearest to p, as the plugin uses them.
          const int di = -static_cast<int>(std::lround(p[0] / 0.2e-3));
          const int dj = -static_cast<int>(std::lround(p[1] / 0.2e-3));
          std::vector<float> t;
          s->LatticeTable(d.z, 0.2e-3, 16, kAll,
                          d.upper ? InterfaceSide::kUpper : InterfaceSide::kLower, &t);
          std::fprintf(f,
                       "%s\n  {\"load\": \"%s\", \"x\": %.17g, \"y\": %.17g, "
                       "\"z\": %.17g, \"pitch\": 2e-4, \"upper\": %s, "
                       "\"stress\": [",
                       first ? "" : ",", load_names[load], -di * 0.2e-3, -dj * 0.2e-3, d.z,
                       d.upper ? "true" : "false");
          for (int comp = 0; comp < kNumStress; ++comp)
            std::fprintf(f, "%s%.9g", comp ? ", " : "", TableAt(t, 16, load, comp, di, dj));
          std::fprintf(f, "]}");
          first = false;
        }
    std::fprintf(f, "],\n \"transfer\": [");
    first = true;
    for (const auto& d : depths)
      for (double k : {10.0, 1e3, 1e4, 1e5}) {
        const LayerTransfer t =
            s->TransferAt(k, d.z, d.upper ? InterfaceSide::kUpper : InterfaceSide::kLower);
        std::fprintf(f,
                     "%s\n  {\"k\": %.17g, \"z\": %.17g, \"upper\": %s, \"values\": "
                     "{\"p_xixi\": %.17g, \"p_etaeta\": %.17g, \"p_zz\": %.17g, "
                     "\"p_xiz\": %.17g, \"q_xixi\": %.17g, \"q_etaeta\": %.17g, "
                     "\"q_zz\": %.17g, \"q_xiz\": %.17g, \"a_etaz\": %.17g, "
                     "\"a_xieta\": %.17g}}",
                     first ? "" : ",", k, d.z, d.upper ? "true" : "false", t.p_xixi, t.p_etaeta,
                     t.p_zz, t.p_xiz, t.q_xixi, t.q_etaeta, t.q_zz, t.q_xiz, t.a_etaz, t.a_xieta);
        first = false;
      }
    std::fprintf(f, "]}");
  }
  std::fprintf(f, "\n]}\n");
  Report(std::fclose(f) == 0, "dump", F("wrote %s", path));
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
  TestComplianceTable();
  TestShaoLatticeVsCell();
  TestLoadIntegral();
  TestThinTopLayer();
  TestValidation();
  TestBuildTime();
  if (argc > 2 && std::strcmp(argv[1], "--dump") == 0) Dump(argv[2]);
  std::printf("%s: %d failure(s), %.1f s\n", g_failures ? "FAIL" : "PASS", g_failures, Seconds(t0));
  return g_failures ? 1 : 0;
}
