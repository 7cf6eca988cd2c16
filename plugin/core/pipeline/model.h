// SkinModel: the immutable tables of one configuration (receptor sites,
// skin surface, kernel tables, elastic contact), shared by every MjData of a
// model.
#ifndef MJTOUCH_PIPELINE_MODEL_H_
#define MJTOUCH_PIPELINE_MODEL_H_

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "contact/contact_solver.h"
#include "pipeline/config.h"
#include "pipeline/elastic/grid_cycle.h"
#include "pipeline/elastic/grid_shift.h"
#include "pipeline/state_layout.h"
#include "stress/kernel_tables.h"
#include "stress/stress_tree.h"

namespace mjtouch {

struct ReceptorSite {
  ReceptorClass cls;
  int i, j;         // taxel cell above the site
  double x_m, y_m;  // pad frame (cell centre)
  double depth_m;
  int depth_index;  // kernel table
};

class SkinModel {
 public:
  // Validates geometry, places receptors, builds kernel tables. Cached: equal
  // configurations share one instance.
  static std::shared_ptr<const SkinModel> Build(const SkinConfig& cfg, std::string* error);
  // Receptor layout and output sizes without building tables (for MuJoCo's
  // nstate / nsensordata callbacks).
  static std::vector<ReceptorSite> PlaceReceptors(const SkinConfig& cfg);
  // plugin_state doubles (StateLayout).
  static int StateSize(const SkinConfig& cfg, int nreceptor) {
    return StateLayout(cfg, nreceptor).size;
  }
  static int OutputSize(const SkinConfig& cfg, int nreceptor);
  static int BlockSize(const SkinConfig& cfg, int nreceptor, int block);

  const SkinConfig& config() const { return cfg_; }
  const std::vector<ReceptorSite>& receptors() const { return sites_; }
  const std::vector<double>& skin_z() const { return skin_z_; }
  const SkinBlocks& skin_blocks() const { return skin_blocks_; }
  const KernelTables* kernel() const { return kernel_.get(); }
  const ElasticContact* elastic() const { return elastic_.get(); }
  // `grid_shift` (with `elastic`): the half-cell shifted grid, else null.
  const ShiftedGrid* shifted() const { return shifted_.get(); }
  // `grid_cycle` > 1 (with `elastic`, without `grid_shift`): the offset
  // grids, else null.
  const CycleGrids* cycle() const { return cycle_.get(); }
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
  const StateLayout& state_layout() const { return layout_; }
  int state_size() const { return layout_.size; }
  int output_size() const { return OutputSize(cfg_, static_cast<int>(sites_.size())); }
  std::string Describe() const;
  // Stress components that class c's receptor quantity needs.
  const std::array<bool, kNumStress>& wanted(int c) const { return want_[c]; }

 private:
  SkinConfig cfg_;
  std::vector<ReceptorSite> sites_;
  StateLayout layout_;
  std::vector<double> skin_z_;
  SkinBlocks skin_blocks_;
  std::shared_ptr<const KernelTables> kernel_;
  std::shared_ptr<const ElasticContact> elastic_;  // `elastic` model only
  std::shared_ptr<const ShiftedGrid> shifted_;     // `grid_shift` with `elastic`
  std::shared_ptr<const CycleGrids> cycle_;        // `grid_cycle` > 1 with `elastic`
  std::shared_ptr<const Substrate> substrate_;
  const LayeredSubstrate* layered_ = nullptr;  // substrate_ if layered
  std::shared_ptr<const KernelSpectra> spectra_;
  std::shared_ptr<const StressTree> tree_;
  std::vector<StressSite> stress_sites_;
  Material material_[kNumClasses];
  std::vector<std::array<bool, kNumStress>> want_;  // per class
};

}  // namespace mjtouch

#endif  // MJTOUCH_PIPELINE_MODEL_H_
