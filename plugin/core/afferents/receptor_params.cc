// Stage 4's parameters: the SA1 gains of Wang et al. 2016 (Table 1) and the
// defaults derived from them, and the per-unit variants.
#include <algorithm>
#include <cstdint>

#include "afferents/noise.h"
#include "afferents/receptors.h"

namespace mjtouch {

using afferent_noise::SplitMix64;

void WangTable1Gains(Quantity q, SA1Params* p) {
  switch (q) {
    case Quantity::kCompressiveStrain:  // strain-based model
      p->k0_a_per_pa = 2.73e-12;
      p->k1_a_s_per_pa = 5.29e-12;
      p->i0_a = 4.66e-12;
      break;
    case Quantity::kStrainEnergy:  // SED-based model
      p->k0_a_per_pa = 1.46e-15;
      p->k1_a_s_per_pa = 6.81e-15;
      p->i0_a = 7.59e-12;
      break;
    default:  // stress-based model
      p->k0_a_per_pa = 1.40e-16;
      p->k1_a_s_per_pa = 1.68e-16;
      p->i0_a = 4.94e-12;
      break;
  }
}

void DefaultSA1Gains(Quantity q, SA1Params* p) {
  WangTable1Gains(q, p);
  p->saturation = 0.0;
  if (p->model == SA1Model::kFiltered) {
    // the row's rheobase quantity (heminode 1, the largest M) before rescaling
    double mmax = 0.0;
    for (double m : p->merkel_cells) mmax = std::max(mmax, m);
    const double rheobase =
        (p->threshold_v / p->resistance_ohm - p->i0_a) / (mmax * p->k0_a_per_pa);
    p->saturation = kSA1SaturationOverRheobase * rheobase;
    p->k0_a_per_pa *= kSA1StaticScale;
    p->k1_a_s_per_pa = p->k0_a_per_pa * kSA1RateTimeS;
  }
}

namespace {
// Per class: multipliers of (drive gain, membrane tau, adaptation jump).
// Variant 0 is the calibrated median unit. The spread is of the order of
// TouchSim's fitted afferents (membrane time constants within 0.6-2x of
// their class median, Saal et al. 2017), chosen so that every variant keeps
// its class's tuning (tests/unit/test_afferent_tuning.py).
const VariantScale kVariants[kNumClasses][kNumVariants] = {
    {{1.0, 1.0, 1.0}, {0.75, 1.3, 0.7}, {1.3, 0.8, 1.4}, {0.9, 1.15, 1.2}},
    {{1.0, 1.0, 1.0}, {0.75, 1.3, 0.7}, {1.3, 0.8, 1.4}, {0.9, 1.15, 1.2}},
    {{1.0, 1.0, 1.0}, {0.75, 1.2, 0.7}, {1.3, 0.85, 1.4}, {0.9, 1.1, 1.2}}};
}  // namespace

double NoiseSd(const ReceptorParams& p, ReceptorClass cls) {
  if (cls == ReceptorClass::kSA1 && p.sa1.model == SA1Model::kWang2016) return 0.0;
  return p.noise.sd[static_cast<int>(cls)];
}

const VariantScale& ReceptorVariant(ReceptorClass cls, int variant) {
  return kVariants[static_cast<int>(cls)][variant];
}

int VariantOf(const ReceptorParams& p, ReceptorClass cls, unsigned long long stream) {
  if (!p.varied || (cls == ReceptorClass::kSA1 && p.sa1.model == SA1Model::kWang2016)) return 0;
  // a stream of its own, apart from the noise's (counts 0, 1, ...)
  const uint64_t h = SplitMix64(SplitMix64(SplitMix64(p.noise.seed ^ 0x5a17ULL) ^ stream) ^
                                static_cast<uint64_t>(cls));
  return static_cast<int>(h % kNumVariants);
}

}  // namespace mjtouch
