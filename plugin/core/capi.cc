// C API over the pure-C++ stages, for Python (ctypes) and tests: every stage
// can be called without a MuJoCo scene. Errors are returned as nonzero codes
// with a message in a caller buffer; nothing throws across this boundary.
#include <cmath>
#include <cstring>
#include <map>
#include <sstream>
#include <string>

#include <chrono>
#include <memory>

#include "stress/kernel_tables.h"
#include "substrate/layered.h"
#include "contact/pressure.h"
#include "stress/stress_field.h"
#include "afferents/receptors.h"
#include "pipeline/skin.h"
#include "surface/surface.h"

namespace {

using namespace mjtouch;

// "key=value" pairs separated by newlines or ';' -> getter.
std::map<std::string, std::string> ParseKeyValues(const char* text) {
  std::map<std::string, std::string> kv;
  if (!text) return kv;
  std::string s(text);
  for (char& c : s)
    if (c == ';') c = '\n';
  std::istringstream lines(s);
  std::string line;
  while (std::getline(lines, line)) {
    const size_t eq = line.find('=');
    if (eq == std::string::npos) continue;
    auto trim = [](std::string x) {
      const size_t a = x.find_first_not_of(" \t"), b = x.find_last_not_of(" \t");
      return a == std::string::npos ? std::string() : x.substr(a, b - a + 1);
    };
    kv[trim(line.substr(0, eq))] = trim(line.substr(eq + 1));
  }
  return kv;
}

void CopyError(const std::string& msg, char* buf, int len) {
  if (buf && len > 0) {
    std::strncpy(buf, msg.c_str(), len - 1);
    buf[len - 1] = '\0';
  }
}

bool ParseConfigText(const char* text, SkinConfig* cfg, std::string* error) {
  const auto kv = ParseKeyValues(text);
  const auto& keys = SkinAttributeKeys();
  for (const auto& [k, v] : kv) {
    bool known = false;
    for (const char* key : keys) known = known || k == key;
    if (!known) {
      *error = "mjtouch.skin: unknown attribute `" + k + "`";
      return false;
    }
  }
  return ParseSkinConfig(
      [&](const char* key) {
        auto it = kv.find(key);
        return it == kv.end() ? std::string() : it->second;
      },
      cfg, error);
}

}  // namespace

extern "C" {

__attribute__((visibility("default"))) int mjtouch_abi_version() { return 1; }

// Point-force (load 0: normal, 1: +x, 2: +y; 1 N) or uniform unit traction on
// a square cell (pitch_m > 0) stress in a homogeneous half-space. out: 6 Pa.
__attribute__((visibility("default"))) int mjtouch_halfspace_stress(
    double poisson, int load, double x, double y, double z, double pitch_m, double* out) {
  if (load < 0 || load > 2 || !(z > 0) || poisson <= -1 || poisson > 0.5) return 1;
  HalfSpace hs(poisson);
  Stress6 s;
  if (pitch_m > 0) {
    s = hs.CellStress(static_cast<SurfaceLoad>(load), x, y, z, pitch_m);
  } else {
    s = load == 0 ? hs.Boussinesq(x, y, z) : (load == 1 ? hs.CerrutiX(x, y, z)
                                                        : hs.CerrutiY(x, y, z));
  }
  for (int k = 0; k < 6; ++k) out[k] = s[k];
  return 0;
}

// Stress at `nrec` receptors (cell indices ri, rj; depth index 0) at depth
// z_m from traction fields (n*n each, Pa, row-major j*n+i; shear may be
// null), homogeneous half-space. out: nrec x 6.
__attribute__((visibility("default"))) int mjtouch_halfspace_field_stress(
    double poisson, int n, double pitch_m, double z_m, const float* pressure,
    const float* shear_x, const float* shear_y, int nrec, const int* ri, const int* rj,
    double* out) {
  if (n < 1 || !(pitch_m > 0) || !(z_m > 0)) return 1;
  HalfSpace hs(poisson);
  std::array<bool, kNumStress> all;
  all.fill(true);
  auto kt = BuildKernelTables(hs, n, pitch_m, {z_m}, all);
  ActiveRuns runs;
  for (int j = 0; j < n; ++j) {
    runs.row.push_back(j);
    runs.begin.push_back(0);
    runs.end.push_back(n);
  }
  for (int r = 0; r < nrec; ++r) {
    Stress6 s;
    StressAtReceptor(*kt, 0, ri[r], rj[r], runs, pressure, shear_x, shear_y, all, &s);
    for (int k = 0; k < 6; ++k) out[6 * r + k] = s[k];
  }
  return 0;
}

// Cell-averaged skin surface (pad frame z, m; +inf outside the footprint) for
// a pad with semi-axes (a, b, c) and the ridge attributes in `config`.
__attribute__((visibility("default"))) int mjtouch_skin_surface(
    const char* config, double a, double b, double c, double* out, char* err, int errlen) {
  SkinConfig cfg;
  std::string error;
  if (!ParseConfigText(config, &cfg, &error)) {
    CopyError(error, err, errlen);
    return 1;
  }
  cfg.pad.semi_axes_m[0] = a;
  cfg.pad.semi_axes_m[1] = b;
  cfg.pad.semi_axes_m[2] = c;
  if (!FinalizeSkinConfig(&cfg, &error)) {
    CopyError(error, err, errlen);
    return 1;
  }
  const auto z = SkinSurface(cfg.grid, cfg.pad, cfg.ridges);
  std::memcpy(out, z.data(), z.size() * sizeof(double));
  return 0;
}

// Mean of a bilinear height field (MuJoCo hfield semantics) over a box.
__attribute__((visibility("default"))) double mjtouch_hfield_box_mean(
    int nrow, int ncol, const float* samples, double half_x, double half_y, double elevation,
    double x0, double x1, double y0, double y1) {
  CounterSurface s;
  s.type = CounterSurface::Type::kHeightField;
  s.nrow = nrow;
  s.ncol = ncol;
  s.samples = samples;
  s.half_x_m = half_x;
  s.half_y_m = half_y;
  s.elevation_m = elevation;
  return HeightFieldBoxMean(s, x0, x1, y0, y1);
}

// Winkler pressure for given gaps (m) and coverage on an n x n grid.
__attribute__((visibility("default"))) int mjtouch_winkler_pressure(
    int n, double pitch_m, const double* gap, const double* coverage, double stiffness,
    double force, float* pressure_out, double* approach_out) {
  TaxelGrid grid{n, pitch_m};
  std::vector<double> g(gap, gap + grid.Size()), c(coverage, coverage + grid.Size());
  TractionField tf;
  const bool ok = WinklerPressure(grid, g, c, CellBox::All(grid), stiffness, force, std::nan(""),
                                  &tf);
  FinishTraction(grid, false, &tf);
  std::memcpy(pressure_out, tf.pressure.data(), grid.Size() * sizeof(float));
  *approach_out = tf.approach_m;
  return ok ? 0 : 2;
}

// Drive one receptor of class `cls` (0 SA1, 1 RA, 2 PC) with the quantity
// trace q (Pa) sampled every dt; receptor parameters from `config`
// (attribute=value pairs). Writes spikes per step and voltages.
__attribute__((visibility("default"))) int mjtouch_receptor_run(
    const char* config, int cls, const double* q, int nsteps, double dt, double* spikes,
    double* voltage, double* rate, unsigned long long stream, char* err, int errlen) {
  SkinConfig cfg;
  std::string error;
  if (!ParseConfigText(config, &cfg, &error)) {
    CopyError(error, err, errlen);
    return 1;
  }
  if (cls < 0 || cls >= kNumClasses || !(dt > 0) || nsteps < 1) {
    CopyError("class must be 0 (SA1), 1 (RA) or 2 (PC), dt > 0 and nsteps >= 1", err, errlen);
    return 1;
  }
  // As in the plugin: primed at rest with the first value (no step, no
  // output), then one step of dt per further value; stream = the receptor's
  // index in a plugin instance (its noise sequence).
  const auto c = static_cast<ReceptorClass>(cls);
  const ReceptorStepper stepper(cfg.receptor, dt);
  double state[kReceptorStateSize] = {0};
  PrimeReceptor(cfg.receptor, c, q[0], stream, state);
  if (spikes) spikes[0] = 0;
  if (voltage) voltage[0] = 0;
  if (rate) rate[0] = 0;
  for (int k = 1; k < nsteps; ++k) {
    double v = 0;
    const int s = stepper.Advance(c, q[k], stream, state, &v);
    if (spikes) spikes[k] = s;
    if (voltage) voltage[k] = v;
    if (rate) rate[k] = ReceptorRate(state);
  }
  return 0;
}

// Validate a configuration text; returns 0 or 1 with the message.
__attribute__((visibility("default"))) int mjtouch_check_config(const char* config, char* err,
                                                                int errlen) {
  SkinConfig cfg;
  std::string error;
  if (!ParseConfigText(config, &cfg, &error)) {
    CopyError(error, err, errlen);
    return 1;
  }
  return 0;
}

}  // extern "C"

// ---------------------------------------------------------------------------
// Layered elastic skin (layered.h) and the per-step stress stage
// (stress_field.h) without a MuJoCo scene. Handles are opaque pointers owned
// by the caller (free with the matching *_free). side: -1 the substrate's
// own interface side, 0 upper, 1 lower.

namespace {

bool SideFrom(const mjtouch::LayeredSubstrate* s, int side, mjtouch::InterfaceSide* out) {
  if (side == -1) {
    *out = s->interface_side();
    return true;
  }
  if (side != 0 && side != 1) return false;
  *out = side == 0 ? mjtouch::InterfaceSide::kUpper : mjtouch::InterfaceSide::kLower;
  return true;
}

// Tables, sites and spectra for one grid: the stress stage as the plugin runs it.
struct StressEngine {
  std::unique_ptr<mjtouch::Substrate> halfspace;  // when no layered substrate is given
  std::shared_ptr<const mjtouch::KernelTables> tables;
  std::shared_ptr<const mjtouch::KernelSpectra> spectra;
  std::shared_ptr<const mjtouch::StressTree> tree;
  std::vector<mjtouch::StressSite> sites;
  mjtouch::StressScratch scratch;
  std::vector<mjtouch::Stress6> out;
  mjtouch::ActiveRuns runs;
};

}  // namespace

extern "C" {

// The default (Shao et al. 2010) stack: writes up to max_layers rows of
// (thickness m, E Pa, nu) and *base_rigid; returns the number of layers.
__attribute__((visibility("default"))) int mjtouch_shao_fingertip(double* layers, int max_layers,
                                                                  int* base_rigid) {
  const auto l = LayeredSubstrate::ShaoFingertipLayers();
  const int m = static_cast<int>(l.size());
  for (int i = 0; i < m && i < max_layers; ++i) {
    layers[3 * i] = l[i].thickness_m;
    layers[3 * i + 1] = l[i].young_pa;
    layers[3 * i + 2] = l[i].poisson;
  }
  *base_rigid = LayeredSubstrate::ShaoFingertipBase().rigid ? 1 : 0;
  return m;
}

// layers: nlayers rows (thickness m, E Pa, nu); base: rigid, or an elastic
// half-space (base_young Pa, base_poisson). Returns null with a message.
__attribute__((visibility("default"))) void* mjtouch_layered_create(
    int nlayers, const double* layers, int base_rigid, double base_young, double base_poisson,
    int side, char* err, int errlen) {
  std::vector<ElasticLayer> stack;
  for (int i = 0; i < nlayers; ++i) stack.push_back({layers[3 * i], layers[3 * i + 1], layers[3 * i + 2]});
  LayeredBase base;
  base.rigid = base_rigid != 0;
  base.young_pa = base.rigid ? 0.0 : base_young;
  base.poisson = base.rigid ? 0.0 : base_poisson;
  if (side != 0 && side != 1) {
    CopyError("interface side must be 0 (upper) or 1 (lower)", err, errlen);
    return nullptr;
  }
  std::string error;
  auto s = LayeredSubstrate::Create(
      stack, base, side == 0 ? InterfaceSide::kUpper : InterfaceSide::kLower, &error);
  if (!s) {
    CopyError(error, err, errlen);
    return nullptr;
  }
  return s.release();
}

__attribute__((visibility("default"))) void mjtouch_layered_free(void* h) {
  delete static_cast<LayeredSubstrate*>(h);
}

// Describe() into buf; returns the length needed (with the terminator) if
// buf is too short, else 0.
__attribute__((visibility("default"))) int mjtouch_layered_describe(void* h, char* buf, int len) {
  const std::string s = static_cast<LayeredSubstrate*>(h)->Describe();
  if (static_cast<int>(s.size()) + 1 > len) return static_cast<int>(s.size()) + 1;
  std::memcpy(buf, s.c_str(), s.size() + 1);
  return 0;
}

// 0 if z_m is a valid receptor depth on `side`, else 1 with the reason.
__attribute__((visibility("default"))) int mjtouch_layered_check_depth(void* h, double z_m,
                                                                       int side, char* err,
                                                                       int errlen) {
  const auto* s = static_cast<LayeredSubstrate*>(h);
  InterfaceSide sd;
  if (!SideFrom(s, side, &sd)) {
    CopyError("side must be -1 (default), 0 (upper) or 1 (lower)", err, errlen);
    return 1;
  }
  const std::string why = s->CheckDepth(z_m, sd);
  if (why.empty()) return 0;
  CopyError(why, err, errlen);
  return 1;
}

// Material (E Pa, nu) at depth z_m on `side`; (0, 0) inside a rigid base.
__attribute__((visibility("default"))) int mjtouch_layered_material(void* h, double z_m, int side,
                                                                    double* out2) {
  const auto* s = static_cast<LayeredSubstrate*>(h);
  InterfaceSide sd;
  if (!SideFrom(s, side, &sd)) return 1;
  const Material m = s->MaterialAt(z_m, sd == InterfaceSide::kUpper);
  out2[0] = m.young_pa;
  out2[1] = m.poisson;
  return 0;
}

// The 10 transfer functions (LayerTransfer order) at k_per_m >= 0, depth z_m.
__attribute__((visibility("default"))) int mjtouch_layered_transfer(void* h, double k_per_m,
                                                                    double z_m, int side,
                                                                    double* out10) {
  const auto* s = static_cast<LayeredSubstrate*>(h);
  InterfaceSide sd;
  if (!SideFrom(s, side, &sd) || !(k_per_m >= 0) || !s->CheckDepth(z_m, sd).empty()) return 1;
  const LayerTransfer t = s->TransferAt(k_per_m, z_m, sd);
  const double v[10] = {t.p_xixi, t.p_etaeta, t.p_zz, t.p_xiz, t.q_xixi,
                        t.q_etaeta, t.q_zz, t.q_xiz, t.a_etaz, t.a_xieta};
  std::memcpy(out10, v, sizeof(v));
  return 0;
}

// Fourier surface compliance u_z / p (m/Pa) at k_per_m (0: the finite part).
__attribute__((visibility("default"))) double mjtouch_layered_compliance(void* h, double k_per_m) {
  return static_cast<LayeredSubstrate*>(h)->SurfaceCompliance(k_per_m);
}

// Surface compliance lattice, (2n - 1)^2 floats (layered.h).
__attribute__((visibility("default"))) int mjtouch_layered_compliance_table(void* h,
                                                                            double pitch_m, int n,
                                                                            float* out) {
  if (!(pitch_m > 0) || n < 1) return 1;
  std::vector<float> t;
  static_cast<LayeredSubstrate*>(h)->SurfaceComplianceTable(pitch_m, n, &t);
  std::memcpy(out, t.data(), t.size() * sizeof(float));
  return 0;
}

// Stress (6, Pa) at (x, y, z) for kind 0: a 1 N point force at the origin;
// 1: unit traction on a square cell of side size_m; 2: on a disc of radius
// size_m. load 0 pressure, 1 shear +x, 2 shear +y.
__attribute__((visibility("default"))) int mjtouch_layered_stress(void* h, int kind, int load,
                                                                  double x, double y, double z,
                                                                  double size_m, int side,
                                                                  double* out6) {
  const auto* s = static_cast<LayeredSubstrate*>(h);
  InterfaceSide sd;
  if (!SideFrom(s, side, &sd) || load < 0 || load > 2 || kind < 0 || kind > 2) return 1;
  if (!s->CheckDepth(z, sd).empty() || (kind > 0 && !(size_m > 0))) return 1;
  const auto L = static_cast<SurfaceLoad>(load);
  const Stress6 v = kind == 0 ? s->PointStress(L, x, y, z, sd)
                    : kind == 1 ? s->CellStress(L, x, y, z, size_m, sd)
                                : s->DiscStress(L, x, y, z, size_m, sd);
  for (int k = 0; k < 6; ++k) out6[k] = v[k];
  return 0;
}

// Lattice table at depth z_m, all components: 3 * 6 * (2n - 1)^2 floats in
// the KernelTables layout (kernel.h).
__attribute__((visibility("default"))) int mjtouch_layered_lattice_table(void* h, double z_m,
                                                                         double pitch_m, int n,
                                                                         int side, float* out) {
  const auto* s = static_cast<LayeredSubstrate*>(h);
  InterfaceSide sd;
  if (!SideFrom(s, side, &sd) || !(pitch_m > 0) || n < 1 || !s->CheckDepth(z_m, sd).empty())
    return 1;
  std::array<bool, kNumStress> all;
  all.fill(true);
  std::vector<float> t;
  s->LatticeTable(z_m, pitch_m, n, all, sd, &t);
  std::memcpy(out, t.data(), t.size() * sizeof(float));
  return 0;
}

// A stress stage for an n x n grid: the layered substrate `layered` (its
// interface side), or a homogeneous half-space of Poisson's ratio `poisson`
// when layered is null. Sites: cell (ri, rj), depth depths[depth_index], the
// components in want_mask (bit c for Voigt component c). method 0 auto (FFT
// spectra built where the FFT path can win, as in the plugin), 1 direct (no
// spectra), 2 fft (spectra built), 3 tree (hierarchical, opening angle
// theta; with shear coefficients).
__attribute__((visibility("default"))) void* mjtouch_stress_engine_create(
    void* layered, double poisson, int n, double pitch_m, int ndepth, const double* depths,
    int nsite, const int* ri, const int* rj, const int* depth_index, const int* want_mask,
    int method, double theta, char* err, int errlen) {
  auto e = std::make_unique<StressEngine>();
  if (n < 1 || n > 512 || !(pitch_m > 0) || ndepth < 1 || method < 0 || method > 3 ||
      (method == 3 && !(theta > 0 && theta <= 2))) {
    CopyError("need 1 <= n <= 512, pitch_m > 0, ndepth >= 1, method 0 (auto), 1 (direct), 2 "
              "(fft) or 3 (tree, theta in (0, 2])", err, errlen);
    return nullptr;
  }
  const Substrate* sub = static_cast<LayeredSubstrate*>(layered);
  if (!sub) {
    if (!(poisson > -1 && poisson <= 0.5)) {
      CopyError("poisson is out of range; valid range (-1, 0.5]", err, errlen);
      return nullptr;
    }
    e->halfspace = std::make_unique<HalfSpace>(poisson);
    sub = e->halfspace.get();
  }
  std::array<bool, kNumStress> comps{};
  for (int s = 0; s < nsite; ++s) {
    if (ri[s] < 0 || ri[s] >= n || rj[s] < 0 || rj[s] >= n || depth_index[s] < 0 ||
        depth_index[s] >= ndepth) {
      CopyError("site cell indices must be in [0, n) and depth indices in [0, ndepth)", err, errlen);
      return nullptr;
    }
    StressSite site{ri[s], rj[s], depth_index[s], {}};
    for (int c = 0; c < kNumStress; ++c) {
      site.want[c] = (want_mask[s] >> c) & 1;
      comps[c] = comps[c] || site.want[c];
    }
    e->sites.push_back(site);
  }
  for (int d = 0; d < ndepth; ++d) {
    const auto* l = static_cast<LayeredSubstrate*>(layered);
    const std::string why = l ? l->CheckDepth(depths[d], l->interface_side())
                              : (depths[d] > 0 ? "" : "receptor depth must be > 0 m");
    if (!why.empty()) {
      CopyError(why, err, errlen);
      return nullptr;
    }
  }
  e->tables = BuildKernelTables(*sub, n, pitch_m, std::vector<double>(depths, depths + ndepth),
                                comps);
  const StressCost widest = EstimateStressCost(*e->tables, e->sites, n * n, true);
  if (method == 2 || (method == 0 && widest.fft_s < widest.direct_s))
    e->spectra = BuildKernelSpectra(*e->tables, e->sites);
  if (method == 3) e->tree = StressTree::Build(*e->tables, e->sites, true, theta);
  e->out.resize(e->sites.size());
  return e.release();
}

__attribute__((visibility("default"))) void mjtouch_stress_engine_free(void* h) {
  delete static_cast<StressEngine*>(h);
}

// out6: table build s, spectra build s (0: none), padded FFT size (0: none),
// table bytes per depth, tree build s (0: none), tree terms per site.
__attribute__((visibility("default"))) void mjtouch_stress_engine_info(void* h, double* out6) {
  const auto* e = static_cast<StressEngine*>(h);
  out6[0] = e->tables->build_seconds;
  out6[1] = e->spectra ? e->spectra->build_seconds : 0.0;
  out6[2] = e->spectra ? e->spectra->fft_n : 0;
  out6[3] = e->tables->tables.empty() ? 0.0 : 4.0 * e->tables->tables[0].size();
  out6[4] = e->tree ? e->tree->build_seconds() : 0.0;
  out6[5] = e->tree ? e->tree->mean_terms() : 0.0;
}

// The cost model's estimate (s) of each path: out2 = direct, fft.
__attribute__((visibility("default"))) void mjtouch_stress_engine_cost(void* h, int active_cells,
                                                                       int shear, double* out2) {
  const auto* e = static_cast<StressEngine*>(h);
  const StressCost c = EstimateStressCost(*e->tables, e->sites, active_cells, shear != 0);
  out2[0] = c.direct_s;
  out2[1] = c.fft_s;
}

// Stress at every site (nsite x 6, Pa) from traction fields (n*n float, Pa,
// row-major j * n + i; shear_x / shear_y both null or both given). method 0
// auto, 1 direct, 2 fft, 3 tree. The stage is run `repeats` times (>= 1) and
// *seconds_per_call gets the mean wall time of one (one core; the active
// cells are found once, outside the timing, as the pressure stage gives
// them). *method_used: 1 direct, 2 fft, 3 tree; *active_cells: cells with
// traction.
__attribute__((visibility("default"))) int mjtouch_stress_engine_eval(
    void* h, const float* pressure, const float* shear_x, const float* shear_y, int method,
    int repeats, double* out, double* seconds_per_call, int* method_used, int* active_cells) {
  auto* e = static_cast<StressEngine*>(h);
  if (method < 0 || method > 3 || repeats < 1 || (!shear_x) != (!shear_y)) return 1;
  if (method == 2 && !e->spectra) return 2;
  if (method == 3 && !e->tree) return 3;
  const int n = e->tables->n;
  FindActiveRuns(n, pressure, shear_x, shear_y, &e->runs);
  StressMethod used = StressMethod::kDirect;
  const auto t0 = std::chrono::steady_clock::now();
  for (int k = 0; k < repeats; ++k)
    used = ComputeStresses(*e->tables, e->spectra.get(), e->tree.get(),
                           static_cast<StressMethod>(method),
                           e->sites, e->runs, pressure, shear_x, shear_y, &e->scratch,
                           e->out.data());
  const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (seconds_per_call) *seconds_per_call = dt / repeats;
  if (method_used) *method_used = static_cast<int>(used);
  if (active_cells) *active_cells = e->runs.Count();
  for (size_t s = 0; s < e->out.size(); ++s)
    for (int c = 0; c < kNumStress; ++c) out[6 * s + c] = e->out[s][c];
  return 0;
}

}  // extern "C"
