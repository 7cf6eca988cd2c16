#include "pipeline/attribute_parsers.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "pipeline/text.h"

namespace mjtouch {
namespace {

constexpr double kDefaultRadius = 5e-3;  // receptor population, m
constexpr double kMaxThicknessM = 1.0;
constexpr size_t kMaxLayers = 64;  // LayeredSubstrate::Create's limit

// One number of a layer or of the base, in [lo, hi] or (lo, hi].
bool LayerNumber(AttributeParser* p, const char* key, const std::string& what,
                 const std::string& word, double lo, bool lo_open, double hi, const char* units,
                 double* v) {
  double x;
  if (!ToDouble(word, &x) || (lo_open ? x <= lo : x < lo) || x > hi)
    return p->Fail(Fmt("attribute `%s`: %s = '%s' is out of range; valid range %s%g, %g] %s",
                       key, what.c_str(), word.c_str(), lo_open ? "(" : "[", lo, hi, units));
  *v = x;
  return true;
}

int ClassIndex(const std::string& word) {
  for (int c = 0; c < kNumClasses; ++c)
    if (word == ClassName(static_cast<ReceptorClass>(c))) return c;
  return -1;
}

}  // namespace

bool ParseTextureAttribute(const std::string&, SkinConfig*, AttributeParser*) {
  return true;  // geom names: the MuJoCo adapter resolves them
}

bool ParseOversampleAttribute(const std::string& v, SkinConfig* cfg, AttributeParser* p) {
  if (v == "auto") return true;  // 0: ResolveOversample picks the count
  double count = 0;
  if (!ToDouble(v, &count) || count != std::floor(count) || count < 1 || count > 64)
    return p->Fail(Fmt("attribute `oversample` = '%s' is not valid; valid: auto or an integer "
                       "in [1, 64]", v.c_str()));
  cfg->oversample = static_cast<int>(count);
  return true;
}
void WriteOversampleKey(const SkinConfig& cfg, std::ostream& out) { out << cfg.oversample; }

bool ParseClassesAttribute(const std::string& v, SkinConfig* cfg, AttributeParser* p) {
  for (auto& c : cfg->classes) c.present = false;
  for (const auto& w : Words(v)) {
    const int k = ClassIndex(w);
    if (k < 0)
      return p->Fail(Fmt("attribute `classes`: unknown receptor class '%s'; valid: SA1 RA PC",
                         w.c_str()));
    cfg->classes[k].present = true;
  }
  return true;
}
void WriteClassesKey(const SkinConfig& cfg, std::ostream& out) {
  for (const auto& k : cfg.classes) out << k.present << ' ';
}

bool ParseQuantityAttribute(const std::string& v, SkinConfig* cfg, AttributeParser* p) {
  const auto w = Words(v);
  if (w.size() != kNumClasses)
    return p->Fail("attribute `quantity` needs 3 names (SA1 RA PC); valid: szz maxcomp "
                   "vonmises maxshear sed strain");
  for (int c = 0; c < kNumClasses; ++c) {
    if (!ParseQuantity(w[c], &cfg->classes[c].quantity))
      return p->Fail(Fmt("attribute `quantity`: unknown quantity '%s' for %s; valid: szz "
                         "maxcomp vonmises maxshear sed strain", w[c].c_str(),
                         ClassName(static_cast<ReceptorClass>(c))));
  }
  // SA1 gains default to the Wang 2016 Table 1 row of the SA1 quantity.
  DefaultSA1Gains(cfg->classes[0].quantity, &cfg->receptor.sa1);
  return true;
}
void WriteQuantityKey(const SkinConfig& cfg, std::ostream& out) {
  for (const auto& k : cfg.classes) out << static_cast<int>(k.quantity) << ' ';
}

bool ParseOutputsAttribute(const std::string& v, SkinConfig* cfg, AttributeParser* p) {
  for (bool& o : cfg->outputs) o = false;
  for (const auto& w : Words(v)) {
    int k = -1;
    for (int b = 0; b < kNumOutputs; ++b)
      if (w == OutputName(b)) k = b;
    if (k < 0)
      return p->Fail(Fmt("attribute `outputs`: unknown output '%s'; valid: spikes stress "
                         "voltage force pressure rate coverage", w.c_str()));
    cfg->outputs[k] = true;
  }
  return true;
}
void WriteOutputsKey(const SkinConfig& cfg, std::ostream& out) {
  for (bool o : cfg.outputs) out << o << ' ';
}

bool ParseMerkelAttribute(const std::string& v, SkinConfig* cfg, AttributeParser* p) {
  const char* kWhat =
      "attribute `sa1_merkel`: Merkel cells per heminode must be 1 to 4 numbers in [0, 1000]";
  std::vector<double> m;
  for (const auto& x : Words(v)) {
    double n;
    if (!ToDouble(x, &n) || n < 0 || n > 1000) return p->Fail(kWhat);
    m.push_back(n);
  }
  if (m.empty() || m.size() > 4) return p->Fail(kWhat);
  cfg->receptor.sa1.merkel_cells = m;
  return true;
}
void WriteMerkelKey(const SkinConfig& cfg, std::ostream& out) {
  for (double m : cfg.receptor.sa1.merkel_cells) out << m << ' ';
}

bool ParseSeedAttribute(const std::string& v, SkinConfig* cfg, AttributeParser* p) {
  char* end = nullptr;
  errno = 0;
  const unsigned long long seed = std::strtoull(v.c_str(), &end, 10);
  if (v[0] == '-' || *end != '\0' || errno == ERANGE)
    return p->Fail(Fmt("attribute `seed` = '%s' is not an integer in [0, "
                       "18446744073709551615]", v.c_str()));
  cfg->receptor.noise.seed = seed;
  return true;
}
void WriteSeedKey(const SkinConfig& cfg, std::ostream& out) { out << cfg.receptor.noise.seed; }

// Explicit sites: "CLASS x y depth" (m, pad frame), entries separated by ';'
// or ','. They replace the density population.
bool ParseSitesAttribute(const std::string& v, SkinConfig* cfg, AttributeParser* p) {
  for (const char* key : {"classes", "density", "depth", "radius"}) {
    if (p->Present(key))
      return p->Fail(Fmt("attribute `sites` places the receptors explicitly; remove `%s` "
                         "(valid with `sites`: per-class `quantity` and the afferent "
                         "parameters)", key));
  }
  std::string sites = v;
  for (char& ch : sites)
    if (ch == ';' || ch == ',') ch = ' ';
  const auto w = Words(sites);
  const char* form = "entries 'CLASS x y depth' (CLASS in SA1 RA PC; x, y, depth in m)";
  if (w.size() % 4 != 0)
    return p->Fail(Fmt("attribute `sites` has %zu words; it needs %s separated by ';' or ','",
                       w.size(), form));
  const double limit = cfg->grid.HalfExtent() - cfg->grid.pitch_m;
  bool depth_set[kNumClasses] = {false, false, false};
  for (auto& k : cfg->classes) k.present = false;
  for (size_t e = 0; e < w.size(); e += 4) {
    const int c = ClassIndex(w[e]);
    double x, y, depth;
    if (c < 0 || !ToDouble(w[e + 1], &x) || !ToDouble(w[e + 2], &y) ||
        !ToDouble(w[e + 3], &depth))
      return p->Fail(Fmt("attribute `sites` entry %zu ('%s %s %s %s') is not one of %s",
                         e / 4 + 1, w[e].c_str(), w[e + 1].c_str(), w[e + 2].c_str(),
                         w[e + 3].c_str(), form));
    if (std::abs(x) > limit || std::abs(y) > limit)
      return p->Fail(Fmt("attribute `sites` entry %zu (%s at x = %g, y = %g m) is outside the "
                         "taxel grid; valid range |x|, |y| <= nx * pitch / 2 - pitch = %g m",
                         e / 4 + 1, w[e].c_str(), x, y, limit));
    ClassConfig& k = cfg->classes[c];
    if (!(depth > 0 && depth <= 0.02))
      return p->Fail(Fmt("attribute `sites` entry %zu (%s) depth = %g m is out of range; valid "
                         "range (0, 0.02] m", e / 4 + 1, w[e].c_str(), depth));
    if (depth_set[c] && depth != k.depth_m)
      return p->Fail(Fmt("attribute `sites` entry %zu: every %s site must have the same depth "
                         "(its kernel table and material); got %g and %g m", e / 4 + 1,
                         w[e].c_str(), k.depth_m, depth));
    depth_set[c] = true;
    k.present = true;
    k.depth_m = depth;
    cfg->sites.push_back({static_cast<ReceptorClass>(c), x, y, depth});
  }
  return true;
}
void WriteSitesKey(const SkinConfig& cfg, std::ostream& out) {
  for (const auto& e : cfg.sites)
    out << static_cast<int>(e.cls) << ' ' << e.x_m << ' ' << e.y_m << ' ' << e.depth_m << ' ';
}

// "thickness E nu" groups separated by ';' or ',' (m, Pa, -), top down.
bool ParseLayersAttribute(const std::string& v, SkinConfig* cfg, AttributeParser* p) {
  std::string text = v;
  for (char& ch : text)
    if (ch == ';' || ch == ',') ch = '\n';
  std::istringstream groups(text);
  std::string group;
  std::vector<ElasticLayer> stack;
  while (std::getline(groups, group)) {
    const auto w = Words(group);
    if (w.empty()) continue;
    const int k = static_cast<int>(stack.size()) + 1;
    if (w.size() != 3)
      return p->Fail(Fmt("attribute `layers`: layer %d ('%s') needs 3 numbers: thickness (m), "
                         "Young's modulus E (Pa), Poisson's ratio nu; layers are separated by "
                         "';'", k, Trim(group).c_str()));
    ElasticLayer l;
    if (!LayerNumber(p, "layers", Fmt("layer %d thickness", k), w[0], 0, true, kMaxThicknessM,
                     "m", &l.thickness_m) ||
        !LayerNumber(p, "layers", Fmt("layer %d E", k), w[1], kMinLayerModulusPa, false,
                     kMaxLayerModulusPa, "Pa", &l.young_pa) ||
        !LayerNumber(p, "layers", Fmt("layer %d nu", k), w[2], -1, true, 0.5, "", &l.poisson))
      return false;
    stack.push_back(l);
  }
  if (stack.empty())
    return p->Fail("attribute `layers` has no layer (empty stack); valid: 1 to 64 groups "
                   "'thickness E nu' (m, Pa, -) separated by ';'");
  if (stack.size() > kMaxLayers)
    return p->Fail(Fmt("attribute `layers` has %d layers; valid: 1 to 64",
                       static_cast<int>(stack.size())));
  cfg->layers = stack;
  return true;
}
void WriteLayersKey(const SkinConfig& cfg, std::ostream& out) {
  for (const auto& l : cfg.layers)
    out << l.thickness_m << ' ' << l.young_pa << ' ' << l.poisson << ' ';
}

bool ParseBaseAttribute(const std::string& v, SkinConfig* cfg, AttributeParser* p) {
  if (v == "rigid") {
    cfg->base = LayeredBase{};
    return true;
  }
  const auto w = Words(v);
  LayeredBase b;
  b.rigid = false;
  if (w.size() != 2)
    return p->Fail(Fmt("attribute `base` = '%s' must be 'rigid' (bone) or 'E nu' (an elastic "
                       "half-space: E in [%g, %g] Pa, nu in (-1, 0.5])", v.c_str(),
                       kMinLayerModulusPa, kMaxLayerModulusPa));
  if (!LayerNumber(p, "base", "E", w[0], kMinLayerModulusPa, false, kMaxLayerModulusPa, "Pa",
                   &b.young_pa) ||
      !LayerNumber(p, "base", "nu", w[1], -1, true, 0.5, "", &b.poisson))
    return false;
  cfg->base = b;
  return true;
}
void WriteBaseKey(const SkinConfig& cfg, std::ostream& out) {
  out << cfg.base.rigid << ' ' << cfg.base.young_pa << ' ' << cfg.base.poisson;
}

bool CheckAttributeCombinations(const AttributeParser& p, SkinConfig* cfg, std::string* error) {
  auto fail = [&](const std::string& msg) {
    *error = "mjtouch.skin: " + msg;
    return false;
  };
  if (cfg->oversample > 1 && cfg->pressure_model == PressureModel::kContacts)
    return fail("attribute `oversample` needs pressure=\"winkler\" or \"elastic\" (the "
                "contacts model has no geometry to interpolate over the step); valid with "
                "contacts: 1");
  if (p.Present("stress_theta") && cfg->stress_method != StressMethod::kTree)
    return fail(Fmt("attribute `stress_theta` applies to stress_method=\"tree\" only "
                    "(stress_method is \"%s\")", StressMethodName(cfg->stress_method)));
  if (!cfg->layered) {
    for (const char* key : {"layers", "base", "interface_side"})
      if (p.Present(key))
        return fail(Fmt("attribute `%s` applies to skin=\"layered\" only (skin is "
                        "\"halfspace\")", key));
  } else {
    for (const char* key : {"poisson", "young"})
      if (p.Present(key))
        return fail(Fmt("attribute `%s` applies to skin=\"halfspace\" only; the layered skin "
                        "takes its moduli from `layers` (and `base`)", key));
  }
  if (!CheckElasticSkin(*cfg, error)) return false;
  const double half = cfg->grid.HalfExtent();
  if (cfg->population_radius_m < 0) {
    cfg->population_radius_m = std::min(kDefaultRadius, half - cfg->grid.pitch_m);
    cfg->radius_is_default = true;
  } else if (cfg->population_radius_m > half - cfg->grid.pitch_m) {
    return fail(Fmt("attribute `radius` = %g m exceeds the taxel grid (nx * pitch / 2 - pitch "
                    "= %g m); valid range [0, %g] m", cfg->population_radius_m,
                    half - cfg->grid.pitch_m, half - cfg->grid.pitch_m));
  }
  if (cfg->ridges.enabled && cfg->ridges.pitch_m < 2 * cfg->grid.pitch_m)
    return fail(Fmt("attribute `ridge_pitch` = %g m%s is below two taxels (2 x `pitch` = %g "
                    "m); the grid cannot resolve the ridges: valid `ridge_pitch` >= %g m, or "
                    "`pitch` <= %g m, or ridges=\"false\"", cfg->ridges.pitch_m,
                    cfg->ridge_pitch_is_default ? " (default)" : "", 2 * cfg->grid.pitch_m,
                    2 * cfg->grid.pitch_m, cfg->ridges.pitch_m / 2));
  return true;
}

}  // namespace mjtouch
