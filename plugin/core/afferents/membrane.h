// Leaky integrate-and-fire membranes integrated in closed form: a drive
// linear in time over an interval, minus a spike-triggered adaptation
// current that decays exponentially (the post-spike current of TouchSim,
// Saal et al. 2017, reduced to one exponential). Threshold crossings are
// solved to round-off, so no spike is lost at coarse steps.
#ifndef MJTOUCH_AFFERENTS_MEMBRANE_H_
#define MJTOUCH_AFFERENTS_MEMBRANE_H_

#include <algorithm>
#include <cmath>

namespace mjtouch {

// Spike-triggered adaptation: each spike adds `jump` (threshold units of
// drive) to a current that decays with time constant tau_s and is
// subtracted from every node's drive. jump = 0 disables it.
struct Adaptation {
  double jump = 0.0;
  double tau_s = 0.02;
};

// The exponentials of LinearDriveLIF over one interval length `span`, for a
// membrane time constant tau and an adaptation (its tau_a as LinearDriveLIF
// takes it), evaluated once (ReceptorStepper: per class and variant for the
// step) instead of per receptor per step. The same expressions evaluated
// once: results are bit for bit those without it.
struct MembraneSpan {
  double span = -1.0, tau = 0.0, tau_a = 0.0;
  double decay = 0.0;        // exp(-span / tau)
  double phi1 = 0.0;         // 1 - exp(-span / tau)
  double phi2 = 0.0;         // span / tau - 1 + exp(-span / tau)
  double adapt_decay = 0.0;  // exp(-span / tau_a)
  double adapt_rise = 0.0;   // 1 - exp(span / tau_a - span / tau)
};
MembraneSpan PrecomputeSpan(double span, double tau, const Adaptation& adapt);

// Membranes u_k (over threshold) of `nodes` nodes sharing one spike
// initiation zone: tau du_k/dt = -u_k + a_k + b_k t - w(t) over [0, span],
// w the adaptation current (*adapt at t = 0, decaying with adapt.tau_s,
// +adapt.jump at each spike). Threshold 1; at a spike every node resets to
// 0 and is held there for `refractory` s (`refractory_left` carries over
// between calls). Each spike time (from the interval start) is passed to
// on_spike(t, ctx). Returns the spike count. `pre` (optional): exponentials
// precomputed for intervals of its span (used where an interval has exactly
// that length and tau and the adaptation's tau_a match; ignored otherwise).
// Under a falling drive (b < 0: b tau Phi2 <= 0) the membrane stays below
// u0 + (a - u0) Phi1(t / tau), monotone in t: below max(u0, a), and over
// the whole span (`pre`) below max(u0, its value at the span's end). Whether
// that is under 1 by far more than the round-off of the membrane's closed
// form: then no point of the interval can evaluate to >= 1, and the crossing
// search would return +inf too (this skips its log and exponentials).
inline bool FallingStaysBelow(double u0, double a, double b, double tau, double span,
                              const MembraneSpan* pre) {
  const double margin = 1e-9 * (1.0 + std::abs(u0) + std::abs(a) + std::abs(b) * (tau + span));
  const double bound =
      pre && span == pre->span ? std::max(u0, u0 * pre->decay + a * pre->phi1) : std::max(u0, a);
  return bound < 1.0 - margin;
}

// LinearDriveLIF's common step, inline for ReceptorStepper's per-class
// loops: an interval of exactly pre.span (tau and tau_a those of `pre`), no
// refractory time left. When no node can reach threshold in it (decided as
// LinearDriveLIF decides it at t = 0: FirstCrossing's no-crossing exits, and
// FirstCrossingAdapted starts with FirstCrossing), sets the end membranes
// and the decayed adaptation current as LinearDriveLIF would and returns
// true; otherwise changes nothing and returns false (LinearDriveLIF then
// takes the interval). Bit for bit LinearDriveLIF's results.
inline bool QuietWholeSpan(int nodes, double* u, const double* a, const double* b,
                           const MembraneSpan& pre, double* adapt_current) {
  constexpr int kMaxQuietNodes = 4;
  if (nodes > kMaxQuietNodes) return false;
  const double tau = pre.tau, tau_a = pre.tau_a, span = pre.span;
  const double w = *adapt_current;
  // AdaptResponse(w, tau, tau_a, span, &pre): the same for every node
  const double adapt_end =
      w == 0.0 ? 0.0 : -w * tau_a / (tau_a - tau) * pre.adapt_decay * pre.adapt_rise;
  double end[kMaxQuietNodes];
  for (int k = 0; k < nodes; ++k) {
    const double u0 = u[k], bk = b[k], ak = a[k] + bk * 0.0;  // t = 0, as the loop takes it
    if (u0 >= 1.0) return false;
    const double m = u0 * pre.decay + ak * pre.phi1 + bk * tau * pre.phi2;  // Membrane
    if (u0 - ak + bk * tau < 0.0 && bk < 0.0) {
      if (!FallingStaysBelow(u0, ak, bk, tau, span, &pre)) return false;
    } else if (!(m < 1.0)) {
      return false;
    }
    end[k] = m + adapt_end;
    if (end[k] >= 1.0) return false;
  }
  for (int k = 0; k < nodes; ++k) u[k] = end[k];
  if (w != 0.0) *adapt_current = w * pre.adapt_decay;
  return true;
}

int LinearDriveLIF(int nodes, double* u, const double* a, const double* b, double span, double tau,
                   double refractory, double* refractory_left, const Adaptation& adapt,
                   double* adapt_current, void (*on_spike)(double t, void* ctx), void* ctx,
                   const MembraneSpan* pre = nullptr);

}  // namespace mjtouch

#endif  // MJTOUCH_AFFERENTS_MEMBRANE_H_
