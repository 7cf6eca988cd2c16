// Stage 4's stepper: ReceptorStepper advances each receptor's filters,
// noise and membranes over one step, exactly for a drive linear in the step.
#include "afferents/receptors.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "afferents/matrix_exp.h"
#include "afferents/noise.h"
#include "afferents/receptor_state.h"

namespace mjtouch {

using namespace receptor_state;  // NOLINT: the state slots
using namespace afferent_noise;  // NOLINT: SplitMix64, NormalHashed, Normal, kTwoPi

namespace {

constexpr double kIdleNoiseSds = 4.5;  // ReceptorStepper::Quiescent with noise

// SA1 input saturation q / (1 + |q| / s) (SA1Params::saturation; s = 0:
// none); odd and monotone, so zero crossings and order are kept.
double SaturateSA1(const SA1Params& s, double q) {
  if (s.model != SA1Model::kFiltered || !(s.saturation > 0.0)) return q;
  return q / (1.0 + std::abs(q) / s.saturation);
}

struct SpikeSink {
  double offset;  // start of the current segment in the step, s
  double dt, rate_tau, rate_sum;
};

void OnSpike(double t, void* ctx) {
  auto* sink = static_cast<SpikeSink*>(ctx);
  sink->rate_sum += std::exp(-(sink->dt - (sink->offset + t)) / sink->rate_tau);
}

}  // namespace

namespace {
// Membrane time constant of class cls, variant var (s), as Advance takes it.
double MembraneTau(const ReceptorParams& p, ReceptorClass cls, const VariantScale& var) {
  switch (cls) {
    case ReceptorClass::kSA1: return p.sa1.resistance_ohm * p.sa1.capacitance_f * var.tau;
    case ReceptorClass::kRA: return p.ra.tau_s * var.tau;
    default: return p.pc.tau_s * var.tau;
  }
}
}  // namespace

ReceptorStepper::ReceptorStepper(const ReceptorParams& p, double dt_s) : p_(p), dt_(dt_s) {
  // Exact propagation of x' = A x + B v for v constant over dt: the
  // exponential of the augmented matrix [[A, B], [0, 0]] dt.
  auto build_h = [](double dt_s, int n, const double* A, const double* B, const double* c,
                    Filter* f) {
    const int m = n + 1;
    double M[25] = {0}, E[25];
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) M[i * m + j] = A[i * n + j] * dt_s;
      M[i * m + n] = B[i] * dt_s;
    }
    Expm(m, M, E);
    f->n = n;
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) f->phi[i * n + j] = E[i * m + j];
      f->gamma[i] = E[i * m + n];
      f->c[i] = c[i];
    }
  };
  auto build = [&](int n, const double* A, const double* B, const double* c, Filter* f) {
    build_h(dt_s, n, A, B, c, f);
  };
  {  // SA1 (kFiltered): y = w^2 / (s + w)^2 v
    const double w = kTwoPi * p.sa1.lowpass_hz;
    const double A[4] = {-w, 0, w, -w}, B[2] = {w, 0}, c[2] = {0, 1};
    build(2, A, B, c, &sa1_);
  }
  {  // RA: y = x2 = w^2 / (s + w)^2 v; x3 = y / (1 + tau_m s), its sustained part
    const double w = kTwoPi * p.ra.lowpass_hz, wm = 1.0 / p.ra.sustained_tau_s;
    const double A[9] = {-w, 0, 0, w, -w, 0, 0, wm, -wm}, B[3] = {w, 0, 0}, c[3] = {0, 1, 0};
    build(3, A, B, c, &ra_);
    for (int level = 1; level <= kMaxSubLevels; ++level)
      build_h(std::ldexp(dt_s, -level), 3, A, B, c, &sub_[0][level - 1]);
  }
  {  // PC: a = v / (s + wh); b_k = wl b_{k-1} / (s + wl); y = s^2 b3
    const double wh = kTwoPi * p.pc.highpass_hz, wl = kTwoPi * p.pc.lowpass_hz;
    const double A[16] = {-wh, 0, 0, 0, wl, -wl, 0, 0, 0, wl, -wl, 0, 0, 0, wl, -wl};
    const double B[4] = {1, 0, 0, 0};
    const double c[4] = {0, wl * wl, -2 * wl * wl, wl * wl};
    build(4, A, B, c, &pc_);
    for (int level = 1; level <= kMaxSubLevels; ++level)
      build_h(std::ldexp(dt_s, -level), 4, A, B, c, &sub_[1][level - 1]);
  }
  noise_rho_ = std::exp(-dt_s / p.noise.tau_s);
  rate_decay_ = std::exp(-dt_s / p.rate_tau_s);
  seed_hash_ = SplitMix64(p.noise.seed);
  sa1_scale_ = p.sa1.resistance_ohm / p.sa1.threshold_v;
  for (int c = 0; c < kNumClasses; ++c)
    noise_gain_[c] =
        NoiseSd(p, static_cast<ReceptorClass>(c)) * std::sqrt(1.0 - noise_rho_ * noise_rho_);
  sustained_ = p.ra.sustained;
  saturation_[0] = 0.0;
  saturation_[1] = p.ra.saturation;
  saturation_[2] = p.pc.saturation;
  for (int k = 0; k < 2; ++k) {
    for (int level = 0; level < kMaxSubLevels; ++level) {
      sub_error_den_[k][level] = 4.0 * saturation_[k + 1] * std::ldexp(1.0, 2 * level);
      sub_error_skip_[k][level] = 0.99e-4 * sub_error_den_[k][level];
    }
  }
  static_assert(kMaxNodes == 4, "sa1_m_ holds kMaxNodes heminodes");
  sa1_nodes_ = static_cast<int>(std::min<size_t>(p.sa1.merkel_cells.size(), kMaxNodes));
  zero_rate_ = 0.0 / p.rate_tau_s;
  for (int c = 0; c < kNumClasses; ++c) {
    const ReceptorClass cls = static_cast<ReceptorClass>(c);
    noise_on_[c] = NoiseSd(p, cls) > 0.0;
    for (int v = 0; v < kNumVariants; ++v) {
      const VariantScale& var = ReceptorVariant(cls, v);
      tau_[c][v] = MembraneTau(p, cls, var);
      step_span_[c][v] = PrecomputeSpan(dt_s, tau_[c][v], p.adapt[c]);
      if (c > 0)  // Finish's sub-step length h = dt / nsub, bit for bit
        for (int level = 1; level <= kMaxSubLevels; ++level)
          sub_span_[c - 1][level - 1][v] =
              PrecomputeSpan(dt_s / (1 << level), tau_[c][v], p.adapt[c]);
      jump_[c][v] = p.adapt[c].jump * var.adapt;
      gain_[c][v] = cls == ReceptorClass::kSA1  ? var.gain
                    : cls == ReceptorClass::kRA ? p.ra.gain_s_per_pa * var.gain
                                                : p.pc.gain_s2_per_pa * var.gain;
    }
  }
  if (p.sa1.model == SA1Model::kWang2016)
    for (int v = 0; v < kNumVariants; ++v) jump_[0][v] = 0.0;
  for (int v = 0; v < kNumVariants; ++v)
    for (int k = 0; k < sa1_nodes_; ++k)
      sa1_m_[v][k] = p.sa1.merkel_cells[k] * ReceptorVariant(ReceptorClass::kSA1, v).gain;
}

void PrimeReceptor(const ReceptorParams& p, ReceptorClass cls, double q, unsigned long long stream,
                   double* st) {
  std::fill(st, st + kReceptorStateSize, 0.0);
  st[kPrevQ] = q;
  st[kHasPrev] = 1.0;
  st[kVariant] = VariantOf(p, cls, stream);
  const double sd = NoiseSd(p, cls);
  if (sd > 0.0) st[kNoise] = sd * Normal(p.noise.seed, stream, 0);
}

double ReceptorRate(const double* st) { return st[kRate]; }

namespace {
// One exact step of an n-pole filter (f.n == N): y0 = c . x, x <- phi x +
// gamma vel, y1 = c . x; the operations and their order of Filter's
// runtime-length loops.
template <int N>
void FilterStep(const double* phi, const double* gamma, const double* c, double vel, double* x,
                double* x_start, double* y0, double* y1) {
  double s[N], nx[N];
  for (int i = 0; i < N; ++i) s[i] = x_start[i] = x[i];
  double a0 = 0.0, a1 = 0.0;
  for (int i = 0; i < N; ++i) a0 += c[i] * s[i];
  for (int i = 0; i < N; ++i) {
    double acc = gamma[i] * vel;
    for (int j = 0; j < N; ++j) acc += phi[i * N + j] * s[j];
    nx[i] = acc;
  }
  for (int i = 0; i < N; ++i) {
    x[i] = nx[i];
    a1 += c[i] * nx[i];
  }
  *y0 = a0;
  *y1 = a1;
}
}  // namespace

int ReceptorStepper::Advance(ReceptorClass cls, double q1, unsigned long long stream, double* st,
                             double* voltage) const {
  switch (cls) {
    case ReceptorClass::kSA1: return AdvanceAs<ReceptorClass::kSA1>(q1, stream, st, voltage);
    case ReceptorClass::kRA: return AdvanceAs<ReceptorClass::kRA>(q1, stream, st, voltage);
    default: return AdvanceAs<ReceptorClass::kPC>(q1, stream, st, voltage);
  }
}

void ReceptorStepper::Noise(int ci, unsigned long long stream, double* st, double* n0,
                            double* n1) const {
  *n0 = *n1 = st[kNoise];
  if (noise_on_[ci]) {  // exact Ornstein-Uhlenbeck update
    const double count = st[kCount] + 1.0;
    st[kCount] = count;
    *n1 = noise_rho_ * *n0 +
          noise_gain_[ci] * NormalHashed(seed_hash_, stream, static_cast<uint64_t>(count));
    st[kNoise] = *n1;
  }
}

void ReceptorStepper::NoiseRun(int ci, int n, unsigned long long stream, double* state, double* n0,
                               double* n1) const {
  double u1[kNoiseRun], u2[kNoiseRun];
  for (int i = 0; i < n; ++i) {
    double* st = state + static_cast<size_t>(i) * kReceptorStateSize;
    n0[i] = n1[i] = st[kNoise];
    if (!noise_on_[ci]) continue;
    // NormalHashed's uniforms, the hashes of the run independent of each other
    const double count = st[kCount] + 1.0;
    st[kCount] = count;
    const uint64_t h1 =
        SplitMix64(SplitMix64(seed_hash_ ^ (stream + i)) ^ static_cast<uint64_t>(count));
    const uint64_t h2 = SplitMix64(h1);
    u1[i] = (static_cast<double>(h1 >> 11) + 0.5) * 0x1p-53;
    u2[i] = static_cast<double>(h2 >> 11) * 0x1p-53;
  }
  if (!noise_on_[ci]) return;
  for (int i = 0; i < n; ++i) u1[i] = std::log(u1[i]);
  for (int i = 0; i < n; ++i) u2[i] = std::cos(kTwoPi * u2[i]);
  for (int i = 0; i < n; ++i) {
    n1[i] = noise_rho_ * n0[i] + noise_gain_[ci] * (std::sqrt(-2.0 * u1[i]) * u2[i]);
    state[static_cast<size_t>(i) * kReceptorStateSize + kNoise] = n1[i];
  }
}

template <ReceptorClass C>
int ReceptorStepper::AdvanceAs(double q1, unsigned long long stream, double* st,
                               double* voltage) const {
  constexpr int ci = static_cast<int>(C);
  if (st[kHasPrev] <= 0.0) PrimeReceptor(p_, C, q1, stream, st);
  const double dt = dt_;
  Drive d;
  const double q0 = st[kPrevQ];
  d.v = (q1 - q0) / dt;  // q linear over the step
  st[kPrevQ] = q1;
  Noise(ci, stream, st, &d.n0, &d.n1);
  d.variant = static_cast<int>(st[kVariant]);
  const int variant = d.variant;
  // Drive before rectification at the step ends (units of threshold).
  double y0, y1;
  if constexpr (C == ReceptorClass::kSA1) {
    const SA1Params& s = p_.sa1;
    d.nodes = sa1_nodes_;
    const double scale = sa1_scale_;  // A -> threshold units
    // saturated input (kFiltered), taken linear over the step like q
    const double qs0 = SaturateSA1(s, q0), qs1 = SaturateSA1(s, q1);
    double r0, r1;  // the rate term at the step ends
    if (s.model == SA1Model::kWang2016) {
      r0 = r1 = std::abs(d.v);
    } else {
      const double vs = (qs1 - qs0) / dt;
      FilterStep<2>(sa1_.phi, sa1_.gamma, sa1_.c, vs, st + kF0, d.x_start, &y0, &y1);
      r0 = 1.0 * y0;
      r1 = 1.0 * y1;
    }
    const double* m = sa1_m_[variant];
    for (int k = 0; k < d.nodes; ++k) {
      d.l0[k] = scale * (m[k] * (s.k0_a_per_pa * qs0 + s.k1_a_s_per_pa * r0) + s.i0_a);
      d.l1[k] = scale * (m[k] * (s.k0_a_per_pa * qs1 + s.k1_a_s_per_pa * r1) + s.i0_a);
    }
  } else {
    const Filter& f = C == ReceptorClass::kRA ? ra_ : pc_;
    constexpr int n = C == ReceptorClass::kRA ? 3 : 4;
    FilterStep<n>(f.phi, f.gamma, f.c, d.v, st + kF0, d.x_start, &y0, &y1);
    d.nodes = 1;
    const double g = gain_[ci][variant];
    if constexpr (C == ReceptorClass::kRA) {
      d.l0[0] = SustainedNorm(g * y0, g * d.x_start[2]);
      d.l1[0] = SustainedNorm(g * y1, g * st[kF0 + 2]);
    } else {
      d.l0[0] = g * y0;
      d.l1[0] = g * y1;
    }
  }

  return FromDrive<C>(d, st, voltage);
}

int ReceptorStepper::FromDriveAs(ReceptorClass cls, const Drive& d, double* st,
                                 double* voltage) const {
  switch (cls) {
    case ReceptorClass::kSA1: return FromDrive<ReceptorClass::kSA1>(d, st, voltage);
    case ReceptorClass::kRA: return FromDrive<ReceptorClass::kRA>(d, st, voltage);
    default: return FromDrive<ReceptorClass::kPC>(d, st, voltage);
  }
}

template <ReceptorClass C>
int ReceptorStepper::FromDrive(const Drive& d, double* st, double* voltage) const {
  constexpr int ci = static_cast<int>(C);
  const double dt = dt_;
  const int variant = d.variant;
  // The common step: one segment over the whole step (no RA sub-steps, no
  // rectification kink), as Finish takes it.
  double la[kMaxNodes], lb[kMaxNodes];
  const int nodes = C == ReceptorClass::kSA1 ? d.nodes : 1;
  if constexpr (C != ReceptorClass::kSA1) {
    constexpr int k = ci - 1;
    const double sat = saturation_[ci];
    if (sat > 0.0) {
      const double dd = d.l1[0] - d.l0[0];
      if (!(dd * dd <= sub_error_skip_[k][0]) && dd * dd / sub_error_den_[k][0] > 1e-4)
        return Finish(C, d, st, voltage);  // sub-steps
      la[0] = d.l0[0] * sat / (sat + std::abs(d.l0[0]));
      lb[0] = d.l1[0] * sat / (sat + std::abs(d.l1[0]));
    } else {
      la[0] = d.l0[0];
      lb[0] = d.l1[0];
    }
  } else {
    for (int k = 0; k < nodes; ++k) {
      la[k] = d.l0[k];
      lb[k] = d.l1[k];
    }
  }
  bool kink = false;
  for (int k = 0; k < nodes; ++k)
    kink = kink | ((la[k] < 0.0) & (lb[k] > 0.0)) | ((la[k] > 0.0) & (lb[k] < 0.0));
  if (kink) return Finish(C, d, st, voltage);
  const double span = dt - 0.0;
  double a[kMaxNodes], b[kMaxNodes];
  for (int k = 0; k < nodes; ++k) {
    // Finish's drive at t = 0 and t = dt
    const double ea = la[k] + (lb[k] - la[k]) * 0.0, eb = la[k] + (lb[k] - la[k]) * 1.0;
    const double ra = C == ReceptorClass::kRA ? std::abs(ea) : std::max(0.0, ea);
    const double rb = C == ReceptorClass::kRA ? std::abs(eb) : std::max(0.0, eb);
    a[k] = ra + d.n0 + (d.n1 - d.n0) * 0.0;
    b[k] = (rb + d.n0 + (d.n1 - d.n0) * 1.0 - a[k]) / span;
  }
  const MembraneSpan& pre = step_span_[ci][variant];
  int spikes = 0;
  double rate_add = zero_rate_;
  if (!(st[kRefractory] > 0.0) && QuietWholeSpan(nodes, st + kU0, a, b, pre, st + kAdapt)) {
    // no spike
  } else {
    const double refractory = C == ReceptorClass::kSA1  ? p_.sa1.refractory_s
                              : C == ReceptorClass::kRA ? p_.ra.refractory_s
                                                        : p_.pc.refractory_s;
    Adaptation adapt = p_.adapt[ci];
    adapt.jump = jump_[ci][variant];
    SpikeSink sink{0.0, dt, p_.rate_tau_s, 0.0};
    spikes = LinearDriveLIF(nodes, st + kU0, a, b, span, tau_[ci][variant], refractory,
                            st + kRefractory, adapt, st + kAdapt, OnSpike, &sink, &pre);
    rate_add = sink.rate_sum / p_.rate_tau_s;
  }
  st[kRate] = st[kRate] * rate_decay_ + rate_add;
  double vmax = st[kU0];
  for (int k = 1; k < nodes; ++k) vmax = std::max(vmax, st[kU0 + k]);
  *voltage = vmax;
  return spikes;
}

int ReceptorStepper::Finish(ReceptorClass cls, const Drive& d, double* st, double* voltage) const {
  const double dt = dt_;
  const int ci = static_cast<int>(cls);
  const int variant = d.variant;
  const int nodes = d.nodes;
  const double n0 = d.n0, n1 = d.n1, v = d.v;
  const double* l0 = d.l0;
  const double* l1 = d.l1;
  const bool full_wave = cls == ReceptorClass::kRA;
  const double tau = tau_[ci][variant];
  const double refractory = cls == ReceptorClass::kSA1  ? p_.sa1.refractory_s
                            : cls == ReceptorClass::kRA ? p_.ra.refractory_s
                                                        : p_.pc.refractory_s;
  Adaptation adapt = p_.adapt[ci];
  adapt.jump = jump_[ci][variant];

  // Saturation of the RA and PC drives, d s / (s + |d|) (TouchSim's input
  // saturation, Saal et al. 2017; an odd monotone map keeps the zero
  // crossings). The saturated drive is not linear within a step: it is
  // evaluated at 2^k sub-step ends (the filter propagated exactly to each)
  // and taken linear between, k the smallest (at most kMaxSubLevels) that
  // bounds the interpolation error |l1 - l0|^2 / (4 s 4^k) (the map's
  // curvature is at most 2 / s) by 1e-4 threshold units.
  const double sat = saturation_[ci];
  const int sk = cls == ReceptorClass::kPC ? 1 : 0;  // sub-step tables
  auto saturate = [sat](double x) { return x * sat / (sat + std::abs(x)); };
  int nsub = 1;
  const MembraneSpan* pre = &step_span_[ci][variant];  // intervals of a whole (sub-)step
  double knots[(1 << kMaxSubLevels) + 1];              // node 0's drive at the sub-step ends
  if (sat > 0.0) {
    const double dl = l1[0] - l0[0];
    int level = 0;
    // d^2 at most 0.99e-4 den fails the test without the division
    while (level < kMaxSubLevels && !(dl * dl <= sub_error_skip_[sk][level]) &&
           dl * dl / sub_error_den_[sk][level] > 1e-4)
      ++level;
    nsub = 1 << level;
    if (level > 0) pre = &sub_span_[sk][level - 1][variant];
    knots[0] = saturate(l0[0]);
    knots[nsub] = saturate(l1[0]);
    if (nsub > 1) {
      const Filter& f = sub_[sk][level - 1];
      const double gain = gain_[ci][variant];
      double x[4], nx[4];
      std::copy(d.x_start, d.x_start + 4, x);
      for (int j = 1; j < nsub; ++j) {
        double y = 0.0;
        for (int i = 0; i < f.n; ++i) {
          double acc = f.gamma[i] * v;
          for (int m = 0; m < f.n; ++m) acc += f.phi[i * f.n + m] * x[m];
          nx[i] = acc;
        }
        for (int i = 0; i < f.n; ++i) {
          x[i] = nx[i];
          y += f.c[i] * x[i];
        }
        knots[j] =
            saturate(cls == ReceptorClass::kRA ? SustainedNorm(gain * y, gain * x[2]) : gain * y);
      }
    }
  }

  SpikeSink sink{0.0, dt, p_.rate_tau_s, 0.0};
  int spikes = 0;
  const double h = dt / nsub;
  for (int j = 0; j < nsub; ++j) {
    // Sub-step [t0, t1] of the step, drive linear from la to lb per node.
    const double t0 = j * h, t1 = j + 1 == nsub ? dt : (j + 1) * h;
    double la[kMaxNodes], lb[kMaxNodes];
    for (int k = 0; k < nodes; ++k) {
      la[k] = sat > 0.0 ? knots[j] : l0[k];
      lb[k] = sat > 0.0 ? knots[j + 1] : l1[k];
    }
    // Segments between the rectification kinks: the drive is linear in each.
    const double len = t1 - t0;
    double cuts[kMaxNodes + 2];
    int ncut = 0;
    cuts[ncut++] = t0;
    for (int k = 0; k < nodes; ++k) {
      // bitwise: no branch on the (unpredictable) signs themselves
      if (((la[k] < 0.0) & (lb[k] > 0.0)) | ((la[k] > 0.0) & (lb[k] < 0.0))) {
        const double t = t0 + len * la[k] / (la[k] - lb[k]);
        if (t > t0 && t < t1) cuts[ncut++] = t;
      }
    }
    for (int i = 2; i < ncut; ++i)  // insertion sort of the kinks
      for (int m = i; m > 1 && cuts[m] < cuts[m - 1]; --m) std::swap(cuts[m], cuts[m - 1]);
    cuts[ncut++] = t1;
    // (t - t0) / len and t / dt, their exact values at the ends without a division
    auto drive = [&](int k, double t) {
      const double f = t == t0 ? 0.0 : t == t1 ? 1.0 : (t - t0) / len;
      const double l = la[k] + (lb[k] - la[k]) * f;
      const double rect = full_wave ? std::abs(l) : std::max(0.0, l);
      return rect + n0 + (n1 - n0) * (t == 0.0 ? 0.0 : t == dt ? 1.0 : t / dt);
    };
    for (int i = 0; i + 1 < ncut; ++i) {
      const double ta = cuts[i], tb = cuts[i + 1], span = tb - ta;
      if (!(span > 0.0)) continue;
      double a[kMaxNodes], b[kMaxNodes];
      for (int k = 0; k < nodes; ++k) {
        a[k] = drive(k, ta);
        b[k] = (drive(k, tb) - a[k]) / span;
      }
      sink.offset = ta;
      spikes += LinearDriveLIF(nodes, st + kU0, a, b, span, tau, refractory, st + kRefractory,
                               adapt, st + kAdapt, OnSpike, &sink, pre);
    }
  }
  st[kRate] = st[kRate] * rate_decay_ + sink.rate_sum / p_.rate_tau_s;
  double vmax = st[kU0];
  for (int k = 1; k < nodes; ++k) vmax = std::max(vmax, st[kU0 + k]);
  *voltage = vmax;
  return spikes;
}

bool ReceptorStepper::Quiescent(ReceptorClass cls, const double* st) const {
  if (st[kRefractory] > 0.0 || st[kPrevQ] != 0.0 || st[kHasPrev] <= 0.0) return false;
  const VariantScale& var = ReceptorVariant(cls, static_cast<int>(st[kVariant]));
  // Noise: kIdleNoiseSds stationary membrane sds (OU of correlation tau_n
  // through the membrane tau_m: sd sqrt(tau_n / (tau_n + tau_m))) are added
  // to the drive bound; a receptor resting further below threshold fires
  // from noise alone at < 3e-3 Hz, which the idle skip drops.
  double noise_margin = 0.0;
  const double sd = NoiseSd(p_, cls);
  if (sd > 0.0) {
    const double tau_m =
        var.tau * (cls == ReceptorClass::kSA1  ? p_.sa1.resistance_ohm * p_.sa1.capacitance_f
                   : cls == ReceptorClass::kRA ? p_.ra.tau_s
                                               : p_.pc.tau_s);
    noise_margin = kIdleNoiseSds * sd * std::sqrt(p_.noise.tau_s / (p_.noise.tau_s + tau_m));
  }
  // Filters of chained real poles: no state entry ever exceeds the sum of
  // the current ones (each propagator entry is (w t)^k / k! exp(-w t) <= 1),
  // so |y| <= sum |c| * n * max |x|.
  // The RA's third state (its sustained drive) only divides the drive
  // (|drive| <= |gain y|) and does not feed y: its bound takes x1, x2.
  auto filter_bound = [&](const Filter& f) {
    const int n = &f == &ra_ ? 2 : f.n;
    double csum = 0.0, xmax = 0.0;
    for (int i = 0; i < n; ++i) {
      csum += std::abs(f.c[i]);
      xmax = std::max(xmax, std::abs(st[kF0 + i]));
    }
    return csum * n * xmax;
  };
  const double gain_scale = var.gain;
  if (cls == ReceptorClass::kSA1) {
    // A membrane below 1 under a drive bounded below 1 stays below 1; the
    // adaptation current only lowers the drive.
    const SA1Params& s = p_.sa1;
    const double scale = s.resistance_ohm / s.threshold_v;
    const int nodes = static_cast<int>(std::min<size_t>(s.merkel_cells.size(), kMaxNodes));
    double mmax = 0.0;
    for (int k = 0; k < nodes; ++k) mmax = std::max(mmax, s.merkel_cells[k] * gain_scale);
    const double dyn =
        s.model == SA1Model::kFiltered ? scale * mmax * s.k1_a_s_per_pa * filter_bound(sa1_) : 0.0;
    const double bias = scale * s.i0_a;  // drive at q = 0
    if (!(bias + dyn + noise_margin < 1.0)) return false;
    for (int k = 0; k < nodes; ++k)
      if (!(st[kU0 + k] < 1.0)) return false;
    return true;
  }
  // A drive bound of 1e-6 (threshold units) keeps a membrane below 1 unless
  // it already is within 1e-6 of it.
  const Filter& f = cls == ReceptorClass::kRA ? ra_ : pc_;
  const double gain = cls == ReceptorClass::kRA ? p_.ra.gain_s_per_pa : p_.pc.gain_s2_per_pa;
  const double bound = gain * gain_scale * filter_bound(f);
  return bound < 1e-6 && noise_margin < 1.0 - 2e-6 && st[kU0] < 1.0 - 1e-6;
}

}  // namespace mjtouch
