// The sensordata blocks (OutputBlock order) from the last evaluation.
#include <algorithm>

#include "pipeline/step.h"

namespace mjtouch {

double IndentationLimit(const SkinConfig& cfg) {
  if (cfg.layered && cfg.base.rigid) {
    double depth = 0.0;
    for (const auto& l : cfg.layers) depth += l.thickness_m;
    return depth;
  }
  return cfg.pad.semi_axes_m[2];
}

bool IndentationBeyondSkin(const SkinModel& model, const double* state) {
  return state[kStContactValid] > 0.0 && state[kStContactDepth] > IndentationLimit(model.config());
}

void WriteOutputs(const SkinModel& model, const StepInput& in, bool touching, const double* state,
                  const Workspace& ws, double* out) {
  const SkinConfig& cfg = model.config();
  const int nrec = static_cast<int>(model.receptors().size());
  const StateLayout& layout = model.state_layout();
  const double* last_spikes = ws.spikes.data();
  const double* last_voltage =
      layout.voltage_in_state ? state + layout.last_voltage : ws.voltage.data();
  const TractionField& tf = ws.traction;
  double* cursor = out;
  if (cfg.outputs[kOutSpikes]) {
    std::copy(last_spikes, last_spikes + nrec, cursor);
    cursor += nrec;
  }
  if (cfg.outputs[kOutStress]) {
    if (touching)
      std::copy(ws.quantity.begin(), ws.quantity.end(), cursor);
    else
      std::fill(cursor, cursor + nrec, 0.0);
    cursor += nrec;
  }
  if (cfg.outputs[kOutVoltage]) {
    std::copy(last_voltage, last_voltage + nrec, cursor);
    cursor += nrec;
  }
  if (cfg.outputs[kOutForce]) {
    cursor[0] = touching ? in.normal_force_n : 0.0;
    cursor[1] = touching ? in.shear_x_n : 0.0;
    cursor[2] = touching ? in.shear_y_n : 0.0;
    cursor[3] = touching ? state[kStContactDepth] : 0.0;  // indentation depth
    cursor[4] = touching && IndentationBeyondSkin(model, state) ? 1.0 : 0.0;
    cursor += kForceBlockSize;
  }
  if (cfg.outputs[kOutPressure]) {
    const size_t N = cfg.grid.Size();
    if (touching)
      std::copy(tf.pressure_pa.begin(), tf.pressure_pa.begin() + N, cursor);
    else
      std::fill(cursor, cursor + N, 0.0);
    cursor += N;
  }
  if (cfg.outputs[kOutRate]) {
    for (int r = 0; r < nrec; ++r) cursor[r] = ReceptorRate(layout.receptor(state, r));
    cursor += nrec;
  }
  if (cfg.outputs[kOutCoverage]) {
    cursor[0] = in.contact_normal_n > 0.0 ? in.patch_normal_n / in.contact_normal_n : 1.0;
    cursor[1] = in.contact_normal_n;
    cursor += kCoverageBlockSize;
  }
  if (cfg.outputs[kOutStick]) {  // 1 stick, 0 slip, -1 unloaded (or no contact)
    const size_t N = cfg.grid.Size();
    const auto& stick = ws.tangential_result.stick;
    for (size_t k = 0; k < N; ++k)
      cursor[k] = touching && tf.pressure_pa[k] > 0.0 ? (stick[k] ? 1.0 : 0.0) : -1.0;
    cursor += N;
  }
  if (cfg.outputs[kOutSlip]) {  // all zero without contact
    cursor[0] = touching ? ws.tangential_result.stuck_share : 0.0;
    cursor[1] = touching ? in.friction_mu : 0.0;
    cursor[2] = touching ? ws.tangential.shift_x_m : 0.0;
    cursor[3] = touching ? ws.tangential.shift_y_m : 0.0;
    cursor += kSlipBlockSize;
  }
  if (cfg.outputs[kOutShear]) {  // x then y, Pa
    const size_t N = cfg.grid.Size();
    if (touching) {
      std::copy(tf.shear_x_pa.begin(), tf.shear_x_pa.begin() + N, cursor);
      std::copy(tf.shear_y_pa.begin(), tf.shear_y_pa.begin() + N, cursor + N);
    } else {
      std::fill(cursor, cursor + 2 * N, 0.0);
    }
    cursor += 2 * N;
  }
}

}  // namespace mjtouch
