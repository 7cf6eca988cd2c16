#include "skin.h"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>
#include <mutex>
#include <sstream>

namespace mjtouch {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kGoldenAngle = 2.39996322972865332;  // pi (3 - sqrt 5)
// Kernel tables above this size are refused (shared per model, float32).
constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr double kDefaultRadius = 5e-3;  // receptor population, m
constexpr double kMaxTableBytes = 1024.0 * 1024.0 * 1024.0;

std::string Trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t\n\r");
  if (a == std::string::npos) return "";
  const size_t b = s.find_last_not_of(" \t\n\r");
  return s.substr(a, b - a + 1);
}

std::vector<std::string> Words(const std::string& s) {
  std::istringstream ss(s);
  std::vector<std::string> out;
  std::string w;
  while (ss >> w) out.push_back(w);
  return out;
}

std::string Fmt(const char* fmt, ...) __attribute__((format(printf, 1, 2)));
std::string Fmt(const char* fmt, ...) {
  char buf[512];
  va_list ap;
  va_start(ap, fmt);
  std::vsnprintf(buf, sizeof(buf), fmt, ap);
  va_end(ap);
  return buf;
}

bool ToDouble(const std::string& w, double* v) {
  const char* s = w.c_str();
  char* end = nullptr;
  *v = std::strtod(s, &end);
  return end != s && *end == '\0' && std::isfinite(*v);
}

// Reads attribute `key` as a number in [lo, hi] (open ends when lo_open /
// hi_open). Unset keeps *v (the default).
class Reader {
 public:
  Reader(const AttributeGetter& get, std::string* error) : get_(get), error_(error) {}
  bool ok() const { return ok_; }

  void Number(const char* key, double* v, double lo, bool lo_open, double hi,
              bool hi_open, const char* units) {
    if (!ok_) return;
    const std::string raw = Trim(get_(key));
    if (raw.empty()) return;
    double x;
    if (!ToDouble(raw, &x)) {
      Fail(Fmt("attribute `%s` = '%s' is not a number; valid range %s%g, %g%s %s",
               key, raw.c_str(), lo_open ? "(" : "[", lo, hi, hi_open ? ")" : "]", units));
      return;
    }
    const bool low = lo_open ? x <= lo : x < lo;
    const bool high = hi_open ? x >= hi : x > hi;
    if (low || high) {
      Fail(Fmt("attribute `%s` = %g is out of range; valid range %s%g, %g%s %s", key, x,
               lo_open ? "(" : "[", lo, hi, hi_open ? ")" : "]", units));
      return;
    }
    *v = x;
  }

  void Integer(const char* key, int* v, int lo, int hi) {
    if (!ok_) return;
    const std::string raw = Trim(get_(key));
    if (raw.empty()) return;
    double x;
    if (!ToDouble(raw, &x) || x != std::floor(x)) {
      Fail(Fmt("attribute `%s` = '%s' is not an integer; valid range [%d, %d]", key,
               raw.c_str(), lo, hi));
      return;
    }
    if (x < lo || x > hi) {
      Fail(Fmt("attribute `%s` = %g is out of range; valid range [%d, %d]", key, x, lo, hi));
      return;
    }
    *v = static_cast<int>(x);
  }

  void Bool(const char* key, bool* v) {
    if (!ok_) return;
    const std::string raw = Trim(get_(key));
    if (raw.empty()) return;
    if (raw == "true" || raw == "1") { *v = true; return; }
    if (raw == "false" || raw == "0") { *v = false; return; }
    Fail(Fmt("attribute `%s` = '%s' must be true or false", key, raw.c_str()));
  }

  // Exactly one number per receptor class (SA1 RA PC).
  void PerClass(const char* key, double out[kNumClasses], double lo, bool lo_open,
                double hi, bool hi_open, const char* units) {
    if (!ok_) return;
    const std::string raw = Trim(get_(key));
    if (raw.empty()) return;
    const auto w = Words(raw);
    if (w.size() != kNumClasses) {
      Fail(Fmt("attribute `%s` = '%s' needs 3 numbers (SA1 RA PC), each in %s%g, %g%s %s",
               key, raw.c_str(), lo_open ? "(" : "[", lo, hi, hi_open ? ")" : "]", units));
      return;
    }
    for (int c = 0; c < kNumClasses; ++c) {
      double x;
      const bool bad = !ToDouble(w[c], &x) || (lo_open ? x <= lo : x < lo) ||
                       (hi_open ? x >= hi : x > hi);
      if (bad) {
        Fail(Fmt("attribute `%s` entry %d ('%s', %s) is out of range; valid range %s%g, %g%s %s",
                 key, c + 1, w[c].c_str(), ClassName(static_cast<ReceptorClass>(c)),
                 lo_open ? "(" : "[", lo, hi, hi_open ? ")" : "]", units));
        return;
      }
      out[c] = x;
    }
  }

  std::string Raw(const char* key) { return ok_ ? Trim(get_(key)) : ""; }
  void Fail(const std::string& msg) {
    if (ok_) *error_ = "mjtouch.skin: " + msg;
    ok_ = false;
  }

 private:
  const AttributeGetter& get_;
  std::string* error_;
  bool ok_ = true;
};

std::array<bool, kNumStress> ComponentsFor(Quantity q) {
  std::array<bool, kNumStress> w{};
  if (q == Quantity::kCompressiveSzz) {
    w[kSzz] = true;
  } else {
    w.fill(true);
  }
  return w;
}

std::string CacheKey(const SkinConfig& c) {
  std::ostringstream s;
  s.precision(17);
  s << c.grid.n << ' ' << c.grid.pitch_m << ' ' << static_cast<int>(c.pad.shape) << ' '
    << c.pad.semi_axes_m[0] << ' ' << c.pad.semi_axes_m[1] << ' ' << c.pad.semi_axes_m[2]
    << ' ' << c.ridges.enabled << ' ' << c.ridges.pitch_m << ' ' << c.ridges.height_m << ' '
    << c.ridges.angle_rad << ' ' << c.stiffness_pa_per_m << ' ' << c.poisson << ' '
    << c.shear << ' ' << c.population_radius_m;
  for (const auto& k : c.classes)
    s << ' ' << k.present << ' ' << k.density_per_cm2 << ' ' << k.depth_m << ' '
      << static_cast<int>(k.quantity);
  const auto& r = c.receptor;
  for (double m : r.sa1.merkel_cells) s << ' ' << m;
  s << ' ' << r.sa1.k0_a_per_pa << ' ' << r.sa1.k1_a_s_per_pa << ' ' << r.sa1.i0_a << ' '
    << r.sa1.capacitance_f << ' ' << r.sa1.resistance_ohm << ' ' << r.sa1.threshold_v << ' '
    << r.sa1.refractory_s << ' ' << r.ra.gain_s_per_pa << ' ' << r.ra.tau_s << ' '
    << r.ra.refractory_s << ' ' << r.pc.gain_s_per_pa << ' ' << r.pc.highpass_hz << ' '
    << r.pc.tau_s << ' ' << r.pc.refractory_s;
  for (bool o : c.outputs) s << ' ' << o;
  return s.str();
}

}  // namespace

const char* OutputName(int block) {
  static const char* names[kNumOutputs] = {"spikes", "stress", "voltage", "force", "pressure"};
  return names[block];
}

SkinConfig::SkinConfig() {
  // Human fingertip innervation (Johansson & Vallbo 1979), per cm^2.
  // Depths: Merkel and Meissner endings at the epidermis/dermis junction
  // (~0.7-0.8 mm, Shao et al. 2010); Pacinian corpuscles ~2 mm deep.
  classes[0] = {true, 70.0, 0.75e-3, Quantity::kMaxCompressive};
  classes[1] = {true, 140.0, 0.75e-3, Quantity::kCompressiveSzz};
  classes[2] = {true, 21.0, 2.0e-3, Quantity::kCompressiveSzz};
}

const std::vector<const char*>& SkinAttributeKeys() {
  static const std::vector<const char*> keys = {
      "texture", "texture_group", "nx", "pitch", "ridges", "ridge_pitch", "ridge_height", "ridge_angle",
      "stiffness", "poisson", "shear", "classes", "density", "depth", "quantity", "radius",
      "outputs", "sa1_merkel", "sa1_k0", "sa1_k1", "sa1_i0", "sa1_c", "sa1_r", "sa1_vth",
      "ra_gain", "ra_tau", "pc_gain", "pc_tau", "pc_highpass", "refractory"};
  return keys;
}

bool ParseSkinConfig(const AttributeGetter& get, SkinConfig* cfg, std::string* error) {
  Reader r(get, error);
  r.Integer("nx", &cfg->grid.n, 4, 512);
  r.Integer("texture_group", &cfg->texture_group, 0, 5);
  r.Number("pitch", &cfg->grid.pitch_m, 0, true, 1e-2, false, "m");
  r.Bool("ridges", &cfg->ridges.enabled);
  r.Number("ridge_pitch", &cfg->ridges.pitch_m, 0, true, 1e-2, false, "m");
  r.Number("ridge_height", &cfg->ridges.height_m, 0, true, 1e-3, false, "m");
  double angle_deg = cfg->ridges.angle_rad * 180.0 / kPi;
  r.Number("ridge_angle", &angle_deg, -180, false, 180, false, "deg");
  cfg->ridges.angle_rad = angle_deg * kPi / 180.0;
  r.Number("stiffness", &cfg->stiffness_pa_per_m, 0, true, 1e12, false, "Pa/m");
  r.Number("poisson", &cfg->poisson, -1, true, 0.5, false, "");
  r.Bool("shear", &cfg->shear);
  // Unset radius: 5 mm, shrunk to fit the grid and the pad (see SkinModel::Build).
  cfg->population_radius_m = -1.0;
  r.Number("radius", &cfg->population_radius_m, 0, false, 0.1, false, "m");

  const std::string classes = r.Raw("classes");
  if (!classes.empty()) {
    for (auto& c : cfg->classes) c.present = false;
    for (const auto& w : Words(classes)) {
      int k = -1;
      for (int c = 0; c < kNumClasses; ++c)
        if (w == ClassName(static_cast<ReceptorClass>(c))) k = c;
      if (k < 0) {
        r.Fail(Fmt("attribute `classes`: unknown receptor class '%s'; valid: SA1 RA PC",
                   w.c_str()));
        break;
      }
      cfg->classes[k].present = true;
    }
  }
  double density[kNumClasses], depth[kNumClasses];
  for (int c = 0; c < kNumClasses; ++c) {
    density[c] = cfg->classes[c].density_per_cm2;
    depth[c] = cfg->classes[c].depth_m;
  }
  r.PerClass("density", density, 0, false, 1e4, false, "per cm^2");
  r.PerClass("depth", depth, 0, true, 0.02, false, "m");
  for (int c = 0; c < kNumClasses; ++c) {
    cfg->classes[c].density_per_cm2 = density[c];
    cfg->classes[c].depth_m = depth[c];
  }
  const std::string quantity = r.Raw("quantity");
  if (!quantity.empty()) {
    const auto w = Words(quantity);
    if (w.size() != kNumClasses) {
      r.Fail("attribute `quantity` needs 3 names (SA1 RA PC); valid: szz maxcomp vonmises maxshear");
    } else {
      for (int c = 0; c < kNumClasses && r.ok(); ++c) {
        if (!ParseQuantity(w[c], &cfg->classes[c].quantity)) {
          r.Fail(Fmt("attribute `quantity`: unknown quantity '%s' for %s; valid: szz maxcomp "
                     "vonmises maxshear", w[c].c_str(), ClassName(static_cast<ReceptorClass>(c))));
        }
      }
    }
  }
  const std::string outputs = r.Raw("outputs");
  if (!outputs.empty()) {
    for (bool& o : cfg->outputs) o = false;
    for (const auto& w : Words(outputs)) {
      int k = -1;
      for (int b = 0; b < kNumOutputs; ++b)
        if (w == OutputName(b)) k = b;
      if (k < 0) {
        r.Fail(Fmt("attribute `outputs`: unknown output '%s'; valid: spikes stress voltage "
                   "force pressure", w.c_str()));
        break;
      }
      cfg->outputs[k] = true;
    }
  }
  auto& p = cfg->receptor;
  const std::string merkel = r.Raw("sa1_merkel");
  if (!merkel.empty()) {
    const auto w = Words(merkel);
    std::vector<double> m;
    for (const auto& x : w) {
      double v;
      if (!ToDouble(x, &v) || v < 0 || v > 1000) {
        r.Fail("attribute `sa1_merkel`: Merkel cells per heminode must be 1 to 4 numbers in [0, 1000]");
        break;
      }
      m.push_back(v);
    }
    if (r.ok() && (m.empty() || m.size() > 4))
      r.Fail("attribute `sa1_merkel`: Merkel cells per heminode must be 1 to 4 numbers in [0, 1000]");
    if (r.ok()) p.sa1.merkel_cells = m;
  }
  r.Number("sa1_k0", &p.sa1.k0_a_per_pa, 0, false, 1e-6, false, "A/Pa");
  r.Number("sa1_k1", &p.sa1.k1_a_s_per_pa, 0, false, 1e-6, false, "A s/Pa");
  r.Number("sa1_i0", &p.sa1.i0_a, -1e-6, false, 1e-6, false, "A");
  r.Number("sa1_c", &p.sa1.capacitance_f, 0, true, 1, false, "F");
  r.Number("sa1_r", &p.sa1.resistance_ohm, 0, true, 1e15, false, "Ohm");
  r.Number("sa1_vth", &p.sa1.threshold_v, 0, true, 10, false, "V");
  r.Number("ra_gain", &p.ra.gain_s_per_pa, 0, false, 1, false, "s/Pa");
  r.Number("ra_tau", &p.ra.tau_s, 0, true, 10, false, "s");
  r.Number("pc_gain", &p.pc.gain_s_per_pa, 0, false, 1, false, "s/Pa");
  r.Number("pc_tau", &p.pc.tau_s, 0, true, 10, false, "s");
  r.Number("pc_highpass", &p.pc.highpass_hz, 0, true, 1e5, false, "Hz");
  double refractory = p.sa1.refractory_s;
  r.Number("refractory", &refractory, 0, true, 1, false, "s");
  p.sa1.refractory_s = p.ra.refractory_s = p.pc.refractory_s = refractory;
  if (!r.ok()) return false;

  // Cross-attribute checks.
  const double half = cfg->grid.HalfExtent();
  if (cfg->population_radius_m < 0) {
    cfg->population_radius_m = std::min(kDefaultRadius, half - cfg->grid.pitch_m);
    cfg->radius_is_default = true;
  } else if (cfg->population_radius_m > half - cfg->grid.pitch_m) {
    *error = Fmt("mjtouch.skin: attribute `radius` = %g m exceeds the taxel grid (nx * pitch / 2 "
                 "- pitch = %g m); valid range [0, %g] m", cfg->population_radius_m,
                 half - cfg->grid.pitch_m, half - cfg->grid.pitch_m);
    return false;
  }
  if (cfg->ridges.enabled && cfg->ridges.pitch_m < 2 * cfg->grid.pitch_m) {
    *error = Fmt("mjtouch.skin: attribute `ridge_pitch` = %g m is below two taxels (2 * pitch "
                 "= %g m); the grid cannot resolve the ridges", cfg->ridges.pitch_m,
                 2 * cfg->grid.pitch_m);
    return false;
  }
  const double table_bytes = 4.0 * kNumLoads * kNumStress * std::pow(2.0 * cfg->grid.n - 1, 2);
  if (table_bytes * 2 > kMaxTableBytes) {
    *error = Fmt("mjtouch.skin: attribute `nx` = %d needs %.0f MiB of kernel tables per depth; "
                 "the limit is %.0f MiB in all", cfg->grid.n, table_bytes / 1048576.0,
                 kMaxTableBytes / 1048576.0);
    return false;
  }
  return true;
}

std::vector<ReceptorSite> SkinModel::PlaceReceptors(const SkinConfig& cfg) {
  // Sunflower (Vogel) spiral per class: deterministic, even areal density.
  std::vector<ReceptorSite> sites;
  const double R = cfg.population_radius_m;
  const double area_cm2 = kPi * R * R * 1e4;
  std::vector<double> depths;
  for (int c = 0; c < kNumClasses; ++c) {
    const ClassConfig& k = cfg.classes[c];
    if (!k.present) continue;
    int depth_index = -1;
    for (size_t d = 0; d < depths.size(); ++d)
      if (depths[d] == k.depth_m) depth_index = static_cast<int>(d);
    if (depth_index < 0) {
      depth_index = static_cast<int>(depths.size());
      depths.push_back(k.depth_m);
    }
    const int count = static_cast<int>(std::lround(k.density_per_cm2 * area_cm2));
    for (int s = 0; s < count; ++s) {
      const double r = R * std::sqrt((s + 0.5) / count);
      const double th = s * kGoldenAngle + 0.5 * c;  // offset classes
      ReceptorSite site;
      site.cls = static_cast<ReceptorClass>(c);
      site.i = cfg.grid.Nearest(r * std::cos(th));
      site.j = cfg.grid.Nearest(r * std::sin(th));
      site.x_m = cfg.grid.Centre(site.i);
      site.y_m = cfg.grid.Centre(site.j);
      site.depth_m = k.depth_m;
      site.depth_index = depth_index;
      sites.push_back(site);
    }
  }
  return sites;
}

int SkinModel::BlockSize(const SkinConfig& cfg, int nrec, int block) {
  if (!cfg.outputs[block]) return 0;
  switch (block) {
    case kOutForce: return kForceBlockSize;
    case kOutPressure: return static_cast<int>(cfg.grid.Size());
    default: return nrec;
  }
}

int SkinModel::OutputSize(const SkinConfig& cfg, int nrec) {
  int total = 0;
  for (int b = 0; b < kNumOutputs; ++b) total += BlockSize(cfg, nrec, b);
  return total;
}

bool FinalizeSkinConfig(SkinConfig* cfg, std::string* error) {
  const double* ax = cfg->pad.semi_axes_m;
  if (!(ax[0] > 0 && ax[1] > 0 && ax[2] > 0)) {
    *error = "mjtouch.skin: the pad geom must have positive size";
    return false;
  }
  // Receptor sites must lie under the pad's skin (the receptor count depends
  // on attributes only, so this is a check, not a refit).
  const double footprint = 0.9 * std::min(ax[0], ax[1]);
  if (cfg->population_radius_m > footprint) {
    *error = Fmt("mjtouch.skin: attribute `radius` = %g m%s exceeds 0.9 x the pad's smaller "
                 "semi-axis; valid range [0, %g] m", cfg->population_radius_m,
                 cfg->radius_is_default ? " (default)" : "", footprint);
    return false;
  }
  return true;
}

std::shared_ptr<const SkinModel> SkinModel::Build(const SkinConfig& cfg_in, std::string* error) {
  SkinConfig cfg = cfg_in;
  if (!FinalizeSkinConfig(&cfg, error)) return nullptr;
  static std::mutex mu;
  static std::map<std::string, std::weak_ptr<const SkinModel>> cache;
  const std::string key = CacheKey(cfg);
  std::lock_guard<std::mutex> lock(mu);
  if (auto hit = cache[key].lock()) return hit;

  auto model = std::shared_ptr<SkinModel>(new SkinModel());
  model->cfg_ = cfg;
  model->sites_ = PlaceReceptors(cfg);
  model->skin_z_ = SkinSurface(cfg.grid, cfg.pad, cfg.ridges);
  // Kernel tables only for the depths and components the receptors use, and
  // only if an output needs stress.
  const bool need_stress = cfg.outputs[kOutSpikes] || cfg.outputs[kOutStress] ||
                           cfg.outputs[kOutVoltage];
  std::vector<double> depths;
  std::array<bool, kNumStress> comps{};
  for (const auto& s : model->sites_) {
    if (static_cast<int>(depths.size()) <= s.depth_index) depths.push_back(s.depth_m);
    const auto w = ComponentsFor(cfg.classes[static_cast<int>(s.cls)].quantity);
    for (int k = 0; k < kNumStress; ++k) comps[k] = comps[k] || w[k];
  }
  for (int c = 0; c < kNumClasses; ++c)
    model->want_.push_back(ComponentsFor(cfg.classes[c].quantity));
  if (need_stress && !depths.empty()) {
    HalfSpace half_space(cfg.poisson);
    model->kernel_ = BuildKernelTables(half_space, cfg.grid.n, cfg.grid.pitch_m, depths, comps);
  }
  cache[key] = model;
  return model;
}

std::string SkinModel::Describe() const {
  int count[kNumClasses] = {0, 0, 0};
  for (const auto& s : sites_) count[static_cast<int>(s.cls)]++;
  return Fmt("mjtouch.skin: %dx%d taxels at %.3g mm, %d SA1 / %d RA / %d PC, kernel %.3f s",
             cfg_.grid.n, cfg_.grid.n, cfg_.grid.pitch_m * 1e3, count[0], count[1], count[2],
             kernel_ ? kernel_->build_seconds : 0.0);
}

void ResetState(const SkinModel& model, double* state) {
  std::fill(state, state + model.state_size(), 0.0);
}

void Step(const SkinModel& model, const StepInput& in, double time_s, double* state,
          Workspace* ws, double* out) {
  const SkinConfig& cfg = model.config();
  const auto& sites = model.receptors();
  const int nrec = static_cast<int>(sites.size());
  double* receptor_state = state + kStateHeader;
  double* last_spikes = receptor_state + static_cast<size_t>(nrec) * kReceptorStateSize;
  double* last_voltage = last_spikes + nrec;
  // Receptors integrate over the time elapsed since the previous call, so a
  // repeated mj_forward at the same time changes nothing.
  const bool time_valid = state[3] > 0.0;
  const double elapsed = time_valid ? time_s - state[2] : 0.0;
  state[2] = time_s;
  state[3] = 1.0;

  ws->quantity.assign(nrec, 0.0);
  TractionField& tf = ws->traction;
  bool touching = false;
  if (in.in_contact && in.normal_force_n > 0.0 && !in.surfaces.empty()) {
    // Warm start: the last step's indentation depth (approach minus smallest
    // gap) bounds which cells can touch; cells provably above 1.5x that
    // depth are not rendered. If the solved contact reaches the cull level,
    // render everything and solve again, so the result is exact either way.
    const bool warm = state[1] > 0.0;
    const double depth_prev = state[0];
    const double cull_rel = warm ? 1.5 * depth_prev + 20e-6 : kInfinity;
    const double cull = RenderGap(cfg.grid, model.skin_z(), in.pad_pose, in.surfaces, cull_rel,
                                  &ws->gap, &ws->coverage);
    double gmin = kInfinity;
    for (size_t i = 0; i < ws->gap.size(); ++i)
      if (ws->coverage[i] > 0.0) gmin = std::min(gmin, ws->gap[i]);
    const double guess = warm ? gmin + depth_prev : std::nan("");
    touching = WinklerPressure(cfg.grid, ws->gap, ws->coverage, cfg.stiffness_pa_per_m,
                               in.normal_force_n, guess, &tf);
    if (touching && tf.approach_m >= cull) {
      RenderGap(cfg.grid, model.skin_z(), in.pad_pose, in.surfaces, kInfinity, &ws->gap,
                &ws->coverage);
      touching = WinklerPressure(cfg.grid, ws->gap, ws->coverage, cfg.stiffness_pa_per_m,
                                 in.normal_force_n, std::nan(""), &tf);
    }
    if (touching) {
      gmin = kInfinity;
      for (size_t i = 0; i < ws->gap.size(); ++i)
        if (ws->coverage[i] > 0.0) gmin = std::min(gmin, ws->gap[i]);
      state[0] = tf.approach_m - gmin;
    }
  }
  if (touching) {
    state[1] = 1.0;
    if (cfg.shear) UniformSlipShear(cfg.grid, in.normal_force_n, in.shear_x_n, in.shear_y_n, &tf);
    const KernelTables* kt = model.kernel();
    if (kt) {
      for (int r = 0; r < nrec; ++r) {
        const ReceptorSite& s = sites[r];
        const int c = static_cast<int>(s.cls);
        Stress6 sig;
        StressAtReceptor(*kt, s.depth_index, s.i, s.j, tf.runs, tf.pressure.data(),
                         cfg.shear ? tf.shear_x.data() : nullptr,
                         cfg.shear ? tf.shear_y.data() : nullptr, model.wanted(c), &sig);
        ws->quantity[r] = ReceptorQuantity(cfg.classes[c].quantity, sig.data());
      }
    }
  } else {
    state[1] = 0.0;
  }

  // Receptors advance every step (membranes decay without contact).
  const bool need_receptors = cfg.outputs[kOutSpikes] || cfg.outputs[kOutVoltage];
  if (need_receptors) {
    for (int r = 0; r < nrec; ++r) {
      double* st = receptor_state + static_cast<size_t>(r) * kReceptorStateSize;
      if (elapsed > 0.0) {
        double v;
        last_spikes[r] = AdvanceReceptor(sites[r].cls, cfg.receptor, ws->quantity[r],
                                         elapsed, st, &v);
        last_voltage[r] = v;
      } else if (!time_valid) {
        PrimeReceptor(ws->quantity[r], st);
      }
    }
  }
  double* cursor = out;
  if (cfg.outputs[kOutSpikes]) {
    std::copy(last_spikes, last_spikes + nrec, cursor);
    cursor += nrec;
  }
  if (cfg.outputs[kOutStress]) {
    std::copy(ws->quantity.begin(), ws->quantity.end(), cursor);
    cursor += nrec;
  }
  if (cfg.outputs[kOutVoltage]) {
    std::copy(last_voltage, last_voltage + nrec, cursor);
    cursor += nrec;
  }
  if (cfg.outputs[kOutForce]) {
    cursor[0] = touching ? in.normal_force_n : 0.0;
    cursor[1] = touching ? in.shear_x_n : 0.0;
    cursor[2] = touching ? in.shear_y_n : 0.0;
    cursor[3] = touching ? state[0] : 0.0;  // indentation depth
    cursor += kForceBlockSize;
  }
  if (cfg.outputs[kOutPressure]) {
    const size_t N = cfg.grid.Size();
    for (size_t i = 0; i < N; ++i) cursor[i] = touching ? tf.pressure[i] : 0.0;
    cursor += N;
  }
}

}  // namespace mjtouch
