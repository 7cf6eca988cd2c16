#include "pipeline/skin.h"

#include <algorithm>
#include <cmath>
#include <cerrno>
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

// The elastic skin: `skin` (layered | halfspace), `layers` ("thickness E nu"
// groups separated by ';' or ','; m, Pa, -), `base` (rigid | "E nu"),
// `interface_side` (upper | lower), `stress_method` (tree | direct | fft |
// auto), `stress_theta` (tree's opening angle).
void ParseElasticSkin(Reader& r, SkinConfig* cfg) {
  constexpr double kMaxThicknessM = 1.0, kMaxYoungPa = 1e12;
  constexpr size_t kMaxLayers = 64;  // LayeredSubstrate::Create's limit
  const std::string method = r.Raw("stress_method");
  if (!method.empty() && !ParseStressMethod(method, &cfg->stress_method))
    r.Fail(Fmt("attribute `stress_method` = '%s' is not one of: tree direct fft auto",
               method.c_str()));
  r.Number("stress_theta", &cfg->stress_theta, 0, true, 2, false, "(block side / distance)");
  if (r.ok() && !r.Raw("stress_theta").empty() && cfg->stress_method != StressMethod::kTree)
    r.Fail(Fmt("attribute `stress_theta` applies to stress_method=\"tree\" only (stress_method "
               "is \"%s\")", StressMethodName(cfg->stress_method)));
  const std::string skin = r.Raw("skin");
  if (skin == "layered") {
    cfg->layered = true;
  } else if (skin == "halfspace") {
    cfg->layered = false;
  } else if (!skin.empty()) {
    r.Fail(Fmt("attribute `skin` = '%s' is not one of: layered halfspace", skin.c_str()));
  }
  if (!r.ok()) return;
  if (!cfg->layered) {
    for (const char* key : {"layers", "base", "interface_side"}) {
      if (!r.Raw(key).empty()) {
        r.Fail(Fmt("attribute `%s` applies to skin=\"layered\" only (skin is \"halfspace\")", key));
        return;
      }
    }
    return;
  }
  for (const char* key : {"poisson", "young"}) {
    if (!r.Raw(key).empty()) {
      r.Fail(Fmt("attribute `%s` applies to skin=\"halfspace\" only; the layered skin takes its "
                 "moduli from `layers` (and `base`)", key));
      return;
    }
  }
  // One number of a layer or of the base, with its valid range.
  auto number = [&](const char* key, const std::string& what, const std::string& word, double lo,
                    double hi, const char* units, double* v) {
    double x;
    if (!ToDouble(word, &x) || x <= lo || x > hi) {
      r.Fail(Fmt("attribute `%s`: %s = '%s' is out of range; valid range (%g, %g] %s", key,
                 what.c_str(), word.c_str(), lo, hi, units));
      return false;
    }
    *v = x;
    return true;
  };
  const std::string layers = r.Raw("layers");
  if (!layers.empty()) {
    std::string text = layers;
    for (char& ch : text)
      if (ch == ';' || ch == ',') ch = '\n';
    std::istringstream groups(text);
    std::string group;
    std::vector<ElasticLayer> stack;
    while (std::getline(groups, group)) {
      const auto w = Words(group);
      if (w.empty()) continue;
      const int k = static_cast<int>(stack.size()) + 1;
      if (w.size() != 3) {
        r.Fail(Fmt("attribute `layers`: layer %d ('%s') needs 3 numbers: thickness (m), Young's "
                   "modulus E (Pa), Poisson's ratio nu; layers are separated by ';'",
                   k, Trim(group).c_str()));
        return;
      }
      ElasticLayer l;
      if (!number("layers", Fmt("layer %d thickness", k), w[0], 0, kMaxThicknessM, "m",
                  &l.thickness_m) ||
          !number("layers", Fmt("layer %d E", k), w[1], 0, kMaxYoungPa, "Pa", &l.young_pa) ||
          !number("layers", Fmt("layer %d nu", k), w[2], -1, 0.5, "", &l.poisson))
        return;
      stack.push_back(l);
    }
    if (stack.empty()) {
      r.Fail("attribute `layers` has no layer (empty stack); valid: 1 to 64 groups 'thickness E "
             "nu' (m, Pa, -) separated by ';'");
      return;
    }
    if (stack.size() > kMaxLayers) {
      r.Fail(Fmt("attribute `layers` has %d layers; valid: 1 to 64",
                 static_cast<int>(stack.size())));
      return;
    }
    cfg->layers = stack;
  }
  const std::string base = r.Raw("base");
  if (base == "rigid") {
    cfg->base = LayeredBase{};
  } else if (!base.empty()) {
    const auto w = Words(base);
    LayeredBase b;
    b.rigid = false;
    if (w.size() != 2) {
      r.Fail(Fmt("attribute `base` = '%s' must be 'rigid' (bone) or 'E nu' (an elastic "
                 "half-space: E in (0, %g] Pa, nu in (-1, 0.5])", base.c_str(), kMaxYoungPa));
      return;
    }
    if (!number("base", "E", w[0], 0, kMaxYoungPa, "Pa", &b.young_pa) ||
        !number("base", "nu", w[1], -1, 0.5, "", &b.poisson))
      return;
    cfg->base = b;
  }
  const std::string side = r.Raw("interface_side");
  if (side == "upper") {
    cfg->interface_side = InterfaceSide::kUpper;
  } else if (side == "lower") {
    cfg->interface_side = InterfaceSide::kLower;
  } else if (!side.empty()) {
    r.Fail(Fmt("attribute `interface_side` = '%s' is not one of: upper lower", side.c_str()));
  }
}

bool NeedsMaterial(Quantity q) {
  return q == Quantity::kStrainEnergy || q == Quantity::kCompressiveStrain;
}

// Receptor quantity from the stress; strain and SED from the material at the
// receptor (the layer's E and nu).
double QuantityAt(Quantity q, const Stress6& stress, const Material& m) {
  switch (q) {
    case Quantity::kStrainEnergy: return StrainEnergyDensity(stress, m);
    case Quantity::kCompressiveStrain: {
      const Stress6 strain = StrainFromStress(stress, m);
      return ReceptorQuantity(Quantity::kMaxCompressive, strain.data());
    }
    default: return ReceptorQuantity(q, stress.data());
  }
}

// Receptor depths inside the elastic skin; strain and SED need a material.
bool CheckElasticSkin(const SkinConfig& cfg, std::string* error) {
  std::unique_ptr<LayeredSubstrate> sub;
  if (cfg.layered) {
    std::string why;
    sub = LayeredSubstrate::Create(cfg.layers, cfg.base, cfg.interface_side, &why);
    if (!sub) {
      *error = "mjtouch.skin: attribute `layers` / `base`: " + why;
      return false;
    }
  }
  for (int c = 0; c < kNumClasses; ++c) {
    const ClassConfig& k = cfg.classes[c];
    if (!k.present) continue;
    const char* name = ClassName(static_cast<ReceptorClass>(c));
    if (!sub) {
      if (NeedsMaterial(k.quantity)) {
        *error = Fmt("mjtouch.skin: attribute `quantity`: '%s' for %s needs skin=\"layered\" (a "
                     "homogeneous half-space skin has no Young's modulus); valid with "
                     "skin=\"halfspace\": szz maxcomp vonmises maxshear",
                     QuantityName(k.quantity), name);
        return false;
      }
      continue;
    }
    const std::string why = sub->CheckDepth(k.depth_m, cfg.interface_side);
    if (!why.empty()) {
      const bool upper = cfg.interface_side == InterfaceSide::kUpper;
      // The depth came from `sites` (its first entry of this class) or `depth`.
      std::string where = Fmt("`depth` entry %d", c + 1);
      for (size_t e = 0; e < cfg.sites.size(); ++e) {
        if (static_cast<int>(cfg.sites[e].cls) == c) {
          where = Fmt("`sites` entry %zu", e + 1);
          break;
        }
      }
      *error = Fmt("mjtouch.skin: attribute %s (%s, %g m) is outside the elastic skin (%s); "
                   "valid range (0, %g%s m for these `layers` over a rigid `base`%s",
                   where.c_str(), name, k.depth_m, why.c_str(), sub->stack_depth_m(),
                   upper ? "]" : ")", upper ? "" : " with interface_side=\"lower\"");
      return false;
    }
  }
  return true;
}

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
    << c.ridges.angle_rad << ' ' << static_cast<int>(c.ridges.profile) << ' '
    << static_cast<int>(c.pressure_model) << ' ' << c.young_pa
    << ' ' << c.tolerance << ' ' << c.stiffness_pa_per_m << ' ' << c.poisson << ' '
    << c.shear << ' ' << c.population_radius_m;
  for (const auto& k : c.classes)
    s << ' ' << k.present << ' ' << k.density_per_cm2 << ' ' << k.depth_m << ' '
      << static_cast<int>(k.quantity);
  s << " receptors " << ReceptorParamsKey(c.receptor) << " sites";
  for (const auto& e : c.sites)
    s << ' ' << static_cast<int>(e.cls) << ' ' << e.x_m << ' ' << e.y_m << ' ' << e.depth_m;
  for (bool o : c.outputs) s << ' ' << o;
  s << " skin " << c.layered << ' ' << c.base.rigid << ' ' << c.base.young_pa << ' '
    << c.base.poisson << ' ' << static_cast<int>(c.interface_side) << ' '
    << static_cast<int>(c.stress_method) << ' ' << c.stress_theta << ' ' << c.oversample;
  for (const auto& l : c.layers) s << ' ' << l.thickness_m << ' ' << l.young_pa << ' ' << l.poisson;
  return s.str();
}

// Stage 4 attributes: afferent parameters (README "Afferent models") and
// explicit receptor sites. Call after `classes`, `quantity` and the grid.
void ParseAfferents(Reader& r, SkinConfig* cfg) {
  auto& p = cfg->receptor;
  // SA1 gains default to the Wang 2016 Table 1 row of the SA1 quantity.
  WangTable1Gains(cfg->classes[0].quantity, &p.sa1);
  r.Number("sa1_k0", &p.sa1.k0_a_per_pa, 0, false, 1e-6, false, "A per unit of q");
  r.Number("sa1_k1", &p.sa1.k1_a_s_per_pa, 0, false, 1e-6, false, "A s per unit of q");
  r.Number("sa1_i0", &p.sa1.i0_a, -1e-6, false, 1e-6, false, "A");
  r.Number("sa1_c", &p.sa1.capacitance_f, 0, true, 1, false, "F");
  r.Number("sa1_r", &p.sa1.resistance_ohm, 0, true, 1e15, false, "Ohm");
  r.Number("sa1_vth", &p.sa1.threshold_v, 0, true, 10, false, "V");
  r.Number("ra_gain", &p.ra.gain_s_per_pa, 0, false, 1, false, "s/Pa");
  r.Number("ra_lowpass", &p.ra.lowpass_hz, 0, true, 1e4, false, "Hz");
  r.Number("ra_tau", &p.ra.tau_s, 0, true, 10, false, "s");
  r.Number("pc_gain", &p.pc.gain_s2_per_pa, 0, false, 1, false, "s^2/Pa");
  r.Number("pc_highpass", &p.pc.highpass_hz, 0, true, 1e5, false, "Hz");
  r.Number("pc_lowpass", &p.pc.lowpass_hz, 0, true, 1e5, false, "Hz");
  r.Number("pc_tau", &p.pc.tau_s, 0, true, 10, false, "s");
  double refractory = p.sa1.refractory_s;
  r.Number("refractory", &refractory, 0, true, 1, false, "s");
  p.sa1.refractory_s = p.ra.refractory_s = p.pc.refractory_s = refractory;
  r.PerClass("noise", p.noise.sd, 0, false, 100, false, "(threshold units)");
  r.Number("noise_tau", &p.noise.tau_s, 0, true, 10, false, "s");
  const std::string seed = r.Raw("seed");
  if (!seed.empty()) {
    char* end = nullptr;
    errno = 0;
    const unsigned long long v = std::strtoull(seed.c_str(), &end, 10);
    if (seed[0] == '-' || *end != '\0' || errno == ERANGE) {
      r.Fail(Fmt("attribute `seed` = '%s' is not an integer in [0, 18446744073709551615]",
                 seed.c_str()));
    } else {
      p.noise.seed = v;
    }
  }
  r.Number("rate_tau", &p.rate_tau_s, 0, true, 100, false, "s");

  // Explicit sites: "CLASS x y depth" (m, pad frame), entries separated by
  // ';' or ','. They replace the density population.
  std::string sites = r.Raw("sites");
  if (sites.empty() || !r.ok()) return;
  for (const char* key : {"classes", "density", "depth", "radius"}) {
    if (!r.Raw(key).empty()) {
      r.Fail(Fmt("attribute `sites` places the receptors explicitly; remove `%s` (valid with "
                 "`sites`: per-class `quantity` and the afferent parameters)", key));
      return;
    }
  }
  for (char& ch : sites)
    if (ch == ';' || ch == ',') ch = ' ';
  const auto w = Words(sites);
  const char* form = "entries 'CLASS x y depth' (CLASS in SA1 RA PC; x, y, depth in m)";
  if (w.size() % 4 != 0) {
    r.Fail(Fmt("attribute `sites` has %zu words; it needs %s separated by ';' or ','",
               w.size(), form));
    return;
  }
  const double limit = cfg->grid.HalfExtent() - cfg->grid.pitch_m;
  bool depth_set[kNumClasses] = {false, false, false};
  for (auto& k : cfg->classes) k.present = false;
  for (size_t e = 0; e < w.size(); e += 4) {
    int c = -1;
    for (int k = 0; k < kNumClasses; ++k)
      if (w[e] == ClassName(static_cast<ReceptorClass>(k))) c = k;
    double x, y, depth;
    if (c < 0 || !ToDouble(w[e + 1], &x) || !ToDouble(w[e + 2], &y) ||
        !ToDouble(w[e + 3], &depth)) {
      r.Fail(Fmt("attribute `sites` entry %zu ('%s %s %s %s') is not one of %s", e / 4 + 1,
                 w[e].c_str(), w[e + 1].c_str(), w[e + 2].c_str(), w[e + 3].c_str(), form));
      return;
    }
    if (std::abs(x) > limit || std::abs(y) > limit) {
      r.Fail(Fmt("attribute `sites` entry %zu (%s at x = %g, y = %g m) is outside the taxel "
                 "grid; valid range |x|, |y| <= nx * pitch / 2 - pitch = %g m", e / 4 + 1,
                 w[e].c_str(), x, y, limit));
      return;
    }
    ClassConfig& k = cfg->classes[c];
    if (!(depth > 0 && depth <= 0.02)) {
      r.Fail(Fmt("attribute `sites` entry %zu (%s) depth = %g m is out of range; valid range "
                 "(0, 0.02] m", e / 4 + 1, w[e].c_str(), depth));
      return;
    }
    if (depth_set[c] && depth != k.depth_m) {
      r.Fail(Fmt("attribute `sites` entry %zu: every %s site must have the same depth (its "
                 "kernel table and material); got %g and %g m", e / 4 + 1, w[e].c_str(),
                 k.depth_m, depth));
      return;
    }
    depth_set[c] = true;
    k.present = true;
    k.depth_m = depth;
    cfg->sites.push_back({static_cast<ReceptorClass>(c), x, y, depth});
  }
}

}  // namespace

const char* OutputName(int block) {
  static const char* names[kNumOutputs] = {"spikes", "stress", "voltage", "force", "pressure",
                                           "rate"};
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
      "ridge_profile",
      "pressure", "young", "tolerance", "stiffness", "poisson", "shear", "classes", "density", "depth", "quantity", "radius",
      "outputs", "sa1_merkel", "sa1_k0", "sa1_k1", "sa1_i0", "sa1_c", "sa1_r", "sa1_vth",
      "ra_gain", "ra_tau", "pc_gain", "pc_tau", "pc_highpass", "refractory", "visual",
      "ra_lowpass", "pc_lowpass", "noise", "noise_tau", "seed", "rate_tau", "sites",
      "skin", "layers", "base", "interface_side", "stress_method", "stress_theta", "oversample"};
  return keys;
}

bool ParseSkinConfig(const AttributeGetter& get, SkinConfig* cfg, std::string* error) {
  Reader r(get, error);
  r.Integer("nx", &cfg->grid.n, 4, 512);
  r.Integer("texture_group", &cfg->texture_group, 0, 5);
  r.Number("pitch", &cfg->grid.pitch_m, 0, true, 1e-2, false, "m");
  r.Bool("ridges", &cfg->ridges.enabled);
  r.Number("ridge_pitch", &cfg->ridges.pitch_m, 0, true, 1e-2, false, "m");
  cfg->ridge_pitch_is_default = r.Raw("ridge_pitch").empty();
  r.Number("ridge_height", &cfg->ridges.height_m, 0, true, 1e-3, false, "m");
  const std::string profile = r.Raw("ridge_profile");
  if (!profile.empty() && !ParseRidgeProfile(profile, &cfg->ridges.profile)) {
    r.Fail(Fmt("attribute `ridge_profile` = '%s' is not a ridge profile; valid: sine triangle "
               "square", profile.c_str()));
  }
  double angle_deg = cfg->ridges.angle_rad * 180.0 / kPi;
  r.Number("ridge_angle", &angle_deg, -180, false, 180, false, "deg");
  cfg->ridges.angle_rad = angle_deg * kPi / 180.0;
  const std::string pressure = r.Raw("pressure");
  if (!pressure.empty() && !ParsePressureModel(pressure, &cfg->pressure_model)) {
    r.Fail(Fmt("attribute `pressure` = '%s' is not a pressure model; valid: contacts winkler "
               "elastic", pressure.c_str()));
  }
  const std::string oversample = Trim(r.Raw("oversample"));
  double count = 0;
  if (!oversample.empty() && oversample != "auto" &&
      (!ToDouble(oversample, &count) || count != std::floor(count) || count < 1 || count > 64)) {
    r.Fail(Fmt("attribute `oversample` = '%s' is not valid; valid: auto or an integer in [1, 64]",
               oversample.c_str()));
  } else if (!oversample.empty() && oversample != "auto") {
    cfg->oversample = static_cast<int>(count);
  }
  if (r.ok() && cfg->oversample > 1 && cfg->pressure_model == PressureModel::kContacts)
    r.Fail("attribute `oversample` needs pressure=\"winkler\" or \"elastic\" (the contacts model "
           "has no geometry to interpolate over the step); valid with contacts: 1");
  r.Number("young", &cfg->young_pa, 0, true, 1e10, false, "Pa");
  r.Number("tolerance", &cfg->tolerance, 0, true, 0.1, false, "");
  r.Number("stiffness", &cfg->stiffness_pa_per_m, 0, true, 1e12, false, "Pa/m");
  r.Number("poisson", &cfg->poisson, -1, true, 0.5, false, "");
  r.Bool("shear", &cfg->shear);
  const std::string visual = r.Raw("visual");
  if (!visual.empty()) {
    static const char* kVisual[] = {"none", "pad", "above", "both"};
    int k = -1;
    for (int v = 0; v < 4; ++v)
      if (visual == kVisual[v]) k = v;
    if (k < 0) {
      r.Fail(Fmt("attribute `visual` = '%s' is not one of: none pad above both", visual.c_str()));
    } else {
      cfg->visual = static_cast<VisualMode>(k);
    }
  }
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
      r.Fail("attribute `quantity` needs 3 names (SA1 RA PC); valid: szz maxcomp vonmises maxshear "
             "sed strain");
    } else {
      for (int c = 0; c < kNumClasses && r.ok(); ++c) {
        if (!ParseQuantity(w[c], &cfg->classes[c].quantity)) {
          r.Fail(Fmt("attribute `quantity`: unknown quantity '%s' for %s; valid: szz maxcomp "
                     "vonmises maxshear sed strain", w[c].c_str(),
                     ClassName(static_cast<ReceptorClass>(c))));
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
                   "force pressure rate", w.c_str()));
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
  ParseAfferents(r, cfg);
  if (r.ok()) ParseElasticSkin(r, cfg);
  if (!r.ok()) return false;
  if (!CheckElasticSkin(*cfg, error)) return false;

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
    *error = Fmt("mjtouch.skin: attribute `ridge_pitch` = %g m%s is below two taxels (2 x "
                 "`pitch` = %g m); the grid cannot resolve the ridges: valid `ridge_pitch` >= %g "
                 "m, or `pitch` <= %g m, or ridges=\"false\"", cfg->ridges.pitch_m,
                 cfg->ridge_pitch_is_default ? " (default)" : "", 2 * cfg->grid.pitch_m,
                 2 * cfg->grid.pitch_m, cfg->ridges.pitch_m / 2);
    return false;
  }
  return true;
}

bool CheckTactileRate(const SkinConfig& cfg, double timestep_s, std::string* error) {
  // Only the afferents filter: without spikes, voltage or rate outputs the
  // stress is merely sampled.
  const bool afferents =
      cfg.outputs[kOutSpikes] || cfg.outputs[kOutVoltage] || cfg.outputs[kOutRate];
  if (!(timestep_s > 0.0) || !afferents) return true;
  const double rate_hz = cfg.oversample / timestep_s;
  const struct { ReceptorClass cls; double corner_hz; const char* key; } bands[] = {
      {ReceptorClass::kPC, cfg.receptor.pc.lowpass_hz, "pc_lowpass"},
      {ReceptorClass::kRA, cfg.receptor.ra.lowpass_hz, "ra_lowpass"}};
  for (const auto& b : bands) {
    if (!cfg.classes[static_cast<int>(b.cls)].present) continue;
    const double need_hz = 8.0 * b.corner_hz;
    if (rate_hz >= need_hz * (1 - 1e-12)) continue;
    const int k = static_cast<int>(std::ceil(need_hz * timestep_s * (1 - 1e-12)));
    *error = Fmt("mjtouch.skin: %s afferents need tactile sampling of at least %g Hz (8 x `%s` "
                 "= %g Hz: their band reaches a few times the corner); the timestep %g s with "
                 "`oversample` = %d samples at %g Hz: set `oversample` >= %d (valid [1, 64]), "
                 "or remove %s from `classes`", ClassName(b.cls), need_hz, b.key, b.corner_hz,
                 timestep_s, cfg.oversample, rate_hz, k, ClassName(b.cls));
    return false;
  }
  return true;
}

void ResolveOversample(SkinConfig* cfg, double timestep_s) {
  if (cfg->oversample > 0) return;
  cfg->oversample = 1;
  if (cfg->pressure_model == PressureModel::kContacts || !(timestep_s > 0.0)) return;
  std::string unused;
  while (cfg->oversample < 64 && !CheckTactileRate(*cfg, timestep_s, &unused)) ++cfg->oversample;
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
    if (!cfg.sites.empty()) {  // `sites`: this class's entries, in the order given
      for (const auto& e : cfg.sites) {
        if (static_cast<int>(e.cls) != c) continue;
        ReceptorSite site;
        site.cls = e.cls;
        site.i = cfg.grid.Nearest(e.x_m);
        site.j = cfg.grid.Nearest(e.y_m);
        site.x_m = cfg.grid.Centre(site.i);
        site.y_m = cfg.grid.Centre(site.j);
        site.depth_m = k.depth_m;
        site.depth_index = depth_index;
        sites.push_back(site);
      }
      continue;
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
  for (size_t e = 0; e < cfg->sites.size(); ++e) {
    const ExplicitSite& s = cfg->sites[e];
    if (std::hypot(s.x_m, s.y_m) > footprint) {
      *error = Fmt("mjtouch.skin: attribute `sites` entry %zu (%s at x = %g, y = %g m) is not "
                   "under the pad; valid: within %g m of the pole (0.9 x the smaller semi-axis)",
                   e + 1, ClassName(s.cls), s.x_m, s.y_m, footprint);
      return false;
    }
  }
  if (cfg->sites.empty() && cfg->population_radius_m > footprint) {
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
  model->skin_blocks_ = MakeSkinBlocks(cfg.grid, model->skin_z_);
  // Kernel tables only for the depths and components the receptors use, and
  // only if an output needs stress.
  const bool need_stress = cfg.outputs[kOutSpikes] || cfg.outputs[kOutStress] ||
                           cfg.outputs[kOutVoltage] || cfg.outputs[kOutRate];
  std::vector<double> depths;
  std::array<bool, kNumStress> comps{};
  for (const auto& s : model->sites_) {
    if (static_cast<int>(depths.size()) <= s.depth_index) depths.push_back(s.depth_m);
    const auto w = ComponentsFor(cfg.classes[static_cast<int>(s.cls)].quantity);
    for (int k = 0; k < kNumStress; ++k) comps[k] = comps[k] || w[k];
  }
  for (int c = 0; c < kNumClasses; ++c)
    model->want_.push_back(ComponentsFor(cfg.classes[c].quantity));
  // The elastic skin, and the material at each class's depth.
  if (!CheckElasticSkin(cfg, error)) return nullptr;
  if (cfg.layered) {
    std::string why;
    std::shared_ptr<LayeredSubstrate> layered =
        LayeredSubstrate::Create(cfg.layers, cfg.base, cfg.interface_side, &why);
    if (!layered) {
      *error = "mjtouch.skin: attribute `layers` / `base`: " + why;
      return nullptr;
    }
    for (int c = 0; c < kNumClasses; ++c)
      model->material_[c] = layered->MaterialAt(cfg.classes[c].depth_m,
                                                cfg.interface_side == InterfaceSide::kUpper);
    model->layered_ = layered.get();
    model->substrate_ = std::move(layered);
  } else {
    model->substrate_ = std::make_shared<HalfSpace>(cfg.poisson);
  }
  for (const auto& s : model->sites_)
    model->stress_sites_.push_back({s.i, s.j, s.depth_index, model->want_[static_cast<int>(s.cls)]});
  if (need_stress && !depths.empty()) {
    model->kernel_ = BuildKernelTables(*model->substrate_, cfg.grid.n, cfg.grid.pitch_m, depths,
                                       comps);
    const KernelTables& kt = *model->kernel_;
    if (cfg.stress_method == StressMethod::kTree) {
      model->tree_ = StressTree::Build(kt, model->stress_sites_, cfg.shear, cfg.stress_theta);
    } else {
      // FFT spectra only where the FFT path can win (for the widest possible
      // contact, every cell active) and fits in memory.
      constexpr double kMaxSpectraBytes = 256.0 * 1024 * 1024;
      const double bytes = KernelSpectraBytes(kt, model->stress_sites_);
      const StressCost widest =
          EstimateStressCost(kt, model->stress_sites_, cfg.grid.n * cfg.grid.n, cfg.shear);
      if (cfg.stress_method == StressMethod::kFft && bytes > kMaxSpectraBytes) {
        *error = Fmt("mjtouch.skin: attribute `stress_method` = fft needs %.0f MiB of kernel "
                     "spectra at nx = %d; the limit is %.0f MiB (use tree, auto or direct)",
                     bytes / 1048576.0, cfg.grid.n, kMaxSpectraBytes / 1048576.0);
        return nullptr;
      }
      const bool fft = cfg.stress_method == StressMethod::kFft ||
                       (cfg.stress_method == StressMethod::kAuto && bytes <= kMaxSpectraBytes &&
                        widest.fft_s < widest.direct_s);
      if (fft) model->spectra_ = BuildKernelSpectra(kt, model->stress_sites_);
    }
  }
  if (cfg.pressure_model == PressureModel::kElastic) {
    // Surface compliance of the skin: the layered stack's, or a homogeneous
    // half-space's (young, poisson).
    model->elastic_ = std::make_shared<ElasticContact>(
        model->layered_
            ? LayeredCompliance(*model->layered_, cfg.grid.pitch_m, cfg.grid.n)
            : HalfSpaceCompliance(cfg.young_pa, cfg.poisson, cfg.grid.pitch_m, cfg.grid.n));
  }
  cache[key] = model;
  return model;
}

std::string SkinModel::Describe() const {
  int count[kNumClasses] = {0, 0, 0};
  for (const auto& s : sites_) count[static_cast<int>(s.cls)]++;
  return Fmt("mjtouch.skin: %dx%d taxels at %.3g mm, %d SA1 / %d RA / %d PC, kernel %.3f s "
             "(%s%s)", cfg_.grid.n, cfg_.grid.n, cfg_.grid.pitch_m * 1e3, count[0], count[1],
             count[2], kernel_build_seconds(), substrate_->Describe().c_str(),
             spectra_ ? "; FFT spectra built"
                      : (tree_ ? Fmt("; stress tree, theta %g, %.0f terms per receptor",
                                     tree_->theta(), tree_->mean_terms()).c_str()
                               : ""));
}

double SkinModel::kernel_build_seconds() const {
  return (kernel_ ? kernel_->build_seconds : 0.0) + (spectra_ ? spectra_->build_seconds : 0.0) +
         (tree_ ? tree_->build_seconds() : 0.0);
}

void ResetState(const SkinModel& model, double* state) {
  std::fill(state, state + model.state_size(), 0.0);
}

namespace {

const ReceptorStepper& StepperFor(const ReceptorParams& p, double dt_s, Workspace* ws) {
  if (!ws->stepper || ws->stepper->dt() != dt_s)
    ws->stepper = std::make_shared<const ReceptorStepper>(p, dt_s);
  return *ws->stepper;
}

}  // namespace

namespace {

// Stages 1-4 at time_s: receptors advance over the time since the last
// evaluation. Leaves the quantities in ws->quantity and each receptor's
// spike count and voltage in `state`; returns whether the skin touches and
// adds the spikes fired to *fired.
bool Evaluate(const SkinModel& model, const StepInput& in, double time_s, double* state,
              Workspace* ws, int* fired) {
  const SkinConfig& cfg = model.config();
  const auto& sites = model.receptors();
  const int nrec = static_cast<int>(sites.size());
  double* receptor_state = state + kStateHeader;
  double* last_spikes = receptor_state + static_cast<size_t>(nrec) * kReceptorStateSize;
  double* last_voltage = last_spikes + nrec;
  // Receptors integrate over the time elapsed since the previous call, so a
  // repeated mj_forward at the same time changes nothing.
  const bool time_valid = state[kStTimeValid] > 0.0;
  const double elapsed = time_valid ? time_s - state[kStLastTime] : 0.0;
  state[kStLastTime] = time_s;
  state[kStTimeValid] = 1.0;

  const TractionField& tf = ws->traction;
  // Stages 1-2: gap and tractions (skin_traction.cc).
  const bool touching = ComputeTraction(model, in, state, ws);
  const bool need_receptors =
      cfg.outputs[kOutSpikes] || cfg.outputs[kOutVoltage] || cfg.outputs[kOutRate];
  // Idle receptors: untouched, quiescent receptors (ReceptorStepper::Quiescent)
  // are not advanced while nothing touches and no output shows their
  // relaxing membranes; the idle time is made up in one exact step when
  // contact resumes. An untouched skin then costs O(1) per step.
  const bool idle = state[kStReceptorsIdle] > 0.0;
  if (!touching && idle && elapsed >= 0.0) {
    // Nothing to do: the last spike counts are zero (idle is entered only
    // after a step without spikes).
    return false;
  }
  ws->quantity.assign(nrec, 0.0);
  const KernelTables* kt = model.kernel();
  if (touching && kt) {
    // Stage 3: stress at the receptors (direct, FFT or tree).
    ws->stress.resize(nrec);
    ws->last_stress_method = ComputeStresses(
        *kt, model.spectra(), model.tree(), cfg.stress_method, model.stress_sites(), tf.runs,
        tf.pressure.data(), cfg.shear ? tf.shear_x.data() : nullptr,
        cfg.shear ? tf.shear_y.data() : nullptr, &ws->stress_scratch, ws->stress.data());
    for (int r = 0; r < nrec; ++r) {
      const int c = static_cast<int>(sites[r].cls);
      ws->quantity[r] = QuantityAt(cfg.classes[c].quantity, ws->stress[r], model.material(c));
    }
  }
  // Stage 4: receptors advance every step (membranes relax without contact).
  if (need_receptors && elapsed > 0.0) {
    if (idle) {  // make up the idle time at q = 0, in one exact step
      const double gap_s = (time_s - elapsed) - state[kStReceptorsTime];
      if (gap_s > 0.0) {
        const ReceptorStepper catch_up(cfg.receptor, gap_s);
        double v;
        for (int r = 0; r < nrec; ++r)
          catch_up.Advance(sites[r].cls, 0.0, r,
                           receptor_state + static_cast<size_t>(r) * kReceptorStateSize, &v);
      }
      state[kStReceptorsIdle] = 0.0;
    }
    const ReceptorStepper& stepper = StepperFor(cfg.receptor, elapsed, ws);
    bool quiescent = !touching && !cfg.outputs[kOutVoltage] && !cfg.outputs[kOutRate];
    for (int r = 0; r < nrec; ++r) {
      double* st = receptor_state + static_cast<size_t>(r) * kReceptorStateSize;
      double v;
      const int k = stepper.Advance(sites[r].cls, ws->quantity[r], r, st, &v);
      last_spikes[r] = k;
      last_voltage[r] = v;
      *fired += k;
      quiescent = quiescent && k == 0 && stepper.Quiescent(sites[r].cls, st);
    }
    if (quiescent) {
      state[kStReceptorsIdle] = 1.0;
      state[kStReceptorsTime] = time_s;
    }
  } else if (need_receptors && !time_valid) {
    for (int r = 0; r < nrec; ++r)
      PrimeReceptor(cfg.receptor, sites[r].cls, ws->quantity[r], r,
                    receptor_state + static_cast<size_t>(r) * kReceptorStateSize);
  }
  return touching;
}

// Unit quaternion (w, x, y, z) of a row-major rotation matrix, and back.
void MatToQuat(const double* m, double* q) {
  const double tr = m[0] + m[4] + m[8];
  if (tr > 0.0) {
    const double s = 2.0 * std::sqrt(tr + 1.0);
    q[0] = 0.25 * s;
    q[1] = (m[7] - m[5]) / s;
    q[2] = (m[2] - m[6]) / s;
    q[3] = (m[3] - m[1]) / s;
  } else if (m[0] > m[4] && m[0] > m[8]) {
    const double s = 2.0 * std::sqrt(1.0 + m[0] - m[4] - m[8]);
    q[0] = (m[7] - m[5]) / s;
    q[1] = 0.25 * s;
    q[2] = (m[1] + m[3]) / s;
    q[3] = (m[2] + m[6]) / s;
  } else if (m[4] > m[8]) {
    const double s = 2.0 * std::sqrt(1.0 + m[4] - m[0] - m[8]);
    q[0] = (m[2] - m[6]) / s;
    q[1] = (m[1] + m[3]) / s;
    q[2] = 0.25 * s;
    q[3] = (m[5] + m[7]) / s;
  } else {
    const double s = 2.0 * std::sqrt(1.0 + m[8] - m[0] - m[4]);
    q[0] = (m[3] - m[1]) / s;
    q[1] = (m[2] + m[6]) / s;
    q[2] = (m[5] + m[7]) / s;
    q[3] = 0.25 * s;
  }
}

void QuatToMat(const double* q, double* m) {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  m[0] = 1 - 2 * (y * y + z * z); m[1] = 2 * (x * y - w * z); m[2] = 2 * (x * z + w * y);
  m[3] = 2 * (x * y + w * z); m[4] = 1 - 2 * (x * x + z * z); m[5] = 2 * (y * z - w * x);
  m[6] = 2 * (x * z - w * y); m[7] = 2 * (y * z + w * x); m[8] = 1 - 2 * (x * x + y * y);
}

// Pose at fraction s of the way from a to b: position linear, rotation
// by spherical linear interpolation.
Pose InterpolatePose(const Pose& a, const Pose& b, double s) {
  Pose out;
  for (int k = 0; k < 3; ++k) out.pos[k] = a.pos[k] + s * (b.pos[k] - a.pos[k]);
  double qa[4], qb[4], q[4];
  MatToQuat(a.mat, qa);
  MatToQuat(b.mat, qb);
  double dot = qa[0] * qb[0] + qa[1] * qb[1] + qa[2] * qb[2] + qa[3] * qb[3];
  if (dot < 0.0) {  // the shorter arc
    for (double& v : qb) v = -v;
    dot = -dot;
  }
  double wa = 1.0 - s, wb = s;
  if (dot < 1.0 - 1e-12) {
    const double theta = std::acos(std::min(1.0, dot));
    wa = std::sin((1.0 - s) * theta) / std::sin(theta);
    wb = std::sin(s * theta) / std::sin(theta);
  }
  double norm = 0.0;
  for (int k = 0; k < 4; ++k) {
    q[k] = wa * qa[k] + wb * qb[k];
    norm += q[k] * q[k];
  }
  for (double& v : q) v /= std::sqrt(norm);
  QuatToMat(q, out.mat);
  return out;
}

void WriteOutputs(const SkinModel& model, const StepInput& in, bool touching,
                  const double* state, const Workspace& ws, double* out) {
  const SkinConfig& cfg = model.config();
  const int nrec = static_cast<int>(model.receptors().size());
  const double* receptor_state = state + kStateHeader;
  const double* last_spikes = receptor_state + static_cast<size_t>(nrec) * kReceptorStateSize;
  const double* last_voltage = last_spikes + nrec;
  const TractionField& tf = ws.traction;
  double* cursor = out;
  if (cfg.outputs[kOutSpikes]) {
    std::copy(last_spikes, last_spikes + nrec, cursor);
    cursor += nrec;
  }
  if (cfg.outputs[kOutStress]) {
    if (touching) std::copy(ws.quantity.begin(), ws.quantity.end(), cursor);
    else std::fill(cursor, cursor + nrec, 0.0);
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
    cursor[3] = touching ? state[kStContactDepth] : 0.0;  // indentation depth
    cursor += kForceBlockSize;
  }
  if (cfg.outputs[kOutPressure]) {
    const size_t N = cfg.grid.Size();
    if (touching) std::copy(tf.pressure_pa.begin(), tf.pressure_pa.begin() + N, cursor);
    else std::fill(cursor, cursor + N, 0.0);
    cursor += N;
  }
  if (cfg.outputs[kOutRate]) {
    for (int r = 0; r < nrec; ++r)
      cursor[r] = ReceptorRate(receptor_state + static_cast<size_t>(r) * kReceptorStateSize);
    cursor += nrec;
  }
}

}  // namespace

int Step(const SkinModel& model, const StepInput& in, double time_s, double* state,
         Workspace* ws, double* out) {
  const SkinConfig& cfg = model.config();
  const int K = cfg.oversample;
  int fired = 0;
  bool touching;
  double* last = K > 1 ? LastPose(model, state) : nullptr;
  const double elapsed = state[kStTimeValid] > 0.0 ? time_s - state[kStLastTime] : 0.0;
  if (K > 1 && last[15] > 0.0 && elapsed > 0.0) {
    // Tactile substeps: the pad's pose and MuJoCo's force interpolated from
    // the last step's (counter-surfaces at this step's pose); spikes summed.
    const int nrec = static_cast<int>(model.receptors().size());
    double* last_spikes = state + kStateHeader + static_cast<size_t>(nrec) * kReceptorStateSize;
    ws->spike_sum.assign(nrec, 0.0);
    Pose from;
    std::copy(last, last + 3, from.pos);
    std::copy(last + 3, last + 12, from.mat);
    StepInput& sub = ws->substep;
    sub.surfaces = in.surfaces;
    sub.contacts = in.contacts;
    sub.in_contact = in.in_contact;
    const double t0 = time_s - elapsed;
    for (int k = 1; k <= K; ++k) {
      const double s = static_cast<double>(k) / K;
      const StepInput* use = &in;
      if (k < K) {
        sub.pad_pose = InterpolatePose(from, in.pad_pose, s);
        sub.normal_force_n = last[12] + s * (in.normal_force_n - last[12]);
        sub.shear_x_n = last[13] + s * (in.shear_x_n - last[13]);
        sub.shear_y_n = last[14] + s * (in.shear_y_n - last[14]);
        use = &sub;
      }
      touching = Evaluate(model, *use, k < K ? t0 + s * elapsed : time_s, state, ws, &fired);
      // (an idle evaluation leaves zero counts: idle follows a silent step)
      for (int r = 0; r < nrec; ++r) ws->spike_sum[r] += last_spikes[r];
    }
    std::copy(ws->spike_sum.begin(), ws->spike_sum.end(), last_spikes);
  } else {
    touching = Evaluate(model, in, time_s, state, ws, &fired);
  }
  if (K > 1) {
    std::copy(in.pad_pose.pos, in.pad_pose.pos + 3, last);
    std::copy(in.pad_pose.mat, in.pad_pose.mat + 9, last + 3);
    last[12] = in.in_contact ? in.normal_force_n : 0.0;
    last[13] = in.in_contact ? in.shear_x_n : 0.0;
    last[14] = in.in_contact ? in.shear_y_n : 0.0;
    last[15] = 1.0;
  }
  WriteOutputs(model, in, touching, state, *ws, out);
  return fired;
}

}  // namespace mjtouch
