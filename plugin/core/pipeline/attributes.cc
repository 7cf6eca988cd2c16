// The attribute table (one row per MJCF attribute) and the generic parsing,
// cache key and README table built from it. Attributes with structure
// (lists, per-class names, the layered stack) have parse functions here
// (attribute_parsers.cc); their rows still give range, units and docs.
#include "pipeline/attributes.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "pipeline/attribute_parsers.h"
#include "pipeline/text.h"

namespace mjtouch {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDefaultRadius = 5e-3;  // receptor population, m

using K = AttributeKind;
using S = AttributeScope;

// Accessors of one SkinConfig field (the parsed value, index unused).
#define FIELD(expr)                                                     \
  [](const SkinConfig& c, int) { return static_cast<double>(c.expr); }, \
      [](SkinConfig* c, int, double v) { c->expr = static_cast<decltype(c->expr)>(v); }
#define CLASS_FIELD(expr)                                                 \
  [](const SkinConfig& c, int k) { return static_cast<double>(c.expr); }, \
      [](SkinConfig* c, int k, double v) { c->expr = v; }
#define NO_FIELD nullptr, nullptr
#define NO_PARSE nullptr, nullptr

// Lower bounds that keep the output finite and physical (values near 1e-300
// gave inf/NaN sensordata or an all-zero force block):
//   pitch >= 1 um: below any skin feature (ridges ~450 um); the kernel
//     tables' cell integrals (areas ~pitch^2) lose all precision far below.
//   moduli (young, layer and base E) >= 100 Pa: the softest tissues and gels
//     (brain 0.1-1 kPa); the surface compliance goes as 1/E and overflows
//     to inf near E = 1e-300 (NaN pressure).
//   layer and base E <= 2e10 Pa: cortical bone (17 GPa, Shao 2010; REFERENCE.md
//     sec. 2), the stiffest tissue under skin; anything stiffer is rigid next
//     to 10-100 kPa skin: say base="rigid".
//   layer thickness in [1 um, 1 m]: 1 um is below every layer of skin (the
//     thinnest, the stratum corneum, is 10-20 um on hairy skin and a few
//     hundred on the fingertip); the kernels' work also grows as the grid's
//     span over the top layer's thickness (CheckKernelBuildWork).
//   nu in (-1, 0.5]: the bounds of an isotropic elastic solid (positive
//     bulk and shear moduli); tissue is 0.4-0.5 (Shao 2010).
//   receptor depth in (0, 0.02] m: endings lie 0.02-2 mm deep (REFERENCE.md
//     sec. 2); 2 cm is the whole pulp and more, and must lie in the stack.
//   stiffness >= 1e5 Pa/m: a Winkler foundation is E / h, and 1 kPa tissue
//     1 cm thick gives 1e5; the overlap is p / k, so far below it the
//     overlap exceeds every pad and the approach solve finds no contact.
constexpr double kMinPitchM = 1e-6;
constexpr double kMinModulusPa = kMinLayerModulusPa;
constexpr double kMinStiffnessPaPerM = 1e5;

// `facing`: the skin's outward direction in the pad geom's frame.
bool ParseFacingAttribute(const std::string& v, SkinConfig* cfg, AttributeParser* p) {
  const auto w = Words(v);
  double f[3];
  bool ok = w.size() == 3;
  for (size_t k = 0; ok && k < 3; ++k) ok = ToDouble(w[k], &f[k]) && std::isfinite(f[k]);
  const double norm = ok ? std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]) : 0.0;
  if (!ok || !(norm > 1e-9) || !std::isfinite(norm))
    return p->Fail(
        Fmt("attribute `facing` = '%s' must be 3 finite numbers, not all zero: the "
            "skin's outward direction in the pad geom's frame",
            v.c_str()));
  for (double& x : f) x /= norm;
  SetPadFacing(f, &cfg->pad);
  return true;
}

void WriteFacingKey(const SkinConfig& cfg, std::ostream& out) {
  const double* R = cfg.pad.rotation;  // the skin's -z: minus the third column
  out << -R[2] << ' ' << -R[5] << ' ' << -R[8];
}

const std::vector<AttributeRow>& Rows() {
  static const std::vector<AttributeRow> rows = {
      // -- adapter and grid --------------------------------------------------
      {"texture", K::kCustom, 0, 0, false, false, "geom names", "(none)",
       "textures rendered by the skin (any geom type but sdf, not on the pad's body)",
       "names of geoms in the model", NO_FIELD, ParseTextureAttribute, nullptr, S::kAdapter},
      {"texture_group", K::kInteger, 0, 5, false, false, "", "(none)",
       "non-colliding geoms in this geom group are textures", nullptr, FIELD(texture_group),
       NO_PARSE, S::kModel},
      {"nx", K::kInteger, 4, 512, false, false, "cells", "128", "taxels per side", nullptr,
       FIELD(grid.n), NO_PARSE, S::kModel},
      {"pitch", K::kNumber, kMinPitchM, 1e-2, false, false, "m", "1e-4", "taxel pitch", nullptr,
       FIELD(grid.pitch_m), NO_PARSE, S::kModel},
      {"ridges", K::kBool, 0, 0, false, false, "", "true", "fingerprint ridges on the skin",
       nullptr, FIELD(ridges.enabled), NO_PARSE, S::kModel},
      {"ridge_pitch", K::kNumber, 0, 1e-2, true, false, "m", "4.5e-4",
       "ridge period (Shao et al. 2010); at least 2 taxels", nullptr,
       [](const SkinConfig& c, int) { return c.ridges.pitch_m; },
       [](SkinConfig* c, int, double v) {
         c->ridges.pitch_m = v;
         c->ridge_pitch_is_default = false;
       },
       NO_PARSE, S::kModel},
      {"ridge_height", K::kNumber, 0, 1e-3, true, false, "m", "5e-5",
       "crest-to-valley relief (Shao et al. 2010)", nullptr, FIELD(ridges.height_m), NO_PARSE,
       S::kModel},
      {"ridge_angle", K::kNumber, -180, 180, false, false, "deg", "0",
       "ridge lines vs the pad's y axis (0: perpendicular to pad x)", nullptr,
       [](const SkinConfig& c, int) { return c.ridges.angle_rad; },
       [](SkinConfig* c, int, double deg) { c->ridges.angle_rad = deg * kPi / 180.0; }, NO_PARSE,
       S::kModel},
      {"ridge_profile", K::kChoice, 0, 0, false, false, "", "sine", "ridge cross-section",
       "sine triangle square", FIELD(ridges.profile), NO_PARSE, S::kModel},
      // -- contact (stage 2) -------------------------------------------------
      {"pressure", K::kChoice, 0, 0, false, false, "", "elastic",
       "contact pressure model (the table above)", "contacts winkler elastic",
       FIELD(pressure_model), NO_PARSE, S::kModel},
      {"oversample", K::kCustom, 0, 0, false, false, "", "auto",
       "tactile evaluations per physics step (\"Oversampling\" below)",
       "auto or an integer in [1, 64]", NO_FIELD, ParseOversampleAttribute, WriteOversampleKey,
       S::kModel},
      {"substep", K::kChoice, 0, 0, false, false, "", "full",
       "`oversample` > 1: what each substep evaluates: `full` (all stages at the interpolated "
       "pose) or `receptors` (stages 1-3 once per physics step; the receptors' input "
       "interpolated linearly from the last step's: K times cheaper stages 1-3, texture "
       "content above the physics step's Nyquist frequency lost)",
       "full receptors", FIELD(substep), NO_PARSE, S::kModel},
      {"young", K::kNumber, kMinModulusPa, 1e10, false, false, "Pa", "8e4",
       "`elastic` on skin=\"halfspace\": Young's modulus", nullptr, FIELD(young_pa), NO_PARSE,
       S::kModel},
      {"tolerance", K::kNumber, 0, 0.1, true, false, "", "1e-4",
       "`elastic`: relative L1 pressure change that stops the CG (about its error)", nullptr,
       FIELD(tolerance), NO_PARSE, S::kModel},
      {"contact_solver", K::kChoice, 0, 0, false, false, "", "pcg",
       "`elastic`: `pcg` preconditioned CG, warm start extrapolated from the last two steps; "
       "`pk` Polonsky & Keer's CG from the last step (the reference path)",
       "pcg pk", FIELD(elastic_method), NO_PARSE, S::kModel},
      {"elastic_precision", K::kChoice, 0, 0, false, false, "", "float",
       "`elastic`: arithmetic of the compliance FFTs; `float` (FFTs 1.7-2x, stages 1-2 1.5x "
       "faster; ~1e-7 relative on the displacement, below the float kernel table and the CG "
       "`tolerance`) or `double` (the reference path)",
       "float double", FIELD(elastic_precision), NO_PARSE, S::kModel},
      {"grid_shift", K::kBool, 0, 0, false, false, "", "false",
       "`elastic`: solve again on the grid shifted by half a cell in x and y and average "
       "(cancels the V / pitch line that texture edges sharper than a cell put in the stress; "
       "a step ~1.8x as long at 128 x 0.1 mm)",
       nullptr, FIELD(grid_shift), NO_PARSE, S::kModel},
      {"grid_cycle", K::kInteger, 1, 4, false, false, "grids", "4",
       "`elastic`: each step solves the contact on one of this many grids offset by k / N of a "
       "cell in x and y, in turn, and the stress sees the average of the last N solutions "
       "deposited on the nearest taxels (the texture's sub-cell position no longer locks "
       "to the grid; each grid's solve stops at N x `tolerance`; ~1.3x the step, docs: "
       "Performance). 1: the taxel grid alone. Off with `grid_shift`",
       nullptr, FIELD(grid_cycle), NO_PARSE, S::kModel},
      {"stiffness", K::kNumber, kMinStiffnessPaPerM, 1e12, false, false, "Pa/m", "2e7",
       "Winkler foundation stiffness (sets the contact size, not the force)", nullptr,
       FIELD(stiffness_pa_per_m), NO_PARSE, S::kModel},
      {"poisson", K::kNumber, -1, 0.5, true, false, "", "0.48",
       "skin=\"halfspace\": Poisson's ratio", nullptr, FIELD(poisson), NO_PARSE, S::kModel},
      {"shear", K::kCustom, 0, 0, false, false, "", "true",
       "shear traction from MuJoCo's friction force: `true` uniform full slip (q = p F / P), "
       "`partial` Coulomb stick and slip per cell with memory (mu from the contacts' geoms; "
       "winkler and elastic), `false` none",
       "true false partial", NO_FIELD, ParseShearAttribute, WriteShearKey, S::kModel},
      {"visual", K::kChoice, 0, 0, false, false, "", "both",
       "drawing: `pad` (heatmap on the skin, seen from below), `above` (a copy 2 mm over the "
       "pad), `both`, `none`",
       "none pad above both", FIELD(visual), NO_PARSE, S::kDrawing},
      // -- receptor population -----------------------------------------------
      {"radius", K::kNumber, 0, 0.1, false, false, "m", "min(5e-3, grid)",
       "receptors lie within this distance of the pole; at most 0.9 x the pad's smaller "
       "semi-axis",
       nullptr, FIELD(population_radius_m), NO_PARSE, S::kModel},
      {"classes", K::kCustom, 0, 0, false, false, "", "SA1 RA PC", "receptor classes present",
       "words of: SA1 RA PC", NO_FIELD, ParseClassesAttribute, WriteClassesKey, S::kModel},
      {"density", K::kPerClass, 0, 1e4, false, false, "per cm^2", "70 140 21",
       "SA1 RA PC densities (Johansson & Vallbo 1979)", nullptr,
       CLASS_FIELD(classes[k].density_per_cm2), NO_PARSE, S::kModel},
      {"depth", K::kPerClass, 0, 0.02, true, false, "m", "7.5e-4 7.5e-4 2e-3",
       "SA1 RA PC depths below the surface, inside the skin", nullptr,
       CLASS_FIELD(classes[k].depth_m), NO_PARSE, S::kModel},
      {"quantity", K::kCustom, 0, 0, false, false, "", "maxcomp szz szz",
       "driving quantity per class: `szz` (-s_zz), `maxcomp` (most compressive principal "
       "stress, Wang 2016), `vonmises`, `maxshear`; layered skin also `sed` (strain energy "
       "density), `strain` (most compressive principal strain)",
       "3 names (SA1 RA PC) of: szz maxcomp vonmises maxshear sed strain", NO_FIELD,
       ParseQuantityAttribute, WriteQuantityKey, S::kModel},
      {"outputs", K::kCustom, 0, 0, false, false, "", "spikes stress force",
       "sensordata blocks (\"Sensordata layout\" below)",
       "words of: spikes stress voltage force pressure rate coverage stick slip shear", NO_FIELD,
       ParseOutputsAttribute, WriteOutputsKey, S::kModel},
      // -- afferents (stage 4; README "Afferent models") ---------------------
      {"sa1_model", K::kChoice, 0, 0, false, false, "", "filtered",
       "SA1 model: `filtered` (rate term low-passed and signed, adaptation, variants) or "
       "`wang2016` (abs(dq/dt) as published, Wang et al. 2016); resets the SA1 gains' defaults",
       "filtered wang2016",
       [](const SkinConfig& c, int) { return static_cast<double>(c.receptor.sa1.model); },
       [](SkinConfig* c, int, double index) {
         c->receptor.sa1.model = static_cast<SA1Model>(static_cast<int>(index));
         DefaultSA1Gains(c->classes[0].quantity, &c->receptor.sa1);
       },
       NO_PARSE, S::kModel},
      {"sa1_merkel", K::kCustom, 0, 0, false, false, "cells per heminode", "8 5 3 1",
       "SA1 Merkel cells per heminode (Wang 2016)", "1 to 4 numbers in [0, 1000]", NO_FIELD,
       ParseMerkelAttribute, WriteMerkelKey, S::kModel},
      {"sa1_k0", K::kNumber, 0, 1e-6, false, false, "A per unit of q", "9.8e-16",
       "SA1 static gain (`filtered`: 7 x the Wang 2016 Table 1 row of the SA1 `quantity`; "
       "`wang2016`: the row, 1.40e-16 for stress)",
       nullptr, FIELD(receptor.sa1.k0_a_per_pa), NO_PARSE, S::kModel},
      {"sa1_k1", K::kNumber, 0, 1e-6, false, false, "A s per unit of q", "4.9e-17",
       "SA1 dynamic gain (`filtered`: 0.05 s x `sa1_k0`; `wang2016`: the Table 1 row, 1.68e-16 "
       "for stress)",
       nullptr, FIELD(receptor.sa1.k1_a_s_per_pa), NO_PARSE, S::kModel},
      {"sa1_i0", K::kNumber, -1e-6, 1e-6, false, false, "A", "4.94e-12",
       "SA1 bias current (Wang 2016 Table 1 row of the SA1 `quantity`)", nullptr,
       FIELD(receptor.sa1.i0_a), NO_PARSE, S::kModel},
      {"sa1_c", K::kNumber, 0, 1, true, false, "F", "1e-11", "SA1 membrane capacitance", nullptr,
       FIELD(receptor.sa1.capacitance_f), NO_PARSE, S::kModel},
      {"sa1_r", K::kNumber, 0, 1e15, true, false, "Ohm", "1.5e9", "SA1 membrane resistance",
       nullptr, FIELD(receptor.sa1.resistance_ohm), NO_PARSE, S::kModel},
      {"sa1_vth", K::kNumber, 0, 10, true, false, "V", "0.03", "SA1 spike threshold", nullptr,
       FIELD(receptor.sa1.threshold_v), NO_PARSE, S::kModel},
      {"sa1_lowpass", K::kNumber, 0, 1e4, true, false, "Hz", "30",
       "SA1 (`filtered`): corner of the two-pole low-pass on the rate term", nullptr,
       FIELD(receptor.sa1.lowpass_hz), NO_PARSE, S::kModel},
      {"sa1_saturation", K::kNumber, 0, 1e12, false, false, "units of q", "60508.9285714",
       "SA1 (`filtered`): input saturation q / (1 + abs(q) / s) (0: none); default 4.5 x the "
       "Wang 2016 row's rheobase (60.5 kPa for the stress quantities)",
       nullptr, FIELD(receptor.sa1.saturation), NO_PARSE, S::kModel},
      {"ra_gain", K::kNumber, 0, 1, false, false, "s/Pa", "5.92e-5", "RA drive gain", nullptr,
       FIELD(receptor.ra.gain_s_per_pa), NO_PARSE, S::kModel},
      {"ra_lowpass", K::kNumber, 0, 1e4, true, false, "Hz", "40", "RA low-pass corner", nullptr,
       FIELD(receptor.ra.lowpass_hz), NO_PARSE, S::kModel},
      {"ra_saturation", K::kNumber, 0, 1e6, false, false, "(threshold units)", "12",
       "RA drive saturation s: d s / (s + abs(d)), d the drive (0: none)", nullptr,
       FIELD(receptor.ra.saturation), NO_PARSE, S::kModel},
      {"ra_tau", K::kNumber, 0, 10, true, false, "s", "5e-3", "RA membrane time constant", nullptr,
       FIELD(receptor.ra.tau_s), NO_PARSE, S::kModel},
      {"ra_sustained", K::kNumber, 0, 1e6, false, false, "(threshold units)", "1",
       "RA gain control by the sustained drive m (the drive low-passed over `ra_sustained_tau`): "
       "drive / (1 + abs(m) / s) (0: none)",
       nullptr, FIELD(receptor.ra.sustained), NO_PARSE, S::kModel},
      {"ra_sustained_tau", K::kNumber, 0, 10, true, false, "s", "0.05",
       "RA time constant of the sustained drive (`ra_sustained`)", nullptr,
       FIELD(receptor.ra.sustained_tau_s), NO_PARSE, S::kModel},
      {"pc_gain", K::kNumber, 0, 1, false, false, "s^2/Pa", "3.94e-6", "PC drive gain", nullptr,
       FIELD(receptor.pc.gain_s2_per_pa), NO_PARSE, S::kModel},
      {"pc_highpass", K::kNumber, 0, 1e5, true, false, "Hz", "300", "PC capsule high-pass corner",
       nullptr, FIELD(receptor.pc.highpass_hz), NO_PARSE, S::kModel},
      {"pc_lowpass", K::kNumber, 0, 1e5, true, false, "Hz", "250", "PC low-pass corner", nullptr,
       FIELD(receptor.pc.lowpass_hz), NO_PARSE, S::kModel},
      {"pc_tau", K::kNumber, 0, 10, true, false, "s", "1.5e-3", "PC membrane time constant",
       nullptr, FIELD(receptor.pc.tau_s), NO_PARSE, S::kModel},
      {"pc_saturation", K::kNumber, 0, 1e6, false, false, "(threshold units)", "0",
       "PC drive saturation s: d s / (s + abs(d)), d the drive (0: none)", nullptr,
       FIELD(receptor.pc.saturation), NO_PARSE, S::kModel},
      {"refractory", K::kNumber, 0, 1, true, false, "s", "1e-3",
       "absolute refractory period of SA1 and RA (PC: `pc_refractory`)", nullptr,
       [](const SkinConfig& c, int) { return c.receptor.sa1.refractory_s; },
       [](SkinConfig* c, int, double v) {
         c->receptor.sa1.refractory_s = c->receptor.ra.refractory_s = v;
       },
       NO_PARSE, S::kModel},
      {"pc_refractory", K::kNumber, 0, 1, true, false, "s", "2.4e-3",
       "PC absolute refractory period: one spike per lobe of a ramp corner's drive", nullptr,
       FIELD(receptor.pc.refractory_s), NO_PARSE, S::kModel},
      {"adapt", K::kPerClass, 0, 100, false, false, "(threshold units)", "4.5 1.3 0.7",
       "SA1 RA PC spike-triggered adaptation: the jump of an inhibitory current at each spike",
       nullptr, CLASS_FIELD(receptor.adapt[k].jump), NO_PARSE, S::kModel},
      {"adapt_tau", K::kPerClass, 0, 10, true, false, "s", "0.05 0.03 0.02",
       "SA1 RA PC adaptation decay time", nullptr, CLASS_FIELD(receptor.adapt[k].tau_s), NO_PARSE,
       S::kModel},
      {"population", K::kChoice, 0, 0, false, false, "", "varied",
       "`varied`: each receptor takes one of 4 parameter sets of its class, picked from "
       "(`seed`, receptor index); `uniform`: the median set",
       "uniform varied", FIELD(receptor.varied), NO_PARSE, S::kModel},
      {"noise", K::kPerClass, 0, 100, false, false, "(threshold units)", "0.35 0.35 0.12",
       "SA1 RA PC membrane noise standard deviation", nullptr, CLASS_FIELD(receptor.noise.sd[k]),
       NO_PARSE, S::kModel},
      {"noise_tau", K::kNumber, 0, 10, true, false, "s", "2e-3", "membrane noise correlation time",
       nullptr, FIELD(receptor.noise.tau_s), NO_PARSE, S::kModel},
      {"seed", K::kCustom, 0, 0, false, false, "", "0", "membrane noise seed",
       "an integer in [0, 18446744073709551615]", NO_FIELD, ParseSeedAttribute, WriteSeedKey,
       S::kModel},
      {"rate_tau", K::kNumber, 0, 100, true, false, "s", "0.05",
       "`rate` output: exponential smoothing time", nullptr, FIELD(receptor.rate_tau_s), NO_PARSE,
       S::kModel},
      {"sites", K::kCustom, 0, 0, false, false, "m", "(none)",
       "explicit receptors \"CLASS x y depth; ...\" (pad frame), replacing the density "
       "population",
       "entries 'CLASS x y depth' separated by ';' (CLASS in SA1 RA PC; |x|, |y| inside the "
       "grid and under the "
       "pad; depth in (0, 0.02] m, one per class)",
       NO_FIELD, ParseSitesAttribute, WriteSitesKey, S::kModel},
      // -- the elastic skin (stage 3) ----------------------------------------
      {"stress_method", K::kChoice, 0, 0, false, false, "", "auto",
       "stage 3: `auto` (direct or FFT, whichever is cheaper this step; exact), `direct`, "
       "`fft`, `tree` (hierarchical, approximate)",
       "tree direct fft auto",
       [](const SkinConfig& c, int) { return static_cast<double>(c.stress_method); },
       [](SkinConfig* c, int, double index) {
         static const StressMethod kMethods[] = {StressMethod::kTree, StressMethod::kDirect,
                                                 StressMethod::kFft, StressMethod::kAuto};
         c->stress_method = kMethods[static_cast<int>(index)];
       },
       NO_PARSE, S::kModel},
      {"stress_theta", K::kNumber, 0, 2, true, false, "(block side / distance)", "0.5",
       "`tree`'s opening angle; RMS stress error 3e-4 to 1e-3 at 0.5", nullptr, FIELD(stress_theta),
       NO_PARSE, S::kModel},
      {"threads", K::kInteger, 1, 64, false, false, "", "1",
       "threads per step for the `elastic` solve's FFTs and preconditioner and for stage 3 "
       "(a shared pool; the same bits for any count). 1: outer parallelism (rollout, sweeps) "
       "keeps every core busy without oversubscription",
       nullptr, FIELD(threads), NO_PARSE, S::kModel},
      {"skin", K::kChoice, 0, 0, false, false, "", "layered",
       "`layered` (`layers` over `base`) or `halfspace` (`poisson`)", "layered halfspace",
       [](const SkinConfig& c, int) { return c.layered ? 1.0 : 0.0; },
       [](SkinConfig* c, int, double index) { c->layered = index == 0; }, NO_PARSE, S::kModel},
      {"layers", K::kCustom, 0, 0, false, false, "m Pa -", "Shao 2010",
       "\"thickness E nu; ...\" top down; default 7e-4 8e4 0.48; 8e-4 5e4 0.48; 2.5e-3 2.4e4 "
       "0.4 (epidermis, dermis, subcutis)",
       "1 to 64 layers separated by ';', thickness {T} m, E {E} Pa, nu (-1, 0.5]", NO_FIELD,
       ParseLayersAttribute, WriteLayersKey, S::kModel},
      {"base", K::kCustom, 0, 0, false, false, "Pa -", "rigid",
       "under the stack: `rigid` (bone) or \"E nu\" (an elastic half-space)",
       "rigid, or E in {E} Pa and nu in (-1, 0.5]", NO_FIELD, ParseBaseAttribute, WriteBaseKey,
       S::kModel},
      {"interface_side", K::kChoice, 0, 0, false, false, "", "upper",
       "a receptor exactly on an interface takes the layer `upper` or `lower`", "upper lower",
       FIELD(interface_side), NO_PARSE, S::kModel},
      // -- robots --------------------------------------------------------------
      {"pad_geom", K::kCustom, 0, 0, false, false, "geom name", "(none)",
       "the pad geom's name as written beside `texture` (mjtouch.attach sets it): the prefix "
       "and suffix MjSpec.attach adds to the pad's name are added to each `texture` name",
       "the pad's name without MjSpec.attach's prefix and suffix", NO_FIELD,
       [](const std::string&, SkinConfig*, AttributeParser*) { return true; }, nullptr,
       S::kAdapter},
      {"facing", K::kCustom, 0, 0, false, false, "(direction)", "0 0 -1",
       "the skin's outward direction in the pad geom's frame as written (a mesh: its file's "
       "axes, not MuJoCo's principal axes): the skin's frame is the geom's turned by the "
       "smallest rotation taking -z to it (+z: a half turn about x); the pad's surface is the "
       "geom's exact near side seen along it (a mesh: its convex hull's, which MuJoCo collides)",
       "3 finite numbers, not all zero (normalised)", NO_FIELD, ParseFacingAttribute,
       WriteFacingKey, S::kModel},
  };
  return rows;
}

std::string NumberText(const AttributeRow& row) {
  if (row.kind == K::kInteger)
    return Fmt("[%d, %d]", static_cast<int>(row.lo), static_cast<int>(row.hi));
  return Fmt("%s%g, %g%s", row.lo_open ? "(" : "[", row.lo, row.hi, row.hi_open ? ")" : "]");
}

bool InRange(const AttributeRow& row, double x) {
  const bool low = row.lo_open ? x <= row.lo : x < row.lo;
  const bool high = row.hi_open ? x >= row.hi : x > row.hi;
  return !low && !high;
}

// Parses one present, non-empty value of a table-driven row.
bool ParseValue(const AttributeRow& row, const std::string& raw, SkinConfig* cfg,
                AttributeParser* p) {
  const char* key = row.key;
  switch (row.kind) {
    case K::kNumber: {
      double x;
      if (!ToDouble(raw, &x))
        return p->Fail(Fmt("attribute `%s` = '%s' is not a number; valid range %s %s", key,
                           raw.c_str(), NumberText(row).c_str(), row.units));
      if (!InRange(row, x))
        return p->Fail(Fmt("attribute `%s` = %g is out of range; valid range %s %s", key, x,
                           NumberText(row).c_str(), row.units));
      row.set(cfg, 0, x);
      return true;
    }
    case K::kInteger: {
      double x;
      if (!ToDouble(raw, &x) || x != std::floor(x))
        return p->Fail(Fmt("attribute `%s` = '%s' is not an integer; valid range %s", key,
                           raw.c_str(), NumberText(row).c_str()));
      if (x < row.lo || x > row.hi)
        return p->Fail(Fmt("attribute `%s` = %g is out of range; valid range %s", key, x,
                           NumberText(row).c_str()));
      row.set(cfg, 0, x);
      return true;
    }
    case K::kBool:
      if (raw == "true" || raw == "1") {
        row.set(cfg, 0, 1);
        return true;
      }
      if (raw == "false" || raw == "0") {
        row.set(cfg, 0, 0);
        return true;
      }
      return p->Fail(Fmt("attribute `%s` = '%s' must be true or false", key, raw.c_str()));
    case K::kChoice: {
      const auto choices = Words(row.choices_or_range);
      const auto it = std::find(choices.begin(), choices.end(), raw);
      if (it == choices.end())
        return p->Fail(Fmt("attribute `%s` = '%s' is unknown; valid: %s", key, raw.c_str(),
                           row.choices_or_range));
      row.set(cfg, 0, static_cast<double>(it - choices.begin()));
      return true;
    }
    case K::kPerClass: {
      std::vector<std::string> w;
      if (!ListWords(p, key, raw, "3 numbers (SA1 RA PC)", &w)) return false;
      if (w.size() != kNumClasses)
        return p->Fail(Fmt("attribute `%s` = '%s' needs 3 numbers (SA1 RA PC), each in %s %s", key,
                           raw.c_str(), NumberText(row).c_str(), row.units));
      double x[kNumClasses];
      for (int c = 0; c < kNumClasses; ++c) {
        if (!ToDouble(w[c], &x[c]) || !InRange(row, x[c]))
          return p->Fail(
              Fmt("attribute `%s` entry %d ('%s', %s) is out of range; valid range "
                  "%s %s",
                  key, c + 1, w[c].c_str(), ClassName(static_cast<ReceptorClass>(c)),
                  NumberText(row).c_str(), row.units));
      }
      for (int c = 0; c < kNumClasses; ++c) row.set(cfg, c, x[c]);
      return true;
    }
    case K::kCustom: return row.parse(raw, cfg, p);
  }
  return false;
}

}  // namespace

bool AttributeParser::Fail(const std::string& msg) {
  if (ok_) *error_ = "mjtouch.skin: " + msg;
  ok_ = false;
  return false;
}

bool AttributeParser::Present(const char* key) const {
  return std::find(present_.begin(), present_.end(), key) != present_.end();
}

const std::vector<AttributeRow>& SkinAttributes() { return Rows(); }

std::string ValidRangeText(const AttributeRow& row) {
  switch (row.kind) {
    case K::kNumber:
    case K::kInteger: return NumberText(row);
    case K::kBool: return "true false";
    case K::kChoice: return row.choices_or_range;
    case K::kPerClass: return "3 numbers (SA1 RA PC), each in " + NumberText(row);
    case K::kCustom: {
      // {E}, {T}: the layer moduli's and thicknesses' ranges
      std::string text = row.choices_or_range;
      size_t at = text.find("{E}");
      if (at != std::string::npos)
        text.replace(at, 3, Fmt("[%g, %g]", kMinLayerModulusPa, kMaxLayerModulusPa));
      at = text.find("{T}");
      if (at != std::string::npos)
        text.replace(at, 3, Fmt("[%g, %g]", kMinLayerThicknessM, kMaxLayerThicknessM));
      return text;
    }
  }
  return "";
}

const std::vector<const char*>& SkinAttributeKeys() {
  static const std::vector<const char*> keys = [] {
    std::vector<const char*> k;
    for (const auto& row : Rows()) k.push_back(row.key);
    return k;
  }();
  return keys;
}

bool ParseSkinAttributes(const AttributeLookup& lookup, SkinConfig* cfg, std::string* error) {
  AttributeParser p(error);
  std::vector<std::optional<std::string>> raw;
  for (const auto& row : Rows()) {
    raw.push_back(lookup(row.key));
    if (raw.back()) p.MarkPresent(row.key);
  }
  // Defaults that depend on other attributes: the SA1 gains follow the SA1
  // quantity (set again when `quantity` is parsed); an unset radius (-1) is
  // fitted to the grid below.
  DefaultSA1Gains(cfg->classes[0].quantity, &cfg->receptor.sa1);
  cfg->population_radius_m = -1.0;
  for (size_t i = 0; i < Rows().size() && p.ok(); ++i) {
    const AttributeRow& row = Rows()[i];
    if (!raw[i]) continue;
    const std::string value = Trim(*raw[i]);
    if (value.empty()) {
      const bool units = *row.units && row.kind != K::kCustom;
      p.Fail(Fmt("attribute `%s` is empty; remove it for the default (%s) or give a value: %s%s%s",
                 row.key, row.default_text, ValidRangeText(row).c_str(), units ? " " : "",
                 units ? row.units : ""));
      break;
    }
    ParseValue(row, value, cfg, &p);
  }
  if (!p.ok()) return false;
  return CheckAttributeCombinations(p, cfg, error);
}

bool ParseSkinConfig(const AttributeGetter& get, SkinConfig* cfg, std::string* error) {
  return ParseSkinAttributes(
      [&](const char* key) -> std::optional<std::string> {
        std::string v = get(key);
        if (v.empty()) return std::nullopt;  // "" is unset (MuJoCo stores both alike)
        return v;
      },
      cfg, error);
}

std::string ConfigCacheKey(const SkinConfig& c) {
  std::ostringstream s;
  s.precision(17);
  s << "pad " << static_cast<int>(c.pad.shape) << ' ' << c.pad.semi_axes_m[0] << ' '
    << c.pad.semi_axes_m[1] << ' ' << c.pad.semi_axes_m[2];
  if (c.pad.mesh) s << " mesh " << c.pad.mesh->key;
  for (const auto& row : Rows()) {
    if (row.scope != S::kModel) continue;
    s << " | " << row.key << ' ';
    switch (row.kind) {
      case K::kCustom:
        if (!row.cache_key)
          throw std::logic_error(std::string("attribute row `") + row.key + "` has no cache key");
        row.cache_key(c, s);
        break;
      case K::kPerClass:
        for (int k = 0; k < kNumClasses; ++k) s << row.get(c, k) << ' ';
        break;
      default: s << row.get(c, 0);
    }
  }
  return s.str();
}

std::string AttributeTableMarkdown() {
  std::string out = "| key | default | units | valid | meaning |\n|---|---|---|---|---|\n";
  for (const auto& row : Rows()) {
    std::string valid = ValidRangeText(row), pipe = "|";
    for (size_t at = valid.find(pipe); at != std::string::npos; at = valid.find(pipe, at + 2))
      valid.replace(at, 1, "\\|");  // a literal | inside a table cell
    out += "| `" + std::string(row.key) + "` | " + row.default_text + " | " + row.units + " | " +
           valid + " | " + row.meaning + " |\n";
  }
  return out;
}

}  // namespace mjtouch
