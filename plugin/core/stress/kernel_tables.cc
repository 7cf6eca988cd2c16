#include "stress/kernel_tables.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "common/simd.h"

namespace mjtouch {

std::shared_ptr<const KernelTables> BuildKernelTables(
    const Substrate& substrate, int n, double pitch_m, const std::vector<double>& depths_m,
    const std::array<bool, kNumStress>& components) {
  const auto t0 = std::chrono::steady_clock::now();
  auto kt = std::make_shared<KernelTables>();
  kt->n = n;
  kt->pitch_m = pitch_m;
  kt->depths_m = depths_m;
  kt->components = components;
  kt->tables.resize(depths_m.size());
  for (size_t d = 0; d < depths_m.size(); ++d) {
    substrate.LatticeTable(depths_m[d], pitch_m, n, components, &kt->tables[d]);
  }
  const int L = 2 * n - 1;
  bool symmetric = true;
  for (size_t d = 0; d < depths_m.size() && symmetric; ++d)
    for (int load = 0; load < kNumLoads; ++load)
      for (int c = 0; c < kNumStress; ++c) {
        if (!components[c]) continue;
        const auto l = static_cast<SurfaceLoad>(load);
        const auto comp = static_cast<StressComponent>(c);
        const float* K = kt->At(static_cast<int>(d), l, comp);
        const float sx = MirrorSign(0, l, comp), sy = MirrorSign(1, l, comp);
        float peak = 0, err = 0;
        for (int y = 0; y < L; ++y)
          for (int x = 0; x < L; ++x) {
            const float k = K[static_cast<size_t>(y) * L + x];
            peak = std::max(peak, std::fabs(k));
            err = std::max(err, std::fabs(k - sx * K[static_cast<size_t>(y) * L + (L - 1 - x)]));
            err = std::max(err, std::fabs(k - sy * K[static_cast<size_t>(L - 1 - y) * L + x]));
          }
        symmetric = symmetric && err <= 1e-6f * peak;
      }
  kt->mirror_symmetric = symmetric;
  kt->build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return kt;
}

namespace {

// sum_i (Kp[i] p[i] + Kx[i] x[i] + Ky[i] y[i]) over [0, len) with 8 float
// lanes (vectorisable without reassociation, so the result is deterministic);
// x / y may be null. Built for AVX2 where the CPU has it; FMA contraction is
// off (-ffp-contract=off) so every path rounds identically.
MJTOUCH_TARGET_CLONES
float Dot3(const float* Kp, const float* Kx, const float* Ky, const float* p, const float* x,
           const float* y, int len) {
  float acc[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  int i = 0;
  if (x && y) {
    for (; i + 8 <= len; i += 8)
      for (int k = 0; k < 8; ++k)
        acc[k] += Kp[i + k] * p[i + k] + Kx[i + k] * x[i + k] + Ky[i + k] * y[i + k];
    for (; i < len; ++i) acc[0] += Kp[i] * p[i] + Kx[i] * x[i] + Ky[i] * y[i];
  } else {
    for (; i + 8 <= len; i += 8)
      for (int k = 0; k < 8; ++k) acc[k] += Kp[i + k] * p[i + k];
    for (; i < len; ++i) acc[0] += Kp[i] * p[i];
  }
  return ((acc[0] + acc[4]) + (acc[1] + acc[5])) + ((acc[2] + acc[6]) + (acc[3] + acc[7]));
}

}  // namespace

void StressAtReceptor(const KernelTables& kt, int depth_index, int ri, int rj,
                      const ActiveRuns& runs, const float* pressure, const float* shear_x,
                      const float* shear_y, const std::array<bool, kNumStress>& want,
                      Stress6* out) {
  const int n = kt.n;
  const int L = 2 * n - 1;
  const bool shear = shear_x && shear_y;
  for (int c = 0; c < kNumStress; ++c) {
    (*out)[c] = 0.0;
    if (!want[c]) continue;
    const auto comp = static_cast<StressComponent>(c);
    const float* Kp = kt.At(depth_index, kLoadPressure, comp);
    const float* Kx = kt.At(depth_index, kLoadShearX, comp);
    const float* Ky = kt.At(depth_index, kLoadShearY, comp);
    double total = 0.0;
    for (size_t r = 0; r < runs.row.size(); ++r) {
      const int j = runs.row[r];
      const int b = runs.begin[r];
      // Table entry for source (i, j) at receptor (ri, rj): offset (i - ri, j - rj).
      const size_t krow = static_cast<size_t>(j - rj + n - 1) * L + (b - ri + n - 1);
      const size_t trow = static_cast<size_t>(j) * n + b;
      total +=
          Dot3(Kp + krow, Kx + krow, Ky + krow, pressure + trow, shear ? shear_x + trow : nullptr,
               shear ? shear_y + trow : nullptr, runs.end[r] - b);
    }
    (*out)[c] = total;
  }
}

}  // namespace mjtouch
