// The tactile pipeline's configuration: what the MJCF attributes set
// (attributes.h parses them) and the checks that need the pad or timestep.
#ifndef MJTOUCH_PIPELINE_CONFIG_H_
#define MJTOUCH_PIPELINE_CONFIG_H_

#include <memory>
#include <string>
#include <vector>

#include "afferents/receptors.h"
#include "common/grid.h"
#include "contact/contact_solver.h"
#include "contact/pressure.h"
#include "stress/stress_field.h"
#include "substrate/layered.h"
#include "surface/surface.h"

namespace mjtouch {

// Output blocks, in sensordata order.
enum OutputBlock {
  kOutSpikes = 0,
  kOutStress,
  kOutVoltage,
  kOutForce,
  kOutPressure,
  kOutRate,
  kOutCoverage,
  kOutStick,
  kOutSlip,
  kOutShear,
  kNumOutputs
};
const char* OutputName(int block);
// normal, tangential x, y (N, pad frame), indentation (m), and 1 when the
// indentation exceeds the skin (IndentationLimit) else 0
constexpr int kForceBlockSize = 5;
// Share of MuJoCo's normal force on the pad geom that lands on the skin's
// patch (1 without contact), and that normal force (N).
constexpr int kCoverageBlockSize = 2;
// shear="partial": the stuck share of the loaded cells, the friction
// coefficient used, the counter-body's tangential shift x, y (m, pad frame)
constexpr int kSlipBlockSize = 4;

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
  bool ridge_pitch_is_default = true;                      // (error messages)
  PressureModel pressure_model = PressureModel::kElastic;  // `pressure`
  double stiffness_pa_per_m = 2e7;                         // Winkler foundation
  double young_pa = 8e4;    // `elastic`: homogeneous skin (Shao 2010 epidermis)
  double tolerance = 1e-4;  // `elastic`: relative L1 pressure change per iteration (~ its error)
  ElasticMethod elastic_method = ElasticMethod::kPreconditioned;  // `contact_solver`
  ApplyPrecision elastic_precision = ApplyPrecision::kFloat;      // `elastic_precision`
  bool grid_shift = false;  // `elastic`: average with the half-cell shifted grid (grid_shift.h)
  int grid_cycle = 4;       // `elastic`: sub-cell offset grids solved in turn (grid_cycle.h)
  double poisson = 0.48;    // homogeneous skin (Shao 2010 epidermis)
  // Elastic skin: a layered stack (`skin` = layered: `layers` over `base`,
  // default the Shao et al. 2010 fingertip) or a homogeneous half-space
  // (`skin` = halfspace, `poisson`).
  bool layered = true;
  std::vector<ElasticLayer> layers = LayeredSubstrate::ShaoFingertipLayers();
  LayeredBase base = LayeredSubstrate::ShaoFingertipBase();
  InterfaceSide interface_side = InterfaceSide::kUpper;
  StressMethod stress_method = StressMethod::kAuto;  // `stress_method` (exact by default)
  double stress_theta = 0.5;                         // `stress_theta`: tree's opening angle
  int threads = 1;  // `threads`: elastic solve's and stage 3's threads per step (same bits)
  // `oversample`: tactile evaluations per physics step (the pad's pose and
  // MuJoCo's contact force interpolated over the step); 0 (`auto`) until
  // ResolveOversample sets the smallest that resolves the afferents.
  int oversample = 0;
  // `substep`: what each oversampled substep evaluates: all the stages at
  // the interpolated pose (kFull), or only the receptors, on the quantity
  // interpolated between the last step's and this step's (kReceptors:
  // stages 1-3 once per physics step).
  enum class Substep { kFull = 0, kReceptors };
  Substep substep = Substep::kFull;
  bool shear = true;
  // shear="partial": Coulomb partial slip per cell with memory (tangential.h)
  // instead of uniform full slip; needs `shear`.
  bool shear_partial = false;
  int texture_group = -1;             // non-colliding geoms in this group are textures (-1: none)
  double population_radius_m = 5e-3;  // receptors within this distance of the pole
  bool radius_is_default = false;     // unset: fitted to the grid and pad
  ClassConfig classes[kNumClasses];
  ReceptorParams receptor;
  bool outputs[kNumOutputs] = {true, true, false, true, false, false, false, false, false, false};
  // `sites`: explicit receptors (replace the density population when set).
  std::vector<ExplicitSite> sites;
  // Where the MuJoCo adapter draws the pressure heatmap and receptor flashes
  // (drawing only: not part of the physics, nor of the kernel cache key).
  VisualMode visual = VisualMode::kBoth;

  SkinConfig();
};

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
// The layered stack of a skin="layered" config; null (and *error naming
// `layers` / `base`) if it does not build.
std::unique_ptr<LayeredSubstrate> CreateLayeredSkin(const SkinConfig& cfg, std::string* error);
// Every class's receptor depth lies inside the layered stack `skin` (null:
// the half-space skin, which has no depth limit); `strain` and `sed` need a
// layered skin. SkinModel::Build checks the stack it builds.
bool CheckElasticSkin(const SkinConfig& cfg, const LayeredSubstrate* skin, std::string* error);
// The same after parsing: builds the stack first (CreateLayeredSkin).
bool CheckElasticSkin(const SkinConfig& cfg, std::string* error);

}  // namespace mjtouch

#endif  // MJTOUCH_PIPELINE_CONFIG_H_
