// C API over the pure-C++ stages, for Python (ctypes) and tests: every stage
// can be called without a MuJoCo scene. Errors are returned as nonzero codes
// with a message in a caller buffer; nothing throws across this boundary.
#include <cmath>
#include <cstring>
#include <map>
#include <sstream>
#include <string>

#include "kernel.h"
#include "pressure.h"
#include "receptors.h"
#include "skin.h"
#include "surface.h"

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
  const bool ok = WinklerPressure(grid, g, c, stiffness, force, std::nan(""), &tf);
  std::memcpy(pressure_out, tf.pressure.data(), grid.Size() * sizeof(float));
  *approach_out = tf.approach_m;
  return ok ? 0 : 2;
}

// Drive one receptor of class `cls` (0 SA1, 1 RA, 2 PC) with the quantity
// trace q (Pa) sampled every dt; receptor parameters from `config`
// (attribute=value pairs). Writes spikes per step and voltages.
__attribute__((visibility("default"))) int mjtouch_receptor_run(
    const char* config, int cls, const double* q, int nsteps, double dt, double* spikes,
    double* voltage, char* err, int errlen) {
  SkinConfig cfg;
  std::string error;
  if (!ParseConfigText(config, &cfg, &error)) {
    CopyError(error, err, errlen);
    return 1;
  }
  if (cls < 0 || cls >= kNumClasses || !(dt > 0)) {
    CopyError("class must be 0 (SA1), 1 (RA) or 2 (PC) and dt > 0", err, errlen);
    return 1;
  }
  double state[kReceptorStateSize] = {0};
  PrimeReceptor(q[0], state);
  for (int k = 0; k < nsteps; ++k) {
    double v = 0;
    const int s = AdvanceReceptor(static_cast<ReceptorClass>(cls), cfg.receptor, q[k], dt,
                                  state, &v);
    if (spikes) spikes[k] = s;
    if (voltage) voltage[k] = v;
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
