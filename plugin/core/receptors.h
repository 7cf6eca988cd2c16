// Stage 4: mechanoreceptor afferents. Each class turns its receptor quantity
// q(t) (Pa, e.g. the most compressive principal stress at the site) into spikes
// with leaky integrate-and-fire membranes integrated EXACTLY over each step for
// a current held constant over the step: rates do not depend on dt and no
// spike is lost at coarse dt (several spikes per step are counted).
#ifndef MJTOUCH_CORE_RECEPTORS_H_
#define MJTOUCH_CORE_RECEPTORS_H_

#include <string>
#include <vector>

namespace mjtouch {

enum class ReceptorClass { kSA1 = 0, kRA = 1, kPC = 2 };
constexpr int kNumClasses = 3;
const char* ClassName(ReceptorClass c);

// Which stress measure drives a class.
enum class Quantity { kCompressiveSzz, kMaxCompressive, kVonMises, kMaxShear };
const char* QuantityName(Quantity q);
bool ParseQuantity(const std::string& s, Quantity* q);
// Compressive-positive receptor quantity from a stress tensor (Voigt, Pa).
double ReceptorQuantity(Quantity q, const double stress[6]);

// SA1: Wang et al. 2016 (after Lesniak et al. 2014). Heminode k of the
// branching afferent collects current I_k = M_k (k0 q + k1 |dq/dt|) + I0
// (negative clipped to 0) and integrates C dU/dt + U/R = I_k; when any
// heminode reaches U_th all reset to 0 (spike-initiation zone shared).
struct SA1Params {
  std::vector<double> merkel_cells = {8, 5, 3, 1};  // M_k per heminode
  double k0_a_per_pa = 1.40e-16;     // static gain (Wang 2016, Table 1)
  double k1_a_s_per_pa = 1.68e-16;   // dynamic gain (Wang 2016, Table 1)
  double i0_a = 4.94e-12;            // bias current (Wang 2016, Table 1)
  double capacitance_f = 10e-12;     // C
  double resistance_ohm = 1.5e9;     // R
  double threshold_v = 30e-3;        // U_th
  double refractory_s = 1e-3;        // absolute refractory period
};

// RA (Meissner, FA1): driven by the rectified rate of change of q, so silent
// in a steady hold. Normalised membrane tau dU/dt = -U + gain |dq/dt|,
// threshold 1. Membrane time constant in the 3-9 ms range of TouchSim
// (Saal et al. 2017) gives the tens-of-Hz best frequency.
struct RAParams {
  // 1 / (|dq/dt| at threshold): 1e4 Pa/s, i.e. ~50 Pa at 30 Hz, which is
  // ~5 um of skin indentation at 0.5 N (~10 Pa/um): RA thresholds are
  // ~10 um at 20-40 Hz (Johansson et al. 1982). Provisional, see issue 5.
  double gain_s_per_pa = 1.0e-4;
  double tau_s = 5e-3;
  double refractory_s = 1e-3;
};

// PC (Pacinian, FA2): driven by the rectified output of a first-order
// high-pass of dq/dt (an acceleration-like stage standing in for the
// lamellar capsule's band-pass), short membrane time constant (~1-2 ms).
struct PCParams {
  // 1 / (filtered |dq/dt| at threshold): 1e3 Pa/s, ~0.6 Pa at 250 Hz, i.e.
  // ~0.06 um (PC thresholds: tens of nm at 200-300 Hz). Provisional.
  double gain_s_per_pa = 1.0e-3;
  double highpass_hz = 150.0;
  double tau_s = 1.5e-3;
  double refractory_s = 1e-3;
};

// Doubles of plugin state per receptor (membranes, refractory clock,
// previous q, filter state); the layout is private to receptors.cc.
constexpr int kReceptorStateSize = 8;

struct ReceptorParams {
  SA1Params sa1;
  RAParams ra;
  PCParams pc;
};

// Advance one receptor by dt with the quantity q_now at the end of the step
// (Pa). `has_prev` says whether state holds a previous q (else dq/dt = 0).
// Returns the number of spikes fired in the step; writes the normalised
// membrane potential (U / threshold of the most depolarised node) to *voltage.
int AdvanceReceptor(ReceptorClass cls, const ReceptorParams& p, double q_now,
                    double dt, double* state, double* voltage);

// Record q as the previous value without advancing (first call).
void PrimeReceptor(double q_now, double* state);

// Exact LIF over a step: membrane tau dU/dt = -U + u_inf with U reset to 0
// at threshold `theta`, absolute refractory period `refractory` (> 0) during
// which U is held at 0. `refractory_left` carries over between steps. Several
// membranes (heminodes) share one reset. Returns the spike count.
int ExactLIFStep(int nodes, double* u, const double* u_inf, double tau,
                 double theta, double refractory, double* refractory_left,
                 double dt);

}  // namespace mjtouch

#endif  // MJTOUCH_CORE_RECEPTORS_H_
