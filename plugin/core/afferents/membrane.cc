#include "afferents/membrane.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace mjtouch {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int kMaxNodes = 4;  // receptors.cc: SA1 heminodes

// 1 - exp(-x) and x - 1 + exp(-x), accurate for small x.
double Phi1(double x) { return -std::expm1(-x); }
double Phi2(double x) {
  if (x >= 0.1) return x - Phi1(x);
  double term = x * x / 2.0, sum = 0.0;
  for (int k = 3; k < 16; ++k) {  // x^2/2! - x^3/3! + ..., 0.1^16/16! ~ 5e-30
    sum += term;
    term *= -x / k;
  }
  return sum;
}

// Equal time constants make kappa singular; a relative offset of 1e-9
// changes the membrane by ~1e-9 of the adaptation current.
double AdaptTau(const Adaptation& adapt, double tau) {
  return std::abs(adapt.tau_s - tau) < 1e-9 * tau ? tau * (1 + 1e-9) : adapt.tau_s;
}

// Membrane at time s from u0 under the drive a + b t: exact solution of
// tau du/dt = -u + a + b t. `pre` (tau its own): its exponentials at s = its span.
double Membrane(double u0, double a, double b, double tau, double s, const MembraneSpan* pre) {
  if (pre && s == pre->span) return u0 * pre->decay + a * pre->phi1 + b * tau * pre->phi2;
  const double x = s / tau;
  return u0 * std::exp(-x) + a * Phi1(x) + b * tau * Phi2(x);
}

// The membrane's response at s to the current -c exp(-t / tau_a) from t = 0
// (u(0) = 0): -c kappa (exp(-s / tau_a) - exp(-s / tau)),
// kappa = tau_a / (tau_a - tau).
double AdaptResponse(double c, double tau, double tau_a, double s, const MembraneSpan* pre) {
  if (c == 0.0) return 0.0;
  if (pre && s == pre->span) return -c * tau_a / (tau_a - tau) * pre->adapt_decay * pre->adapt_rise;
  const double x = s / tau, xa = s / tau_a;
  // exp(-xa) - exp(-x) = exp(-xa) (1 - exp(xa - x)), accurate for small s
  return -c * tau_a / (tau_a - tau) * std::exp(-xa) * -std::expm1(xa - x);
}

// First time in (0, span] at which the membrane reaches 1, or +inf. With
// c = u0 - a + b tau the membrane is a + b (t - tau) + c exp(-t / tau):
// convex for c >= 0 (one crossing at most, from below), concave for c < 0
// (rising to a maximum at tau ln(c / (b tau)) when b < 0).
double FirstCrossing(double u0, double a, double b, double tau, double span,
                     const MembraneSpan* pre) {
  if (u0 >= 1.0) return 0.0;
  double hi = span;
  const double c = u0 - a + b * tau;
  if (c < 0.0 && b < 0.0) {
    if (FallingStaysBelow(u0, a, b, tau, span, pre)) return kInf;
    const double ratio = c / (b * tau);
    if (ratio <= 1.0) return kInf;  // falling from the start
    hi = std::min(span, tau * std::log(ratio));
  }
  if (Membrane(u0, a, b, tau, hi, pre) < 1.0) return kInf;
  // Bracketed: f(lo) < 0 <= f(hi), f increasing through its one root.
  // Safeguarded Newton; returns the bracket's upper end (membrane >= 1).
  const double tol = 1e-15 * span;
  double lo = 0.0, s = hi;
  for (int it = 0; it < 200; ++it) {
    const double u = Membrane(u0, a, b, tau, s, nullptr);
    if (u >= 1.0)
      hi = s;
    else
      lo = s;
    if (hi - lo <= tol) break;
    const double du = (a + b * s - u) / tau;
    double next = du > 0.0 ? s - (u - 1.0) / du : 0.5 * (lo + hi);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    if (std::abs(next - s) <= tol) {
      // Converged: close the bracket above, stepping up from the estimate
      // by doubling steps (rounding can leave the membrane just below 1 a
      // tol above it; stopping there returned the old upper end, up to the
      // whole span late).
      const double base = std::max(next, s);
      for (double step = tol; base + step < hi; step *= 2.0) {
        if (Membrane(u0, a, b, tau, base + step, nullptr) >= 1.0) {
          hi = base + step;
          break;
        }
      }
      break;
    }
    s = next;
  }
  return hi;
}

// g(t) = A + B t + C exp(-l1 t) + D exp(-l2 t) and its derivatives.
struct ExpSum {
  double A, B, C, l1, D, l2;
  double g(double t) const { return A + B * t + C * std::exp(-l1 * t) + D * std::exp(-l2 * t); }
  double d1(double t) const { return B - C * l1 * std::exp(-l1 * t) - D * l2 * std::exp(-l2 * t); }
};

// Root of a monotone f on [lo, hi] with f(lo), f(hi) of opposite signs:
// bisection to round-off; returns the end where f has the sign of f(hi).
template <class F>
double Bisect(const F& f, double lo, double hi) {
  const bool up = f(hi) >= 0.0;
  for (int it = 0; it < 200 && hi - lo > 1e-15 * std::max(hi, 1e-300); ++it) {
    const double mid = 0.5 * (lo + hi);
    if ((f(mid) >= 0.0) == up)
      hi = mid;
    else
      lo = mid;
  }
  return hi;
}

// First crossing of 1 in [0, span] of the membrane under a + b t minus the
// adaptation current c exp(-t / tau_a) (c > 0). The adapted membrane lies
// below the free one, so it crosses no earlier than the free one does (t0);
// u - 1 = A + B t + C e^{-t/tau} + D e^{-t/tau_a} has a second derivative
// with at most one sign change, so at most two extrema: split [t0, span]
// at them and take the first monotone piece that reaches 1.
double FirstCrossingAdapted(double u0, double a, double b, double tau, double c, double tau_a,
                            double span, const MembraneSpan* pre) {
  const double t0 = FirstCrossing(u0, a, b, tau, span, pre);
  if (!(t0 <= span)) return kInf;
  if (t0 == 0.0) return 0.0;  // u0 >= 1
  const double kappa = tau_a / (tau_a - tau);
  const ExpSum e{a - b * tau - 1.0, b,          u0 - a + b * tau + c * kappa,
                 1.0 / tau,         -c * kappa, 1.0 / tau_a};
  double pts[6];
  int n = 0;
  pts[n++] = t0;
  // inflection: C l1^2 e^{-l1 t} = -D l2^2 e^{-l2 t}
  const double r = -e.C * e.l1 * e.l1 / (e.D * e.l2 * e.l2);
  if (r > 0.0) {
    const double ti = std::log(r) / (e.l1 - e.l2);
    if (ti > t0 && ti < span) pts[n++] = ti;
  }
  pts[n++] = span;
  // extrema of g: roots of g' (monotone between inflections)
  double cuts[6];
  int m = 0;
  cuts[m++] = t0;
  for (int i = 0; i + 1 < n; ++i) {
    const double p = pts[i], q = pts[i + 1];
    const double dp = e.d1(p), dq = e.d1(q);
    if ((dp < 0.0) != (dq < 0.0)) {
      const double root = Bisect([&](double t) { return e.d1(t); }, p, q);
      if (root > cuts[m - 1] && root < span) cuts[m++] = root;
    }
    if (i + 2 < n) cuts[m++] = q;
  }
  cuts[m++] = span;
  if (e.g(t0) >= 0.0) return t0;
  for (int i = 0; i + 1 < m; ++i) {
    const double p = cuts[i], q = cuts[i + 1];
    if (!(q > p)) continue;
    if (e.g(q) >= 0.0) {
      if (e.g(p) >= 0.0) return p;
      return Bisect([&](double t) { return e.g(t); }, p, q);
    }
  }
  return kInf;
}

}  // namespace

MembraneSpan PrecomputeSpan(double span, double tau, const Adaptation& adapt) {
  MembraneSpan p;
  p.span = span;
  p.tau = tau;
  p.tau_a = AdaptTau(adapt, tau);
  // as Membrane, AdaptResponse and LinearDriveLIF's decay evaluate them
  const double x = span / tau, xa = span / p.tau_a;
  p.decay = std::exp(-x);
  p.phi1 = Phi1(x);
  p.phi2 = Phi2(x);
  p.adapt_decay = std::exp(-xa);
  p.adapt_rise = -std::expm1(xa - x);
  return p;
}

int LinearDriveLIF(int nodes, double* u, const double* a, const double* b, double span, double tau,
                   double refractory, double* refractory_left, const Adaptation& adapt,
                   double* adapt_current, void (*on_spike)(double t, void* ctx), void* ctx,
                   const MembraneSpan* pre) {
  const double tau_a = AdaptTau(adapt, tau);
  if (pre && !(pre->tau == tau && pre->tau_a == tau_a)) pre = nullptr;
  int spikes = 0;
  double t = 0.0;
  double& w = *adapt_current;
  auto decay = [&](double s) {
    if (w != 0.0) w *= pre && s == pre->span ? pre->adapt_decay : std::exp(-s / tau_a);
  };
  // The common step: the whole interval of `pre`, no refractory time, no
  // spike (membrane.h).
  if (pre && span == pre->span && !(*refractory_left > 0.0) &&
      QuietWholeSpan(nodes, u, a, b, *pre, adapt_current))
    return 0;
  while (t < span) {
    if (*refractory_left > 0.0) {  // membranes held at reset
      const double used = std::min(*refractory_left, span - t);
      *refractory_left -= used;
      t += used;
      decay(used);
      for (int k = 0; k < nodes; ++k) u[k] = 0.0;
      if (t >= span) break;
    }
    const double left = span - t;
    double hit = kInf;
    for (int k = 0; k < nodes; ++k) {
      const double ak = a[k] + b[k] * t;
      const double h = w > 0.0 ? FirstCrossingAdapted(u[k], ak, b[k], tau, w, tau_a, left, pre)
                               : FirstCrossing(u[k], ak, b[k], tau, left, pre);
      hit = std::min(hit, h);
    }
    if (!(hit <= left)) {
      double end[kMaxNodes];
      bool over = false;
      const double adapt_end = AdaptResponse(w, tau, tau_a, left, pre);  // the same for every node
      for (int k = 0; k < nodes && k < kMaxNodes; ++k) {
        end[k] = Membrane(u[k], a[k] + b[k] * t, b[k], tau, left, pre) + adapt_end;
        over = over || end[k] >= 1.0;
      }
      if (!over) {
        for (int k = 0; k < nodes && k < kMaxNodes; ++k) u[k] = end[k];
        decay(left);
        break;
      }
      // The search found no crossing but the membrane ends at or over
      // threshold (the bracket closure in FirstCrossing once returned the
      // span's end for a crossing early in it: 5 in 2e6 random intervals;
      // fixed, kept as a guard against round-off at the very end): fire at
      // the interval's end rather than carry a membrane over threshold.
      hit = left;
    }
    t += hit;
    decay(hit);
    ++spikes;
    if (on_spike) on_spike(t, ctx);
    for (int k = 0; k < nodes; ++k) u[k] = 0.0;
    w += adapt.jump;
    *refractory_left = refractory;
  }
  return spikes;
}

}  // namespace mjtouch
