// C API over stages 1-2 (surface rendering, contact pressure), for Python
// (mjtouch.core) and tests: every function runs without a MuJoCo scene.
// Nothing throws across this boundary; errors are nonzero return codes.
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "contact/contact_solver.h"
#include "contact/pressure.h"
#include "substrate/substrate.h"
#include "surface/surface.h"

namespace {
using namespace mjtouch;
}  // namespace

extern "C" {

// Half-space surface compliance table (m/Pa), layout as
// HalfSpaceSurfaceComplianceTable: (2n - 1)^2 floats.
__attribute__((visibility("default"))) int mjtouch_surface_compliance(
    double young, double poisson, double pitch_m, int n, float* out) {
  if (!(young > 0) || !(poisson > -1 && poisson <= 0.5) || !(pitch_m > 0) || n < 1) return 1;
  std::vector<float> t;
  HalfSpaceSurfaceComplianceTable(young, poisson, pitch_m, n, &t);
  std::memcpy(out, t.data(), t.size() * sizeof(float));
  return 0;
}

// Elastic (boundary-element) contact of a homogeneous half-space skin on an
// nx x ny grid (row-major j * nx + i). periodic = 0: non-periodic (DC-FFT,
// needs nx == ny); 1: periodic (nx, ny products of 2, 3, 5). gap: m (non-
// finite: cannot touch); pressure: in = initial guess (zeros: none), out =
// solution (Pa). stats: iterations, converged, last change, approach (m),
// contact cells, largest contact gap (m).
__attribute__((visibility("default"))) int mjtouch_elastic_pressure(
    int nx, int ny, double pitch_m, const double* gap, double young, double poisson,
    double force, int periodic, double tolerance, int max_iterations, double* pressure,
    double* stats) {
  if (nx < 1 || ny < 1 || !(pitch_m > 0) || !(young > 0) || !(poisson > -1 && poisson <= 0.5) ||
      !(tolerance > 0) || max_iterations < 1)
    return 1;
  if (!periodic && nx != ny) return 1;
  if (periodic && (!IsFftSize(nx) || !IsFftSize(ny))) return 1;
  const size_t N = static_cast<size_t>(nx) * ny;
  std::vector<double> g(gap, gap + N), p(pressure, pressure + N);
  ElasticWork work;
  ElasticSolveStats st;
  bool ok;
  if (periodic) {
    const double e_star = young / (1.0 - poisson * poisson);
    SurfaceCompliance K(nx, ny, pitch_m, [&](double k) { return 2.0 / (e_star * k); });
    ok = SolveElasticContact(K, g, CellBox{0, 0, nx, ny}, force, tolerance, max_iterations, &p,
                             &work, &st);
  } else {
    ok = SolveElasticContact(*HalfSpaceCompliance(young, poisson, pitch_m, nx), g,
                             CellBox{0, 0, nx, nx}, force, tolerance, max_iterations, &p, &work,
                             &st);
  }
  std::memcpy(pressure, p.data(), N * sizeof(double));
  stats[0] = st.iterations;
  stats[1] = st.converged;
  stats[2] = st.change;
  stats[3] = st.approach_m;
  stats[4] = st.contact_cells;
  stats[5] = st.max_contact_gap_m;
  return ok ? 0 : 2;
}

// The same on an n x n non-periodic grid with a given compliance table
// ((2n-1)^2 floats, m/Pa, the layout of HalfSpaceSurfaceComplianceTable),
// e.g. LayeredSubstrate::SurfaceComplianceTable for a layered skin.
__attribute__((visibility("default"))) int mjtouch_elastic_pressure_table(
    int n, double pitch_m, const double* gap, const float* table, double force, double tolerance,
    int max_iterations, double* pressure, double* stats) {
  if (n < 1 || !(pitch_m > 0) || !(tolerance > 0) || max_iterations < 1 || !table) return 1;
  const size_t N = static_cast<size_t>(n) * n, L = 2 * static_cast<size_t>(n) - 1;
  std::vector<double> g(gap, gap + N), p(pressure, pressure + N);
  ElasticWork work;
  ElasticSolveStats st;
  const SurfaceCompliance K(n, pitch_m, std::vector<float>(table, table + L * L));
  const bool ok =
      SolveElasticContact(K, g, CellBox{0, 0, n, n}, force, tolerance, max_iterations, &p, &work,
                          &st);
  std::memcpy(pressure, p.data(), N * sizeof(double));
  const double out[6] = {static_cast<double>(st.iterations), static_cast<double>(st.converged),
                         st.change, st.approach_m, static_cast<double>(st.contact_cells),
                         st.max_contact_gap_m};
  std::memcpy(stats, out, sizeof(out));
  return ok ? 0 : 2;
}

}  // extern "C"

namespace {

// desc: type (CounterSurface::Type as int), pos[3], mat[9] (row-major,
// local -> world), size[3], half_x, half_y, elevation, max_height.
bool SurfaceFromDesc(const double* desc, int nrow, int ncol, const float* samples,
                     std::vector<double>* prefix, CounterSurface* s) {
  const int type = static_cast<int>(desc[0]);
  if (type < 0 || type > static_cast<int>(CounterSurface::Type::kCylinder)) return false;
  s->type = static_cast<CounterSurface::Type>(type);
  for (int k = 0; k < 3; ++k) s->pose.pos[k] = desc[1 + k];
  for (int k = 0; k < 9; ++k) s->pose.mat[k] = desc[4 + k];
  for (int k = 0; k < 3; ++k) s->size_m[k] = desc[13 + k];
  s->half_x_m = desc[16];
  s->half_y_m = desc[17];
  s->elevation_m = desc[18];
  s->max_height_m = desc[19];
  if (s->type == CounterSurface::Type::kHeightField) {
    if (nrow < 2 || ncol < 2 || !samples) return false;
    s->nrow = nrow;
    s->ncol = ncol;
    s->samples = samples;
    *prefix = HeightFieldRowPrefix(nrow, ncol, samples);
    s->row_prefix = prefix->data();
  }
  return true;
}

}  // namespace

extern "C" {

// Render the gap (m; +inf: no surface) and coverage of an n x n grid of
// pitch pitch_m for a skin height field skin_z (pad frame, n*n) at pad pose
// (pos[3], mat[9]) against nsurf surfaces (desc: 20 doubles each, see
// SurfaceFromDesc; height-field samples shared by all height-field
// surfaces). area_average = 0: point sampling at cell centres.
__attribute__((visibility("default"))) int mjtouch_render_gap(
    int n, double pitch_m, const double* skin_z, const double* pad_pos, const double* pad_mat,
    int nsurf, const double* desc, int nrow, int ncol, const float* samples, int area_average,
    double* gap, double* coverage) {
  if (n < 1 || !(pitch_m > 0) || nsurf < 0) return 1;
  TaxelGrid grid{n, pitch_m};
  std::vector<double> z(skin_z, skin_z + grid.Size());
  Pose pad;
  for (int k = 0; k < 3; ++k) pad.pos[k] = pad_pos[k];
  for (int k = 0; k < 9; ++k) pad.mat[k] = pad_mat[k];
  std::vector<CounterSurface> surfaces(nsurf);
  std::vector<std::vector<double>> prefixes(nsurf);
  for (int k = 0; k < nsurf; ++k)
    if (!SurfaceFromDesc(desc + 20 * k, nrow, ncol, samples, &prefixes[k], &surfaces[k])) return 1;
  std::vector<double> g, c;
  RenderGap(grid, z, pad, surfaces, std::numeric_limits<double>::infinity(), &g, &c,
            area_average != 0);
  std::memcpy(gap, g.data(), g.size() * sizeof(double));
  std::memcpy(coverage, c.data(), c.size() * sizeof(double));
  return 0;
}

// Exact cell mean of the ridge relief (m, protrusion positive) over a square
// cell of side h centred at s (m along the ridge normal); profile 0 sine,
// 1 triangle, 2 square.
__attribute__((visibility("default"))) double mjtouch_ridge_cell_mean(
    int profile, double pitch_m, double height_m, double angle_rad, double s_m, double h_m) {
  Ridges r;
  r.profile = static_cast<RidgeProfile>(profile);
  r.pitch_m = pitch_m;
  r.height_m = height_m;
  r.angle_rad = angle_rad;
  return h_m > 0 ? RidgeCellMean(r, s_m, h_m) : RidgeRelief(r, s_m);
}

// Skin surface of a pad of shape 0 sphere, 1 ellipsoid, 2 capsule, 3 box
// with half extents (a, b, c) (capsule: r, r, r + half length); ridge
// parameters as in RidgeCellMean, ridges off when height_m <= 0.
__attribute__((visibility("default"))) int mjtouch_pad_surface(
    int n, double pitch_m, int shape, double a, double b, double c, int profile,
    double ridge_pitch_m, double ridge_height_m, double ridge_angle_rad, double* out) {
  if (n < 1 || !(pitch_m > 0) || shape < 0 || shape > 3 || !(a > 0 && b > 0 && c > 0)) return 1;
  TaxelGrid grid{n, pitch_m};
  PadGeometry pad;
  pad.shape = static_cast<PadShape>(shape);
  pad.semi_axes_m[0] = a;
  pad.semi_axes_m[1] = b;
  pad.semi_axes_m[2] = c;
  Ridges r;
  r.enabled = ridge_height_m > 0;
  r.profile = static_cast<RidgeProfile>(profile);
  r.pitch_m = ridge_pitch_m;
  r.height_m = ridge_height_m;
  r.angle_rad = ridge_angle_rad;
  const auto z = SkinSurface(grid, pad, r);
  std::memcpy(out, z.data(), z.size() * sizeof(double));
  return 0;
}

// Shear for a pressure field (n*n, Pa): model 0 full-slip (UniformSlipShear)
// from the normal and tangential force; writes qx, qy (Pa).
__attribute__((visibility("default"))) int mjtouch_slip_shear(
    int n, double pitch_m, const double* pressure, double fn, double fx, double fy, double* qx,
    double* qy) {
  if (n < 1 || !(pitch_m > 0)) return 1;
  TaxelGrid grid{n, pitch_m};
  TractionField tf;
  ClearTraction(grid, &tf);
  tf.pressure_pa.assign(pressure, pressure + grid.Size());
  tf.box = CellBox::All(grid);
  UniformSlipShear(grid, fn, fx, fy, &tf);
  std::memcpy(qx, tf.shear_x_pa.data(), grid.Size() * sizeof(double));
  std::memcpy(qy, tf.shear_y_pa.data(), grid.Size() * sizeof(double));
  return 0;
}

// `contacts` model: splat ncontact contacts (x, y, fx, fy, fz per contact,
// pad frame) onto the grid: pressure, qx, qy (Pa, n*n).
__attribute__((visibility("default"))) int mjtouch_splat_contacts(
    int n, double pitch_m, int ncontact, const double* contacts, double* pressure, double* qx,
    double* qy) {
  if (n < 2 || !(pitch_m > 0) || ncontact < 0) return 1;
  TaxelGrid grid{n, pitch_m};
  std::vector<ContactPoint> cps(ncontact);
  for (int k = 0; k < ncontact; ++k) {
    cps[k].x_m = contacts[5 * k + 0];
    cps[k].y_m = contacts[5 * k + 1];
    for (int d = 0; d < 3; ++d) cps[k].force_n[d] = contacts[5 * k + 2 + d];
  }
  TractionField tf;
  const bool ok = SplatContacts(grid, cps, &tf);
  std::memcpy(pressure, tf.pressure_pa.data(), grid.Size() * sizeof(double));
  std::memcpy(qx, tf.shear_x_pa.data(), grid.Size() * sizeof(double));
  std::memcpy(qy, tf.shear_y_pa.data(), grid.Size() * sizeof(double));
  return ok ? 0 : 2;
}

}  // extern "C"
