#include "pipeline/attribute_parsers.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "pipeline/model.h"
#include "pipeline/text.h"

namespace mjtouch {
namespace {

constexpr double kDefaultRadius = 5e-3;  // receptor population, m
constexpr size_t kMaxLayers = 64;        // LayeredSubstrate::Create's limit

// One number of a layer or of the base, in [lo, hi] or (lo, hi].
bool LayerNumber(AttributeParser* p, const char* key, const std::string& what,
                 const std::string& word, double lo, bool lo_open, double hi, const char* units,
                 double* v) {
  double x;
  const bool number = ToDouble(word, &x);
  const char* where = !number                        ? "is not a finite number;"
                      : (lo_open ? x <= lo : x < lo) ? "is below the"
                      : x > hi                       ? "is above the"
                                                     : nullptr;
  if (where)
    return p->Fail(Fmt("attribute `%s`: %s = '%s'%s%s %s valid range %s%g, %g]%s%s", key,
                       what.c_str(), word.c_str(), *units ? " " : "", units, where,
                       lo_open ? "(" : "[", lo, hi, *units ? " " : "", units));
  *v = x;
  return true;
}

// The one grammar of the composite attributes: a value is entries separated
// by ';' (several only in `layers` and `sites`), an entry is words separated
// by whitespace. ',' is no separator anywhere: "SA1,0,0,1e-3" is an error,
// not four entries of one word.
bool EntryList(AttributeParser* p, const char* key, const std::string& value, const char* form,
               std::vector<std::vector<std::string>>* entries) {
  if (value.find(',') != std::string::npos)
    return p->Fail(
        Fmt("attribute `%s`: ',' is not a separator; valid: %s, words separated by "
            "spaces, entries by ';'",
            key, form));
  entries->clear();
  size_t start = 0;
  while (true) {
    const size_t end = value.find(';', start);
    const std::string entry = value.substr(start, end == std::string::npos ? end : end - start);
    const auto w = Words(entry);
    if (w.empty())
      return p->Fail(
          Fmt("attribute `%s`: entry %zu is empty (a ';' with nothing on one side); "
              "valid: %s separated by ';'",
              key, entries->size() + 1, form));
    entries->push_back(w);
    if (end == std::string::npos) return true;
    start = end + 1;
  }
}

int ClassIndex(const std::string& word) {
  for (int c = 0; c < kNumClasses; ++c)
    if (word == ClassName(static_cast<ReceptorClass>(c))) return c;
  return -1;
}

// The layered kernels' build (LatticeTable, SurfaceComplianceTable)
// integrates over wavenumbers up to ~50 / thickness of the top layer, with
// panels no wider than pi / r out to the grid's half-diagonal r, and
// subdivides a source cell into squares of ~thickness / 2: its work grows as
// r / thickness and (pitch / thickness)^2. Bounded before it starts so that
// no `layers` value costs more than a few seconds (at the bounds, ~1-2 s on
// one core; a 1e-30 m layer never returned).
constexpr double kMaxSpanPerThickness = 5e3;  // half-diagonal / thickness
constexpr double kMaxPitchPerThickness = 50;  // pitch / thickness

bool CheckKernelBuildWork(const SkinConfig& cfg, std::string* error) {
  if (!cfg.layered || cfg.layers.empty()) return true;
  const double pitch = cfg.grid.pitch_m;
  const double span = std::sqrt(2.0) * (cfg.grid.n - 0.5) * pitch + pitch;
  const double t = cfg.layers[0].thickness_m;
  const double need = std::max(span / kMaxSpanPerThickness, pitch / kMaxPitchPerThickness);
  if (t >= need) return true;
  *error =
      Fmt("mjtouch.skin: attribute `layers`: layer 1 thickness = %g m is below %g m, the "
          "least the kernel build allows on this grid (its work grows as the grid's "
          "half-diagonal %g m / thickness, at most %g, and pitch / thickness, at most %g); "
          "valid: layer 1 thickness >= %g m, or a smaller `nx` x `pitch`",
          t, need, span, kMaxSpanPerThickness, kMaxPitchPerThickness, need);
  return false;
}

// Every class in `classes` gets at least one receptor when an output needs
// them (a zero-receptor class would silently shrink the blocks).
bool CheckReceptorCounts(const SkinConfig& cfg, std::string* error) {
  const bool receptor_outputs = cfg.outputs[kOutSpikes] || cfg.outputs[kOutStress] ||
                                cfg.outputs[kOutVoltage] || cfg.outputs[kOutRate];
  if (!receptor_outputs || !cfg.sites.empty()) return true;
  int count[kNumClasses] = {0, 0, 0};
  for (const auto& s : SkinModel::PlaceReceptors(cfg)) ++count[static_cast<int>(s.cls)];
  const double r = cfg.population_radius_m;
  for (int c = 0; c < kNumClasses; ++c) {
    const ClassConfig& k = cfg.classes[c];
    if (!k.present || count[c] > 0) continue;
    const char* name = ClassName(static_cast<ReceptorClass>(c));
    *error =
        Fmt("mjtouch.skin: no %s receptor: `density` entry %d (%g per cm^2) x pi `radius`^2 "
            "(%g m%s) = %g receptors rounds to 0; valid: density x pi radius^2 >= 0.5 "
            "(radius in cm): raise `density` or `radius`%s, or remove %s from `classes`",
            name, c + 1, k.density_per_cm2, r,
            cfg.radius_is_default ? " (default): min(5e-3, `nx` * `pitch` / 2 - `pitch`)" : "",
            k.density_per_cm2 * 3.14159265358979 * r * r * 1e4,
            cfg.radius_is_default ? " (or `nx` * `pitch`)" : "", name);
    return false;
  }
  return true;
}

}  // namespace

bool ListWords(AttributeParser* p, const char* key, const std::string& value, const char* form,
               std::vector<std::string>* words) {
  for (const char sep : {',', ';'})
    if (value.find(sep) != std::string::npos)
      return p->Fail(
          Fmt("attribute `%s` = '%s': '%c' is not a separator here; valid: %s, "
              "separated by spaces",
              key, value.c_str(), sep, form));
  *words = Words(value);
  return true;
}

bool ParseTextureAttribute(const std::string&, SkinConfig*, AttributeParser*) {
  return true;  // geom names: the MuJoCo adapter resolves them
}

bool ParseOversampleAttribute(const std::string& v, SkinConfig* cfg, AttributeParser* p) {
  if (v == "auto") return true;  // 0: ResolveOversample picks the count
  double count = 0;
  if (!ToDouble(v, &count) || count != std::floor(count) || count < 1 || count > 64)
    return p->Fail(
        Fmt("attribute `oversample` = '%s' is not valid; valid: auto or an integer "
            "in [1, 64]",
            v.c_str()));
  cfg->oversample = static_cast<int>(count);
  return true;
}
void WriteOversampleKey(const SkinConfig& cfg, std::ostream& out) { out << cfg.oversample; }

bool ParseClassesAttribute(const std::string& v, SkinConfig* cfg, AttributeParser* p) {
  std::vector<std::string> words;
  if (!ListWords(p, "classes", v, "words of SA1 RA PC", &words)) return false;
  for (auto& c : cfg->classes) c.present = false;
  for (const auto& w : words) {
    const int k = ClassIndex(w);
    if (k < 0)
      return p->Fail(
          Fmt("attribute `classes`: unknown receptor class '%s'; valid: SA1 RA PC", w.c_str()));
    cfg->classes[k].present = true;
  }
  return true;
}
void WriteClassesKey(const SkinConfig& cfg, std::ostream& out) {
  for (const auto& k : cfg.classes) out << k.present << ' ';
}

bool ParseQuantityAttribute(const std::string& v, SkinConfig* cfg, AttributeParser* p) {
  std::vector<std::string> w;
  if (!ListWords(p, "quantity", v, "3 names (SA1 RA PC)", &w)) return false;
  if (w.size() != kNumClasses)
    return p->Fail(
        "attribute `quantity` needs 3 names (SA1 RA PC); valid: szz maxcomp "
        "vonmises maxshear sed strain");
  for (int c = 0; c < kNumClasses; ++c) {
    if (!ParseQuantity(w[c], &cfg->classes[c].quantity))
      return p->Fail(
          Fmt("attribute `quantity`: unknown quantity '%s' for %s; valid: szz "
              "maxcomp vonmises maxshear sed strain",
              w[c].c_str(), ClassName(static_cast<ReceptorClass>(c))));
  }
  // SA1 gains default to the Wang 2016 Table 1 row of the SA1 quantity.
  DefaultSA1Gains(cfg->classes[0].quantity, &cfg->receptor.sa1);
  return true;
}
void WriteQuantityKey(const SkinConfig& cfg, std::ostream& out) {
  for (const auto& k : cfg.classes) out << static_cast<int>(k.quantity) << ' ';
}

bool ParseOutputsAttribute(const std::string& v, SkinConfig* cfg, AttributeParser* p) {
  std::vector<std::string> words;
  if (!ListWords(p, "outputs", v,
                 "words of spikes stress voltage force pressure rate stick slip shear", &words))
    return false;
  for (bool& o : cfg->outputs) o = false;
  for (const auto& w : words) {
    int k = -1;
    for (int b = 0; b < kNumOutputs; ++b)
      if (w == OutputName(b)) k = b;
    if (k < 0)
      return p->Fail(
          Fmt("attribute `outputs`: unknown output '%s'; valid: spikes stress "
              "voltage force pressure rate coverage stick slip shear",
              w.c_str()));
    cfg->outputs[k] = true;
  }
  return true;
}
void WriteOutputsKey(const SkinConfig& cfg, std::ostream& out) {
  for (bool o : cfg.outputs) out << o << ' ';
}

bool ParseShearAttribute(const std::string& v, SkinConfig* cfg, AttributeParser* p) {
  cfg->shear_partial = v == "partial";
  if (v == "true" || v == "1" || v == "partial")
    cfg->shear = true;
  else if (v == "false" || v == "0")
    cfg->shear = false;
  else
    return p->Fail(
        Fmt("attribute `shear` = '%s' is unknown; valid: true (full slip) false "
            "partial",
            v.c_str()));
  return true;
}
void WriteShearKey(const SkinConfig& cfg, std::ostream& out) {
  out << cfg.shear << (cfg.shear_partial ? " partial" : "");
}

bool ParseMerkelAttribute(const std::string& v, SkinConfig* cfg, AttributeParser* p) {
  const char* kWhat =
      "attribute `sa1_merkel`: Merkel cells per heminode must be 1 to 4 numbers in [0, 1000]";
  std::vector<std::string> words;
  if (!ListWords(p, "sa1_merkel", v, "1 to 4 numbers in [0, 1000]", &words)) return false;
  std::vector<double> m;
  for (const auto& x : words) {
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
    return p->Fail(
        Fmt("attribute `seed` = '%s' is not an integer in [0, "
            "18446744073709551615]",
            v.c_str()));
  cfg->receptor.noise.seed = seed;
  return true;
}
void WriteSeedKey(const SkinConfig& cfg, std::ostream& out) { out << cfg.receptor.noise.seed; }

// Explicit sites: entries "CLASS x y depth" (m, pad frame) separated by
// ';'. They replace the density population.
bool ParseSitesAttribute(const std::string& v, SkinConfig* cfg, AttributeParser* p) {
  for (const char* key : {"classes", "density", "depth", "radius"}) {
    if (p->Present(key))
      return p->Fail(
          Fmt("attribute `sites` places the receptors explicitly; remove `%s` "
              "(valid with `sites`: per-class `quantity` and the afferent "
              "parameters)",
              key));
  }
  const char* form = "entries 'CLASS x y depth' (CLASS in SA1 RA PC; x, y, depth in m)";
  std::vector<std::vector<std::string>> entries;
  if (!EntryList(p, "sites", v, form, &entries)) return false;
  const double limit = cfg->grid.HalfExtent() - cfg->grid.pitch_m;
  bool depth_set[kNumClasses] = {false, false, false};
  for (auto& k : cfg->classes) k.present = false;
  for (size_t e = 0; e < entries.size(); ++e) {
    const auto& w = entries[e];
    if (w.size() != 4)
      return p->Fail(
          Fmt("attribute `sites` entry %zu has %zu words; it needs 4: %s separated "
              "by ';'",
              e + 1, w.size(), form));
    const int c = ClassIndex(w[0]);
    double x, y, depth;
    if (c < 0 || !ToDouble(w[1], &x) || !ToDouble(w[2], &y) || !ToDouble(w[3], &depth))
      return p->Fail(Fmt("attribute `sites` entry %zu ('%s %s %s %s') is not one of %s", e + 1,
                         w[0].c_str(), w[1].c_str(), w[2].c_str(), w[3].c_str(), form));
    if (std::abs(x) > limit || std::abs(y) > limit)
      return p->Fail(
          Fmt("attribute `sites` entry %zu (%s at x = %g, y = %g m) is outside the "
              "taxel grid; valid range |x|, |y| <= nx * pitch / 2 - pitch = %g m",
              e + 1, w[0].c_str(), x, y, limit));
    ClassConfig& k = cfg->classes[c];
    if (!(depth > 0 && depth <= 0.02))
      return p->Fail(
          Fmt("attribute `sites` entry %zu (%s) depth = %g m is out of range; valid "
              "range (0, 0.02] m",
              e + 1, w[0].c_str(), depth));
    if (depth_set[c] && depth != k.depth_m)
      return p->Fail(
          Fmt("attribute `sites` entry %zu: every %s site must have the same depth "
              "(its kernel table and material); got %g and %g m",
              e + 1, w[0].c_str(), k.depth_m, depth));
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

// Entries "thickness E nu" (m, Pa, -) separated by ';', top down.
bool ParseLayersAttribute(const std::string& v, SkinConfig* cfg, AttributeParser* p) {
  const char* form = "1 to 64 layers 'thickness E nu' (m, Pa, -)";
  std::vector<std::vector<std::string>> entries;
  if (!EntryList(p, "layers", v, form, &entries)) return false;
  if (entries.size() > kMaxLayers)
    return p->Fail(Fmt("attribute `layers` has %zu layers; valid: 1 to 64", entries.size()));
  std::vector<ElasticLayer> stack;
  for (const auto& w : entries) {
    const int k = static_cast<int>(stack.size()) + 1;
    if (w.size() != 3)
      return p->Fail(
          Fmt("attribute `layers`: layer %d has %zu words; it needs 3 numbers: "
              "thickness (m), Young's modulus E (Pa), Poisson's ratio nu; layers "
              "are separated by ';'",
              k, w.size()));
    ElasticLayer l;
    if (!LayerNumber(p, "layers", Fmt("layer %d thickness", k), w[0], kMinLayerThicknessM, false,
                     kMaxLayerThicknessM, "m", &l.thickness_m) ||
        !LayerNumber(p, "layers", Fmt("layer %d E", k), w[1], kMinLayerModulusPa, false,
                     kMaxLayerModulusPa, "Pa", &l.young_pa) ||
        !LayerNumber(p, "layers", Fmt("layer %d nu", k), w[2], -1, true, 0.5, "", &l.poisson))
      return false;
    stack.push_back(l);
  }
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
  std::vector<std::string> w;
  if (!ListWords(p, "base", v, "'rigid' or 'E nu'", &w)) return false;
  LayeredBase b;
  b.rigid = false;
  if (w.size() != 2)
    return p->Fail(
        Fmt("attribute `base` = '%s' must be 'rigid' (bone) or 'E nu' (an elastic "
            "half-space: E in [%g, %g] Pa, nu in (-1, 0.5])",
            v.c_str(), kMinLayerModulusPa, kMaxLayerModulusPa));
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
    return fail(
        "attribute `oversample` needs pressure=\"winkler\" or \"elastic\" (the "
        "contacts model has no geometry to interpolate over the step); valid with "
        "contacts: 1");
  if (cfg->shear_partial && cfg->pressure_model == PressureModel::kContacts)
    return fail(
        "attribute `shear` = partial needs pressure=\"winkler\" or \"elastic\" (the "
        "contacts model has no pressure field to stick or slip on); valid with "
        "contacts: true false");
  if ((cfg->outputs[kOutStick] || cfg->outputs[kOutSlip]) && !cfg->shear_partial)
    return fail(
        Fmt("attribute `outputs`: `%s` needs shear=\"partial\" (full slip has no stick "
            "zone); valid without it: spikes stress voltage force pressure rate coverage",
            cfg->outputs[kOutStick] ? "stick" : "slip"));
  if (cfg->outputs[kOutShear] && !cfg->shear)
    return fail(
        "attribute `outputs`: `shear` needs shear=\"true\" or \"partial\" (shear is "
        "false: no tangential traction)");
  if (p.Present("stress_theta") && cfg->stress_method != StressMethod::kTree)
    return fail(
        Fmt("attribute `stress_theta` applies to stress_method=\"tree\" only "
            "(stress_method is \"%s\")",
            StressMethodName(cfg->stress_method)));
  if (!cfg->layered) {
    for (const char* key : {"layers", "base", "interface_side"})
      if (p.Present(key))
        return fail(
            Fmt("attribute `%s` applies to skin=\"layered\" only (skin is "
                "\"halfspace\")",
                key));
  } else {
    for (const char* key : {"poisson", "young"})
      if (p.Present(key))
        return fail(
            Fmt("attribute `%s` applies to skin=\"halfspace\" only; the layered skin "
                "takes its moduli from `layers` (and `base`)",
                key));
  }
  if (!CheckKernelBuildWork(*cfg, error) || !CheckElasticSkin(*cfg, error)) return false;
  const double half = cfg->grid.HalfExtent();
  if (cfg->population_radius_m < 0) {
    cfg->population_radius_m = std::min(kDefaultRadius, half - cfg->grid.pitch_m);
    cfg->radius_is_default = true;
  } else if (cfg->population_radius_m > half - cfg->grid.pitch_m) {
    return fail(
        Fmt("attribute `radius` = %g m exceeds the taxel grid (nx * pitch / 2 - pitch "
            "= %g m); valid range [0, %g] m",
            cfg->population_radius_m, half - cfg->grid.pitch_m, half - cfg->grid.pitch_m));
  }
  if (cfg->ridges.enabled && cfg->ridges.pitch_m < 2 * cfg->grid.pitch_m)
    return fail(
        Fmt("attribute `ridge_pitch` = %g m%s is below two taxels (2 x `pitch` = %g "
            "m); the grid cannot resolve the ridges: valid `ridge_pitch` >= %g m, or "
            "`pitch` <= %g m, or ridges=\"false\"",
            cfg->ridges.pitch_m, cfg->ridge_pitch_is_default ? " (default)" : "",
            2 * cfg->grid.pitch_m, 2 * cfg->grid.pitch_m, cfg->ridges.pitch_m / 2));
  return CheckReceptorCounts(*cfg, error);
}

}  // namespace mjtouch
