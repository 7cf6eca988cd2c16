// Stage 4: mechanoreceptor afferents. Each class turns its receptor quantity
// q(t) (Pa, e.g. the most compressive principal stress at the site) into spikes
// with leaky integrate-and-fire membranes integrated in closed form over each
// step (the drive is linear within a step): rates do not depend on dt and no
// spike is lost at coarse dt (several spikes per step are counted).
#ifndef MJTOUCH_AFFERENTS_RECEPTORS_H_
#define MJTOUCH_AFFERENTS_RECEPTORS_H_

#include <cmath>
#include <string>
#include <vector>

#include "afferents/membrane.h"

namespace mjtouch {

enum class ReceptorClass { kSA1 = 0, kRA = 1, kPC = 2 };
constexpr int kNumClasses = 3;
const char* ClassName(ReceptorClass c);

// Which stress measure drives a class.
// kStrainEnergy (SED, J/m^3) and kCompressiveStrain (most compressive
// principal strain, Wang 2016) need the material at the receptor: pipeline/step.cc
// converts them (ReceptorQuantity returns NaN for them).
enum class Quantity {
  kCompressiveSzz,
  kMaxCompressive,
  kVonMises,
  kMaxShear,
  kStrainEnergy,
  kCompressiveStrain
};
const char* QuantityName(Quantity q);
bool ParseQuantity(const std::string& s, Quantity* q);
// Compressive-positive receptor quantity from a stress tensor (Voigt, Pa).
double ReceptorQuantity(Quantity q, const double stress[6]);
// ReceptorQuantity of `count` tensors 6 doubles apart, into out[0 ..
// count - 1]: the same bits (kMaxCompressive: four at a time up to the acos,
// receptor_batch.cc).
void ReceptorQuantities(Quantity q, int count, const double* stress, double* out);

// SA1 (Merkel), after Wang et al. 2016 and Lesniak et al. 2014. Heminode k
// of the branching afferent collects I_k = M_k (k0 q + k1 r) + I0 (negative
// clipped to 0) and integrates C dU/dt + U/R = I_k; when any heminode
// reaches U_th all reset to 0 (spike-initiation zone shared), 1 ms
// refractory, minus a shared adaptation current.
//  - kFiltered (default): r = w^2 / (s + w)^2 dq/dt, the stress rate
//    low-passed (two real poles at lowpass_hz) and signed: loading excites,
//    unloading inhibits (SA1s pause on release; TouchSim's SA1 fits have a
//    negative gain on falling velocity, Saal et al. 2017), and the rate term
//    fades above the corner, so thresholds rise at high frequencies
//    (Johansson et al. 1982; Freeman & Johnson 1982).
//  - kWang2016: r = |dq/dt| unfiltered, no adaptation, no population
//    variants, no noise: Wang 2016's model as published (their specimen study).
enum class SA1Model { kFiltered = 0, kWang2016 = 1 };

struct SA1Params {
  SA1Model model = SA1Model::kFiltered;
  std::vector<double> merkel_cells = {8, 5, 3, 1};  // M_k per heminode
  double k0_a_per_pa = 1.40e-16;                    // static gain (set by DefaultSA1Gains)
  double k1_a_s_per_pa = 1.68e-16;                  // dynamic gain (set by DefaultSA1Gains)
  double i0_a = 4.94e-12;                           // bias current (Wang 2016, Table 1)
  double capacitance_f = 10e-12;                    // C
  double resistance_ohm = 1.5e9;                    // R
  double threshold_v = 30e-3;                       // U_th
  double refractory_s = 1e-3;                       // absolute refractory period
  double lowpass_hz = 30.0;                         // kFiltered: corner of the rate term
  // kFiltered: the stress is saturated before the heminodes, q_s = q / (1 +
  // |q| / saturation) (units of q; 0: none), TouchSim's saturation form
  // (Saal et al. 2017) on the input: the SA1 rate grows about linearly with
  // indentation while the stress under a probe grows faster (the skin
  // stiffens). Set by DefaultSA1Gains.
  double saturation = 0.0;
};

// Wang et al. 2016, Table 1: the fitted (k0, k1, I0) of the model whose
// input is `q` (stress-based for szz / maxcomp / vonmises / maxshear, in Pa;
// strain-based for `strain`, dimensionless; SED-based for `sed`, J/m^3).
// Units read as SI, as printed ("All values are SI units"); see README.
void WangTable1Gains(Quantity q, SA1Params* p);
// The defaults of p->model for quantity q: kWang2016 the Table 1 row;
// kFiltered the same row with k0 x kSA1StaticScale, k1 = k0 x
// kSA1RateTimeS and the input saturation at kSA1SaturationOverRheobase x
// the row's own rheobase quantity (plugin/README.md, "SA1").
void DefaultSA1Gains(Quantity q, SA1Params* p);
// Calibrated under a 1 mm flat pin (plugin/README.md, "SA1"): the static
// threshold falls from 13.4 kPa (0.4 mm) to ~2 kPa (~0.06 mm of indentation).
constexpr double kSA1StaticScale = 7.0;
constexpr double kSA1RateTimeS = 0.05;
constexpr double kSA1SaturationOverRheobase = 4.5;

// RA (Meissner, FA1): the rate of change of q, low-passed by two equal real
// poles at `lowpass_hz`, y = w^2 / (s + w)^2 dq/dt (Pa/s), full-wave
// rectified (fires on loading and unloading, silent in a steady hold):
// tau dU/dt = -U + |sat(norm(gain y))| - w_adapt, threshold 1, sat(d) = d s / (s + |d|),
// norm(d) = d / (1 + |m| / sustained), m the drive low-passed (sustained_tau_s). The low-pass
// sets the best frequency (tens of Hz; Johansson et al. 1982), the membrane time constant is in
// TouchSim's 3-9 ms range (Saal et al. 2017).
struct RAParams {
  // Calibrated (plugin/README.md, "Dynamic range and thresholds"): absolute threshold 100 Pa at 40
  // Hz.
  double gain_s_per_pa = 5.92e-5;
  double lowpass_hz = 40.0;
  double tau_s = 5e-3;
  double refractory_s = 1e-3;
  // Drive saturation s (threshold units; 0: none): TouchSim saturates its
  // input current (Saal et al. 2017); ramp rates stay physiological, and
  // 1:1 entrainment at 80 Hz stays reachable (plugin/README.md).
  double saturation = 12.0;
  // Gain control by the sustained rate: the drive d = gain y is divided by
  // 1 + |m| / sustained, m = d low-passed with sustained_tau_s (one pole;
  // threshold units; 0: none). A ramp's steady stress rate (same sign for
  // tens of ms) is compressed, as the RA's discharge grows only
  // logarithmically with indentation velocity (Knibestol 1973), while a
  // vibration or a scanned texture (zero-mean rate) keeps its full drive.
  double sustained = 1.0;
  double sustained_tau_s = 0.05;
};

// PC (Pacinian, FA2): stress acceleration through a band-pass,
// y = [s / (s + wh)] [wl^3 / (s + wl)^3] d2q/dt2 (Pa/s^2): the capsule's
// high-pass (Loewenstein & Skalak 1966) on top of the acceleration makes the
// low-frequency flank steep; the low-pass and the short membrane (TouchSim:
// 1-2 ms) bound the high one. Half-wave rectified (one spike per cycle, phase
// locked): tau dU/dt = -U + gain max(0, y) - w_adapt, threshold 1.
struct PCParams {
  // Calibrated (docs/science/afferents.md, "Dynamic range and thresholds"): absolute threshold
  // 0.7 Pa at 250 Hz.
  double gain_s2_per_pa = 3.94e-6;
  // 300 Hz: the rebound lobe of a ramp corner's band-passed acceleration
  // decays as exp(-wh t), so a corner fires once or twice, not three times
  // (150 Hz), where TouchSim's PC fits fire about once (Saal et al. 2017).
  double highpass_hz = 300.0;
  double lowpass_hz = 250.0;
  double tau_s = 1.5e-3;
  // 2.4 ms: one spike per lobe of a ramp corner's drive; under the 2.5 ms
  // cycle of 400 Hz, so the PC follows 1:1 to 400 Hz, the top of the range
  // recorded (Johansson et al. 1982).
  double refractory_s = 2.4e-3;
  // Drive saturation s (threshold units; 0: none), d s / (s + |d|) as the
  // RA's (TouchSim's form, Saal et al. 2017). Off: low enough to cap a ramp
  // corner (~300x threshold) it also ends 1:1 at 250 Hz (~5x;
  // docs/science/afferents.md, PC).
  double saturation = 0.0;
};

// Optional membrane noise: an Ornstein-Uhlenbeck process of standard
// deviation sd[class] (in units of the threshold) and correlation time
// tau_s, added to the drive, updated exactly at each step from a
// counter-based generator (seed, receptor, step count), so runs are
// reproducible bit for bit per seed whatever the thread or copy.
struct NoiseParams {
  // TouchSim's membrane noise (plugin/README.md, "Noise"): the same
  // stationary membrane sd (SA1: the same resting margin in sds).
  double sd[kNumClasses] = {0.35, 0.35, 0.12};
  double tau_s = 2e-3;
  unsigned long long seed = 0;
};

// Population variability: each receptor takes one of kNumVariants parameter
// sets of its class (multipliers of the drive gain, membrane time constant
// and adaptation jump, receptors.cc kVariants), picked by a hash of (seed,
// receptor index), as TouchSim draws each afferent from its class's fitted
// set (Saal et al. 2017: 4 SA1, 9 RA, 4 PC fits).
constexpr int kNumVariants = 4;
struct VariantScale {
  double gain, tau, adapt;
};
const VariantScale& ReceptorVariant(ReceptorClass cls, int variant);

// Doubles of plugin state per receptor (membranes, refractory clock,
// previous q, smoothed rate, noise, step count, filter states, adaptation,
// variant); the layout is private to receptors.cc.
constexpr int kReceptorStateSize = 16;

struct ReceptorParams {
  SA1Params sa1;
  RAParams ra;
  PCParams pc;
  NoiseParams noise;
  // Spike-triggered adaptation per class (membrane.h; README, "Dynamic range").
  Adaptation adapt[kNumClasses] = {{4.5, 0.05}, {1.3, 0.03}, {0.7, 0.02}};
  bool varied = true;        // `population`: variants (true) or the median set only
  double rate_tau_s = 0.05;  // smoothed rate: exponential kernel, s
};

// The variant (0 .. kNumVariants - 1) receptor `stream` uses: 0 without
// variability and for the kWang2016 SA1.
int VariantOf(const ReceptorParams& p, ReceptorClass cls, unsigned long long stream);

// The noise sd of class cls: 0 for the kWang2016 SA1 (as published).
double NoiseSd(const ReceptorParams& p, ReceptorClass cls);

// Advances receptors over a step of dt. q is taken as linear in time between
// the previous value and q_end (so dq/dt is constant over the step); the
// filters are propagated exactly for that input; each class's drive is
// linear between its values at the step ends, rectification kinks located
// exactly; the membranes are then integrated in closed form (first threshold
// crossing solved to round-off), so no spike is lost at coarse dt and several
// spikes per step are counted. Build once per step size, use for every receptor.
class ReceptorStepper {
 public:
  ReceptorStepper(const ReceptorParams& p, double dt_s);
  // Returns the spike count; *voltage = membrane over threshold at the step
  // end (SA1: the most depolarised heminode). `stream` (the receptor's index)
  // selects its noise sequence.
  int Advance(ReceptorClass cls, double q_end, unsigned long long stream, double* state,
              double* voltage) const;
  double dt() const { return dt_; }
  // Advance for `count` receptors of class cls, their states
  // kReceptorStateSize doubles apart from `state`: receptor i takes q_end[i]
  // and stream first_stream + i and leaves its spike count in spikes[i] and
  // its voltage in voltage[i]. The same bits as Advance receptor by
  // receptor. Returns the spikes fired.
  int AdvanceBatch(ReceptorClass cls, int count, const double* q_end,
                   unsigned long long first_stream, double* state, double* spikes,
                   double* voltage) const;
  // Whether the receptor, driven by q = 0 from now on, can never fire again
  // (with noise: fires from noise alone at < 3e-3 Hz, its drive bound 4.5
  // membrane noise sds below threshold): refractory over, previous q zero,
  // the constant drive (SA1: the bias I0) below threshold, filter outputs
  // bounded far below it. Its membranes then only relax, so its steps may be
  // skipped and made up later in one step (pipeline/step.cc: idle
  // receptors; exact without noise, one exact OU transition with it).
  bool Quiescent(ReceptorClass cls, const double* state) const;

 private:
  struct Filter {  // x(t + dt) = phi x + gamma dq/dt; output y = c . x
    int n = 0;
    double phi[16] = {0}, gamma[4] = {0}, c[4] = {0};
  };
  const ReceptorParams& p_;
  double dt_;
  static constexpr int kMaxSubLevels = 3;  // RA / PC saturation: up to 8 sub-steps
  Filter sa1_, ra_, pc_;
  Filter sub_[2][kMaxSubLevels];  // RA (0) and PC (1) filters over dt / 2^k, k = 1..
  double noise_rho_, rate_decay_;
  unsigned long long seed_hash_;             // SplitMix64 of the noise seed
  double sa1_scale_;                         // SA1: R / U_th, A -> threshold units
  double noise_gain_[kNumClasses];           // sd sqrt(1 - rho^2): the OU innovation
  double saturation_[kNumClasses];           // drive saturation (SA1: 0, none)
  double sub_error_den_[2][kMaxSubLevels];   // RA, PC sub-steps: 4 s 4^k
  double sub_error_skip_[2][kMaxSubLevels];  // 0.99e-4 of it
  // Membrane exponentials over a whole step, per class and variant, and
  // over the RA (0) and PC (1) sub-steps dt / 2^k (Finish), per variant.
  MembraneSpan step_span_[kNumClasses][kNumVariants];
  MembraneSpan sub_span_[2][kMaxSubLevels][kNumVariants];
  // Per class and variant, as Advance evaluated them per receptor: the
  // membrane tau (s), the adaptation jump, the drive gain (RA, PC: of the
  // filter output; SA1: the variant's gain) and the SA1 heminodes' M_k gain.
  double tau_[kNumClasses][kNumVariants];
  double jump_[kNumClasses][kNumVariants];
  double gain_[kNumClasses][kNumVariants];
  double sa1_m_[kNumVariants][4];
  int sa1_nodes_;
  bool noise_on_[kNumClasses];
  double zero_rate_;  // 0 / rate_tau_s: the rate's increment in a step without spikes
  double sustained_;  // RAParams::sustained
  // The RA drive d under the gain control of its sustained part m (RAParams::sustained).
  double SustainedNorm(double d, double m) const {
    return sustained_ > 0.0 ? d / (1.0 + std::abs(m) / sustained_) : d;
  }
  // Advance per class (the class's constants and loop lengths fixed); the
  // uncommon steps (rectification kinks, RA sub-steps) go through Finish.
  // AdvanceBatch: groups of 4 receptors of one class in 4-lane vectors, the
  // steps that are not the common one per receptor through FromDrive.
  struct Drive;  // afferents/receptor_state.h
  template <ReceptorClass C>
  int AdvanceAs(double q_end, unsigned long long stream, double* state, double* voltage) const;
  void Noise(int ci, unsigned long long stream, double* state, double* n0, double* n1) const;
  // Noise for n <= kNoiseRun consecutive receptors (streams stream, stream + 1,
  // ...): Noise's bits, the hashes, logs and cosines each in a loop of their own.
  static constexpr int kNoiseRun = 32;
  void NoiseRun(int ci, int n, unsigned long long stream, double* state, double* n0,
                double* n1) const;
  template <ReceptorClass C>
  int FromDrive(const Drive& d, double* state, double* voltage) const;
  int FromDriveAs(ReceptorClass cls, const Drive& d, double* state, double* voltage) const;
  int Finish(ReceptorClass cls, const Drive& d, double* state, double* voltage) const;
  template <ReceptorClass C>
  int Group(const double* q_end, const double* n0, const double* n1, double* state, double* spikes,
            double* voltage) const;
};

// The state of a receptor at rest with quantity q (first call): filters at
// rest, noise drawn from its stationary distribution.
void PrimeReceptor(const ReceptorParams& p, ReceptorClass cls, double q, unsigned long long stream,
                   double* state);
// Exponentially smoothed firing rate (Hz) held in the state.
double ReceptorRate(const double* state);

}  // namespace mjtouch

#endif  // MJTOUCH_AFFERENTS_RECEPTORS_H_
