// mjtouch._core: the layered elastic skin (substrate/layered.h) and the
// per-step stress stage (stress/stress_field.h, stress_tree.h) as Python
// classes, vectorised over points and wavenumbers.
#include <array>
#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nanobind/stl/optional.h>
#include <nanobind/stl/pair.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/unique_ptr.h>
#include <nanobind/stl/vector.h>

#include "common/thread_pool.h"
#include "python/convert.h"
#include "stress/kernel_tables.h"
#include "stress/stress_field.h"
#include "stress/stress_tree.h"
#include "substrate/layered.h"

namespace mjtouch::py {
namespace {

using Side = std::optional<std::string>;

InterfaceSide ParseSide(const LayeredSubstrate& s, const Side& side) {
  if (!side) return s.interface_side();
  if (*side == "upper") return InterfaceSide::kUpper;
  if (*side == "lower") return InterfaceSide::kLower;
  Fail("side '" + *side + "' is not one of None, 'upper', 'lower'");
}

SurfaceLoad ParseLoad(const std::string& load) {
  if (load == "pressure") return kLoadPressure;
  if (load == "shear_x") return kLoadShearX;
  if (load == "shear_y") return kLoadShearY;
  Fail("load '" + load + "' is not one of ['pressure', 'shear_x', 'shear_y']");
}

void CheckDepth(const LayeredSubstrate& s, double z_m, InterfaceSide side) {
  const std::string why = s.CheckDepth(z_m, side);
  if (!why.empty()) Fail(why);
}

std::unique_ptr<LayeredSubstrate> Create(const F64_2& layers, bool base_rigid, double base_young,
                                         double base_poisson, const std::string& interface_side) {
  if (layers.shape(1) != 3 || layers.shape(0) == 0)
    Fail(
        "layers must be a non-empty sequence of (thickness_m, young_pa, poisson) rows, got "
        "shape " +
        ShapeOf(layers));
  if (interface_side != "upper" && interface_side != "lower")
    Fail("interface_side '" + interface_side + "' is not one of 'upper', 'lower'");
  std::vector<ElasticLayer> stack;
  for (size_t i = 0; i < layers.shape(0); ++i)
    stack.push_back({layers(i, 0), layers(i, 1), layers(i, 2)});
  LayeredBase base;
  base.rigid = base_rigid;
  base.young_pa = base_rigid ? 0.0 : base_young;
  base.poisson = base_rigid ? 0.0 : base_poisson;
  std::string error;
  auto s = LayeredSubstrate::Create(
      stack, base, interface_side == "upper" ? InterfaceSide::kUpper : InterfaceSide::kLower,
      &error);
  if (!s) Fail(error);
  return s;
}

Out<double> Transfer(const LayeredSubstrate& s, const F64_1& k_per_m, double z_m,
                     const Side& side) {
  const InterfaceSide sd = ParseSide(s, side);
  CheckDepth(s, z_m, sd);
  const size_t nk = k_per_m.shape(0);
  for (size_t i = 0; i < nk; ++i)
    if (!(k_per_m(i) >= 0)) Fail("k_per_m must be >= 0");
  std::vector<double> out(10 * nk);
  for (size_t i = 0; i < nk; ++i) {
    const LayerTransfer t = s.TransferAt(k_per_m(i), z_m, sd);
    const double v[10] = {t.p_xixi,   t.p_etaeta, t.p_zz,  t.p_xiz,  t.q_xixi,
                          t.q_etaeta, t.q_zz,     t.q_xiz, t.a_etaz, t.a_xieta};
    std::copy(v, v + 10, out.begin() + 10 * i);
  }
  return ToNumpy(std::move(out), {nk, 10});
}

Out<double> Compliance(const LayeredSubstrate& s, const F64_1& k_per_m) {
  const size_t nk = k_per_m.shape(0);
  for (size_t i = 0; i < nk; ++i)
    if (!(k_per_m(i) >= 0)) Fail("k_per_m must be >= 0");
  std::vector<double> out(nk);
  for (size_t i = 0; i < nk; ++i) out[i] = s.SurfaceCompliance(k_per_m(i));
  return ToNumpy(std::move(out), {nk});
}

Out<float> ComplianceTable(const LayeredSubstrate& s, double pitch_m, int n) {
  if (!(pitch_m > 0) || n < 1 || n > 1024) Fail("need pitch_m > 0 and 1 <= n <= 1024");
  std::vector<float> t;
  s.SurfaceComplianceTable(pitch_m, n, &t);
  const size_t L = 2 * static_cast<size_t>(n) - 1;
  return ToNumpy(std::move(t), {L, L});
}

// kind: "point" (1 N at the origin), "cell" (unit traction on a square of side
// size_m), "disc" (unit traction on a disc of radius size_m).
Out<double> StressAt(const LayeredSubstrate& s, const std::string& kind, const std::string& load,
                     const F64_2& points_m, double size_m, const Side& side) {
  const SurfaceLoad l = ParseLoad(load);
  const InterfaceSide sd = ParseSide(s, side);
  const int k = kind == "point" ? 0 : kind == "cell" ? 1 : kind == "disc" ? 2 : -1;
  if (k < 0) Fail("kind '" + kind + "' is not one of 'point', 'cell', 'disc'");
  if (k > 0 && !(size_m > 0)) Fail("invalid arguments (size_m must be > 0)");
  if (points_m.shape(1) != 3)
    Fail("points_m must have shape (npoint, 3), got shape " + ShapeOf(points_m));
  const size_t np = points_m.shape(0);
  for (size_t i = 0; i < np; ++i) CheckDepth(s, points_m(i, 2), sd);
  std::vector<double> out(6 * np);
  for (size_t i = 0; i < np; ++i) {
    const double x = points_m(i, 0), y = points_m(i, 1), z = points_m(i, 2);
    const Stress6 v = k == 0   ? s.PointStress(l, x, y, z, sd)
                      : k == 1 ? s.CellStress(l, x, y, z, size_m, sd)
                               : s.DiscStress(l, x, y, z, size_m, sd);
    for (int c = 0; c < 6; ++c) out[6 * i + c] = v[c];
  }
  return ToNumpy(std::move(out), {np, 6});
}

Out<float> Lattice(const LayeredSubstrate& s, double z_m, double pitch_m, int n, const Side& side) {
  const InterfaceSide sd = ParseSide(s, side);
  CheckDepth(s, z_m, sd);
  if (!(pitch_m > 0) || n < 1 || n > 512) Fail("need pitch_m > 0 and 1 <= n <= 512");
  std::array<bool, kNumStress> all;
  all.fill(true);
  std::vector<float> t;
  s.LatticeTable(z_m, pitch_m, n, all, sd, &t);
  const size_t L = 2 * static_cast<size_t>(n) - 1;
  return ToNumpy(std::move(t), {3, 6, L, L});
}

// Tables, sites and spectra for one grid: the stress stage as the plugin runs it.
class StressEngine {
 public:
  StressEngine(const LayeredSubstrate* layered, double poisson, int n, double pitch_m,
               const F64_1& depths_m, const I32_2& receptors_ij, const I32_1& depth_index,
               const I32_1& want_mask, const std::string& method, double theta) {
    const StressMethod m = ParseMethod(method);
    if (n < 1 || n > 512) Fail("n = " + std::to_string(n) + " is out of range; valid [1, 512]");
    if (!(pitch_m > 0)) Fail("pitch_m must be > 0");
    if (depths_m.shape(0) < 1) Fail("depths_m must hold at least one depth");
    if (m == StressMethod::kTree && !(theta > 0 && theta <= 2))
      Fail("theta = " + std::to_string(theta) + " is out of range; valid range (0, 2]");
    if (receptors_ij.shape(1) != 2)
      Fail("receptors_ij must have shape (nrec, 2), got shape " + ShapeOf(receptors_ij));
    const size_t nsite = receptors_ij.shape(0);
    if (depth_index.shape(0) != nsite || want_mask.shape(0) != nsite)
      Fail("depth_index and want_mask need one entry per receptor (" + std::to_string(nsite) + ")");
    const int ndepth = static_cast<int>(depths_m.shape(0));
    const Substrate* sub = layered;
    if (!sub) {
      if (!(poisson > -1 && poisson <= 0.5)) Fail("poisson is out of range; valid range (-1, 0.5]");
      halfspace_ = std::make_unique<HalfSpace>(poisson);
      sub = halfspace_.get();
    }
    std::array<bool, kNumStress> comps{};
    for (size_t s = 0; s < nsite; ++s) {
      const int i = receptors_ij(s, 0), j = receptors_ij(s, 1), d = depth_index(s);
      if (i < 0 || i >= n || j < 0 || j >= n || d < 0 || d >= ndepth)
        Fail("site cell indices must be in [0, n) and depth indices in [0, ndepth)");
      StressSite site{i, j, d, {}};
      for (int c = 0; c < kNumStress; ++c) {
        site.want[c] = (want_mask(s) >> c) & 1;
        comps[c] = comps[c] || site.want[c];
      }
      sites_.push_back(site);
    }
    std::vector<double> depths(depths_m.data(), depths_m.data() + ndepth);
    for (double z : depths) {
      const std::string why = layered ? layered->CheckDepth(z, layered->interface_side())
                                      : (z > 0 ? "" : "receptor depth must be > 0 m");
      if (!why.empty()) Fail(why);
    }
    tables_ = BuildKernelTables(*sub, n, pitch_m, depths, comps);
    const StressCost widest = EstimateStressCost(*tables_, sites_, n * n, true);
    if (m == StressMethod::kFft || (m == StressMethod::kAuto && widest.fft_s < widest.direct_s))
      spectra_ = BuildKernelSpectra(*tables_, sites_);
    if (m == StressMethod::kTree) tree_ = StressTree::Build(*tables_, sites_, true, theta);
    out_.resize(sites_.size());
  }

  static StressMethod ParseMethod(const std::string& method) {
    StressMethod m;
    if (!ParseStressMethod(method, &m))
      Fail("method '" + method + "' is not one of ['auto', 'direct', 'fft', 'tree']");
    return m;
  }

  int n() const { return tables_->n; }
  bool mirror_symmetric() const { return tables_->mirror_symmetric; }
  size_t nrec() const { return sites_.size(); }
  double table_build_s() const { return tables_->build_seconds; }
  double spectra_build_s() const { return spectra_ ? spectra_->build_seconds : 0.0; }
  int fft_n() const { return spectra_ ? spectra_->fft_n : 0; }
  size_t table_bytes_per_depth() const {
    return tables_->tables.empty() ? 0 : sizeof(float) * tables_->tables[0].size();
  }
  double tree_build_s() const { return tree_ ? tree_->build_seconds() : 0.0; }
  double tree_terms_per_site() const { return tree_ ? tree_->mean_terms() : 0.0; }

  std::tuple<double, double> Cost(int active_cells, bool shear, bool folded) const {
    const StressCost c = EstimateStressCost(*tables_, sites_, active_cells, shear, folded);
    return {c.direct_s, c.fft_s};
  }

  // (stress nrec x 6 Pa, mean seconds per call over `repeats`, path used,
  // cells with traction). The active cells are found once, outside the
  // timing, as the pressure stage gives them.
  std::tuple<Out<double>, double, std::string, int> Stress(
      const F32_2& pressure_pa, std::optional<F32_2> shear_x_pa, std::optional<F32_2> shear_y_pa,
      const std::string& method, int repeats, std::optional<std::pair<double, double>> slip,
      bool fold, int threads, bool fold_legacy, bool split) {
    const StressMethod m = ParseMethod(method);
    if (threads < 1 || threads > ThreadPool::kMaxThreads)
      Fail("threads = " + std::to_string(threads) + " is out of range; valid range [1, " +
           std::to_string(ThreadPool::kMaxThreads) + "]");
    StressOptions opt;
    opt.fold = fold;
    opt.threads = threads;
    opt.fold_legacy = fold_legacy;
    if (slip) {
      opt.uniform_slip = !split;  // split: any shear, partial slip's path
      opt.fold_general = split;
      opt.slip_x = slip->first;
      opt.slip_y = slip->second;
    }
    const size_t n = tables_->n;
    RequireShape(pressure_pa, "pressure_pa", n, n, "(the engine's grid)");
    const auto [sx, sy] = ShearFields(shear_x_pa, shear_y_pa, n);
    if (repeats < 1) Fail("repeats must be >= 1");
    if (m == StressMethod::kFft && !spectra_)
      Fail("method 'fft' needs FFT spectra: create the engine with method='fft'");
    if (m == StressMethod::kTree && !tree_)
      Fail("method 'tree' needs the tree: create the engine with method='tree'");
    if (slip && !sx) Fail("slip needs the shear fields it describes (shear_x_pa, shear_y_pa)");
    FindActiveRuns(static_cast<int>(n), pressure_pa.data(), sx, sy, &runs_);
    StressMethod used = StressMethod::kDirect;
    const auto t0 = std::chrono::steady_clock::now();
    for (int k = 0; k < repeats; ++k)
      used = ComputeStresses(*tables_, spectra_.get(), tree_.get(), m, sites_, runs_,
                             pressure_pa.data(), sx, sy, &scratch_, out_.data(), opt);
    const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::vector<double> out(6 * sites_.size());
    for (size_t s = 0; s < sites_.size(); ++s)
      for (int c = 0; c < kNumStress; ++c) out[6 * s + c] = out_[s][c];
    return {ToNumpy(std::move(out), {sites_.size(), 6}), dt / repeats, StressMethodName(used),
            runs_.Count()};
  }

 private:
  std::unique_ptr<Substrate> halfspace_;  // when no layered substrate is given
  std::shared_ptr<const KernelTables> tables_;
  std::shared_ptr<const KernelSpectra> spectra_;
  std::shared_ptr<const StressTree> tree_;
  std::vector<StressSite> sites_;
  StressScratch scratch_;
  std::vector<Stress6> out_;
  ActiveRuns runs_;
};

}  // namespace

void BindLayered(nb::module_& m) {
  m.def(
      "shao_fingertip",
      []() {
        std::vector<std::tuple<double, double, double>> layers;
        for (const auto& l : LayeredSubstrate::ShaoFingertipLayers())
          layers.emplace_back(l.thickness_m, l.young_pa, l.poisson);
        return std::make_tuple(layers, LayeredSubstrate::ShaoFingertipBase().rigid);
      },
      "The default skin (Shao et al. 2010 fingertip): layers as (thickness m, E Pa,\n"
      "nu) from the surface down, and whether the base is rigid (bone).");

  nb::class_<LayeredSubstrate>(m, "LayeredSubstrate",
                               "A stack of welded elastic layers over a rigid base or an elastic\n"
                               "half-space (substrate/layered.h). side arguments: None (the\n"
                               "interface side chosen at creation), 'upper' or 'lower'.")
      .def_static("create", &Create, nb::arg("layers").noconvert(), nb::arg("base_rigid"),
                  nb::arg("base_young_pa"), nb::arg("base_poisson"), nb::arg("interface_side"),
                  "layers: (nlayer, 3) rows (thickness m, E Pa, nu) from the surface down;\n"
                  "ValueError naming the bad field and its valid range.")
      .def("describe", &LayeredSubstrate::Describe, "One-line description of the stack.")
      .def(
          "check_depth",
          [](const LayeredSubstrate& s, double z_m, const Side& side) {
            CheckDepth(s, z_m, ParseSide(s, side));
          },
          nb::arg("z_m"), nb::arg("side").none() = nb::none(),
          "Raise ValueError if z_m is not a valid receptor depth on side.")
      .def(
          "material",
          [](const LayeredSubstrate& s, double z_m, const Side& side) {
            const Material mat = s.MaterialAt(z_m, ParseSide(s, side) == InterfaceSide::kUpper);
            return std::make_tuple(mat.young_pa, mat.poisson);
          },
          nb::arg("z_m"), nb::arg("side").none() = nb::none(),
          "(E Pa, nu) at depth z_m; (0, 0) inside a rigid base.")
      .def("transfer", &Transfer, nb::arg("k_per_m").noconvert(), nb::arg("z_m"),
           nb::arg("side").none() = nb::none(),
           "The 10 point-force transfer functions (LayerTransfer order) at each\n"
           "wavenumber k_per_m (1D, >= 0) and depth z_m: (nk, 10).")
      .def("compliance", &Compliance, nb::arg("k_per_m").noconvert(),
           "Fourier surface compliance u_z / p (m/Pa) at each k_per_m (1D, >= 0; 0: the\n"
           "finite part).")
      .def("compliance_table", &ComplianceTable, nb::arg("pitch_m"), nb::arg("n"),
           "Surface compliance lattice ((2n-1) x (2n-1) float32, m/Pa).")
      .def("stress", &StressAt, nb::arg("kind"), nb::arg("load"), nb::arg("points_m").noconvert(),
           nb::arg("size_m"), nb::arg("side").none() = nb::none(),
           "Stress (npoint x 6, Pa) at points_m (npoint x 3) from a 1 N point force\n"
           "(kind 'point'), unit traction on a square cell of side size_m ('cell') or a\n"
           "disc of radius size_m ('disc') at the origin.")
      .def("lattice_table", &Lattice, nb::arg("z_m"), nb::arg("pitch_m"), nb::arg("n"),
           nb::arg("side").none() = nb::none(),
           "The plugin's kernel table at depth z_m: (3, 6, 2n-1, 2n-1) float32.");

  nb::class_<StressEngine>(m, "StressEngine",
                           "The plugin's per-step stress stage for an n x n grid.")
      .def(nb::init<const LayeredSubstrate*, double, int, double, const F64_1&, const I32_2&,
                    const I32_1&, const I32_1&, const std::string&, double>(),
           nb::arg("layered").none(), nb::arg("poisson"), nb::arg("n"), nb::arg("pitch_m"),
           nb::arg("depths_m").noconvert(), nb::arg("receptors_ij").noconvert(),
           nb::arg("depth_index").noconvert(), nb::arg("want_mask").noconvert(), nb::arg("method"),
           nb::arg("theta"), nb::keep_alive<1, 2>(),
           "layered: a LayeredSubstrate, or None for a homogeneous half-space of\n"
           "poisson. Sites: cells receptors_ij (nrec x 2), depth_index into depths_m,\n"
           "want_mask bit c for Voigt component c. method 'auto' (FFT spectra where\n"
           "they can win), 'direct', 'fft', 'tree' (opening angle theta).")
      .def_prop_ro("n", &StressEngine::n, "Grid side (cells).")
      .def_prop_ro("nrec", &StressEngine::nrec, "Number of sites.")
      .def_prop_ro("mirror_symmetric", &StressEngine::mirror_symmetric,
                   "Whether the tables are mirror images (the folded path needs it).")
      .def_prop_ro("table_build_s", &StressEngine::table_build_s, "Kernel table build time, s.")
      .def_prop_ro("spectra_build_s", &StressEngine::spectra_build_s,
                   "FFT spectra build time, s (0: none).")
      .def_prop_ro("fft_n", &StressEngine::fft_n, "Padded FFT size (0: none).")
      .def_prop_ro("table_bytes_per_depth", &StressEngine::table_bytes_per_depth,
                   "Kernel table bytes per depth.")
      .def_prop_ro("tree_build_s", &StressEngine::tree_build_s, "Tree build time, s (0: none).")
      .def_prop_ro("tree_terms_per_site", &StressEngine::tree_terms_per_site,
                   "Mean tree terms per site (0: no tree).")
      .def("estimated_cost", &StressEngine::Cost, nb::arg("active_cells"), nb::arg("shear"),
           nb::arg("folded") = false,
           "The cost model's (direct, fft) seconds per call; folded: the folded direct path.")
      .def("stress", &StressEngine::Stress, nb::arg("pressure_pa").noconvert(),
           nb::arg("shear_x_pa").noconvert().none() = nb::none(),
           nb::arg("shear_y_pa").noconvert().none() = nb::none(), nb::arg("method") = "auto",
           nb::arg("repeats") = 1, nb::arg("slip").none() = nb::none(), nb::arg("fold") = true,
           nb::arg("threads") = 1, nb::arg("fold_legacy") = false, nb::arg("split") = false,
           "(stress nrec x 6 Pa, seconds per call, path used, active cells) from float32\n"
           "traction fields (n x n, [j, i]); shear both or neither. slip = (rx, ry): the\n"
           "shear is (rx, ry) x pressure, so the direct path folds its tables; fold=False:\n"
           "the reference direct sum. threads in [1, 64]: the same bits for any count.\n"
           "fold_legacy: the folded path unaligned, without its rx cache (same bits; benchmarks).\n"
           "split: with slip, any shear fields by partial slip's path (the pressure folded\n"
           "at slip plus the coarse correction of shear - slip x pressure).");
}

}  // namespace mjtouch::py
