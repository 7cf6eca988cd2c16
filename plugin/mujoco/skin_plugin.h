// MuJoCo adapter for the mjtouch.skin sensor plugin: reads the pad geom, the
// counter-surfaces and MuJoCo's contact forces into a mjtouch::StepInput, runs
// the pure-C++ pipeline (plugin/core/pipeline/skin.h) and writes sensordata.
#ifndef MJTOUCH_MUJOCO_SKIN_PLUGIN_H_
#define MJTOUCH_MUJOCO_SKIN_PLUGIN_H_

#include <map>
#include <memory>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>

#include "pipeline/skin.h"
#include "surface/mesh_surface.h"

namespace mjtouch {

// Per-height-field running integrals (see HeightFieldRowPrefix).
struct HeightFieldCache {
  std::vector<float> samples;  // the samples the rest was built from
  size_t next_block = 0;       // where the next use's moving comparison starts
  bool bad = false;            // a non-finite sample: left out
  std::vector<double> prefix;
  double max_sample = 0;
  bool rows_identical = false;  // a 1D texture (e.g. a grating)
};

class SkinPlugin {
 public:
  static constexpr const char* kName = "mjtouch.skin";

  // Validates every attribute and the model; returns null after mju_warning
  // with a message naming the attribute and its valid range.
  static SkinPlugin* Create(const mjModel* m, mjData* d, int instance);
  static void RegisterPlugin();
  // Attributes alone (all that output and state sizes depend on): MuJoCo
  // asks for those sizes before the sensor's object is resolved.
  // The attribute, pad and timestep checks, run while MuJoCo compiles.
  static bool CheckAtCompile(const mjModel* m, int instance, std::string* error);
  static bool ResolveTextures(const mjModel* m, int instance, const SkinConfig& cfg, int pad,
                              std::vector<int>* textures, std::string* error);
  static bool ParseConfig(const mjModel* m, int instance, SkinConfig* cfg, std::string* error);
  // Attributes plus the pad geometry, for a compiled model.
  static bool ReadConfig(const mjModel* m, int instance, SkinConfig* cfg, int* sensor_id,
                         int* pad_geom, std::string* error);

  // A mesh pad: its surface (ReadPadMesh) and `facing` turned into the
  // compiled geom frame (TurnMeshPad).
  static bool ReadPadMesh(const mjModel* m, int g, PadGeometry* pad, std::string* error);
  static bool TurnMeshPad(const mjModel* m, int g, PadGeometry* pad, std::string* error);

  void Reset(const mjModel* m, mjtNum* plugin_state, int instance);
  void Compute(const mjModel* m, mjData* d, int instance);
  // Draws the last pressure field as a heatmap (on the pad's skin and/or a
  // copy above the pad, per the `visual` attribute) and receptor sites that
  // flash for kFlashS after each spike (visualize.cc).
  void Visualize(const mjModel* m, mjData* d, const mjvOption* opt, mjvScene* scn,
                 int instance) const;
  const SkinModel& model() const { return *model_; }

  // The plugin that `d` owns for `instance`, or null. MuJoCo's Python
  // bindings pickle an mjData as its raw buffer, plugin_data included, so an
  // unpickled mjData holds a pointer it does not own (another mjData's
  // plugin, a freed one, or, from another process, garbage): every callback
  // looks the pointer up among the live plugins before using it.
  static SkinPlugin* Owned(const mjData* d, int instance);
  // Owned, or else a new plugin for `d` built from the model (plugin_state,
  // the time-dependent state, is kept: the rollout continues). Null only if
  // the model is invalid.
  static SkinPlugin* OwnedOrRebuilt(const mjModel* m, mjData* d, int instance);
  const Workspace& workspace() const { return workspace_; }

 private:
  SkinPlugin() = default;
  void GatherInput(const mjModel* m, const mjData* d);
  // Whether contact c's normal (normal_sign: +1 if its frame normal points
  // from the pad into the other geom) faces the skin; 1 if point `pos`
  // (world) lies over a taxel the skin covers, else 0.
  bool FacesSkin(const mjContact& c, const mjtNum* pmat, mjtNum normal_sign) const;
  double PointOnPatch(const mjtNum* pos, const mjtNum* pmat, const mjtNum* ppos) const;
  // mju_warning once when MuJoCo's normal force on the pad lands off the patch.
  void WarnOffPatch(const mjModel* m);
  const HeightFieldCache* HeightField(const mjModel* m, int geom);
  void WarnOnce(const mjModel* m, const double* state);
  const MeshRayCaster* MeshCaster(const mjModel* m, int geom);

  std::shared_ptr<const SkinModel> model_;
  int sensor_id_ = -1;
  int pad_geom_ = -1;
  int pad_body_ = -1;
  std::vector<int> texture_geoms_;
  StepInput input_;
  // A MuJoCo contact on the pad, and the share of it the patch carries.
  struct PadContact {
    int index, other;
    mjtNum sign, f_local[6], f_world[3];
    double share;
  };
  std::vector<PadContact> contacts_;
  PatchFootprint footprint_;  // the pad's near side, for PatchShare
  Workspace workspace_;
  bool warned_beyond_skin_ = false, warned_height_field_ = false;
  std::map<int, HeightFieldCache> hfields_;               // by hfield id, built on first use
  std::map<int, std::unique_ptr<MeshRayCaster>> meshes_;  // by mesh id, built on first use
  // Drawing only (never read by the physics): the `visual` attribute, the
  // contact state of the last evaluation and each receptor's last spike time.
  VisualMode visual_ = VisualMode::kBoth;
  bool touching_ = false;
  bool warned_off_patch_ = false;          // contact off the skin's patch: warned once per data
  std::vector<double> last_spike_time_s_;  // s, per receptor; -inf: none yet
};

}  // namespace mjtouch

#endif  // MJTOUCH_MUJOCO_SKIN_PLUGIN_H_
