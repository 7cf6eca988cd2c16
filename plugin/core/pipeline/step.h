// One step of the pipeline: the engine's inputs (StepInput), per-simulation
// scratch (Workspace) and Step, which runs the stages and writes sensordata.
#ifndef MJTOUCH_PIPELINE_STEP_H_
#define MJTOUCH_PIPELINE_STEP_H_

#include <memory>
#include <vector>

#include "contact/tangential.h"
#include "pipeline/model.h"

namespace mjtouch {

// Per-step inputs from the physics engine (all in world frame except forces).
struct StepInput {
  Pose pad_pose;
  std::vector<CounterSurface> surfaces;
  double normal_force_n = 0;            // total contact force on the pad along pad +z
  double shear_x_n = 0, shear_y_n = 0;  // along pad x, y
  bool in_contact = false;
  std::vector<ContactPoint> contacts;  // MuJoCo's contacts on the pad (pad frame)
  // Sums of MuJoCo's contact normal forces on the pad geom (N): all, and
  // those at points over the skin's patch on its facing side.
  double contact_normal_n = 0, patch_normal_n = 0;
  // shear="partial": Coulomb's mu between the skin and the counter-bodies
  // (the adapter's normal-force-weighted mean over the pad's contacts).
  double friction_mu = 0;
  // The physics timestep (s; 0: unknown). Time advanced by one step differs
  // from it by rounding (t accumulates dt); receptors then integrate over
  // exactly this step, as receptor_run does, and keep one propagator.
  double timestep_s = 0;
};

// Scratch owned per simulation (no state that outlives a step).
struct Workspace {
  // Receptor propagators for the last step size (rebuilt when it changes).
  std::shared_ptr<const ReceptorStepper> stepper;
  std::vector<double> gap, coverage;
  CellBox gap_written;           // outside it gap / coverage are +inf / 0 (RenderOutput::written)
  RenderSummary render_summary;  // the last render's covered cells (winkler)
  RenderScratch render_scratch;
  TractionField traction;
  std::vector<double> quantity;  // per receptor
  // This step's spike counts (summed over `oversample` substeps) and, without
  // the `voltage` output, voltages: per receptor, zero unless the step
  // advanced the receptors (Step sets them before its evaluations).
  std::vector<double> spikes, voltage;
  bool receptor_outputs_written = false;  // since Step last zeroed them
  ElasticStepWork elastic;                // `elastic`
  ElasticSolveStats elastic_stats;        // the last `elastic` solve (diagnostics)
  GridShiftWork grid_shift;               // `grid_shift`
  std::vector<double> pressure_guess;     // `elastic` initial guess, n*n
  std::vector<Stress6> stress;            // per receptor, Pa
  StressScratch stress_scratch;
  StressMethod last_stress_method = StressMethod::kDirect;
  // shear="partial": the tractions read from and written to plugin_state,
  // the last solve's outcome and the half-space compliance (shared).
  TangentialState tangential;
  TangentialResult tangential_result;
  std::shared_ptr<const TangentialCompliance> tangential_compliance;
  StepInput substep;                  // `oversample`: the interpolated input
  std::vector<double> spike_sum;      // `oversample`: spikes over the substeps
  std::vector<double> ramp_quantity;  // substep="receptors": this substep's quantities
};

// What the later stages read of stage 2's field beyond the float pressure
// and the active runs. A model may leave the rest lazy (zero until
// MaterializeTraction; WriteWinklerSlipTraction does).
struct TractionNeeds {
  bool pressure_pa = false;  // the double pressure (the `pressure` output)
  bool shear = false;        // the shear arrays (stress paths other than the folded one)
};

// Stages 1-2 for one step (skin_traction.cc): render the gap and solve the
// tractions into ws->traction with the configured pressure model, writing
// at least what `needs` names. Reads and updates the state header (contact
// depth, valid) and the elastic pressure history (StateLayout). new_time:
// false for a repeated evaluation at the last one's time, which then reads
// the same history. Returns whether the skin touches.
// How stages 1-2 run beyond the configuration (tests and benchmarks).
struct TractionRunOptions {
  // The general (reference) code instead of the fast paths, which give
  // bit-identical results.
  bool reference_paths = false;
  // If set, the CPU time of the surface rendering (s) is added to it.
  double* render_time_s = nullptr;
};

bool ComputeTraction(const SkinModel& model, const StepInput& in, const TractionNeeds& needs,
                     double* state, Workspace* ws, bool new_time = true,
                     const TractionRunOptions& run = TractionRunOptions());

// Reset the state array to its initial value.
void ResetState(const SkinModel& model, double* state);

// Writes the enabled output blocks (outputs.cc) from the last evaluation.
// The deepest indentation the skin can take, m: the stack over a rigid base
// (bone), else the pad's own half-height; beyond it the linear skin is past
// its range (the force block flags it).
double IndentationLimit(const SkinConfig& cfg);
// Whether the last evaluation touched deeper than IndentationLimit.
bool IndentationBeyondSkin(const SkinModel& model, const double* state);

void WriteOutputs(const SkinModel& model, const StepInput& in, bool touching, const double* state,
                  const Workspace& ws, double* out);

// Run the pipeline at simulation time time_s: receptors integrate over the
// time elapsed since the previous call (none on the first call or a repeated
// call at the same time). Writes the enabled output blocks to `out` (length
// model.output_size()) and updates `state`. Returns the number of spikes
// fired in this evaluation (all receptors).
int Step(const SkinModel& model, const StepInput& in, double time_s, double* state, Workspace* ws,
         double* out);

}  // namespace mjtouch

#endif  // MJTOUCH_PIPELINE_STEP_H_
