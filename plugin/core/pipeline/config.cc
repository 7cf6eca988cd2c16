// SkinConfig defaults and the checks that need more than one attribute's
// value: the elastic skin against the receptor depths, the pad (Finalize),
// and the timestep (CheckTactileRate, ResolveOversample).
#include <algorithm>
#include <cmath>
#include <memory>

#include "pipeline/config.h"
#include "pipeline/text.h"

namespace mjtouch {
namespace {

constexpr int kMaxOversample = 64;  // `oversample`'s upper bound

bool NeedsMaterial(Quantity q) {
  return q == Quantity::kStrainEnergy || q == Quantity::kCompressiveStrain;
}

}  // namespace

std::unique_ptr<LayeredSubstrate> CreateLayeredSkin(const SkinConfig& cfg, std::string* error) {
  std::string why;
  auto skin = LayeredSubstrate::Create(cfg.layers, cfg.base, cfg.interface_side, &why);
  if (!skin) *error = "mjtouch.skin: attribute `layers` / `base`: " + why;
  return skin;
}

bool CheckElasticSkin(const SkinConfig& cfg, std::string* error) {
  std::unique_ptr<LayeredSubstrate> skin;
  if (cfg.layered && !(skin = CreateLayeredSkin(cfg, error))) return false;
  return CheckElasticSkin(cfg, skin.get(), error);
}

// Receptor depths inside the elastic skin; strain and SED need a material.
bool CheckElasticSkin(const SkinConfig& cfg, const LayeredSubstrate* sub, std::string* error) {
  for (int c = 0; c < kNumClasses; ++c) {
    const ClassConfig& k = cfg.classes[c];
    if (!k.present) continue;
    const char* name = ClassName(static_cast<ReceptorClass>(c));
    if (!sub) {
      if (NeedsMaterial(k.quantity)) {
        *error =
            Fmt("mjtouch.skin: attribute `quantity`: '%s' for %s needs skin=\"layered\" (a "
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
      *error =
          Fmt("mjtouch.skin: attribute %s (%s, %g m) is outside the elastic skin (%s); "
              "valid range (0, %g%s m for these `layers` over a rigid `base`%s",
              where.c_str(), name, k.depth_m, why.c_str(), sub->stack_depth_m(), upper ? "]" : ")",
              upper ? "" : " with interface_side=\"lower\"");
      return false;
    }
  }
  return true;
}

const char* OutputName(int block) {
  static const char* names[kNumOutputs] = {"spikes", "stress",   "voltage", "force", "pressure",
                                           "rate",   "coverage", "stick",   "slip",  "shear"};
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

bool CheckTactileRate(const SkinConfig& cfg, double timestep_s, std::string* error) {
  // Only the afferents filter: without spikes, voltage or rate outputs the
  // stress is merely sampled.
  const bool afferents =
      cfg.outputs[kOutSpikes] || cfg.outputs[kOutVoltage] || cfg.outputs[kOutRate];
  if (!(timestep_s > 0.0) || !afferents) return true;
  const double rate_hz = cfg.oversample / timestep_s;
  const struct {
    ReceptorClass cls;
    double corner_hz;
    const char* key;
  } bands[] = {{ReceptorClass::kPC, cfg.receptor.pc.lowpass_hz, "pc_lowpass"},
               {ReceptorClass::kRA, cfg.receptor.ra.lowpass_hz, "ra_lowpass"}};
  for (const auto& b : bands) {
    if (!cfg.classes[static_cast<int>(b.cls)].present) continue;
    const double need_hz = 8.0 * b.corner_hz;
    if (rate_hz >= need_hz * (1 - 1e-12)) continue;
    const int k = static_cast<int>(std::ceil(need_hz * timestep_s * (1 - 1e-12)));
    *error =
        Fmt("mjtouch.skin: %s afferents need tactile sampling of at least %g Hz (8 x `%s` "
            "= %g Hz: their band reaches a few times the corner); the timestep %g s with "
            "`oversample` = %d samples at %g Hz: ",
            ClassName(b.cls), need_hz, b.key, b.corner_hz, timestep_s, cfg.oversample, rate_hz);
    // Advice that can be followed: `oversample` only while 64 suffices.
    if (k <= kMaxOversample)
      *error += Fmt("set `oversample` >= %d (valid [1, %d]), or ", k, kMaxOversample);
    else
      *error +=
          Fmt("even `oversample` = %d reaches %g Hz; set `%s` <= %g Hz, or the timestep "
              "<= %g s, or ",
              kMaxOversample, kMaxOversample / timestep_s, b.key, kMaxOversample / timestep_s / 8.0,
              kMaxOversample / need_hz);
    *error += Fmt("remove %s from `classes`", ClassName(b.cls));
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

bool FinalizeSkinConfig(SkinConfig* cfg, std::string* error) {
  const double* ax = cfg->pad.semi_axes_m;
  if (!(ax[0] > 0 && ax[1] > 0 && ax[2] > 0)) {
    *error = "mjtouch.skin: the pad geom must have positive size";
    return false;
  }
  // Receptor sites must lie under the pad's skin (the receptor count depends
  // on attributes only, so this is a check, not a refit).
  const double footprint = 0.9 * PadFootprintSemiAxis(cfg->pad);
  for (size_t e = 0; e < cfg->sites.size(); ++e) {
    const ExplicitSite& s = cfg->sites[e];
    if (std::hypot(s.x_m, s.y_m) > footprint) {
      *error =
          Fmt("mjtouch.skin: attribute `sites` entry %zu (%s at x = %g, y = %g m) is not "
              "under the pad; valid: within %g m of the pole (0.9 x the smaller semi-axis)",
              e + 1, ClassName(s.cls), s.x_m, s.y_m, footprint);
      return false;
    }
  }
  if (cfg->sites.empty() && cfg->population_radius_m > footprint) {
    *error =
        Fmt("mjtouch.skin: attribute `radius` = %g m%s exceeds 0.9 x the pad's smaller "
            "semi-axis; valid range [0, %g] m",
            cfg->population_radius_m, cfg->radius_is_default ? " (default)" : "", footprint);
    return false;
  }
  return true;
}
}  // namespace mjtouch
