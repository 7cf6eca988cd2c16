// mjtouch._core: the pure-C++ stages (plugin/core) for Python, without a
// MuJoCo scene. Arrays in and out are numpy arrays of checked rank and dtype;
// a stage's error message reaches Python as ValueError. This file: the module,
// half-space stress, skin configuration, skin surface and receptors.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <time.h>

#include <nanobind/stl/array.h>
#include <nanobind/stl/map.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>

#include "afferents/receptors.h"
#include "pipeline/skin.h"
#include "python/convert.h"
#include "stress/kernel_tables.h"
#include "stress/stress_field.h"
#include "substrate/substrate.h"
#include "surface/surface.h"

namespace mjtouch::py {
namespace {

using Config = std::map<std::string, std::string>;

SurfaceLoad ParseLoad(const std::string& load) {
  if (load == "pressure") return kLoadPressure;
  if (load == "shear_x") return kLoadShearX;
  if (load == "shear_y") return kLoadShearY;
  Fail("load '" + load + "' is not one of ['pressure', 'shear_x', 'shear_y']");
}

void CheckPoisson(double poisson) {
  if (!(poisson > -1 && poisson <= 0.5))
    Fail("poisson = " + std::to_string(poisson) + " is out of range; valid range (-1, 0.5]");
}

// The plugin's attribute parser over a dict of attribute -> value strings;
// unknown keys are refused like the plugin refuses them.
SkinConfig ParseConfig(const Config& config) {
  const auto& keys = SkinAttributeKeys();
  for (const auto& kv : config) {
    bool known = false;
    for (const char* key : keys) known = known || kv.first == key;
    if (!known) Fail("mjtouch.skin: unknown attribute `" + kv.first + "`");
  }
  SkinConfig cfg;
  std::string error;
  const bool ok = ParseSkinConfig(
      [&](const char* key) {
        const auto it = config.find(key);
        return it == config.end() ? std::string() : it->second;
      },
      &cfg, &error);
  if (!ok) Fail(error);
  return cfg;
}

Out<double> HalfspaceStress(const F64_2& points_m, const std::string& load, double poisson,
                            double cell_m) {
  const SurfaceLoad l = ParseLoad(load);
  CheckPoisson(poisson);
  if (!(cell_m >= 0)) Fail("cell_m = " + std::to_string(cell_m) + " must be >= 0");
  if (points_m.shape(1) != 3)
    Fail("points_m must have shape (npoint, 3), got shape " + ShapeOf(points_m));
  const size_t np = points_m.shape(0);
  const double* p = points_m.data();
  for (size_t k = 0; k < np; ++k)
    if (!(p[3 * k + 2] > 0)) Fail("z_m must be > 0 (points strictly below the surface)");
  const HalfSpace hs(poisson);
  std::vector<double> out(6 * np);
  for (size_t k = 0; k < np; ++k) {
    const double x = p[3 * k], y = p[3 * k + 1], z = p[3 * k + 2];
    Stress6 s;
    if (cell_m > 0) {
      s = hs.CellStress(l, x, y, z, cell_m);
    } else {
      s = l == kLoadPressure ? hs.Boussinesq(x, y, z)
          : l == kLoadShearX ? hs.CerrutiX(x, y, z)
                             : hs.CerrutiY(x, y, z);
    }
    for (int c = 0; c < 6; ++c) out[6 * k + c] = s[c];
  }
  return ToNumpy(std::move(out), {np, 6});
}

Out<double> FieldStress(const F32_2& pressure_pa, double pitch_m, double depth_m,
                        const I32_2& receptors_ij, std::optional<F32_2> shear_x_pa,
                        std::optional<F32_2> shear_y_pa, double poisson) {
  const int n = SquareSide(pressure_pa, "pressure_pa");
  CheckPoisson(poisson);
  if (!(pitch_m > 0) || !(depth_m > 0)) Fail("pitch_m and depth_m must be > 0");
  if (receptors_ij.shape(1) != 2)
    Fail("receptors_ij must have shape (nrec, 2), got shape " + ShapeOf(receptors_ij));
  const size_t nrec = receptors_ij.shape(0);
  const int* ij = receptors_ij.data();
  for (size_t r = 0; r < 2 * nrec; ++r)
    if (ij[r] < 0 || ij[r] >= n)
      Fail("receptor cell indices must be in [0, " + std::to_string(n - 1) + "]");
  const auto [sx, sy] = ShearFields(shear_x_pa, shear_y_pa, n);
  const HalfSpace hs(poisson);
  std::array<bool, kNumStress> all;
  all.fill(true);
  const auto kt = BuildKernelTables(hs, n, pitch_m, {depth_m}, all);
  ActiveRuns runs;
  for (int j = 0; j < n; ++j) {
    runs.row.push_back(j);
    runs.begin.push_back(0);
    runs.end.push_back(n);
  }
  std::vector<double> out(6 * nrec);
  for (size_t r = 0; r < nrec; ++r) {
    Stress6 s;
    StressAtReceptor(*kt, 0, ij[2 * r], ij[2 * r + 1], runs, pressure_pa.data(), sx, sy, all, &s);
    for (int c = 0; c < 6; ++c) out[6 * r + c] = s[c];
  }
  return ToNumpy(std::move(out), {nrec, 6});
}

Out<double> SkinSurfaceOf(std::array<double, 3> semi_axes_m, const Config& config) {
  SkinConfig cfg = ParseConfig(config);
  for (int k = 0; k < 3; ++k) cfg.pad.semi_axes_m[k] = semi_axes_m[k];
  std::string error;
  if (!FinalizeSkinConfig(&cfg, &error)) Fail(error);
  const size_t n = cfg.grid.n;
  return ToNumpy(SkinSurface(cfg.grid, cfg.pad, cfg.ridges), {n, n});
}

Out<double> HfieldBoxMean(const F32_2& samples, double half_x_m, double half_y_m,
                          double elevation_m, const F64_2& boxes) {
  if (samples.shape(0) < 2 || samples.shape(1) < 2)
    Fail("samples must be (nrow >= 2, ncol >= 2), got shape " + ShapeOf(samples));
  if (boxes.shape(1) != 4)
    Fail("boxes must have shape (nbox, 4): x0, x1, y0, y1; got shape " + ShapeOf(boxes));
  CounterSurface s;
  s.type = CounterSurface::Type::kHeightField;
  s.nrow = static_cast<int>(samples.shape(0));
  s.ncol = static_cast<int>(samples.shape(1));
  s.samples = samples.data();
  s.half_x_m = half_x_m;
  s.half_y_m = half_y_m;
  s.elevation_m = elevation_m;
  const size_t nb = boxes.shape(0);
  const double* b = boxes.data();
  std::vector<double> out(nb);
  for (size_t k = 0; k < nb; ++k)
    out[k] = HeightFieldBoxMean(s, b[4 * k], b[4 * k + 1], b[4 * k + 2], b[4 * k + 3]);
  return ToNumpy(std::move(out), {nb});
}

std::tuple<Out<double>, Out<double>, Out<double>> ReceptorRun(const std::string& cls,
                                                              const F64_1& quantity_pa, double dt_s,
                                                              const Config& config,
                                                              uint64_t stream) {
  const SkinConfig cfg = ParseConfig(config);
  int c = -1;
  for (int k = 0; k < kNumClasses; ++k)
    if (cls == ClassName(static_cast<ReceptorClass>(k))) c = k;
  if (c < 0) Fail("receptor class '" + cls + "' is not one of ['PC', 'RA', 'SA1']");
  if (!(dt_s > 0)) Fail("dt_s = " + std::to_string(dt_s) + " must be > 0");
  const size_t nsteps = quantity_pa.shape(0);
  const double* q = quantity_pa.data();
  if (nsteps == 0) Fail("quantity_pa must be a non-empty finite array");
  for (size_t k = 0; k < nsteps; ++k)
    if (!std::isfinite(q[k])) Fail("quantity_pa must be a non-empty finite array");
  // As in the plugin: primed at rest with the first value (no step, no
  // output), then one step of dt per further value; stream = the receptor's
  // index in a plugin instance (its noise sequence).
  const auto rc = static_cast<ReceptorClass>(c);
  const ReceptorStepper stepper(cfg.receptor, dt_s);
  double state[kReceptorStateSize] = {0};
  PrimeReceptor(cfg.receptor, rc, q[0], stream, state);
  std::vector<double> spikes(nsteps, 0.0), voltage(nsteps, 0.0), rate(nsteps, 0.0);
  for (size_t k = 1; k < nsteps; ++k) {
    double v = 0;
    spikes[k] = stepper.Advance(rc, q[k], stream, state, &v);
    voltage[k] = v;
    rate[k] = ReceptorRate(state);
  }
  return {ToNumpy(std::move(spikes), {nsteps}), ToNumpy(std::move(voltage), {nsteps}),
          ToNumpy(std::move(rate), {nsteps})};
}

// Stages 1-2 (ComputeTraction) over a recorded sequence of steps, from a
// fresh state: the per-step CPU time of the whole of stages 1-2 and of its
// rendering (TractionRunOptions::render_time_s), and each step's pressure. `reference`: the general
// (reference) code paths. surfaces: rows as render_gap's; height-field rows read `hfield`.
std::tuple<Out<double>, Out<double>, Out<double>, Out<double>> TractionSteps(
    std::array<double, 3> semi_axes_m, const Config& config, const F64_2& pad_pos,
    const F64_2& pad_mat, const F64_2& forces_n, const F64_2& surfaces, const F32_2& hfield,
    bool reference, bool fields) {
  SkinConfig cfg = ParseConfig(config);
  for (int k = 0; k < 3; ++k) cfg.pad.semi_axes_m[k] = semi_axes_m[k];
  std::string error;
  if (!FinalizeSkinConfig(&cfg, &error)) Fail(error);
  const auto model = SkinModel::Build(cfg, &error);
  if (!model) Fail(error);
  const size_t T = pad_pos.shape(0);
  if (pad_pos.shape(1) != 3 || pad_mat.shape(0) != T || pad_mat.shape(1) != 9 ||
      forces_n.shape(0) != T || forces_n.shape(1) != 3)
    Fail(
        "pad_pos (T, 3), pad_mat (T, 9) and forces_n (T, 3: normal, shear x, shear y) must "
        "agree, got shapes " +
        ShapeOf(pad_pos) + ", " + ShapeOf(pad_mat) + ", " + ShapeOf(forces_n));
  StepInput in;
  std::vector<std::vector<double>> prefixes;
  DecodeSurfaces(surfaces, hfield, &in.surfaces, &prefixes);
  const size_t N = cfg.grid.Size();
  std::vector<double> state(model->state_layout().size, 0.0);
  ResetState(*model, state.data());
  Workspace ws;
  TractionRunOptions run;
  run.reference_paths = reference;
  // fields: per step the 7 planes pressure, shear x, shear y (Pa), their float
  // copies, and the active cells (runs) as 1.
  const size_t planes = fields ? 7 : 1;
  std::vector<double> render_s(T), total_s(T), approach(T), pressure(T * planes * N, 0.0);
  // Thread CPU time: on a shared machine wall time also counts the time the
  // thread waits for a core.
  auto cpu_s = [] {
    timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
  };
  TractionNeeds needs;  // as Step states them; the rest is materialized below
  needs.pressure_pa = cfg.outputs[kOutPressure];
  for (size_t t = 0; t < T; ++t) {
    for (int c = 0; c < 3; ++c) in.pad_pose.pos[c] = pad_pos.data()[3 * t + c];
    for (int c = 0; c < 9; ++c) in.pad_pose.mat[c] = pad_mat.data()[9 * t + c];
    in.normal_force_n = forces_n.data()[3 * t];
    in.shear_x_n = forces_n.data()[3 * t + 1];
    in.shear_y_n = forces_n.data()[3 * t + 2];
    in.in_contact = in.normal_force_n > 0;
    double render = 0.0;
    run.render_time_s = &render;
    const double t0 = cpu_s();
    const bool touching = ComputeTraction(*model, in, needs, state.data(), &ws, true, run);
    total_s[t] = cpu_s() - t0;
    render_s[t] = render;
    approach[t] = touching ? ws.traction.approach_m : std::nan("");
    if (touching) {
      MaterializeTraction(cfg.grid, true, fields, &ws.traction);  // (lazy arrays)
      const TractionField& tf = ws.traction;
      double* out = pressure.data() + t * planes * N;
      std::copy(tf.pressure_pa.begin(), tf.pressure_pa.end(), out);
      if (fields) {
        std::copy(tf.shear_x_pa.begin(), tf.shear_x_pa.end(), out + N);
        std::copy(tf.shear_y_pa.begin(), tf.shear_y_pa.end(), out + 2 * N);
        std::copy(tf.pressure.begin(), tf.pressure.end(), out + 3 * N);
        std::copy(tf.shear_x.begin(), tf.shear_x.end(), out + 4 * N);
        std::copy(tf.shear_y.begin(), tf.shear_y.end(), out + 5 * N);
        for (size_t r = 0; r < tf.runs.row.size(); ++r)
          for (int i = tf.runs.begin[r]; i < tf.runs.end[r]; ++i)
            out[6 * N + static_cast<size_t>(tf.runs.row[r]) * cfg.grid.n + i] = 1.0;
      }
    }
  }
  const size_t n = cfg.grid.n;
  return {ToNumpy(std::move(render_s), {T}), ToNumpy(std::move(total_s), {T}),
          ToNumpy(std::move(approach), {T}),
          fields ? ToNumpy(std::move(pressure), {T, planes, n, n})
                 : ToNumpy(std::move(pressure), {T, n, n})};
}

}  // namespace

void BindStages(nb::module_& m) {
  m.def("traction_steps", &TractionSteps, nb::arg("semi_axes_m"), nb::arg("config"),
        nb::arg("pad_pos").noconvert(), nb::arg("pad_mat").noconvert(),
        nb::arg("forces_n").noconvert(), nb::arg("surfaces").noconvert(),
        nb::arg("hfield").noconvert(), nb::arg("reference") = false, nb::arg("fields") = false,
        "Stages 1-2 (render + pressure model + shear) over T recorded steps from a\n"
        "fresh state, as the plugin runs them: pad pose per step (pad_pos T x 3,\n"
        "pad_mat T x 9 row-major), forces_n (T x 3: normal, shear x, shear y, N, pad\n"
        "frame), surfaces as render_gap's. reference=True: the general code paths.\n"
        "Returns per-step CPU seconds (render alone, whole of stages 1-2), the approach\n"
        "(m, NaN: no contact) and the pressure (T x n x n, Pa); fields=True: T x 7 x n x n,\n"
        "the planes pressure, shear x, shear y (Pa), their float32 copies, and the\n"
        "active cells (1) the stress stage sums over.");
  m.def("halfspace_stress", &HalfspaceStress, nb::arg("points_m").noconvert(),
        nb::arg("load") = "pressure", nb::arg("poisson") = 0.5, nb::arg("cell_m") = 0.0,
        "Stress (npoint x 6, Pa, Voigt xx yy zz xy xz yz; z into the solid, tension\n"
        "positive) in a homogeneous half-space at points_m (npoint x 3: x, y, z > 0)\n"
        "for a 1 N point force (cell_m = 0) or a uniform 1 Pa traction on a square\n"
        "cell of side cell_m at the origin. load: 'pressure', 'shear_x', 'shear_y'.");
  m.def("field_stress", &FieldStress, nb::arg("pressure_pa").noconvert(), nb::arg("pitch_m"),
        nb::arg("depth_m"), nb::arg("receptors_ij").noconvert(),
        nb::arg("shear_x_pa").noconvert().none() = nb::none(),
        nb::arg("shear_y_pa").noconvert().none() = nb::none(), nb::arg("poisson") = 0.5,
        "Stress (nrec x 6, Pa) at depth_m under the taxel cells receptors_ij (nrec x 2\n"
        "int32: i along x, j along y) from float32 traction fields on an n x n grid\n"
        "(indexed [j, i]) of square cells of side pitch_m; homogeneous half-space.\n"
        "Shear fields: both or neither.");
  m.def(
      "check_config", [](const Config& config) { ParseConfig(config); }, nb::arg("config"),
      "Validate plugin attributes (dict attribute -> value string) as the plugin\n"
      "does at model compile time; ValueError with the plugin's message.");
  m.def("skin_surface", &SkinSurfaceOf, nb::arg("semi_axes_m"), nb::arg("config"),
        "Cell-averaged skin height (pad frame z, m; +inf outside the pad) on the\n"
        "nx x nx taxel grid, indexed [j, i], for a pad with semi-axes semi_axes_m and\n"
        "the attributes in config (dict attribute -> value string).");
  m.def("hfield_box_mean", &HfieldBoxMean, nb::arg("samples").noconvert(), nb::arg("half_x_m"),
        nb::arg("half_y_m"), nb::arg("elevation_m"), nb::arg("boxes").noconvert(),
        "Exact mean of MuJoCo's bilinear height field (samples: nrow x ncol float32\n"
        "in [0, 1]) over each box (nbox x 4: x0, x1, y0, y1, m); returns (nbox,).");
  m.def("receptor_run", &ReceptorRun, nb::arg("cls"), nb::arg("quantity_pa").noconvert(),
        nb::arg("dt_s"), nb::arg("config"), nb::arg("stream") = 0,
        "Drive one receptor of class cls ('SA1', 'RA', 'PC') with the quantity trace\n"
        "(one value per step of dt_s) as the plugin does; afferent parameters from\n"
        "config (dict attribute -> value string), stream = the receptor's noise\n"
        "sequence. Returns (spikes per step, membrane over threshold, rate Hz).");
}

NB_MODULE(_core, m) {
  m.doc() =
      "mjtouch's C++ stages (plugin/core) called directly, without a MuJoCo scene;\n"
      "wrapped by mjtouch.core. Errors from the stages raise ValueError.";
  BindStages(m);
  BindContact(m);
  BindTangential(m);
  BindLayered(m);
  BindInstance(m);
  BindAttributes(m);
}

}  // namespace mjtouch::py
