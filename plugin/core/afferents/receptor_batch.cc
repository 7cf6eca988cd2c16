// ReceptorStepper::AdvanceBatch: the receptors of one class four at a time,
// each operation of the common step (receptors.cc, AdvanceAs and FromDrive:
// one segment over the whole step, no spike) on 4-lane GCC vectors, lane by
// lane the scalar operation in the scalar order (no FMA contraction: the
// same bits on every ISA). A lane whose step is not the common one (a
// rectification kink, RA sub-steps, refractory time, a node that may reach
// threshold) continues through FromDrive from the drive computed here, as
// Advance would; the noise (libm log and cos) stays scalar. Also
// ReceptorQuantities, the stress-based quantities of many receptors.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "afferents/receptor_state.h"
#include "afferents/receptors.h"
#include "common/simd.h"

// The 4-lane helpers are inlined (file-local), so their by-value vector ABI
// never applies.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace mjtouch {

using namespace receptor_state;  // NOLINT: the state slots

namespace {

// Four lanes: one AVX2 vector (the clone used on x86 machines that have it),
// two SSE2 / NEON ones elsewhere.
constexpr int kLanes = 4;
typedef double V __attribute__((vector_size(8 * kLanes)));
typedef long long M __attribute__((vector_size(8 * kLanes)));  // lane masks (0 / -1)

V Splat(double x) {
  V r;
  for (int l = 0; l < kLanes; ++l) r[l] = x;
  return r;
}
// std::abs (clears the sign bit, as fabs)
V Abs(const V& x) {
  M mask;
  for (int l = 0; l < kLanes; ++l) mask[l] = 0x7fffffffffffffffLL;
  return reinterpret_cast<V>(reinterpret_cast<M>(x) & mask);
}
// std::max(0.0, x): x if 0 < x, else +0 (also for -0 and NaN)
V MaxZero(const V& x) { return x > 0.0 ? x : Splat(0.0); }
// std::max(a, x): x if a < x, else a
V MaxOf(const V& a, const V& x) { return a < x ? x : a; }
V Load(double* const* st, int slot) {
  V r;
  for (int l = 0; l < kLanes; ++l) r[l] = st[l][slot];
  return r;
}
V FromArray(const double* x) {
  V r;
  std::memcpy(&r, x, sizeof r);
  return r;
}
void Store(double* const* st, int slot, const V& x) {
  for (int l = 0; l < kLanes; ++l) st[l][slot] = x[l];
}

}  // namespace

template <ReceptorClass C>
MJTOUCH_TARGET_CLONES int ReceptorStepper::Group(const double* q1_in, const double* n0s,
                                                 const double* n1s, double* state, double* spikes,
                                                 double* voltage) const {
  constexpr int ci = static_cast<int>(C);
  double* st[kLanes];
  for (int l = 0; l < kLanes; ++l) st[l] = state + static_cast<size_t>(l) * kReceptorStateSize;
  const double dt = dt_;
  int variant[kLanes];
  for (int l = 0; l < kLanes; ++l) variant[l] = static_cast<int>(st[l][kVariant]);
  const V n0 = FromArray(n0s), n1 = FromArray(n1s), q1 = FromArray(q1_in);
  const V q0 = Load(st, kPrevQ);
  const V v = (q1 - q0) / dt;  // q linear over the step
  Store(st, kPrevQ, q1);
  auto per_variant = [&](const double (&table)[kNumVariants]) {
    V r;
    for (int l = 0; l < kLanes; ++l) r[l] = table[variant[l]];
    return r;
  };

  // Drive before rectification at the step ends (AdvanceAs).
  constexpr int nf = C == ReceptorClass::kPC ? 4 : C == ReceptorClass::kRA ? 3 : 2;
  const Filter& f = C == ReceptorClass::kSA1 ? sa1_ : C == ReceptorClass::kRA ? ra_ : pc_;
  V x[nf], nx[nf];
  for (int i = 0; i < nf; ++i) x[i] = Load(st, kF0 + i);
  auto filter = [&](const V& vel, V* y0, V* y1) {  // FilterStep<nf>
    V a0 = Splat(0.0), a1 = Splat(0.0);
    for (int i = 0; i < nf; ++i) a0 += f.c[i] * x[i];
    for (int i = 0; i < nf; ++i) {
      V acc = f.gamma[i] * vel;
      for (int j = 0; j < nf; ++j) acc += f.phi[i * nf + j] * x[j];
      nx[i] = acc;
    }
    for (int i = 0; i < nf; ++i) a1 += f.c[i] * nx[i];
    *y0 = a0;
    *y1 = a1;
    for (int i = 0; i < nf; ++i) Store(st, kF0 + i, nx[i]);
  };
  const int nodes = C == ReceptorClass::kSA1 ? sa1_nodes_ : 1;
  V l0[kMaxNodes], l1[kMaxNodes];
  if constexpr (C == ReceptorClass::kSA1) {
    const SA1Params& s = p_.sa1;  // kFiltered (AdvanceBatch)
    V qs0 = q0, qs1 = q1;         // SaturateSA1
    if (s.saturation > 0.0) {
      qs0 = q0 / (1.0 + Abs(q0) / s.saturation);
      qs1 = q1 / (1.0 + Abs(q1) / s.saturation);
    }
    const V vs = (qs1 - qs0) / dt;
    V y0, y1;
    filter(vs, &y0, &y1);
    const V r0 = 1.0 * y0, r1 = 1.0 * y1;
    for (int k = 0; k < nodes; ++k) {
      V m;
      for (int l = 0; l < kLanes; ++l) m[l] = sa1_m_[variant[l]][k];
      l0[k] = sa1_scale_ * (m * (s.k0_a_per_pa * qs0 + s.k1_a_s_per_pa * r0) + s.i0_a);
      l1[k] = sa1_scale_ * (m * (s.k0_a_per_pa * qs1 + s.k1_a_s_per_pa * r1) + s.i0_a);
    }
  } else {
    V y0, y1;
    const V m0 = x[nf - 1];  // RA: the sustained part at the step start
    filter(v, &y0, &y1);
    const V gain = per_variant(gain_[ci]);
    l0[0] = gain * y0;
    l1[0] = gain * y1;
    if constexpr (C == ReceptorClass::kRA) {
      if (sustained_ > 0.0) {  // SustainedNorm
        l0[0] = l0[0] / (1.0 + Abs(gain * m0) / sustained_);
        l1[0] = l1[0] / (1.0 + Abs(gain * nx[nf - 1]) / sustained_);
      }
    }
  }

  // The common step (FromDrive): `uncommon` marks the lanes that are not.
  M uncommon = reinterpret_cast<M>(Splat(0.0));
  V la[kMaxNodes], lb[kMaxNodes];
  if constexpr (C != ReceptorClass::kSA1) {
    constexpr int k = ci - 1;
    const double sat = saturation_[ci];
    if (sat > 0.0) {
      const V dd = l1[0] - l0[0];
      uncommon |= ~(dd * dd <= sub_error_skip_[k][0]) & (dd * dd / sub_error_den_[k][0] > 1e-4);
      la[0] = l0[0] * sat / (sat + Abs(l0[0]));
      lb[0] = l1[0] * sat / (sat + Abs(l1[0]));
    } else {
      la[0] = l0[0];
      lb[0] = l1[0];
    }
  } else {
    for (int k = 0; k < nodes; ++k) {
      la[k] = l0[k];
      lb[k] = l1[k];
    }
  }
  for (int k = 0; k < nodes; ++k)
    uncommon |= ((la[k] < 0.0) & (lb[k] > 0.0)) | ((la[k] > 0.0) & (lb[k] < 0.0));
  const double span = dt - 0.0;
  V a[kMaxNodes], b[kMaxNodes];
  for (int k = 0; k < nodes; ++k) {
    const V ea = la[k] + (lb[k] - la[k]) * 0.0, eb = la[k] + (lb[k] - la[k]) * 1.0;
    const V ra = C == ReceptorClass::kRA ? Abs(ea) : MaxZero(ea);
    const V rb = C == ReceptorClass::kRA ? Abs(eb) : MaxZero(eb);
    a[k] = ra + n0 + (n1 - n0) * 0.0;
    b[k] = (rb + n0 + (n1 - n0) * 1.0 - a[k]) / span;
  }
  // QuietWholeSpan (membrane.h), lane by lane
  uncommon |= Load(st, kRefractory) > 0.0;
  const MembraneSpan* pre[kLanes];
  for (int l = 0; l < kLanes; ++l) pre[l] = &step_span_[ci][variant[l]];
  auto from_pre = [&](double MembraneSpan::* field) {
    V r;
    for (int l = 0; l < kLanes; ++l) r[l] = pre[l]->*field;
    return r;
  };
  const V tau = from_pre(&MembraneSpan::tau), tau_a = from_pre(&MembraneSpan::tau_a);
  const V decay = from_pre(&MembraneSpan::decay), phi1 = from_pre(&MembraneSpan::phi1);
  const V phi2 = from_pre(&MembraneSpan::phi2);
  const V adapt_decay = from_pre(&MembraneSpan::adapt_decay);
  const V w = Load(st, kAdapt);
  const V adapt_end =
      w == 0.0 ? Splat(0.0)
               : -w * tau_a / (tau_a - tau) * adapt_decay * from_pre(&MembraneSpan::adapt_rise);
  V end[kMaxNodes];
  for (int k = 0; k < nodes; ++k) {
    const V u0 = Load(st, kU0 + k), bk = b[k], ak = a[k] + bk * 0.0;
    uncommon |= u0 >= 1.0;
    const V m = u0 * decay + ak * phi1 + bk * tau * phi2;
    const M falling = (u0 - ak + bk * tau < 0.0) & (bk < 0.0);
    // FallingStaysBelow over the whole span
    const V margin = 1e-9 * (1.0 + Abs(u0) + Abs(ak) + Abs(bk) * (tau + span));
    const V bound = MaxOf(u0, u0 * decay + ak * phi1);
    uncommon |= falling ? ~(bound < 1.0 - margin) : ~(m < 1.0);
    end[k] = m + adapt_end;
    uncommon |= end[k] >= 1.0;
  }
  const V w_end = w != 0.0 ? w * adapt_decay : w;
  const V rate = Load(st, kRate) * rate_decay_ + zero_rate_;
  int total = 0;
  for (int l = 0; l < kLanes; ++l) {
    if (uncommon[l]) {
      Drive d;
      d.nodes = nodes;
      d.variant = variant[l];
      for (int k = 0; k < nodes; ++k) {
        d.l0[k] = l0[k][l];
        d.l1[k] = l1[k][l];
      }
      for (int i = 0; i < 4; ++i) d.x_start[i] = i < nf ? x[i][l] : 0.0;
      d.v = v[l];
      d.n0 = n0s[l];
      d.n1 = n1s[l];
      const int k = FromDriveAs(C, d, st[l], &voltage[l]);
      spikes[l] = k;
      total += k;
      continue;
    }
    double vmax = end[0][l];
    st[l][kU0] = vmax;
    for (int k = 1; k < nodes; ++k) {
      st[l][kU0 + k] = end[k][l];
      vmax = std::max(vmax, end[k][l]);
    }
    st[l][kAdapt] = w_end[l];
    st[l][kRate] = rate[l];
    spikes[l] = 0.0;
    voltage[l] = vmax;
  }
  return total;
}

int ReceptorStepper::AdvanceBatch(ReceptorClass cls, int count, const double* q_end,
                                  unsigned long long first_stream, double* state, double* spikes,
                                  double* voltage) const {
  // The lanes take AdvanceAs's kFiltered SA1 (the kWang2016 one per
  // receptor) with 1 .. kMaxNodes heminodes.
  const bool lanes =
      cls != ReceptorClass::kSA1 || (p_.sa1.model == SA1Model::kFiltered && sa1_nodes_ >= 1);
  const int ci = static_cast<int>(cls);
  int total = 0, i = 0;
  static_assert(kNoiseRun % kLanes == 0, "runs of whole groups");
  // Runs of kNoiseRun receptors: their noise first (NoiseRun), then the
  // groups of kLanes; a run with a receptor to prime goes through Advance.
  while (lanes && count - i >= kLanes) {
    const int n = std::min(kNoiseRun, count - i) / kLanes * kLanes;
    double* st = state + static_cast<size_t>(i) * kReceptorStateSize;
    bool primed = true;
    for (int j = 0; j < n; ++j) primed = primed && !(st[j * kReceptorStateSize + kHasPrev] <= 0.0);
    if (!primed) break;
    double n0[kNoiseRun], n1[kNoiseRun];
    NoiseRun(ci, n, first_stream + i, st, n0, n1);
    for (int j = 0; j < n; j += kLanes) {
      double* sg = st + static_cast<size_t>(j) * kReceptorStateSize;
      const int r = i + j;
      switch (cls) {
        case ReceptorClass::kSA1:
          total +=
              Group<ReceptorClass::kSA1>(q_end + r, n0 + j, n1 + j, sg, spikes + r, voltage + r);
          break;
        case ReceptorClass::kRA:
          total +=
              Group<ReceptorClass::kRA>(q_end + r, n0 + j, n1 + j, sg, spikes + r, voltage + r);
          break;
        default:
          total +=
              Group<ReceptorClass::kPC>(q_end + r, n0 + j, n1 + j, sg, spikes + r, voltage + r);
      }
    }
    i += n;
  }
  for (; i < count; ++i) {
    const int k = Advance(cls, q_end[i], first_stream + i,
                          state + static_cast<size_t>(i) * kReceptorStateSize, &voltage[i]);
    spikes[i] = k;
    total += k;
  }
  return total;
}

void ReceptorQuantities(Quantity q, int count, const double* stress, double* out) {
  int i = 0;
  if (q == Quantity::kMaxCompressive) {
    // Principal's smallest eigenvalue (Smith 1961) up to the acos in lanes,
    // then acos and cos per receptor; a lane with an (almost) diagonal
    // tensor takes ReceptorQuantity.
    for (; i + kLanes <= count; i += kLanes) {
      const double* s = stress + static_cast<size_t>(i) * 6;
      V c[6];
      for (int j = 0; j < 6; ++j)
        for (int l = 0; l < kLanes; ++l) c[j][l] = s[l * 6 + j];
      const V xx = c[0], yy = c[1], zz = c[2], xy = c[3], xz = c[4], yz = c[5];
      const V p1 = xy * xy + xz * xz + yz * yz;
      const V mean = (xx + yy + zz) / 3.0;
      const M diagonal = p1 <= 1e-30 * (xx * xx + yy * yy + zz * zz + 1e-300);
      const V p2 = (xx - mean) * (xx - mean) + (yy - mean) * (yy - mean) +
                   (zz - mean) * (zz - mean) + 2 * p1;
      const V p6 = p2 / 6.0;
      V p;
      for (int l = 0; l < kLanes; ++l) p[l] = std::sqrt(p6[l]);
      const V b00 = (xx - mean) / p, b11 = (yy - mean) / p, b22 = (zz - mean) / p;
      const V b01 = xy / p, b02 = xz / p, b12 = yz / p;
      const V det = b00 * (b11 * b22 - b12 * b12) - b01 * (b01 * b22 - b12 * b02) +
                    b02 * (b01 * b12 - b11 * b02);
      const V half = det / 2.0;  // std::clamp(half, -1, 1)
      const V r = half < -1.0 ? Splat(-1.0) : 1.0 < half ? Splat(1.0) : half;
      double phi[kLanes];
      for (int l = 0; l < kLanes; ++l) phi[l] = diagonal[l] ? 0.0 : std::acos(r[l]) / 3.0;
      for (int l = 0; l < kLanes; ++l) {
        if (diagonal[l]) {
          out[i + l] = ReceptorQuantity(q, s + l * 6);
          continue;
        }
        const double e1 = mean[l] + 2 * p[l] * std::cos(phi[l] + 2.0943951023931957);
        out[i + l] = std::max(0.0, -e1);
      }
    }
  }
  for (; i < count; ++i) out[i] = ReceptorQuantity(q, stress + static_cast<size_t>(i) * 6);
}

}  // namespace mjtouch
