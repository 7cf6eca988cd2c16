// Leaky integrate-and-fire membranes integrated in closed form: a drive
// linear in time over an interval, minus a spike-triggered adaptation
// current that decays exponentially (the post-spike current of TouchSim,
// Saal et al. 2017, reduced to one exponential). Threshold crossings are
// solved to round-off, so no spike is lost at coarse steps.
#ifndef MJTOUCH_AFFERENTS_MEMBRANE_H_
#define MJTOUCH_AFFERENTS_MEMBRANE_H_

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
int LinearDriveLIF(int nodes, double* u, const double* a, const double* b, double span,
                   double tau, double refractory, double* refractory_left,
                   const Adaptation& adapt, double* adapt_current,
                   void (*on_spike)(double t, void* ctx), void* ctx,
                   const MembraneSpan* pre = nullptr);

}  // namespace mjtouch

#endif  // MJTOUCH_AFFERENTS_MEMBRANE_H_
