// mjtouch._core, stage 2b without a MuJoCo scene: partial-slip tangential
// contact (Winkler / FASTSIM springs, elastic half-space) on a given
// pressure field, with the step-to-step memory passed in and returned.
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nanobind/stl/optional.h>
#include <nanobind/stl/shared_ptr.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>

#include "contact/tangential.h"
#include "python/convert.h"

namespace mjtouch::py {
namespace {

std::string Num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%g", v);
  return buf;
}

// The state from Python: both previous traction fields (n x n, Pa) or
// neither, and the shift (m).
TangentialState StateOf(const std::optional<F64_2>& shear_x_pa,
                        const std::optional<F64_2>& shear_y_pa, double shift_x_m, double shift_y_m,
                        size_t n) {
  if (shear_x_pa.has_value() != shear_y_pa.has_value())
    Fail("give both shear_x_pa and shear_y_pa (the previous step's), or neither");
  TangentialState s;
  if (shear_x_pa) {
    RequireShape(*shear_x_pa, "shear_x_pa", n, n, "(the pressure field's)");
    RequireShape(*shear_y_pa, "shear_y_pa", n, n, "(the pressure field's)");
    s.shear_x_pa.assign(shear_x_pa->data(), shear_x_pa->data() + n * n);
    s.shear_y_pa.assign(shear_y_pa->data(), shear_y_pa->data() + n * n);
  }
  s.shift_x_m = shift_x_m;
  s.shift_y_m = shift_y_m;
  return s;
}

nb::dict Outputs(TangentialState&& s, TangentialResult&& r, size_t n) {
  nb::dict d;
  d["shear_x_pa"] = ToNumpy(std::move(s.shear_x_pa), {n, n});
  d["shear_y_pa"] = ToNumpy(std::move(s.shear_y_pa), {n, n});
  d["stick"] = ToNumpy(std::move(r.stick), {n, n});
  d["shift_x_m"] = s.shift_x_m;
  d["shift_y_m"] = s.shift_y_m;
  d["stuck_share"] = r.stuck_share;
  d["loaded_cells"] = r.loaded_cells;
  d["stick_cells"] = r.stick_cells;
  d["full_slip"] = r.full_slip;
  d["iterations"] = r.iterations;
  d["projection_steps"] = r.projection_steps;
  d["change"] = r.change;
  return d;
}

std::vector<double> Pressure(const F64_2& pressure_pa, int* n) {
  *n = SquareSide(pressure_pa, "pressure_pa");
  return std::vector<double>(pressure_pa.data(), pressure_pa.data() + static_cast<size_t>(*n) * *n);
}

nb::dict Winkler(const F64_2& pressure_pa, double pitch_m, double mu, double fx_n, double fy_n,
                 double stiffness_pa_per_m, const std::optional<F64_2>& shear_x_pa,
                 const std::optional<F64_2>& shear_y_pa, double shift_x_m, double shift_y_m) {
  int n;
  const std::vector<double> p = Pressure(pressure_pa, &n);
  TangentialState s = StateOf(shear_x_pa, shear_y_pa, shift_x_m, shift_y_m, n);
  TangentialResult r;
  std::string error;
  if (!SolveTangentialWinkler(TaxelGrid{n, pitch_m}, p, mu, fx_n, fy_n, stiffness_pa_per_m, &s, &r,
                              &error))
    Fail(error);
  return Outputs(std::move(s), std::move(r), n);
}

std::shared_ptr<TangentialCompliance> MakeCompliance(int n, double pitch_m, double young_pa,
                                                     double poisson) {
  if (!(young_pa > 0 && std::isfinite(young_pa)))
    Fail("TangentialCompliance: young_pa = " + Num(young_pa) + " must be > 0");
  if (!(poisson > -1 && poisson <= 0.5))
    Fail("TangentialCompliance: poisson = " + Num(poisson) + " must be in (-1, 0.5]");
  if (!(pitch_m > 0 && std::isfinite(pitch_m)))
    Fail("TangentialCompliance: pitch_m = " + Num(pitch_m) + " must be > 0");
  if (n < 1 || n > 4096)
    Fail("TangentialCompliance: n = " + std::to_string(n) + " must be in [1, 4096]");
  return std::make_shared<TangentialCompliance>(young_pa, poisson, pitch_m, n);
}

Out<double> Table(const TangentialCompliance& K, const std::string& component) {
  const int n = K.n();
  const size_t L = 2 * static_cast<size_t>(n) - 1;
  std::vector<double> t(L * L);
  for (int dj = -(n - 1); dj <= n - 1; ++dj)
    for (int di = -(n - 1); di <= n - 1; ++di) {
      const size_t k = static_cast<size_t>(dj + n - 1) * L + (di + n - 1);
      if (component == "xx")
        t[k] = K.Kxx(di, dj);
      else if (component == "yy")
        t[k] = K.Kyy(di, dj);
      else if (component == "xy")
        t[k] = K.Kxy(di, dj);
      else
        Fail("component '" + component + "' is not one of ('xx', 'yy', 'xy')");
    }
  return ToNumpy(std::move(t), {L, L});
}

std::tuple<Out<double>, Out<double>> Displacement(const TangentialCompliance& K,
                                                  const F64_2& shear_x_pa,
                                                  const F64_2& shear_y_pa) {
  const int n = SquareSide(shear_x_pa, "shear_x_pa");
  if (n != K.n())
    Fail("shear_x_pa is " + ShapeOf(shear_x_pa) + ", the compliance's grid " +
         std::to_string(K.n()) + " x " + std::to_string(K.n()));
  RequireShape(shear_y_pa, "shear_y_pa", n, n, "(shear_x_pa's)");
  const auto s = K.SpectraFor(n, n);
  std::vector<double> ux(static_cast<size_t>(n) * n), uy(ux.size());
  TangentialCompliance::Work w;
  K.Apply(*s, shear_x_pa.data(), shear_y_pa.data(), n, n, ux.data(), uy.data(), &w);
  const size_t N = n;
  return {ToNumpy(std::move(ux), {N, N}), ToNumpy(std::move(uy), {N, N})};
}

nb::dict Elastic(const TangentialCompliance& K, const F64_2& pressure_pa, double mu, double fx_n,
                 double fy_n, double tolerance, int max_iterations,
                 const std::optional<F64_2>& shear_x_pa, const std::optional<F64_2>& shear_y_pa,
                 double shift_x_m, double shift_y_m, const std::string& precision) {
  if (precision != "float" && precision != "double")
    Fail("precision '" + precision + "' is not one of ('float', 'double')");
  int n;
  const std::vector<double> p = Pressure(pressure_pa, &n);
  TangentialState s = StateOf(shear_x_pa, shear_y_pa, shift_x_m, shift_y_m, n);
  TangentialResult r;
  std::string error;
  if (!SolveTangentialElastic(
          TaxelGrid{n, K.pitch_m()}, p, mu, fx_n, fy_n, K, tolerance, max_iterations, &s, &r,
          &error, precision == "float" ? ApplyPrecision::kFloat : ApplyPrecision::kDouble))
    Fail(error);
  return Outputs(std::move(s), std::move(r), n);
}

}  // namespace

void BindTangential(nb::module_& m) {
  m.def("tangential_winkler", &Winkler, nb::arg("pressure_pa").noconvert(), nb::arg("pitch_m"),
        nb::arg("mu"), nb::arg("fx_n"), nb::arg("fy_n"), nb::arg("stiffness_pa_per_m"),
        nb::arg("shear_x_pa").noconvert() = nb::none(),
        nb::arg("shear_y_pa").noconvert() = nb::none(), nb::arg("shift_x_m") = 0.0,
        nb::arg("shift_y_m") = 0.0,
        "Partial slip on a Winkler skin (local tangential springs of stiffness\n"
        "stiffness_pa_per_m, Pa/m, clamped at mu p) for the pressure field (n x n, Pa)\n"
        "and the total tangential force (fx_n, fy_n), from the previous step's\n"
        "tractions and shift (none: unloaded). Returns a dict: shear_x_pa, shear_y_pa,\n"
        "stick (n x n uint8), shift_x_m, shift_y_m, stuck_share, loaded_cells,\n"
        "stick_cells, full_slip, iterations, change.");
  m.def("winkler_tangential_stiffness", &WinklerTangentialStiffness,
        nb::arg("normal_stiffness_pa_per_m"), nb::arg("poisson"),
        "Tangential spring stiffness per area matching a Winkler normal one:\n"
        "k_n 2 (1 - nu) / (2 - nu), the half-space's punch stiffness ratio.");
  nb::class_<TangentialCompliance>(m, "TangentialCompliance",
                                   "A homogeneous half-space's tangential surface compliance on\n"
                                   "an n x n taxel grid (Cerruti, integrated over cells).")
      .def(nb::new_(&MakeCompliance), nb::arg("n"), nb::arg("pitch_m"), nb::arg("young_pa"),
           nb::arg("poisson"))
      .def_prop_ro("n", &TangentialCompliance::n)
      .def_prop_ro("pitch_m", &TangentialCompliance::pitch_m)
      .def("table", &Table, nb::arg("component"),
           "(2n-1) x (2n-1) table (m/Pa) of component 'xx', 'yy' or 'xy', indexed\n"
           "[dj + n - 1, di + n - 1] (field cell minus source cell).")
      .def("displacement", &Displacement, nb::arg("shear_x_pa").noconvert(),
           nb::arg("shear_y_pa").noconvert(),
           "Surface tangential displacement (ux, uy in m, n x n) under the tractions.")
      .def("solve", &Elastic, nb::arg("pressure_pa").noconvert(), nb::arg("mu"), nb::arg("fx_n"),
           nb::arg("fy_n"), nb::arg("tolerance") = 1e-4, nb::arg("max_iterations") = 200,
           nb::arg("shear_x_pa").noconvert() = nb::none(),
           nb::arg("shear_y_pa").noconvert() = nb::none(), nb::arg("shift_x_m") = 0.0,
           nb::arg("shift_y_m") = 0.0, nb::arg("precision") = "float",
           "Partial slip on this half-space skin: as tangential_winkler, with the\n"
           "stop at a relative L1 change of the tractions below tolerance. precision:\n"
           "of the operator's FFTs, 'float' (~1e-7 of the displacement) or 'double'.");
}

}  // namespace mjtouch::py
