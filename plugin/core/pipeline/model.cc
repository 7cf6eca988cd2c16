// SkinModel::Build (receptor placement, skin surface, kernel tables, the
// elastic skin) and the cache that shares one model between equal
// configurations.
#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>

#include "pipeline/attributes.h"
#include "pipeline/model.h"
#include "pipeline/text.h"

namespace mjtouch {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kGoldenAngle = 2.39996322972865332;  // pi (3 - sqrt 5)

std::array<bool, kNumStress> ComponentsFor(Quantity q) {
  std::array<bool, kNumStress> w{};
  if (q == Quantity::kCompressiveSzz) {
    w[kSzz] = true;
  } else {
    w.fill(true);
  }
  return w;
}

}  // namespace

std::vector<ReceptorSite> SkinModel::PlaceReceptors(const SkinConfig& cfg) {
  // Sunflower (Vogel) spiral per class: deterministic, even areal density.
  std::vector<ReceptorSite> sites;
  const double R = cfg.population_radius_m;
  const double area_cm2 = kPi * R * R * 1e4;
  std::vector<double> depths;
  for (int c = 0; c < kNumClasses; ++c) {
    const ClassConfig& k = cfg.classes[c];
    if (!k.present) continue;
    int depth_index = -1;
    for (size_t d = 0; d < depths.size(); ++d)
      if (depths[d] == k.depth_m) depth_index = static_cast<int>(d);
    if (depth_index < 0) {
      depth_index = static_cast<int>(depths.size());
      depths.push_back(k.depth_m);
    }
    if (!cfg.sites.empty()) {  // `sites`: this class's entries, in the order given
      for (const auto& e : cfg.sites) {
        if (static_cast<int>(e.cls) != c) continue;
        ReceptorSite site;
        site.cls = e.cls;
        site.i = cfg.grid.Nearest(e.x_m);
        site.j = cfg.grid.Nearest(e.y_m);
        site.x_m = cfg.grid.Centre(site.i);
        site.y_m = cfg.grid.Centre(site.j);
        site.depth_m = k.depth_m;
        site.depth_index = depth_index;
        sites.push_back(site);
      }
      continue;
    }
    const int count = static_cast<int>(std::lround(k.density_per_cm2 * area_cm2));
    for (int s = 0; s < count; ++s) {
      const double r = R * std::sqrt((s + 0.5) / count);
      const double th = s * kGoldenAngle + 0.5 * c;  // offset classes
      ReceptorSite site;
      site.cls = static_cast<ReceptorClass>(c);
      site.i = cfg.grid.Nearest(r * std::cos(th));
      site.j = cfg.grid.Nearest(r * std::sin(th));
      site.x_m = cfg.grid.Centre(site.i);
      site.y_m = cfg.grid.Centre(site.j);
      site.depth_m = k.depth_m;
      site.depth_index = depth_index;
      sites.push_back(site);
    }
  }
  return sites;
}

int SkinModel::BlockSize(const SkinConfig& cfg, int nrec, int block) {
  if (!cfg.outputs[block]) return 0;
  switch (block) {
    case kOutForce: return kForceBlockSize;
    case kOutPressure: return static_cast<int>(cfg.grid.Size());
    case kOutCoverage: return kCoverageBlockSize;
    case kOutStick: return static_cast<int>(cfg.grid.Size());
    case kOutSlip: return kSlipBlockSize;
    case kOutShear: return 2 * static_cast<int>(cfg.grid.Size());
    default: return nrec;
  }
}

int SkinModel::OutputSize(const SkinConfig& cfg, int nrec) {
  int total = 0;
  for (int b = 0; b < kNumOutputs; ++b) total += BlockSize(cfg, nrec, b);
  return total;
}

std::shared_ptr<const SkinModel> SkinModel::Build(const SkinConfig& cfg_in, std::string* error) {
  SkinConfig cfg = cfg_in;
  if (!FinalizeSkinConfig(&cfg, error)) return nullptr;
  // Models whose every physics attribute (and pad) parse to the same values
  // share one instance (the key comes from the attribute table).
  static std::mutex mu;
  static std::map<std::string, std::weak_ptr<const SkinModel>> cache;
  const std::string key = ConfigCacheKey(cfg);
  std::lock_guard<std::mutex> lock(mu);
  if (auto hit = cache[key].lock()) return hit;

  auto model = std::shared_ptr<SkinModel>(new SkinModel());
  model->cfg_ = cfg;
  model->sites_ = PlaceReceptors(cfg);
  model->layout_ = StateLayout(cfg, static_cast<int>(model->sites_.size()));
  model->skin_z_ = SkinSurface(cfg.grid, cfg.pad, cfg.ridges);
  model->skin_blocks_ = MakeSkinBlocks(cfg.grid, model->skin_z_);
  // Kernel tables only for the depths and components the receptors use, and
  // only if an output needs stress.
  const bool need_stress = cfg.outputs[kOutSpikes] || cfg.outputs[kOutStress] ||
                           cfg.outputs[kOutVoltage] || cfg.outputs[kOutRate];
  std::vector<double> depths;
  std::array<bool, kNumStress> comps{};
  for (const auto& s : model->sites_) {
    if (static_cast<int>(depths.size()) <= s.depth_index) depths.push_back(s.depth_m);
    const auto w = ComponentsFor(cfg.classes[static_cast<int>(s.cls)].quantity);
    for (int k = 0; k < kNumStress; ++k) comps[k] = comps[k] || w[k];
  }
  for (int c = 0; c < kNumClasses; ++c)
    model->want_.push_back(ComponentsFor(cfg.classes[c].quantity));
  // The elastic skin, and the material at each class's depth.
  std::shared_ptr<LayeredSubstrate> layered;
  if (cfg.layered && !(layered = CreateLayeredSkin(cfg, error))) return nullptr;
  if (!CheckElasticSkin(cfg, layered.get(), error)) return nullptr;
  if (layered) {
    for (int c = 0; c < kNumClasses; ++c)
      model->material_[c] =
          layered->MaterialAt(cfg.classes[c].depth_m, cfg.interface_side == InterfaceSide::kUpper);
    model->layered_ = layered.get();
    model->substrate_ = std::move(layered);
  } else {
    model->substrate_ = std::make_shared<HalfSpace>(cfg.poisson);
  }
  for (const auto& s : model->sites_)
    model->stress_sites_.push_back(
        {s.i, s.j, s.depth_index, model->want_[static_cast<int>(s.cls)]});
  if (need_stress && !depths.empty()) {
    model->kernel_ =
        BuildKernelTables(*model->substrate_, cfg.grid.n, cfg.grid.pitch_m, depths, comps);
    const KernelTables& kt = *model->kernel_;
    if (cfg.stress_method == StressMethod::kTree) {
      model->tree_ = StressTree::Build(kt, model->stress_sites_, cfg.shear, cfg.stress_theta);
    } else {
      // FFT spectra only where the FFT path can win (for the widest possible
      // contact, every cell active) and fits in memory.
      constexpr double kMaxSpectraBytes = 256.0 * 1024 * 1024;
      const double bytes = KernelSpectraBytes(kt, model->stress_sites_);
      const StressCost widest = EstimateStressCost(
          kt, model->stress_sites_, cfg.grid.n * cfg.grid.n, cfg.shear,
          !cfg.shear || (cfg.pressure_model != PressureModel::kContacts && !cfg.shear_partial));
      if (cfg.stress_method == StressMethod::kFft && bytes > kMaxSpectraBytes) {
        *error =
            Fmt("mjtouch.skin: attribute `stress_method` = fft needs %.0f MiB of kernel "
                "spectra at nx = %d; the limit is %.0f MiB (use tree, auto or direct)",
                bytes / 1048576.0, cfg.grid.n, kMaxSpectraBytes / 1048576.0);
        return nullptr;
      }
      const bool fft = cfg.stress_method == StressMethod::kFft ||
                       (cfg.stress_method == StressMethod::kAuto && bytes <= kMaxSpectraBytes &&
                        widest.fft_s < widest.direct_s);
      if (fft) model->spectra_ = BuildKernelSpectra(kt, model->stress_sites_);
    }
  }
  if (cfg.pressure_model == PressureModel::kElastic) {
    // Surface compliance of the skin: the layered stack's, or a homogeneous
    // half-space's (young, poisson).
    model->elastic_ = std::make_shared<ElasticContact>(
        model->layered_
            ? LayeredCompliance(*model->layered_, cfg.grid.pitch_m, cfg.grid.n)
            : HalfSpaceCompliance(cfg.young_pa, cfg.poisson, cfg.grid.pitch_m, cfg.grid.n));
    if (cfg.grid_shift) {
      auto sg = std::make_shared<ShiftedGrid>();
      sg->grid = TaxelGrid{cfg.grid.n + 1, cfg.grid.pitch_m};
      sg->skin_z = SkinSurface(sg->grid, cfg.pad, cfg.ridges);
      sg->blocks = MakeSkinBlocks(sg->grid, sg->skin_z);
      sg->elastic = std::make_shared<ElasticContact>(
          model->layered_
              ? LayeredCompliance(*model->layered_, cfg.grid.pitch_m, sg->grid.n)
              : HalfSpaceCompliance(cfg.young_pa, cfg.poisson, cfg.grid.pitch_m, sg->grid.n));
      model->shifted_ = std::move(sg);
    } else if (cfg.grid_cycle > 1) {
      // n + 1 cells k / N of a cell off the taxel grid's corners; one
      // compliance for all (same size and pitch)
      auto cg = std::make_shared<CycleGrids>();
      const int n1 = cfg.grid.n + 1;
      std::shared_ptr<const ElasticContact> ec = std::make_shared<ElasticContact>(
          model->layered_ ? LayeredCompliance(*model->layered_, cfg.grid.pitch_m, n1)
                          : HalfSpaceCompliance(cfg.young_pa, cfg.poisson, cfg.grid.pitch_m, n1));
      cg->grids.resize(cfg.grid_cycle);
      for (int k = 0; k < cfg.grid_cycle; ++k) {
        ShiftedGrid& g = cg->grids[k];
        g.grid = TaxelGrid{n1, cfg.grid.pitch_m, k * cfg.grid.pitch_m / cfg.grid_cycle};
        g.skin_z = SkinSurface(g.grid, cfg.pad, cfg.ridges);
        g.blocks = MakeSkinBlocks(g.grid, g.skin_z);
        g.elastic = ec;
      }
      model->cycle_ = std::move(cg);
    }
  }
  cache[key] = model;
  return model;
}

std::string SkinModel::Describe() const {
  int count[kNumClasses] = {0, 0, 0};
  for (const auto& s : sites_) count[static_cast<int>(s.cls)]++;
  return Fmt(
      "mjtouch.skin: %dx%d taxels at %.3g mm, %d SA1 / %d RA / %d PC, kernel %.3f s "
      "(%s%s)",
      cfg_.grid.n, cfg_.grid.n, cfg_.grid.pitch_m * 1e3, count[0], count[1], count[2],
      kernel_build_seconds(), substrate_->Describe().c_str(),
      spectra_ ? "; FFT spectra built"
               : (tree_ ? Fmt("; stress tree, theta %g, %.0f terms per receptor", tree_->theta(),
                              tree_->mean_terms())
                              .c_str()
                        : ""));
}

double SkinModel::kernel_build_seconds() const {
  return (kernel_ ? kernel_->build_seconds : 0.0) + (spectra_ ? spectra_->build_seconds : 0.0) +
         (tree_ ? tree_->build_seconds() : 0.0);
}
}  // namespace mjtouch
