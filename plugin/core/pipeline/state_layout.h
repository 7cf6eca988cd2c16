// The layout of plugin_state, the per-simulation state MuJoCo copies and
// resets: header slots, receptor membranes, the last outputs, the `elastic`
// pressure history and the last pad pose (StateLayout).
#ifndef MJTOUCH_PIPELINE_STATE_LAYOUT_H_
#define MJTOUCH_PIPELINE_STATE_LAYOUT_H_

#include <algorithm>
#include <cstring>

#include "afferents/receptors.h"
#include "common/grid.h"
#include "pipeline/config.h"

namespace mjtouch {

// plugin_state header slots (StateLayout::header).
enum StateSlot {
  kStContactDepth = 0,  // indentation depth of the last contact, m
  kStContactValid,      // 1 if the last evaluation touched
  kStLastTime,          // time of the last evaluation, s
  kStTimeValid,         // 1 once evaluated
  kStReceptorsIdle,     // 1 while receptors are quiescent and not advanced
  kStReceptorsTime,     // time the receptors were advanced to, s
  kStateHeader
};

// `oversample` > 1: the last step's pad pose, MuJoCo force and whether they
// are valid (StateLayout::last_pose).
enum LastPoseSlot {
  kLpPos = 0,           // pad position, 3 (world, m)
  kLpMat = 3,           // pad rotation, 9 (row-major)
  kLpNormalForce = 12,  // N, pad +z (0 without contact)
  kLpShearX,            // N, pad x
  kLpShearY,            // N, pad y
  kLpValid,             // 1 once recorded
  kLastPoseSize
};

// shear="partial": two buffers of the tangential state (TangentialState),
// each these slots then the tractions x, y (Pa, n*n doubles each). The head
// slot names the buffer holding the last evaluation's state; a step reads it
// and writes the other buffer, except that the substeps after a step's first
// read and write that one: the buffer the step started from stays intact,
// so a repeated evaluation (the head restored from eval_start) reads the
// same state and gives the same bits, oversampled or not.
enum TangentialSlot {
  kTgValid = 0,  // 1 if the tractions hold a contact's
  kTgShiftX,     // counter-body shift, m (pad frame)
  kTgShiftY,
  kTgBoxI0,  // the box outside which the tractions are zero (valid or not)
  kTgBoxJ0,
  kTgBoxNx,
  kTgBoxNy,
  kTangentialSlots
};

enum EvalStartSlot {
  kEsValid = 0,  // 1 once saved
  kEsTime,       // the time of the evaluation it precedes, s
  kEsReceptors,  // 1 if the receptor blocks were saved (0: that evaluation left them)
  kEvalStartSlots
};

// Where each block of plugin_state lives (offsets and sizes in doubles), in
// this order: the header (StateSlot), per-receptor membranes
// (kReceptorStateSize each), with the `voltage` output the last step's
// voltages, for `elastic` the pressure history (below);
// then the last pose (LastPoseSlot; always there: `auto` oversampling depends
// on the timestep, which MuJoCo's state-size callback does not see).
//
// Pressure history (`elastic`): kHistoryBlocks blocks of HistorySlot, then
// 2 n*n floats packed two to a double (n*n doubles): the pressure (Pa) on the
// grid, valid inside the box kHsPBox* (zero outside), and the surface
// displacement K p (m) of that pressure over the box kHsURegion* (row-major,
// at most n*n cells; none if kHsURegionNx is 0),
// which spares the next step's solve the operator application of its warm
// start. Floats: the history only seeds the warm start (the solve converges
// from it; float rounding, 1e-7, is far below its tolerance) and halves the
// state that mj_copyData and mujoco.rollout copy each step. Packed finite
// floats never form a NaN or infinite double.
// One slot names the head block h. Block h holds the evaluation at the
// current time, (h + 2) % 3 the last step's, (h + 1) % 3 the one before: the
// warm start extrapolates 2 p(n-1) - p(n-2). A new time rotates h (no
// copies); a repeated evaluation at the same time (mj_forward twice)
// overwrites block h only, so it starts from the same history and gives the
// same bits.
// `grid_shift`: the same three blocks for the shifted grid's solve ((n+1)^2
// cells, rotating with the same head), after the taxel grid's; absent
// without it.
// `grid_cycle` N > 1 (without `grid_shift`): no taxel grid blocks; a ring of
// 2 N blocks of (n+1)^2 cells, one per step whichever offset grid it
// solved: the grid solved now finds its last solution N steps back, and
// every grid's last two within 2 N - 1 steps. A slot after the head holds
// which grid this time solves.
enum HistorySlot {
  kHsValid = 0,  // touched
  kHsDepth,      // indentation, m
  kHsPBoxI0,
  kHsPBoxJ0,
  kHsPBoxNx,
  kHsPBoxNy,  // box of the pressure
  kHsURegionI0,
  kHsURegionJ0,
  kHsURegionNx,
  kHsURegionNy,  // box of the displacement
  kHistorySlots
};
constexpr int kHistoryBlocks = 3;
constexpr int kMaxGridCycle = 4;  // `grid_cycle`'s largest N

// A history block's packed floats: pressure at [0, ncell), displacement at
// [ncell, 2 ncell) (memcpy: no aliasing of the doubles).
struct HistoryBlock {
  double* slots;
  char* floats;
  size_t ncell;
  float p(size_t k) const { return Get(k); }
  float u(size_t k) const { return Get(ncell + k); }
  void set_p(size_t k, float v) { Set(k, v); }
  void set_u(size_t k, float v) { Set(ncell + k, v); }
  float Get(size_t k) const {
    float v;
    std::memcpy(&v, floats + 4 * k, 4);
    return v;
  }
  void Set(size_t k, float v) { std::memcpy(floats + 4 * k, &v, 4); }
  // count floats from index k on (pressure: k < ncell; displacement: ncell + k)
  void SetRange(size_t k, size_t count, const float* v) {
    std::memcpy(floats + 4 * k, v, 4 * count);
  }
  // count pressures from index k on
  void p_row(size_t k, int count, float* out) const {
    std::memcpy(out, floats + 4 * k, 4 * static_cast<size_t>(std::max(count, 0)));
  }
  // count displacements from index k on
  void u_row(size_t k, int count, float* out) const {
    std::memcpy(out, floats + 4 * (ncell + k), 4 * static_cast<size_t>(count));
  }
  CellBox SlotBox(int first) const {
    return CellBox{static_cast<int>(slots[first]), static_cast<int>(slots[first + 1]),
                   static_cast<int>(slots[first + 2]), static_cast<int>(slots[first + 3])};
  }
  void SetSlotBox(int first, const CellBox& b) {
    slots[first] = b.i0;
    slots[first + 1] = b.j0;
    slots[first + 2] = b.nx;
    slots[first + 3] = b.ny;
  }
  CellBox p_box() const { return SlotBox(kHsPBoxI0); }
  CellBox u_box() const { return SlotBox(kHsURegionI0); }
};

struct StateLayout {
  int receptors = 0, history = 0, last_pose = 0;
  // The `voltage` output's last values (nreceptor; 0 without it): re-output
  // by a step that does not advance the receptors. Spike counts are the
  // step's own (Workspace::spikes): zero unless it advanced them.
  int last_voltage = 0;
  bool voltage_in_state = false;
  // substep="receptors": the last step's receptor quantities (nreceptor)
  int last_quantity = 0;
  int history_block = 0;                       // kHistorySlots + n*n; 0 without `elastic`
  int shifted_history = 0, shifted_block = 0;  // kHistorySlots + (n+1)^2; 0 without `grid_shift`
  int history_head = 0;                        // slot of h
  int ring = kHistoryBlocks;                   // blocks in each history ring
  int cycle = 1, cycle_slot = 0;               // `grid_cycle` N; slot of this time's grid (N > 1)
  // shear="partial": the two tangential buffers (0 without), their head slot
  // (saved in eval_start) and the buffer this step writes (set by Step).
  int tangential = 0, tangential_block = 0, tangential_head = 0, tangential_write = 0;
  // The state before the first evaluation at a time (EvalStartSlot, then
  // the header, the receptor blocks, the history head and the last pose): a
  // repeated evaluation at that time starts again from it (step.cc).
  int eval_start = 0, eval_start_size = 0;
  int size = 0;
  size_t ncell = 0, shifted_ncell = 0;

  StateLayout() = default;
  StateLayout(const SkinConfig& cfg, int nreceptor) {
    receptors = kStateHeader;
    last_voltage = receptors + nreceptor * kReceptorStateSize;
    voltage_in_state = cfg.outputs[kOutVoltage];
    history = last_voltage + (voltage_in_state ? nreceptor : 0);
    const bool elastic = cfg.pressure_model == PressureModel::kElastic;
    ncell = cfg.grid.Size();
    cycle = elastic && !cfg.grid_shift ? cfg.grid_cycle : 1;
    history_block = elastic && cycle == 1 ? kHistorySlots + static_cast<int>(ncell) : 0;
    shifted_history = history + kHistoryBlocks * history_block;
    if (elastic && (cfg.grid_shift || cycle > 1)) {
      shifted_ncell = static_cast<size_t>(cfg.grid.n + 1) * (cfg.grid.n + 1);
      shifted_block = kHistorySlots + static_cast<int>(shifted_ncell);
    }
    if (cycle > 1) ring = 2 * cycle;
    tangential = shifted_history + ring * shifted_block;
    const bool partial = cfg.shear && cfg.shear_partial;
    tangential_block = partial ? kTangentialSlots + 2 * static_cast<int>(ncell) : 0;
    history_head = tangential + 2 * tangential_block;
    cycle_slot = history_head + (elastic ? 1 : 0);
    tangential_head = cycle_slot + (cycle > 1 ? 1 : 0);
    tangential_write = tangential_head + (partial ? 1 : 0);
    last_pose = tangential_write + (partial ? 1 : 0);
    last_quantity = last_pose + kLastPoseSize;
    const bool ramp = cfg.substep == SkinConfig::Substep::kReceptors;
    eval_start = last_quantity + (ramp ? nreceptor : 0);
    eval_start_size =
        kEvalStartSlots + kStateHeader + (history - receptors) + (eval_start - history_head);
    size = eval_start + eval_start_size;
  }
  // Whether any pressure history exists (taxel grid, shifted grid or the
  // `grid_cycle` ring): an idle step must still rotate it.
  bool has_history() const { return history_block > 0 || shifted_block > 0; }
  // Block k steps back from the head (0: this time, 1: last step, 2: the one
  // before).
  HistoryBlock history_at(double* state, int back) const {
    return Block(state, history, history_block, ncell, back);
  }
  // The same for the shifted grid (`grid_shift`), or the ring's block k
  // steps back (`grid_cycle`).
  HistoryBlock shifted_history_at(double* state, int back) const {
    return Block(state, shifted_history, shifted_block, shifted_ncell, back);
  }
  // Tangential buffer b (0 or 1): its slots, then x and y tractions.
  double* tangential_at(double* state, int b) const {
    return state + tangential + static_cast<size_t>(b) * tangential_block;
  }
  // Receptor r's membrane block.
  double* receptor(double* state, int r) const {
    return state + receptors + static_cast<size_t>(r) * kReceptorStateSize;
  }
  const double* receptor(const double* state, int r) const {
    return state + receptors + static_cast<size_t>(r) * kReceptorStateSize;
  }

 private:
  HistoryBlock Block(double* state, int first, int block, size_t cells, int back) const {
    const int h = static_cast<int>(state[history_head]);
    double* b = state + first + static_cast<size_t>((h + ring - back) % ring) * block;
    return HistoryBlock{b, reinterpret_cast<char*>(b + kHistorySlots), cells};
  }
};

}  // namespace mjtouch

#endif  // MJTOUCH_PIPELINE_STATE_LAYOUT_H_
