#include "stress/stress_tree.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "common/simd.h"

namespace mjtouch {
namespace {

constexpr int kSlots = 8;  // component slots of a multi-component site (SIMD width)

uint32_t Pack(int level, int bi, int bj) {
  return static_cast<uint32_t>(level) << 24 | static_cast<uint32_t>(bj) << 12 |
         static_cast<uint32_t>(bi);
}

// One site's terms, with compile-time sizes: S component slots (1 or 8), LD
// loads (1 or 3). Multi-component sites keep one accumulator per slot
// (k summed in order); single-component sites one per moment index (summed in
// order at the end). Every lane adds in a fixed order, so vector and scalar
// builds give the same bits (no FMA contraction: -ffp-contract=off).
template <int S, int LD>
inline void SiteSumT(const uint32_t* block, size_t nterm, const float* coef, int stride_loads,
                     int n, const int* box, const std::vector<float>* moments,
                     const int* blocks_per_level, const float* const* traction, float* out_slots) {
  constexpr int kAcc = S == 1 ? 3 * LD : S;
  float acc[kAcc] = {};
  const float* c = coef;
  for (size_t t = 0; t < nterm; ++t) {
    const uint32_t packed = block[t];
    const int level = static_cast<int>(packed >> 24);
    const int bj = static_cast<int>((packed >> 12) & 0xfff), bi = static_cast<int>(packed & 0xfff);
    const int* b = box + 4 * level;
    const bool in = bi >= b[0] && bi <= b[1] && bj >= b[2] && bj <= b[3];
    if (level == 0) {
      if (in) {
        const size_t k = static_cast<size_t>(bj) * n + bi;
        for (int ld = 0; ld < LD; ++ld) {
          const float v = traction[ld][k];
          if (S == 1)
            acc[3 * ld] += c[ld] * v;
          else
            for (int s = 0; s < S; ++s) acc[s] += c[ld * S + s] * v;
        }
      }
      c += static_cast<size_t>(stride_loads) * S;
    } else {
      if (in) {
        const float* m =
            moments[level].data() + (static_cast<size_t>(bj) * blocks_per_level[level] + bi) * 9;
        for (int k = 0; k < 3 * LD; ++k) {
          if (S == 1)
            acc[k] += c[k] * m[k];
          else
            for (int s = 0; s < S; ++s) acc[s] += c[k * S + s] * m[k];
        }
      }
      c += static_cast<size_t>(stride_loads) * 3 * S;
    }
  }
  if (S == 1) {
    float total = 0;
    for (int k = 0; k < kAcc; ++k) total += acc[k];
    out_slots[0] = total;
  } else {
    for (int s = 0; s < S; ++s) out_slots[s] = acc[s];
  }
}

MJTOUCH_TARGET_CLONES
void SiteSum(const uint32_t* block, size_t nterm, const float* coef, int slots, int loads,
             int stride_loads, int n, const int* box, const std::vector<float>* moments,
             const int* blocks_per_level, const float* const* traction, float* out_slots) {
  if (slots == 1 && loads == 1)
    SiteSumT<1, 1>(block, nterm, coef, stride_loads, n, box, moments, blocks_per_level, traction,
                   out_slots);
  else if (slots == 1)
    SiteSumT<1, 3>(block, nterm, coef, stride_loads, n, box, moments, blocks_per_level, traction,
                   out_slots);
  else if (loads == 1)
    SiteSumT<kSlots, 1>(block, nterm, coef, stride_loads, n, box, moments, blocks_per_level,
                        traction, out_slots);
  else
    SiteSumT<kSlots, 3>(block, nterm, coef, stride_loads, n, box, moments, blocks_per_level,
                        traction, out_slots);
}

}  // namespace

std::shared_ptr<const StressTree> StressTree::Build(const KernelTables& kt,
                                                    const std::vector<StressSite>& sites,
                                                    bool shear, double theta) {
  const auto t0 = std::chrono::steady_clock::now();
  auto tree = std::shared_ptr<StressTree>(new StressTree());
  const int n = kt.n, L = 2 * n - 1;
  const double h = kt.pitch_m;
  tree->n_ = n;
  tree->theta_ = theta;
  tree->loads_ = shear ? kNumLoads : 1;
  int levels = 1;
  while ((1 << (levels - 1)) < n) ++levels;
  tree->levels_ = levels;
  const int loads = tree->loads_;
  tree->sites_.resize(sites.size());
  struct Node {
    int level, bi, bj;
  };
  std::vector<Node> stack;
  for (size_t s = 0; s < sites.size(); ++s) {
    const StressSite& site = sites[s];
    SiteTerms& st = tree->sites_[s];
    for (int c = 0; c < kNumStress; ++c)
      if (site.want[c] && kt.components[c]) st.comps[st.ncomp++] = c;
    const int slots = st.ncomp == 1 ? 1 : kSlots;
    const double z = kt.depths_m[site.depth_index];
    const float* K[kNumLoads][kNumStress] = {};
    for (int l = 0; l < loads; ++l)
      for (int a = 0; a < st.ncomp; ++a)
        K[l][a] = kt.At(site.depth_index, static_cast<SurfaceLoad>(l),
                        static_cast<StressComponent>(st.comps[a]));
    auto table = [&](int l, int a, int i, int j) {
      return static_cast<double>(
          K[l][a][static_cast<size_t>(j - site.j + n - 1) * L + (i - site.i + n - 1)]);
    };
    stack.assign(1, Node{levels - 1, 0, 0});
    while (!stack.empty()) {
      const Node b = stack.back();
      stack.pop_back();
      const int i0 = tree->BlockLo(b.level, b.bi), i1 = tree->BlockHi(b.level, b.bi);
      const int j0 = tree->BlockLo(b.level, b.bj), j1 = tree->BlockHi(b.level, b.bj);
      if (i0 >= n || j0 >= n) continue;
      const double xc = tree->BlockCentre(b.level, b.bi), yc = tree->BlockCentre(b.level, b.bj);
      const double dx = (xc - site.i) * h, dy = (yc - site.j) * h;
      const double R = std::sqrt(dx * dx + dy * dy + z * z);
      const double side = std::max(i1 - i0, j1 - j0) * h;
      if (b.level > 0 && side > theta * R) {
        for (int q = 3; q >= 0; --q)  // children, visited in (bj, bi) order
          stack.push_back(Node{b.level - 1, 2 * b.bi + (q & 1), 2 * b.bj + (q >> 1)});
        continue;
      }
      st.block.push_back(Pack(b.level, b.bi, b.bj));
      const int moments = b.level == 0 ? 1 : 3;
      const size_t base = st.coef.size();
      st.coef.resize(base + static_cast<size_t>(loads) * moments * slots, 0.0f);
      // Least-squares plane over the (clipped) block; X, Y are centred, so
      // the fit decouples: K0 = mean, K1 = sum K X / sum X^2.
      double sxx = 0, syy = 0;
      for (int i = i0; i < i1; ++i) sxx += (i - xc) * (i - xc);
      for (int j = j0; j < j1; ++j) syy += (j - yc) * (j - yc);
      sxx *= (j1 - j0);
      syy *= (i1 - i0);
      const double cells = static_cast<double>(i1 - i0) * (j1 - j0);
      for (int l = 0; l < loads; ++l)
        for (int a = 0; a < st.ncomp; ++a) {
          double k0 = 0, kx = 0, ky = 0;
          for (int j = j0; j < j1; ++j)
            for (int i = i0; i < i1; ++i) {
              const double v = table(l, a, i, j);
              k0 += v;
              kx += v * (i - xc);
              ky += v * (j - yc);
            }
          float* c = st.coef.data() + base + static_cast<size_t>(l) * moments * slots;
          c[a] = static_cast<float>(k0 / cells);
          if (moments == 3) {
            c[slots + a] = sxx > 0 ? static_cast<float>(kx / sxx) : 0.0f;
            c[2 * slots + a] = syy > 0 ? static_cast<float>(ky / syy) : 0.0f;
          }
        }
    }
  }
  tree->build_seconds_ =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return tree;
}

double StressTree::mean_terms() const {
  if (sites_.empty()) return 0.0;
  double t = 0;
  for (const auto& s : sites_) t += s.block.size();
  return t / sites_.size();
}

void StressTree::Compute(const ActiveRuns& runs, const float* pressure, const float* shear_x,
                         const float* shear_y, TreeScratch* w, Stress6* out) const {
  const int n = n_;
  for (size_t s = 0; s < sites_.size(); ++s) out[s].fill(0.0);
  if (runs.row.empty()) return;
  const int loads = (shear_x && shear_y) ? loads_ : 1;
  const float* traction[kNumLoads] = {pressure, shear_x, shear_y};
  // Active bounding box per level.
  w->box.assign(4 * levels_, 0);
  int i0 = n, i1 = -1, j0 = n, j1 = -1;
  for (size_t r = 0; r < runs.row.size(); ++r) {
    i0 = std::min(i0, runs.begin[r]);
    i1 = std::max(i1, runs.end[r] - 1);
    j0 = std::min(j0, runs.row[r]);
    j1 = std::max(j1, runs.row[r]);
  }
  for (int l = 0; l < levels_; ++l) {
    int* b = &w->box[4 * l];
    b[0] = i0 >> l;
    b[1] = i1 >> l;
    b[2] = j0 >> l;
    b[3] = j1 >> l;
  }
  // Moments: level 1 from the cells, each further level from its children.
  w->moments.resize(levels_);
  for (int l = 1; l < levels_; ++l) {
    const int nb = Blocks(l);
    auto& M = w->moments[l];
    M.resize(static_cast<size_t>(nb) * nb * 9);
    const int* b = &w->box[4 * l];
    for (int bj = b[2]; bj <= b[3]; ++bj)
      for (int bi = b[0]; bi <= b[1]; ++bi) {
        float* m = M.data() + (static_cast<size_t>(bj) * nb + bi) * 9;
        std::fill(m, m + 9, 0.0f);
        const float xc = static_cast<float>(BlockCentre(l, bi));
        const float yc = static_cast<float>(BlockCentre(l, bj));
        if (l == 1) {
          for (int j = BlockLo(1, bj); j < BlockHi(1, bj); ++j)
            for (int i = BlockLo(1, bi); i < BlockHi(1, bi); ++i) {
              const size_t k = static_cast<size_t>(j) * n + i;
              for (int ld = 0; ld < loads; ++ld) {
                const float t = traction[ld][k];
                m[3 * ld] += t;
                m[3 * ld + 1] += t * (i - xc);
                m[3 * ld + 2] += t * (j - yc);
              }
            }
          continue;
        }
        const int nc = Blocks(l - 1);
        const int* cb = &w->box[4 * (l - 1)];
        const auto& C = w->moments[l - 1];
        for (int q = 0; q < 4; ++q) {
          const int ci = 2 * bi + (q & 1), cj = 2 * bj + (q >> 1);
          if (ci < cb[0] || ci > cb[1] || cj < cb[2] || cj > cb[3] || ci >= nc || cj >= nc)
            continue;
          const float* c = C.data() + (static_cast<size_t>(cj) * nc + ci) * 9;
          const float ox = static_cast<float>(BlockCentre(l - 1, ci)) - xc;
          const float oy = static_cast<float>(BlockCentre(l - 1, cj)) - yc;
          for (int ld = 0; ld < loads; ++ld) {
            m[3 * ld] += c[3 * ld];
            m[3 * ld + 1] += c[3 * ld + 1] + c[3 * ld] * ox;
            m[3 * ld + 2] += c[3 * ld + 2] + c[3 * ld] * oy;
          }
        }
      }
  }
  // Terms. Blocks outside the active box have no traction and are skipped;
  // inside it an inactive block adds exact zeros, so skipping changes no bit.
  int blocks_per_level[32];
  for (int l = 0; l < levels_; ++l) blocks_per_level[l] = Blocks(l);
  for (size_t s = 0; s < sites_.size(); ++s) {
    const SiteTerms& st = sites_[s];
    float acc[kSlots];
    SiteSum(st.block.data(), st.block.size(), st.coef.data(), st.ncomp == 1 ? 1 : kSlots, loads,
            loads_, n, w->box.data(), w->moments.data(), blocks_per_level, traction, acc);
    for (int a = 0; a < st.ncomp; ++a) out[s][st.comps[a]] = acc[a];
  }
}

}  // namespace mjtouch
