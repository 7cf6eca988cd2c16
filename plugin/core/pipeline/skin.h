// The whole tactile pipeline for one fingertip, independent of MuJoCo:
//   surface.h   (stage 1) skin and counter-surface geometry -> gap per taxel
//   pressure.h  (stage 2) gap + contact force -> pressure and shear tractions
//   kernel.h    (stage 3) tractions -> stress tensor at receptor sites
//   receptors.h (stage 4) stress -> SA1 / RA / PC spikes
// SkinModel is immutable and shared by every MjData of a model; the per-step
// mutable state lives in a caller-owned double array (MuJoCo plugin_state) and
// scratch buffers in a Workspace (MuJoCo plugin_data).
#ifndef MJTOUCH_PIPELINE_SKIN_H_
#define MJTOUCH_PIPELINE_SKIN_H_

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "common/grid.h"
#include "stress/kernel_tables.h"
#include "substrate/layered.h"
#include "contact/contact_solver.h"
#include "contact/pressure.h"
#include "afferents/receptors.h"
#include "stress/stress_field.h"
#include "stress/stress_tree.h"
#include "surface/surface.h"

namespace mjtouch {

// Output blocks, in sensordata order.
enum OutputBlock {
  kOutSpikes = 0, kOutStress, kOutVoltage, kOutForce, kOutPressure, kOutRate, kNumOutputs
};
const char* OutputName(int block);
constexpr int kForceBlockSize = 4;  // normal, tangential x, y (N, pad frame), indentation (m)

// `visual` attribute: none, pad (on the skin), above (a copy over the pad), both.
enum class VisualMode { kNone = 0, kPad, kAbove, kBoth };

// A receptor placed by the `sites` attribute (pad frame, m).
struct ExplicitSite {
  ReceptorClass cls;
  double x_m, y_m, depth_m;
};

struct ClassConfig {
  bool present = true;
  double density_per_cm2 = 0;
  double depth_m = 0;
  Quantity quantity = Quantity::kCompressiveSzz;
};

struct SkinConfig {
  TaxelGrid grid{128, 1e-4};
  PadGeometry pad;  // filled by the caller (MuJoCo: the pad geom's size)
  Ridges ridges;
  bool ridge_pitch_is_default = true;  // (error messages)
  PressureModel pressure_model = PressureModel::kWinkler;  // `pressure`
  double stiffness_pa_per_m = 2e7;  // Winkler foundation
  double young_pa = 8e4;            // `elastic`: homogeneous skin (Shao 2010 epidermis)
  double tolerance = 1e-4;          // `elastic`: relative L1 pressure change per iteration (~ its error)
  double poisson = 0.48;            // homogeneous skin (Shao 2010 epidermis)
  // Elastic skin: a layered stack (`skin` = layered: `layers` over `base`,
  // default the Shao et al. 2010 fingertip) or a homogeneous half-space
  // (`skin` = halfspace, `poisson`).
  bool layered = true;
  std::vector<ElasticLayer> layers = LayeredSubstrate::ShaoFingertipLayers();
  LayeredBase base = LayeredSubstrate::ShaoFingertipBase();
  InterfaceSide interface_side = InterfaceSide::kUpper;
  StressMethod stress_method = StressMethod::kAuto;  // `stress_method` (exact by default)
  double stress_theta = 0.5;  // `stress_theta`: tree's opening angle
  // `oversample`: tactile evaluations per physics step (the pad's pose and
  // MuJoCo's contact force interpolated over the step); 0 (`auto`) until
  // ResolveOversample sets the smallest that resolves the afferents.
  int oversample = 0;
  bool shear = true;
  int texture_group = -1;  // non-colliding geoms in this group are textures (-1: none)
  double population_radius_m = 5e-3;  // receptors within this distance of the pole
  bool radius_is_default = false;    // unset: fitted to the grid and pad
  ClassConfig classes[kNumClasses];
  ReceptorParams receptor;
  bool outputs[kNumOutputs] = {true, true, false, true, false, false};
  // `sites`: explicit receptors (replace the density population when set).
  std::vector<ExplicitSite> sites;
  // Where the MuJoCo adapter draws the pressure heatmap and receptor flashes
  // (drawing only: not part of the physics, nor of the kernel cache key).
  VisualMode visual = VisualMode::kBoth;

  SkinConfig();
};

// Parse the MJCF config attributes through `get` (returns "" when unset).
// Returns false with a message naming the attribute and its valid range.
using AttributeGetter = std::function<std::string(const char* key)>;
bool ParseSkinConfig(const AttributeGetter& get, SkinConfig* cfg, std::string* error);
// Pad-dependent checks and defaults; call after cfg->pad is set and before
// PlaceReceptors (idempotent).
bool FinalizeSkinConfig(SkinConfig* cfg, std::string* error);
// Whether the tactile sampling rate, oversample / timestep_s, resolves every
// present afferent class's band: PC and RA respond up to a few times their
// low-pass corner (their drive falls only as 1/f above it), so they need at
// least 8 x the corner (PC: 2 kHz at the default 250 Hz; RA: 320 Hz), when
// an output shows the afferents (spikes, voltage, rate). Else false with a
// message naming the rate needed and the `oversample` that gives it.
bool CheckTactileRate(const SkinConfig& cfg, double timestep_s, std::string* error);
// `oversample` = auto (0): the smallest count in [1, 64] that passes
// CheckTactileRate at timestep_s (1 for the contacts model, which has no
// geometry to interpolate); an explicit count is kept.
void ResolveOversample(SkinConfig* cfg, double timestep_s);
// All attribute keys, for plugin registration.
const std::vector<const char*>& SkinAttributeKeys();

// plugin_state header slots, then the receptors (StateSize).
enum StateSlot {
  kStContactDepth = 0,  // indentation depth of the last contact, m
  kStContactValid,      // 1 if the last evaluation touched
  kStLastTime,          // time of the last evaluation, s
  kStTimeValid,         // 1 once evaluated
  kStReceptorsIdle,     // 1 while receptors are quiescent and not advanced
  kStReceptorsTime,     // time the receptors were advanced to, s
  kStateHeader
};

struct ReceptorSite {
  ReceptorClass cls;
  int i, j;           // taxel cell above the site
  double x_m, y_m;    // pad frame (cell centre)
  double depth_m;
  int depth_index;    // kernel table
};

class SkinModel {
 public:
  // Validates geometry, places receptors, builds kernel tables. Cached: equal
  // configurations share one instance.
  static std::shared_ptr<const SkinModel> Build(const SkinConfig& cfg, std::string* error);
  // Receptor layout and output sizes without building tables (for MuJoCo's
  // nstate / nsensordata callbacks).
  static std::vector<ReceptorSite> PlaceReceptors(const SkinConfig& cfg);
  // Header (StateSlot), per-receptor membranes, the last step's spike counts
  // and voltages (re-output on repeated calls), and for `elastic` the last
  // pressure field (n*n, Pa: the next step's warm start).
  // (The last-pose block is always there: `auto` oversampling depends on the
  // timestep, which MuJoCo's state-size callback does not see.)
  static int StateSize(const SkinConfig& cfg, int nreceptor) {
    return kStateHeader + nreceptor * (kReceptorStateSize + 2) +
           (cfg.pressure_model == PressureModel::kElastic ? static_cast<int>(cfg.grid.Size()) : 0) +
           kOversampleStateSize;
  }
  // For `oversample` > 1: the last step's pad pose (pos 3, rotation 9),
  // MuJoCo force (normal, shear x, y) and whether they are valid.
  static constexpr int kOversampleStateSize = 16;
  static int OutputSize(const SkinConfig& cfg, int nreceptor);
  static int BlockSize(const SkinConfig& cfg, int nreceptor, int block);

  const SkinConfig& config() const { return cfg_; }
  const std::vector<ReceptorSite>& receptors() const { return sites_; }
  const std::vector<double>& skin_z() const { return skin_z_; }
  const SkinBlocks& skin_blocks() const { return skin_blocks_; }
  const KernelTables* kernel() const { return kernel_.get(); }
  const ElasticContact* elastic() const { return elastic_.get(); }
  // The elastic skin (HalfSpace or LayeredSubstrate), its FFT spectra (null
  // unless the FFT path can pay off), the receptor sites as the stress stage
  // sees them, and the material at each class's depth (for `sed`, `strain`;
  // zero for a half-space skin, which has no Young's modulus).
  const Substrate& substrate() const { return *substrate_; }
  const LayeredSubstrate* layered() const { return layered_; }
  const KernelSpectra* spectra() const { return spectra_.get(); }
  const StressTree* tree() const { return tree_.get(); }  // null unless stress_method = tree
  const std::vector<StressSite>& stress_sites() const { return stress_sites_; }
  const Material& material(int c) const { return material_[c]; }
  // Seconds spent building the kernel tables (and FFT spectra), once per
  // configuration (cached: shared by every MjData of a model).
  double kernel_build_seconds() const;
  int state_size() const { return StateSize(cfg_, static_cast<int>(sites_.size())); }
  int output_size() const { return OutputSize(cfg_, static_cast<int>(sites_.size())); }
  std::string Describe() const;
  // Stress components that class c's receptor quantity needs.
  const std::array<bool, kNumStress>& wanted(int c) const { return want_[c]; }

 private:
  SkinConfig cfg_;
  std::vector<ReceptorSite> sites_;
  std::vector<double> skin_z_;
  SkinBlocks skin_blocks_;
  std::shared_ptr<const KernelTables> kernel_;
  std::shared_ptr<const ElasticContact> elastic_;  // `elastic` model only
  std::shared_ptr<const Substrate> substrate_;
  const LayeredSubstrate* layered_ = nullptr;  // substrate_ if layered
  std::shared_ptr<const KernelSpectra> spectra_;
  std::shared_ptr<const StressTree> tree_;
  std::vector<StressSite> stress_sites_;
  Material material_[kNumClasses];
  std::vector<std::array<bool, kNumStress>> want_;  // per class
};

// Per-step inputs from the physics engine (all in world frame except forces).
struct StepInput {
  Pose pad_pose;
  std::vector<CounterSurface> surfaces;
  double normal_force_n = 0;   // total contact force on the pad along pad +z
  double shear_x_n = 0, shear_y_n = 0;  // along pad x, y
  bool in_contact = false;
  std::vector<ContactPoint> contacts;  // MuJoCo's contacts on the pad (pad frame)
};

// Scratch owned per simulation (no state that outlives a step).
struct Workspace {
  // Receptor propagators for the last step size (rebuilt when it changes).
  std::shared_ptr<const ReceptorStepper> stepper;
  std::vector<double> gap, coverage;
  TractionField traction;
  std::vector<double> quantity;  // per receptor
  ElasticWork elastic;
  ElasticSolveStats elastic_stats;  // the last `elastic` solve (diagnostics)
  std::vector<double> pressure_guess;  // `elastic` initial guess, n*n
  std::vector<Stress6> stress;   // per receptor, Pa
  StressScratch stress_scratch;
  StressMethod last_stress_method = StressMethod::kDirect;
  StepInput substep;            // `oversample`: the interpolated input
  std::vector<double> spike_sum;  // `oversample`: spikes over the substeps
};

// The last step's spike count per receptor (nreceptor values inside `state`).
inline const double* LastSpikes(const SkinModel& model, const double* state) {
  return state + kStateHeader + model.receptors().size() * kReceptorStateSize;
}
// `elastic`: the last pressure field (n*n, Pa) inside `state`.
inline double* LastPressure(const SkinModel& model, double* state) {
  return state + kStateHeader + model.receptors().size() * (kReceptorStateSize + 2);
}
// `oversample` > 1: the last step's pose and force inside `state`.
inline double* LastPose(const SkinModel& model, double* state) {
  return LastPressure(model, state) +
         (model.config().pressure_model == PressureModel::kElastic ? model.config().grid.Size()
                                                                   : 0);
}

// Stages 1-2 for one step (skin_traction.cc): render the gap and solve the
// tractions into ws->traction with the configured pressure model. Reads and
// updates the state header (contact depth, level, valid). Returns whether
// the skin touches.
bool ComputeTraction(const SkinModel& model, const StepInput& in, double* state, Workspace* ws);

// Reset the state array to its initial value.
void ResetState(const SkinModel& model, double* state);

// Run the pipeline at simulation time time_s: receptors integrate over the
// time elapsed since the previous call (none on the first call or a repeated
// call at the same time). Writes the enabled output blocks to `out` (length
// model.output_size()) and updates `state`. Returns the number of spikes
// fired in this evaluation (all receptors).
int Step(const SkinModel& model, const StepInput& in, double time_s, double* state,
          Workspace* ws, double* out);

}  // namespace mjtouch

#endif  // MJTOUCH_PIPELINE_SKIN_H_
