// Standalone check of ReceptorStepper::AdvanceBatch (plugin/core/afferents/
// receptor_batch.cc: one class's receptors in four lanes) against Advance,
// receptor by receptor: over random scenarios (parameters, step sizes,
// quantities that make the receptors fire, kink, sub-step, rest, refractory
// and adapt), every step's spike counts, voltages and the whole receptor
// state must be the same bits. ReceptorQuantities (the quantities of many
// receptors at once) against ReceptorQuantity likewise. ~2 s.
//   ./test_receptor_batch   # PASS/FAIL lines, exit status 1 on failure
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <vector>

#include "afferents/receptors.h"

using namespace mjtouch;

namespace {

bool SameBits(double x, double y) { return std::memcmp(&x, &y, sizeof x) == 0; }

}  // namespace

int main() {
  const int kScenarios = 150, kReceptors = 39, kSteps = 400;
  int bad = 0;
  long spikes = 0, kinds[3] = {0, 0, 0};
  for (int sc = 0; sc < kScenarios; ++sc) {
    std::mt19937_64 rng(sc);
    std::uniform_real_distribution<double> U(0.0, 1.0);
    ReceptorParams p;
    const Quantity quantities[3] = {Quantity::kMaxCompressive, Quantity::kCompressiveSzz,
                                    Quantity::kStrainEnergy};
    p.sa1.model = sc % 5 == 4 ? SA1Model::kWang2016 : SA1Model::kFiltered;
    DefaultSA1Gains(quantities[sc % 3], &p.sa1);
    if (sc % 7 == 3) p.sa1.merkel_cells = {6, 2};
    if (sc % 4 == 1) p.ra.saturation = 0.0;
    if (sc % 6 == 5) p.ra.sustained = 0.0;
    if (sc % 4 == 3) p.pc.saturation = 1.0 + 8.0 * U(rng);  // PC sub-steps
    if (sc % 4 == 2) p.noise.sd[0] = p.noise.sd[1] = p.noise.sd[2] = 0.0;
    if (sc % 3 == 0) p.noise.sd[1] = p.noise.sd[2] = 1.5 * U(rng);
    p.noise.seed = rng();
    p.varied = sc % 5 != 0;
    const double dts[5] = {1e-4, 2e-3, 1e-5, 5e-4, 1e-3};
    const ReceptorStepper stepper(p, dts[sc % 5]);
    const double dt = stepper.dt();
    // three class runs, as the model lays the receptors out
    std::vector<ReceptorClass> cls(kReceptors);
    std::vector<double> amp(kReceptors), freq(kReceptors), phase(kReceptors), offset(kReceptors);
    for (int r = 0; r < kReceptors; ++r) {
      cls[r] = static_cast<ReceptorClass>(r * 3 / kReceptors);
      amp[r] = std::pow(10.0, 1.0 + 4.5 * U(rng));  // Pa
      freq[r] = std::pow(10.0, 3.0 * U(rng));       // Hz
      phase[r] = 6.28 * U(rng);
      offset[r] = (U(rng) - 0.3) * amp[r];
    }
    std::vector<double> st_one(kReceptors * kReceptorStateSize, 0.0), st_batch = st_one;
    std::vector<double> q(kReceptors), k_batch(kReceptors), v_batch(kReceptors);
    for (int s = 0; s < kSteps; ++s) {
      for (int r = 0; r < kReceptors; ++r) {
        q[r] = offset[r] + amp[r] * std::sin(6.283185307179586 * freq[r] * s * dt + phase[r]);
        if ((s / 37 + r) % 11 == 0) q[r] = 0.0;  // stretches at rest
      }
      for (int r = 0; r < kReceptors;) {
        int end = r + 1;
        while (end < kReceptors && cls[end] == cls[r]) ++end;
        stepper.AdvanceBatch(cls[r], end - r, &q[r], r, &st_batch[r * kReceptorStateSize],
                             &k_batch[r], &v_batch[r]);
        r = end;
      }
      for (int r = 0; r < kReceptors; ++r) {
        double v;
        const int k = stepper.Advance(cls[r], q[r], r, &st_one[r * kReceptorStateSize], &v);
        spikes += k;
        kinds[static_cast<int>(cls[r])] += k;
        bool same = k == k_batch[r] && SameBits(v, v_batch[r]);
        for (int i = 0; i < kReceptorStateSize; ++i)
          same = same &&
                 SameBits(st_one[r * kReceptorStateSize + i], st_batch[r * kReceptorStateSize + i]);
        if (!same && ++bad <= 5)
          std::printf(
              "FAIL: scenario %d step %d receptor %d (%s): spikes %d / %g, voltage "
              "%.17g / %.17g\n",
              sc, s, r, ClassName(cls[r]), k, k_batch[r], v, v_batch[r]);
      }
    }
  }
  std::printf("%d scenarios x %d receptors x %d steps: %ld spikes (SA1 %ld, RA %ld, PC %ld)\n",
              kScenarios, kReceptors, kSteps, spikes, kinds[0], kinds[1], kinds[2]);
  // the scenarios must make every class fire, or the check would not reach
  // FromDrive's spiking steps
  if (kinds[0] == 0 || kinds[1] == 0 || kinds[2] == 0) {
    std::printf("FAIL: a class never fired\n");
    ++bad;
  }
  {  // ReceptorQuantities against ReceptorQuantity: random tensors over ten
     // decades, some diagonal, some with round-off shears, some isotropic
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> U(-1.0, 1.0);
    const int n = 4003;
    std::vector<double> stress(6 * n), batch(n);
    for (int i = 0; i < n; ++i) {
      double* s = &stress[6 * i];
      const double scale = std::pow(10.0, 5.0 * (U(rng) + 1.0));  // Pa
      for (int j = 0; j < 3; ++j) s[j] = scale * (U(rng) - 0.8);
      const int kind = i % 8;
      for (int j = 3; j < 6; ++j)
        s[j] = kind == 0 ? 0.0 : kind == 1 ? 1e-17 * scale * U(rng) : 0.3 * scale * U(rng);
      if (kind == 2) s[1] = s[2] = s[0];
    }
    int bad_q = 0;
    for (int quantity = 0; quantity < 4; ++quantity) {  // szz, maxcomp, vonmises, maxshear
      const Quantity q = static_cast<Quantity>(quantity);
      ReceptorQuantities(q, n, stress.data(), batch.data());
      for (int i = 0; i < n; ++i)
        if (!SameBits(batch[i], ReceptorQuantity(q, &stress[6 * i])) && ++bad_q <= 5)
          std::printf("FAIL: %s of tensor %d: %.17g, ReceptorQuantity %.17g\n", QuantityName(q), i,
                      batch[i], ReceptorQuantity(q, &stress[6 * i]));
    }
    std::printf("ReceptorQuantities: %d tensors x 4 quantities, %d differ\n", n, bad_q);
    bad += bad_q;
  }
  std::printf("%s: %d failure(s)\n", bad ? "FAIL" : "PASS", bad);
  return bad ? 1 : 0;
}
