// Step: stages 1-4 at one time (Evaluate), repeated over `oversample`
// substeps with the pad's pose and MuJoCo's force interpolated, then the
// outputs written (outputs.cc).
#include <algorithm>
#include <cmath>

#include "pipeline/step.h"

namespace mjtouch {

void ResetState(const SkinModel& model, double* state) {
  std::fill(state, state + model.state_size(), 0.0);
}

namespace {

const ReceptorStepper& StepperFor(const ReceptorParams& p, double dt_s, Workspace* ws) {
  if (!ws->stepper || ws->stepper->dt() != dt_s)
    ws->stepper = std::make_shared<const ReceptorStepper>(p, dt_s);
  return *ws->stepper;
}

// The end of the run of one class's receptors that starts at r (receptors
// are grouped by class; their states are consecutive).
template <typename Sites>
int ClassRunEnd(const Sites& sites, int r, int nrec) {
  int end = r + 1;
  while (end < nrec && sites[end].cls == sites[r].cls) ++end;
  return end;
}

// Receptor quantity from the stress; strain and SED from the material at the
// receptor (the layer's E and nu).
double QuantityAt(Quantity q, const Stress6& stress, const Material& m) {
  switch (q) {
    case Quantity::kStrainEnergy: return StrainEnergyDensity(stress, m);
    case Quantity::kCompressiveStrain: {
      const Stress6 strain = StrainFromStress(stress, m);
      return ReceptorQuantity(Quantity::kMaxCompressive, strain.data());
    }
    default: return ReceptorQuantity(q, stress.data());
  }
}

// Stage 3's path for this step's field (it depends on the active cells) and
// what it reads of the field.
struct StressPlan {
  StressMethod method;
  StressOptions options;
  TractionNeeds reads;
};

StressPlan PlanStresses(const SkinModel& model, const KernelTables& kt, const TractionField& tf) {
  const SkinConfig& cfg = model.config();
  StressPlan plan;
  plan.options = StressOptions{tf.uniform_slip, tf.slip_x, tf.slip_y, true, cfg.threads};
  plan.options.fold_general = cfg.shear_partial;  // partial slip: its shear folded too
  plan.method = ResolveStressMethod(kt, model.spectra(), model.tree(), cfg.stress_method,
                                    model.stress_sites(), tf.runs.Count(), cfg.shear, plan.options);
  plan.reads.shear = PathReadsShear(kt, plan.method, cfg.shear, plan.options);
  return plan;
}

// Stages 1-4 at time_s: receptors advance over the time since the last
// evaluation. Leaves the quantities in ws->quantity and each receptor's
// spike count and voltage in `state`; returns whether the skin touches and
// adds the spikes fired to *fired.
// substep="receptors" (ramp set): stages 1-3 at time_s only; the receptors
// then advance over `substeps` equal parts of the elapsed time on the
// quantity interpolated linearly from ramp_from's (the last step's), their
// spike counts summed.
struct QuantityRamp {
  const double* from;  // per receptor, the last step's quantity
  int substeps;
};

bool Evaluate(const SkinModel& model, const StepInput& in, double time_s, double nominal_s,
              double* state, Workspace* ws, int* fired, const QuantityRamp* ramp = nullptr) {
  const SkinConfig& cfg = model.config();
  const auto& sites = model.receptors();
  const int nrec = static_cast<int>(sites.size());
  const StateLayout& layout = model.state_layout();
  double* last_spikes = ws->spikes.data();
  double* last_voltage = layout.voltage_in_state ? state + layout.last_voltage : ws->voltage.data();
  // Receptors integrate over the time elapsed since the previous call, so a
  // repeated mj_forward at the same time changes nothing.
  const bool time_valid = state[kStTimeValid] > 0.0;
  const double elapsed = time_valid ? time_s - state[kStLastTime] : 0.0;
  state[kStLastTime] = time_s;
  state[kStTimeValid] = 1.0;

  const TractionField& tf = ws->traction;
  // Stages 1-2: gap and tractions (skin_traction.cc).
  TractionNeeds outputs_read;
  outputs_read.pressure_pa = cfg.outputs[kOutPressure];
  outputs_read.shear = cfg.outputs[kOutShear];
  const bool touching =
      ComputeTraction(model, in, outputs_read, state, ws, !(time_valid && elapsed == 0.0));
  if (touching && outputs_read.shear) MaterializeTraction(cfg.grid, false, true, &ws->traction);
  const bool need_receptors =
      cfg.outputs[kOutSpikes] || cfg.outputs[kOutVoltage] || cfg.outputs[kOutRate];
  // Idle receptors: untouched, quiescent receptors (ReceptorStepper::Quiescent)
  // are not advanced while nothing touches and no output shows their
  // relaxing membranes; the idle time is made up in one exact step when
  // contact resumes. An untouched skin then costs O(1) per step.
  const bool idle = state[kStReceptorsIdle] > 0.0;
  if (!touching && idle && elapsed >= 0.0) {
    // Nothing to do: no spikes (idle receptors never fire; without the
    // `voltage` output no voltage is shown).
    return false;
  }
  ws->quantity.assign(nrec, 0.0);
  const KernelTables* kt = model.kernel();
  if (touching && kt) {
    // Stage 3: stress at the receptors (direct, FFT or tree).
    ws->stress.resize(nrec);
    // The folded direct sum reads the pressure alone (shear = slip x
    // pressure): the arrays the pressure model left lazy are written only
    // for what the plan reads.
    const StressPlan plan = PlanStresses(model, *kt, tf);
    MaterializeTraction(cfg.grid, plan.reads.pressure_pa, plan.reads.shear, &ws->traction);
    ws->last_stress_method =
        ComputeStresses(*kt, model.spectra(), model.tree(), plan.method, model.stress_sites(),
                        tf.runs, tf.pressure.data(), cfg.shear ? tf.shear_x.data() : nullptr,
                        cfg.shear ? tf.shear_y.data() : nullptr, &ws->stress_scratch,
                        ws->stress.data(), plan.options);
    // per run of one class's receptors; stress-based quantities at once
    static_assert(sizeof(Stress6) == 6 * sizeof(double), "stress tensors 6 doubles apart");
    for (int r = 0; r < nrec;) {
      const int c = static_cast<int>(sites[r].cls);
      const int end = ClassRunEnd(sites, r, nrec);
      const Quantity q = cfg.classes[c].quantity;
      if (q == Quantity::kStrainEnergy || q == Quantity::kCompressiveStrain) {
        for (; r < end; ++r) ws->quantity[r] = QuantityAt(q, ws->stress[r], model.material(c));
      } else {
        ReceptorQuantities(q, end - r, ws->stress[r].data(), ws->quantity.data() + r);
        r = end;
      }
    }
  }
  // Stage 4: receptors advance every step (membranes relax without contact).
  if (need_receptors && elapsed > 0.0) {
    if (idle) {  // make up the idle time at q = 0, in one exact step
      const double gap_s = (time_s - elapsed) - state[kStReceptorsTime];
      if (gap_s > 0.0) {
        const ReceptorStepper catch_up(cfg.receptor, gap_s);
        double v;
        for (int r = 0; r < nrec; ++r)
          catch_up.Advance(sites[r].cls, 0.0, r, layout.receptor(state, r), &v);
      }
      state[kStReceptorsIdle] = 0.0;
    }
    const int parts = ramp ? ramp->substeps : 1;
    const double part_s = elapsed / parts;
    // one step of the timestep (or substep) up to rounding: exactly it
    const double step_s =
        nominal_s > 0.0 && std::abs(part_s - nominal_s) <= 1e-9 * nominal_s ? nominal_s : part_s;
    const ReceptorStepper& stepper = StepperFor(cfg.receptor, step_s, ws);
    ws->receptor_outputs_written = true;
    if (ramp) ws->spike_sum.assign(nrec, 0.0);
    for (int k = 1; k <= parts; ++k) {
      const double* q = ws->quantity.data();
      if (ramp) {
        const double s = static_cast<double>(k) / parts;
        ws->ramp_quantity.resize(nrec);
        for (int r = 0; r < nrec; ++r)
          ws->ramp_quantity[r] = ramp->from[r] + s * (ws->quantity[r] - ramp->from[r]);
        q = ws->ramp_quantity.data();
      }
      // each run of one class's receptors at once (their states are consecutive)
      for (int r = 0; r < nrec;) {
        const int end = ClassRunEnd(sites, r, nrec);
        *fired += stepper.AdvanceBatch(sites[r].cls, end - r, q + r, r, layout.receptor(state, r),
                                       last_spikes + r, last_voltage + r);
        r = end;
      }
      if (ramp)
        for (int r = 0; r < nrec; ++r) ws->spike_sum[r] += last_spikes[r];
    }
    if (ramp) std::copy(ws->spike_sum.begin(), ws->spike_sum.end(), last_spikes);
    bool quiescent = !touching && !cfg.outputs[kOutVoltage] && !cfg.outputs[kOutRate];
    for (int r = 0; r < nrec && quiescent; ++r)
      quiescent =
          last_spikes[r] == 0.0 && stepper.Quiescent(sites[r].cls, layout.receptor(state, r));
    if (quiescent) {
      state[kStReceptorsIdle] = 1.0;
      state[kStReceptorsTime] = time_s;
    }
  } else if (need_receptors && !time_valid) {
    for (int r = 0; r < nrec; ++r)
      PrimeReceptor(cfg.receptor, sites[r].cls, ws->quantity[r], r, layout.receptor(state, r));
  }
  return touching;
}

// Unit quaternion (w, x, y, z) of a row-major rotation matrix, and back.
void MatToQuat(const double* m, double* q) {
  const double tr = m[0] + m[4] + m[8];
  if (tr > 0.0) {
    const double s = 2.0 * std::sqrt(tr + 1.0);
    q[0] = 0.25 * s;
    q[1] = (m[7] - m[5]) / s;
    q[2] = (m[2] - m[6]) / s;
    q[3] = (m[3] - m[1]) / s;
  } else if (m[0] > m[4] && m[0] > m[8]) {
    const double s = 2.0 * std::sqrt(1.0 + m[0] - m[4] - m[8]);
    q[0] = (m[7] - m[5]) / s;
    q[1] = 0.25 * s;
    q[2] = (m[1] + m[3]) / s;
    q[3] = (m[2] + m[6]) / s;
  } else if (m[4] > m[8]) {
    const double s = 2.0 * std::sqrt(1.0 + m[4] - m[0] - m[8]);
    q[0] = (m[2] - m[6]) / s;
    q[1] = (m[1] + m[3]) / s;
    q[2] = 0.25 * s;
    q[3] = (m[5] + m[7]) / s;
  } else {
    const double s = 2.0 * std::sqrt(1.0 + m[8] - m[0] - m[4]);
    q[0] = (m[3] - m[1]) / s;
    q[1] = (m[2] + m[6]) / s;
    q[2] = (m[5] + m[7]) / s;
    q[3] = 0.25 * s;
  }
}

void QuatToMat(const double* q, double* m) {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  m[0] = 1 - 2 * (y * y + z * z);
  m[1] = 2 * (x * y - w * z);
  m[2] = 2 * (x * z + w * y);
  m[3] = 2 * (x * y + w * z);
  m[4] = 1 - 2 * (x * x + z * z);
  m[5] = 2 * (y * z - w * x);
  m[6] = 2 * (x * z - w * y);
  m[7] = 2 * (y * z + w * x);
  m[8] = 1 - 2 * (x * x + y * y);
}

// Poses a fraction s of the way from a to b: position linear, rotation by
// spherical linear interpolation (the end rotations converted once).
class PoseInterpolator {
 public:
  PoseInterpolator(const Pose& a, const Pose& b) : a_(a), b_(b) {
    MatToQuat(a.mat, qa_);
    MatToQuat(b.mat, qb_);
    dot_ = qa_[0] * qb_[0] + qa_[1] * qb_[1] + qa_[2] * qb_[2] + qa_[3] * qb_[3];
    if (dot_ < 0.0) {  // the shorter arc
      for (double& v : qb_) v = -v;
      dot_ = -dot_;
    }
    if (dot_ < 1.0 - 1e-12) theta_ = std::acos(std::min(1.0, dot_));
  }

  Pose At(double s) const {
    Pose out;
    for (int k = 0; k < 3; ++k) out.pos[k] = a_.pos[k] + s * (b_.pos[k] - a_.pos[k]);
    double wa = 1.0 - s, wb = s;
    if (dot_ < 1.0 - 1e-12) {
      wa = std::sin((1.0 - s) * theta_) / std::sin(theta_);
      wb = std::sin(s * theta_) / std::sin(theta_);
    }
    double q[4], norm = 0.0;
    for (int k = 0; k < 4; ++k) {
      q[k] = wa * qa_[k] + wb * qb_[k];
      norm += q[k] * q[k];
    }
    for (double& v : q) v /= std::sqrt(norm);
    QuatToMat(q, out.mat);
    return out;
  }

 private:
  const Pose& a_;
  const Pose& b_;
  double qa_[4], qb_[4], dot_ = 1.0, theta_ = 0.0;
};

// The receptors' inputs at a time are that evaluation's own: the first
// evaluation at a new time saves the state it starts from; a repeated one at
// the same time (mj_forward, then mj_step with other ctrl) restores it and
// evaluates again, giving what it alone would give. The pressure history is
// restored through its head (the block written at this time is rewritten);
// with `elastic` and oversample > 1 the first evaluation's substeps also
// overwrite the older blocks the warm start reads, so there the repeat
// agrees with the step alone to the solver's `tolerance`, not bit for bit.
// An idle skin out of contact (ComputeTraction returns before touching
// anything but the header, Evaluate before stage 4) leaves the receptor
// blocks and the last quantities (zero while idle) as they are: they are not
// saved, and a repeat finds them unchanged.
void SaveOrRestoreEvaluationStart(const StateLayout& lay, double time_s, bool receptors_unchanged,
                                  double* state) {
  double* saved = state + lay.eval_start;
  struct Span {
    int first, count;
    bool receptors;
  };
  const Span spans[] = {{0, kStateHeader, false},
                        {lay.receptors, lay.history - lay.receptors, true},
                        {lay.history_head, lay.last_quantity - lay.history_head, false},
                        {lay.last_quantity, lay.eval_start - lay.last_quantity, true}};
  const bool repeat = state[kStTimeValid] > 0.0 && state[kStLastTime] == time_s &&
                      saved[kEsValid] > 0.0 && saved[kEsTime] == time_s;
  if (!repeat) saved[kEsReceptors] = receptors_unchanged ? 0.0 : 1.0;
  const bool with_receptors = saved[kEsReceptors] > 0.0;
  double* at = saved + kEvalStartSlots;
  for (const Span& sp : spans) {
    if (!sp.receptors || with_receptors) {
      if (repeat)
        std::copy(at, at + sp.count, state + sp.first);
      else
        std::copy(state + sp.first, state + sp.first + sp.count, at);
    }
    at += sp.count;
  }
  saved[kEsValid] = 1.0;
  saved[kEsTime] = time_s;
}

}  // namespace

int Step(const SkinModel& model, const StepInput& in, double time_s, double* state, Workspace* ws,
         double* out) {
  const SkinConfig& cfg = model.config();
  const int K = cfg.oversample;
  int fired = 0;
  const StateLayout& lay = model.state_layout();
  SaveOrRestoreEvaluationStart(lay, time_s, state[kStReceptorsIdle] > 0.0 && !in.in_contact, state);
  const size_t nreceptor = model.receptors().size();
  if (ws->spikes.size() != nreceptor || ws->receptor_outputs_written) {
    ws->spikes.assign(nreceptor, 0.0);
    if (!lay.voltage_in_state) ws->voltage.assign(nreceptor, 0.0);
    ws->receptor_outputs_written = false;
  }
  if (lay.tangential_block > 0)  // this step writes the buffer it did not start from
    state[lay.tangential_write] = 1.0 - state[lay.tangential_head];
  bool touching;
  double* last = K > 1 ? state + model.state_layout().last_pose : nullptr;
  const double elapsed = state[kStTimeValid] > 0.0 ? time_s - state[kStLastTime] : 0.0;
  // Idle receptors and no contact: each evaluation only moves the header on
  // (no pose is read, no spike fired), so none is interpolated or summed;
  // without a pressure history (taxel, shifted or cycled grids) or
  // tangential buffers to advance, the header is all there is: set it as
  // the evaluations would.
  const bool quiet = state[kStReceptorsIdle] > 0.0 && !in.in_contact;
  if (quiet && elapsed > 0.0 && !lay.has_history() && lay.tangential_block == 0) {
    state[kStLastTime] = time_s;
    state[kStTimeValid] = 1.0;
    state[kStContactValid] = 0.0;
    touching = false;
  } else if (K > 1 && last[kLpValid] > 0.0 && elapsed > 0.0 && quiet) {
    const double t0 = time_s - elapsed;
    for (int k = 1; k <= K; ++k)
      touching = Evaluate(model, in, k < K ? t0 + static_cast<double>(k) / K * elapsed : time_s,
                          in.timestep_s / K, state, ws, &fired);
  } else if (K > 1 && last[kLpValid] > 0.0 && elapsed > 0.0 &&
             cfg.substep == SkinConfig::Substep::kReceptors) {
    const QuantityRamp ramp{state + lay.last_quantity, K};
    touching = Evaluate(model, in, time_s, in.timestep_s / K, state, ws, &fired, &ramp);
  } else if (K > 1 && last[kLpValid] > 0.0 && elapsed > 0.0) {
    // Tactile substeps: the pad's pose and MuJoCo's force interpolated from
    // the last step's (counter-surfaces at this step's pose); spikes summed.
    const int nrec = static_cast<int>(model.receptors().size());
    double* last_spikes = ws->spikes.data();
    ws->spike_sum.assign(nrec, 0.0);
    Pose from;
    std::copy(last + kLpPos, last + kLpPos + 3, from.pos);
    std::copy(last + kLpMat, last + kLpMat + 9, from.mat);
    StepInput& sub = ws->substep;
    sub.surfaces = in.surfaces;
    sub.contacts = in.contacts;
    sub.in_contact = in.in_contact;
    sub.friction_mu = in.friction_mu;
    sub.timestep_s = in.timestep_s;
    const double t0 = time_s - elapsed;
    const PoseInterpolator pose(from, in.pad_pose);
    for (int k = 1; k <= K; ++k) {
      const double s = static_cast<double>(k) / K;
      const StepInput* use = &in;
      if (k < K) {
        sub.pad_pose = pose.At(s);
        sub.normal_force_n = last[kLpNormalForce] + s * (in.normal_force_n - last[kLpNormalForce]);
        sub.shear_x_n = last[kLpShearX] + s * (in.shear_x_n - last[kLpShearX]);
        sub.shear_y_n = last[kLpShearY] + s * (in.shear_y_n - last[kLpShearY]);
        use = &sub;
      }
      touching = Evaluate(model, *use, k < K ? t0 + s * elapsed : time_s, in.timestep_s / K, state,
                          ws, &fired);
      // (an idle evaluation leaves zero counts: idle follows a silent step)
      for (int r = 0; r < nrec; ++r) ws->spike_sum[r] += last_spikes[r];
    }
    std::copy(ws->spike_sum.begin(), ws->spike_sum.end(), last_spikes);
    ws->receptor_outputs_written = true;
  } else {
    touching = Evaluate(model, in, time_s, in.timestep_s / std::max(K, 1), state, ws, &fired);
  }
  if (K > 1) {
    std::copy(in.pad_pose.pos, in.pad_pose.pos + 3, last + kLpPos);
    std::copy(in.pad_pose.mat, in.pad_pose.mat + 9, last + kLpMat);
    last[kLpNormalForce] = in.in_contact ? in.normal_force_n : 0.0;
    last[kLpShearX] = in.in_contact ? in.shear_x_n : 0.0;
    last[kLpShearY] = in.in_contact ? in.shear_y_n : 0.0;
    last[kLpValid] = 1.0;
    if (cfg.substep == SkinConfig::Substep::kReceptors && !quiet) {  // (quiet: zero already)
      double* q = state + lay.last_quantity;
      const int nrec = static_cast<int>(model.receptors().size());
      if (touching && static_cast<int>(ws->quantity.size()) == nrec)
        std::copy(ws->quantity.begin(), ws->quantity.end(), q);
      else
        std::fill(q, q + nrec, 0.0);
    }
  }
  WriteOutputs(model, in, touching, state, *ws, out);
  return fired;
}

}  // namespace mjtouch
