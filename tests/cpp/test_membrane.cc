// Standalone check of the afferents' exact LIF integrator
// (plugin/core/afferents/membrane.*): over random one-step intervals (the
// ranges the SA1, RA and PC membranes meet: linear drive, adaptation current,
// one node), the first spike LinearDriveLIF reports is the membrane's first
// threshold crossing, found by dense sampling of the closed form. A spike
// late by up to the whole interval (a bracket closure that returns the
// interval's end) fails it. The same
// intervals with the exponentials precomputed for their span (MembraneSpan,
// as ReceptorStepper passes them) must give the same spikes, membrane and
// adaptation current bit for bit.
//   ./test_membrane   # PASS/FAIL lines, exit status 1 on failure
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>

#include "afferents/membrane.h"

using namespace mjtouch;

namespace {

// u(s) - 1 in closed form: tau du/dt = -u + a + b t - c exp(-t / tau_a).
double Excess(double u0, double a, double b, double c, double tau, double tau_a, double s) {
  const double x = s / tau;
  const double free = u0 * std::exp(-x) - a * std::expm1(-x) + b * tau * (x + std::expm1(-x));
  const double adapt = -c * tau_a / (tau_a - tau) * (std::exp(-s / tau_a) - std::exp(-x));
  return free + adapt - 1.0;
}

void OnSpike(double t, void* ctx) {
  double* first = static_cast<double*>(ctx);
  if (!(*first >= 0.0)) *first = t;
}

bool SameBits(double x, double y) { return std::memcmp(&x, &y, sizeof x) == 0; }

}  // namespace

int main() {
  // (tau, tau_a) of SA1 (R C), RA, PC
  const double taus[3][2] = {{0.015, 0.05}, {5e-3, 0.03}, {1.5e-3, 0.02}};
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const int kIntervals = 1000000, kSamples = 200;
  int bad = 0, bad_pre = 0;
  double worst = 0.0;
  for (int it = 0; it < kIntervals; ++it) {
    const double tau = taus[it % 3][0], tau_a = taus[it % 3][1];
    const double span = 1e-4 * (1.0 + 9.0 * U(rng));
    double u = -1.0 + 2.0 * U(rng);
    const double u0 = u;
    const double a = -5.0 + 15.0 * U(rng);
    const double b = (-1.0 + 2.0 * U(rng)) * (U(rng) < 0.5 ? 1e4 : 10.0);
    const double c = it % 2 ? 0.0 : 10.0 * U(rng) * U(rng);
    double w = c, refractory_left = 0.0, first = -1.0;
    const int spikes = LinearDriveLIF(1, &u, &a, &b, span, tau, 1e-3, &refractory_left,
                                      Adaptation{0.0, tau_a}, &w, OnSpike, &first);
    {  // the precomputed exponentials: the same result, bit for bit
      const Adaptation adapt{0.0, tau_a};
      const MembraneSpan pre = PrecomputeSpan(span, tau, adapt);
      double u2 = u0, w2 = c, refractory2 = 0.0, first2 = -1.0;
      const int spikes2 = LinearDriveLIF(1, &u2, &a, &b, span, tau, 1e-3, &refractory2, adapt, &w2,
                                         OnSpike, &first2, &pre);
      if (spikes2 != spikes || !SameBits(u2, u) || !SameBits(w2, w) || !SameBits(first2, first) ||
          !SameBits(refractory2, refractory_left)) {
        if (bad_pre < 5)
          std::printf(
              "  interval %d: u0 %.17g a %.17g b %.17g c %.17g span %.17g: precomputed "
              "spans give spike %.17g, u %.17g (direct %.17g, %.17g)\n",
              it, u0, a, b, c, span, first2, u2, first, u);
        ++bad_pre;
      }
    }
    double brute = -1.0;
    for (int k = 1; k <= kSamples; ++k) {
      const double s = span * k / kSamples;
      if (Excess(u0, a, b, c, tau, tau_a, s) >= 0.0) {
        brute = s;
        break;
      }
    }
    // A spike is at threshold, no later than the first sample over it and
    // within one sample of it (a crossing and return between samples may
    // give a spike without a sample over threshold).
    const bool at_threshold = first >= 0.0 && Excess(u0, a, b, c, tau, tau_a, first) >= -1e-9;
    const bool ok = brute < 0.0 ? (first < 0.0 || at_threshold)
                                : at_threshold && first <= brute + 1e-12 &&
                                      first > brute - span / kSamples - 1e-12;
    if (!ok) {
      if (bad < 5)
        std::printf(
            "  interval %d: u0 %.17g a %.17g b %.17g c %.17g span %.17g: spike %.9g, "
            "sampled crossing %.9g\n",
            it, u0, a, b, c, span, first, brute);
      ++bad;
      if (first >= 0.0 && brute >= 0.0) worst = std::max(worst, (first - brute) / span);
    }
  }
  std::printf("%s first spike = first crossing: %d of %d intervals off (worst %.3g of the span)\n",
              bad ? "FAIL" : "PASS", bad, kIntervals, worst);
  std::printf("%s precomputed spans = direct, bit for bit: %d of %d intervals off\n",
              bad_pre ? "FAIL" : "PASS", bad_pre, kIntervals);
  const int failures = (bad ? 1 : 0) + (bad_pre ? 1 : 0);
  std::printf("%s: %d failure(s)\n", failures ? "FAIL" : "PASS", failures);
  return failures ? 1 : 0;
}
