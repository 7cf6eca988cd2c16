#include "receptors.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace mjtouch {
namespace {

// State slots.
enum { kU0 = 0, kU1, kU2, kU3, kRefractory, kPrevQ, kFilter, kHasPrev };
constexpr int kMaxNodes = 4;

void Principal(const double s[6], double* l1, double* l2, double* l3) {
  // Eigenvalues of a symmetric 3x3 (Smith 1961), ascending.
  const double xx = s[0], yy = s[1], zz = s[2], xy = s[3], xz = s[4], yz = s[5];
  const double p1 = xy * xy + xz * xz + yz * yz;
  const double q = (xx + yy + zz) / 3.0;
  if (p1 <= 1e-30 * (xx * xx + yy * yy + zz * zz + 1e-300)) {
    double e[3] = {xx, yy, zz};
    std::sort(e, e + 3);
    *l1 = e[0]; *l2 = e[1]; *l3 = e[2];
    return;
  }
  const double p2 = (xx - q) * (xx - q) + (yy - q) * (yy - q) + (zz - q) * (zz - q) + 2 * p1;
  const double p = std::sqrt(p2 / 6.0);
  const double b00 = (xx - q) / p, b11 = (yy - q) / p, b22 = (zz - q) / p;
  const double b01 = xy / p, b02 = xz / p, b12 = yz / p;
  const double det = b00 * (b11 * b22 - b12 * b12) - b01 * (b01 * b22 - b12 * b02) +
                     b02 * (b01 * b12 - b11 * b02);
  const double r = std::clamp(det / 2.0, -1.0, 1.0);
  const double phi = std::acos(r) / 3.0;
  const double e3 = q + 2 * p * std::cos(phi);
  const double e1 = q + 2 * p * std::cos(phi + 2.0943951023931957);
  *l1 = e1;
  *l3 = e3;
  *l2 = 3 * q - e1 - e3;
}

}  // namespace

const char* ClassName(ReceptorClass c) {
  switch (c) {
    case ReceptorClass::kSA1: return "SA1";
    case ReceptorClass::kRA: return "RA";
    default: return "PC";
  }
}

const char* QuantityName(Quantity q) {
  switch (q) {
    case Quantity::kCompressiveSzz: return "szz";
    case Quantity::kMaxCompressive: return "maxcomp";
    case Quantity::kVonMises: return "vonmises";
    default: return "maxshear";
  }
}

bool ParseQuantity(const std::string& s, Quantity* q) {
  if (s == "szz") { *q = Quantity::kCompressiveSzz; return true; }
  if (s == "maxcomp") { *q = Quantity::kMaxCompressive; return true; }
  if (s == "vonmises") { *q = Quantity::kVonMises; return true; }
  if (s == "maxshear") { *q = Quantity::kMaxShear; return true; }
  return false;
}

double ReceptorQuantity(Quantity q, const double s[6]) {
  switch (q) {
    case Quantity::kCompressiveSzz: return -s[2];
    case Quantity::kVonMises: {
      const double a = s[0] - s[1], b = s[1] - s[2], c = s[2] - s[0];
      return std::sqrt(0.5 * (a * a + b * b + c * c) +
                       3.0 * (s[3] * s[3] + s[4] * s[4] + s[5] * s[5]));
    }
    default: {
      double l1, l2, l3;
      Principal(s, &l1, &l2, &l3);
      if (q == Quantity::kMaxCompressive) return std::max(0.0, -l1);
      return 0.5 * (l3 - l1);
    }
  }
}

int ExactLIFStep(int nodes, double* u, const double* u_inf, double tau,
                 double theta, double refractory, double* refractory_left,
                 double dt) {
  int spikes = 0;
  double t = 0.0;
  auto hold = [&](double span) {  // refractory: membranes clamped at reset
    const double used = std::min(*refractory_left, span);
    *refractory_left -= used;
    if (used > 0.0) for (int k = 0; k < nodes; ++k) u[k] = 0.0;
    return used;
  };
  t += hold(dt);
  while (t < dt) {
    const double left = dt - t;
    double t_hit = std::numeric_limits<double>::infinity();
    for (int k = 0; k < nodes; ++k) {
      if (u_inf[k] > theta && u[k] < theta) {
        t_hit = std::min(t_hit, tau * std::log((u_inf[k] - u[k]) / (u_inf[k] - theta)));
      } else if (u[k] >= theta) {
        t_hit = 0.0;
      }
    }
    if (t_hit > left) {
      const double decay = std::exp(-left / tau);
      for (int k = 0; k < nodes; ++k) u[k] = u_inf[k] + (u[k] - u_inf[k]) * decay;
      break;
    }
    ++spikes;
    t += t_hit;
    for (int k = 0; k < nodes; ++k) u[k] = 0.0;
    *refractory_left = refractory;
    t += hold(dt - t);
  }
  return spikes;
}

void PrimeReceptor(double q, double* st) {
  st[kPrevQ] = q;
  st[kHasPrev] = 1.0;
}

int AdvanceReceptor(ReceptorClass cls, const ReceptorParams& p, double q,
                    double dt, double* st, double* voltage) {
  const double dq = st[kHasPrev] > 0.0 ? (q - st[kPrevQ]) / dt : 0.0;
  st[kPrevQ] = q;
  st[kHasPrev] = 1.0;
  double u_inf[kMaxNodes] = {0, 0, 0, 0};
  int spikes = 0;
  double theta = 1.0;
  int nodes = 1;
  switch (cls) {
    case ReceptorClass::kSA1: {
      const SA1Params& s = p.sa1;
      nodes = static_cast<int>(std::min<size_t>(s.merkel_cells.size(), kMaxNodes));
      const double drive = s.k0_a_per_pa * q + s.k1_a_s_per_pa * std::abs(dq);
      for (int k = 0; k < nodes; ++k) {
        const double current = std::max(0.0, s.merkel_cells[k] * drive + s.i0_a);
        u_inf[k] = current * s.resistance_ohm;
      }
      theta = s.threshold_v;
      spikes = ExactLIFStep(nodes, st + kU0, u_inf, s.resistance_ohm * s.capacitance_f,
                            theta, s.refractory_s, st + kRefractory, dt);
      break;
    }
    case ReceptorClass::kRA: {
      u_inf[0] = p.ra.gain_s_per_pa * std::abs(dq);
      spikes = ExactLIFStep(1, st + kU0, u_inf, p.ra.tau_s, 1.0, p.ra.refractory_s,
                            st + kRefractory, dt);
      break;
    }
    case ReceptorClass::kPC: {
      // Exact first-order high-pass of the (step-constant) rate dq/dt:
      // y' = -y / tau_hp + d(dq)/dt. A step in dq/dt of size D adds D to y,
      // which then decays; we carry y at the end of the step.
      const double tau_hp = 1.0 / (2.0 * 3.14159265358979323846 * p.pc.highpass_hz);
      double y = st[kFilter];
      // st[kU3] stores the previous dq/dt for the PC (one node only uses kU0).
      const double jump = dq - st[kU3];
      st[kU3] = dq;
      const double decay = std::exp(-dt / tau_hp);
      // Mean of |y| over the step drives the membrane (y decays within it).
      const double y0 = y + jump;
      const double mean_abs = std::abs(y0) * (1.0 - decay) * tau_hp / dt;
      y = y0 * decay;
      st[kFilter] = y;
      u_inf[0] = p.pc.gain_s_per_pa * mean_abs;
      spikes = ExactLIFStep(1, st + kU0, u_inf, p.pc.tau_s, 1.0, p.pc.refractory_s,
                            st + kRefractory, dt);
      break;
    }
  }
  double vmax = 0.0;
  for (int k = 0; k < nodes; ++k) vmax = std::max(vmax, st[kU0 + k] / theta);
  *voltage = vmax;
  return spikes;
}

}  // namespace mjtouch
