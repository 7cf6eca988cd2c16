// mjtouch._core, stages 1-2 without a MuJoCo scene: surface rendering (gap
// and coverage against counter-surfaces, pad and ridge surfaces) and contact
// pressure (contacts splat, Winkler, elastic boundary-element solve, shear).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include <nanobind/stl/array.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>

#include "common/fft.h"
#include "contact/compliance.h"
#include "contact/contact_solver.h"
#include "contact/pressure.h"
#include "python/convert.h"
#include "substrate/substrate.h"
#include "surface/surface.h"

namespace mjtouch::py {
namespace {

constexpr const char* kNoLoad = "no cell can carry the load (all gaps infinite or force <= 0)";

std::string Num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%g", v);
  return buf;
}

void RequirePositive(double v, const char* what, const char* name) {
  if (!(v > 0))
    Fail(std::string(what) + ": invalid arguments: " + name + " = " + Num(v) + " must be > 0");
}

RidgeProfile ParseProfile(const std::string& profile) {
  if (profile == "sine") return RidgeProfile::kSine;
  if (profile == "triangle") return RidgeProfile::kTriangle;
  if (profile == "square") return RidgeProfile::kSquare;
  Fail("profile '" + profile + "' is not one of ('sine', 'triangle', 'square')");
}

std::tuple<Out<float>, double> Winkler(const F64_2& gap_m, const F64_2& coverage, double pitch_m,
                                       double stiffness_pa_per_m, double force_n,
                                       double approach_guess_m, bool reference) {
  const int n = SquareSide(gap_m, "gap_m");
  RequireShape(coverage, "coverage", n, n, "(gap_m's)");
  RequirePositive(pitch_m, "winkler_pressure", "pitch_m");
  RequirePositive(stiffness_pa_per_m, "winkler_pressure", "stiffness_pa_per_m");
  const TaxelGrid grid{n, pitch_m};
  const std::vector<double> g(gap_m.data(), gap_m.data() + grid.Size());
  const std::vector<double> c(coverage.data(), coverage.data() + grid.Size());
  TractionField tf;
  const bool ok = (reference ? WinklerPressureReference : WinklerPressure)(
      grid, g, c, CellBox::All(grid), stiffness_pa_per_m, force_n, approach_guess_m, &tf);
  if (!ok) Fail(kNoLoad);
  FinishTraction(grid, false, &tf);
  const size_t N = n;
  return {ToNumpy(std::move(tf.pressure), {N, N}), tf.approach_m};
}

Out<float> HalfSpaceComplianceTable(int n, double pitch_m, double young_pa, double poisson) {
  if (!(young_pa > 0 && poisson > -1 && poisson <= 0.5 && pitch_m > 0 && n >= 1))
    Fail("need young_pa > 0, poisson in (-1, 0.5], pitch_m > 0, n >= 1");
  std::vector<float> t;
  HalfSpaceSurfaceComplianceTable(young_pa, poisson, pitch_m, n, &t);
  const size_t L = 2 * static_cast<size_t>(n) - 1;
  return ToNumpy(std::move(t), {L, L});
}

// (pressure Pa, stats) of one solve; the stats as the Python dict.
std::tuple<Out<double>, nb::dict> Solved(const mjtouch::SurfaceCompliance& K, const F64_2& gap_m,
                                         const F64_2& initial_pa, int nx, int ny, double force_n,
                                         double tolerance, int max_iterations,
                                         const std::string& method, const std::string& precision) {
  if (precision != "double" && precision != "float")
    Fail("elastic_pressure: invalid arguments: precision = '" + precision +
         "' is not one of 'double' (the reference), 'float' (the plugin's default FFTs)");
  if (method != "pcg" && method != "pk")
    Fail("elastic_pressure: invalid arguments: method = '" + method +
         "' is not one of 'pcg' (preconditioned CG), 'pk' (Polonsky & Keer)");
  const size_t N = static_cast<size_t>(nx) * ny;
  const std::vector<double> g(gap_m.data(), gap_m.data() + N);
  std::vector<double> p(initial_pa.data(), initial_pa.data() + N);
  ElasticWork work;
  ElasticSolveStats st;
  ElasticSolveOptions options;
  options.tolerance = tolerance;
  options.max_iterations = max_iterations;
  options.method = method == "pk" ? ElasticMethod::kPolonskyKeer : ElasticMethod::kPreconditioned;
  options.precision = precision == "float" ? ApplyPrecision::kFloat : ApplyPrecision::kDouble;
  const bool ok =
      SolveElasticContact(K, g, CellBox{0, 0, nx, ny}, force_n, options, &p, &work, &st);
  if (!ok) Fail(kNoLoad);
  nb::dict info;
  info["iterations"] = st.iterations;
  info["converged"] = static_cast<bool>(st.converged);
  info["change"] = st.change;
  info["approach_m"] = st.approach_m;
  info["contact_cells"] = st.contact_cells;
  info["max_contact_gap_m"] = st.max_contact_gap_m;
  info["fft_applies"] = st.applies;
  return {ToNumpy(std::move(p), {static_cast<size_t>(ny), static_cast<size_t>(nx)}), info};
}

void CheckSolve(const F64_2& gap_m, const F64_2& initial_pa, double pitch_m, double tolerance,
                int max_iterations) {
  RequireShape(initial_pa, "initial_pa", gap_m.shape(0), gap_m.shape(1), "(gap_m's)");
  if (gap_m.size() == 0) Fail("gap_m must not be empty");
  RequirePositive(pitch_m, "elastic_pressure", "pitch_m");
  RequirePositive(tolerance, "elastic_pressure", "tolerance");
  if (max_iterations < 1) Fail("elastic_pressure: invalid arguments: max_iterations must be >= 1");
}

std::tuple<Out<double>, nb::dict> ElasticHalfSpace(const F64_2& gap_m, const F64_2& initial_pa,
                                                   double pitch_m, double force_n, double young_pa,
                                                   double poisson, bool periodic, double tolerance,
                                                   int max_iterations, const std::string& method,
                                                   const std::string& precision) {
  CheckSolve(gap_m, initial_pa, pitch_m, tolerance, max_iterations);
  RequirePositive(young_pa, "elastic_pressure", "young_pa");
  if (!(poisson > -1 && poisson <= 0.5))
    Fail("elastic_pressure: invalid arguments: poisson = " + Num(poisson) +
         " is out of range; valid range (-1, 0.5]");
  const int ny = static_cast<int>(gap_m.shape(0)), nx = static_cast<int>(gap_m.shape(1));
  if (periodic) {
    if (!IsFftSize(nx) || !IsFftSize(ny))
      Fail("periodic grid " + ShapeOf(gap_m) + ": sizes must be products of 2, 3 and 5");
    const double e_star = young_pa / (1.0 - poisson * poisson);
    const mjtouch::SurfaceCompliance K(nx, ny, pitch_m,
                                       [&](double k) { return 2.0 / (e_star * k); });
    return Solved(K, gap_m, initial_pa, nx, ny, force_n, tolerance, max_iterations, method,
                  precision);
  }
  if (nx != ny) Fail("non-periodic grids must be square, got shape " + ShapeOf(gap_m));
  return Solved(*HalfSpaceCompliance(young_pa, poisson, pitch_m, nx), gap_m, initial_pa, nx, nx,
                force_n, tolerance, max_iterations, method, precision);
}

std::tuple<Out<double>, nb::dict> ElasticTable(const F64_2& gap_m, const F64_2& initial_pa,
                                               double pitch_m, double force_n, const F32_2& table,
                                               double tolerance, int max_iterations,
                                               const std::string& method,
                                               const std::string& precision) {
  CheckSolve(gap_m, initial_pa, pitch_m, tolerance, max_iterations);
  const int n = SquareSide(gap_m, "gap_m");
  const size_t L = 2 * static_cast<size_t>(n) - 1;
  bool finite = true;
  for (size_t k = 0; k < table.size(); ++k) finite = finite && std::isfinite(table.data()[k]);
  if (table.shape(0) != L || table.shape(1) != L || !finite)
    Fail("compliance_m_per_pa must be a finite (" + std::to_string(L) + ", " + std::to_string(L) +
         ") table for a " + std::to_string(n) + " x " + std::to_string(n) + " grid, got shape " +
         ShapeOf(table));
  const mjtouch::SurfaceCompliance K(n, pitch_m,
                                     std::vector<float>(table.data(), table.data() + L * L));
  return Solved(K, gap_m, initial_pa, n, n, force_n, tolerance, max_iterations, method, precision);
}

// surfaces: one row of 20 per counter-surface: type (CounterSurface::Type),
// pos[3], mat[9] (row-major, local -> world), size[3], half_x, half_y,
// elevation, max_height; height-field rows read `hfield`.
std::tuple<Out<double>, Out<double>> Render(const F64_2& skin_z_m, double pitch_m,
                                            const F64_2& surfaces, std::array<double, 3> pad_pos,
                                            std::array<double, 9> pad_mat, const F32_2& hfield,
                                            bool area_average, bool fast_paths) {
  const int n = SquareSide(skin_z_m, "skin_z_m");
  RequirePositive(pitch_m, "render_gap", "pitch_m");
  const TaxelGrid grid{n, pitch_m};
  Pose pad;
  for (int k = 0; k < 3; ++k) pad.pos[k] = pad_pos[k];
  for (int k = 0; k < 9; ++k) pad.mat[k] = pad_mat[k];
  std::vector<CounterSurface> list;
  std::vector<std::vector<double>> prefixes;
  DecodeSurfaces(surfaces, hfield, &list, &prefixes);
  const std::vector<double> z(skin_z_m.data(), skin_z_m.data() + grid.Size());
  std::vector<double> g, c;
  RenderRequest request{grid, z, pad, list};
  request.area_average = area_average;
  request.fast_paths = fast_paths;
  RenderGap(request, RenderOutput{&g, &c});
  const size_t N = n;
  return {ToNumpy(std::move(g), {N, N}), ToNumpy(std::move(c), {N, N})};
}

Out<double> RidgeMean(const F64_1& s_m, const std::string& profile, double pitch_m, double height_m,
                      double angle_rad, double cell_m) {
  Ridges r;
  r.profile = ParseProfile(profile);
  r.pitch_m = pitch_m;
  r.height_m = height_m;
  r.angle_rad = angle_rad;
  const size_t ns = s_m.shape(0);
  std::vector<double> out(ns);
  for (size_t k = 0; k < ns; ++k)
    out[k] = cell_m > 0 ? RidgeCellMean(r, s_m.data()[k], cell_m) : RidgeRelief(r, s_m.data()[k]);
  return ToNumpy(std::move(out), {ns});
}

Out<double> PadSurface(const std::string& shape, std::array<double, 3> half_extents_m, int n,
                       double pitch_m, const std::string& profile, double ridge_pitch_m,
                       double ridge_height_m, double ridge_angle_rad) {
  static const char* kShapes[] = {"sphere", "ellipsoid", "capsule", "box"};
  int shape_index = -1;
  for (int k = 0; k < 4; ++k)
    if (shape == kShapes[k]) shape_index = k;
  if (shape_index < 0)
    Fail("shape '" + shape + "' is not one of ('sphere', 'ellipsoid', 'capsule', 'box')");
  const RidgeProfile rp = ParseProfile(profile);
  if (n < 1 || !(pitch_m > 0) ||
      !(half_extents_m[0] > 0 && half_extents_m[1] > 0 && half_extents_m[2] > 0))
    Fail("pad_surface: need n >= 1, pitch_m > 0 and positive half extents");
  const TaxelGrid grid{n, pitch_m};
  PadGeometry pad;
  pad.shape = static_cast<PadShape>(shape_index);
  for (int k = 0; k < 3; ++k) pad.semi_axes_m[k] = half_extents_m[k];
  Ridges r;
  r.enabled = ridge_height_m > 0;
  r.profile = rp;
  r.pitch_m = ridge_pitch_m;
  r.height_m = ridge_height_m;
  r.angle_rad = ridge_angle_rad;
  const size_t N = n;
  return ToNumpy(SkinSurface(grid, pad, r), {N, N});
}

std::tuple<Out<double>, Out<double>> SlipShear(const F64_2& pressure_pa, double pitch_m,
                                               double normal_n, double fx_n, double fy_n) {
  const int n = SquareSide(pressure_pa, "pressure_pa");
  RequirePositive(pitch_m, "slip_shear", "pitch_m");
  const TaxelGrid grid{n, pitch_m};
  TractionField tf;
  ClearTraction(grid, &tf);
  tf.pressure_pa.assign(pressure_pa.data(), pressure_pa.data() + grid.Size());
  tf.box = CellBox::All(grid);
  UniformSlipShear(grid, normal_n, fx_n, fy_n, &tf);
  const size_t N = n;
  return {ToNumpy(std::move(tf.shear_x_pa), {N, N}), ToNumpy(std::move(tf.shear_y_pa), {N, N})};
}

std::tuple<Out<double>, Out<double>, Out<double>> Splat(const F64_2& contacts, int n,
                                                        double pitch_m) {
  if (n < 2 || !(pitch_m > 0)) Fail("splat_contacts: need n >= 2 and pitch_m > 0");
  if (contacts.shape(1) != 5)
    Fail("contacts must have shape (ncontact, 5): x, y, fx, fy, fz; got shape " +
         ShapeOf(contacts));
  const TaxelGrid grid{n, pitch_m};
  std::vector<ContactPoint> cps(contacts.shape(0));
  for (size_t k = 0; k < cps.size(); ++k) {
    const double* c = contacts.data() + 5 * k;
    cps[k].x_m = c[0];
    cps[k].y_m = c[1];
    for (int d = 0; d < 3; ++d) cps[k].force_n[d] = c[2 + d];
  }
  TractionField tf;
  SplatContacts(grid, cps, &tf);  // false (no normal force): an all-zero field, as before
  const size_t N = n;
  return {ToNumpy(std::move(tf.pressure_pa), {N, N}), ToNumpy(std::move(tf.shear_x_pa), {N, N}),
          ToNumpy(std::move(tf.shear_y_pa), {N, N})};
}

}  // namespace

void DecodeSurfaces(const F64_2& surfaces, const F32_2& hfield, std::vector<CounterSurface>* out,
                    std::vector<std::vector<double>>* out_prefixes) {
  if (surfaces.shape(1) != 20)
    Fail("surfaces must have shape (nsurface, 20), got shape " + ShapeOf(surfaces));
  const size_t ns = surfaces.shape(0);
  std::vector<CounterSurface>& list = *out;
  list.assign(ns, CounterSurface{});
  std::vector<std::vector<double>>& prefixes = *out_prefixes;
  prefixes.assign(ns, {});
  constexpr int kLastType = static_cast<int>(CounterSurface::Type::kCylinder);
  for (size_t k = 0; k < ns; ++k) {
    const double* d = surfaces.data() + 20 * k;
    CounterSurface& s = list[k];
    if (!(d[0] >= 0 && d[0] <= kLastType) || d[0] != std::floor(d[0]))
      Fail("surface " + std::to_string(k) + ": type code " + Num(d[0]) + " is not in [0, " +
           std::to_string(kLastType) + "]");
    s.type = static_cast<CounterSurface::Type>(static_cast<int>(d[0]));
    for (int c = 0; c < 3; ++c) s.pose.pos[c] = d[1 + c];
    for (int c = 0; c < 9; ++c) s.pose.mat[c] = d[4 + c];
    for (int c = 0; c < 3; ++c) s.size_m[c] = d[13 + c];
    s.half_x_m = d[16];
    s.half_y_m = d[17];
    s.elevation_m = d[18];
    s.max_height_m = d[19];
    if (s.type == CounterSurface::Type::kHeightField) {
      if (hfield.shape(0) < 2 || hfield.shape(1) < 2)
        Fail("surface " + std::to_string(k) +
             ": a height field needs hfield with at least 2 x 2 "
             "samples, got shape " +
             ShapeOf(hfield));
      s.nrow = static_cast<int>(hfield.shape(0));
      s.ncol = static_cast<int>(hfield.shape(1));
      s.samples = hfield.data();
      prefixes[k] = HeightFieldRowPrefix(s.nrow, s.ncol, s.samples);
      s.row_prefix = prefixes[k].data();
      s.rows_identical = true;  // as the plugin detects 1D textures
      for (int r = 1; r < s.nrow && s.rows_identical; ++r)
        s.rows_identical = std::equal(s.samples, s.samples + s.ncol, s.samples + r * s.ncol);
    }
  }
}

void BindContact(nb::module_& m) {
  m.def("winkler_pressure", &Winkler, nb::arg("gap_m").noconvert(), nb::arg("coverage").noconvert(),
        nb::arg("pitch_m"), nb::arg("stiffness_pa_per_m"), nb::arg("force_n"),
        nb::arg("approach_guess_m") = std::numeric_limits<double>::quiet_NaN(),
        nb::arg("reference") = false,
        "Winkler pressure (n x n float32, Pa) whose integral equals force_n on the\n"
        "gap field gap_m (n x n, m) with cell coverage, and the solved approach (m).\n"
        "approach_guess_m warm-starts the solve (NaN: none); reference=True: the\n"
        "unoptimised solve (bit-identical).");
  m.def("surface_compliance", &HalfSpaceComplianceTable, nb::arg("n"), nb::arg("pitch_m"),
        nb::arg("young_pa"), nb::arg("poisson"),
        "Homogeneous half-space surface compliance table ((2n-1) x (2n-1) float32,\n"
        "m/Pa), indexed [dj + n - 1, di + n - 1].");
  m.def("elastic_pressure", &ElasticHalfSpace, nb::arg("gap_m").noconvert(),
        nb::arg("initial_pa").noconvert(), nb::arg("pitch_m"), nb::arg("force_n"),
        nb::arg("young_pa"), nb::arg("poisson"), nb::arg("periodic"), nb::arg("tolerance"),
        nb::arg("max_iterations"), nb::arg("method") = "pcg", nb::arg("precision") = "double",
        "Boundary-element contact of a homogeneous half-space skin (young_pa, poisson)\n"
        "against the gap field (ny x nx, m; inf: cannot touch) under force_n,\n"
        "warm-started from initial_pa. Non-periodic grids square; periodic sizes\n"
        "products of 2, 3, 5. method: 'pcg' (preconditioned CG) or 'pk' (Polonsky &\n"
        "Keer, the reference). precision: of the operator's FFTs, 'double' (the\n"
        "reference) or 'float' (the plugin's default). Returns (pressure Pa, stats dict).");
  m.def("elastic_pressure_table", &ElasticTable, nb::arg("gap_m").noconvert(),
        nb::arg("initial_pa").noconvert(), nb::arg("pitch_m"), nb::arg("force_n"),
        nb::arg("compliance_m_per_pa").noconvert(), nb::arg("tolerance"), nb::arg("max_iterations"),
        nb::arg("method") = "pcg", nb::arg("precision") = "double",
        "The same on an n x n non-periodic grid for any skin given by its surface\n"
        "compliance table ((2n-1) x (2n-1) float32, m/Pa).");
  m.def("render_gap", &Render, nb::arg("skin_z_m").noconvert(), nb::arg("pitch_m"),
        nb::arg("surfaces").noconvert(), nb::arg("pad_pos"), nb::arg("pad_mat"),
        nb::arg("hfield").noconvert(), nb::arg("area_average"), nb::arg("fast_paths") = true,
        "Stage 1: (gap m, inf where no surface; coverage) of each cell of an n x n\n"
        "skin (pad-frame heights skin_z_m) at the pad pose (pad_pos, pad_mat row-major)\n"
        "against surfaces (nsurface x 20: type code, pos 3, mat 9, size 3, half 2,\n"
        "elevation, max height); height fields read hfield (nrow x ncol float32).\n"
        "fast_paths=False: the general per-cell code (bit-identical reference).");
  m.def("ridge_cell_mean", &RidgeMean, nb::arg("s_m").noconvert(), nb::arg("profile"),
        nb::arg("pitch_m"), nb::arg("height_m"), nb::arg("angle_rad"), nb::arg("cell_m"),
        "Ridge relief (m, protrusion positive) at distances s_m (1D) along the ridge\n"
        "normal, averaged exactly over a square cell of side cell_m (0: point value).");
  m.def("pad_surface", &PadSurface, nb::arg("shape"), nb::arg("half_extents_m"), nb::arg("n"),
        nb::arg("pitch_m"), nb::arg("profile"), nb::arg("ridge_pitch_m"), nb::arg("ridge_height_m"),
        nb::arg("ridge_angle_rad"),
        "Cell-averaged skin height (pad frame z, m; inf outside the pad), n x n [j, i],\n"
        "of a pad shape ('sphere', 'ellipsoid', 'capsule', 'box'); ridges off when\n"
        "ridge_height_m <= 0.");
  m.def("slip_shear", &SlipShear, nb::arg("pressure_pa").noconvert(), nb::arg("pitch_m"),
        nb::arg("normal_n"), nb::arg("fx_n"), nb::arg("fy_n"),
        "Full-slip shear traction (qx, qy in Pa) for a pressure field (n x n) and the\n"
        "contact's normal and tangential (fx, fy) force.");
  m.def("splat_contacts", &Splat, nb::arg("contacts").noconvert(), nb::arg("n"), nb::arg("pitch_m"),
        "`contacts` model: rows (x, y, fx, fy, fz) in the pad frame (m, N) spread onto\n"
        "the n x n grid. Returns (pressure, qx, qy) in Pa.");
}

}  // namespace mjtouch::py
