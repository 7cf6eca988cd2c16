// The Winkler solve's fast path (pressure.h: SolveWinkler, WinklerPressure,
// WriteWinklerSlipTraction): WinklerPressureReference's result bit for bit,
// in a few passes over the rows of the rendered box, without packing the
// candidates (three stores per cell, which bound a packing pass) and, for
// the plugin's step, without clearing the last field first and writing only
// the arrays the step reads (MaterializeTraction writes the others on demand).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "common/simd.h"
#include "contact/pressure.h"
#include "contact/traction_cells.h"

#if MJTOUCH_X86_SIMD
#include <emmintrin.h>
#endif

// The 4-lane helpers are inlined into the target_clones functions, so their
// by-value vector ABI never applies.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace mjtouch {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Four double lanes (one AVX2 vector, two SSE2 ones in the default clone;
// the lanes round alike in both).
typedef double v4d __attribute__((vector_size(32)));
typedef long long v4l __attribute__((vector_size(32)));
typedef float v4f __attribute__((vector_size(16)));

#if !MJTOUCH_X86_SIMD
// ScanCandidates' two lanes without SSE2.
typedef double v2d __attribute__((vector_size(16)));
typedef long long v2l __attribute__((vector_size(16)));
// |x| by clearing the sign bit, as SSE2's andpd with the mask (NaN stays NaN).
inline v2d Abs(v2d x) {
  const v2l mask = {0x7fffffffffffffffLL, 0x7fffffffffffffffLL};
  return reinterpret_cast<v2d>(reinterpret_cast<v2l>(x) & mask);
}
#endif

// A candidate cell: coverage > 0 and a finite gap (the reference's test).
inline bool Candidate(double g, double w) { return (w > 0.0) & (std::abs(g) < kInf); }
// The same in four lanes (0 / -1 masks; |g| by clearing the sign bit).
inline v4l Candidates(const v4d& g, const v4d& w) {
  const v4l abs_mask = {0x7fffffffffffffffLL, 0x7fffffffffffffffLL, 0x7fffffffffffffffLL,
                        0x7fffffffffffffffLL};
  const v4d zero = {0, 0, 0, 0}, inf = {kInf, kInf, kInf, kInf};
  return (w > zero) & (reinterpret_cast<v4d>(reinterpret_cast<v4l>(g) & abs_mask) < inf);
}

// The smallest gap and the largest coverage of the box's candidates, and
// per row of the box the span [begin, end) that holds its candidates (rows
// without any are left out). The extrema run in four lanes (minsd's latency
// would bound one chain), SSE2 by hand (GCC turns the selects into
// branches). The minimum does not depend on the order but for the sign of a
// zero: a zero minimum is taken again in box order, as std::min keeps it.
// `covered_min`: the smallest gap of the cells with coverage > 0 (MinGap's,
// -inf included) but for the sign of a zero.
void ScanCandidates(const TaxelGrid& grid, const double* gap, const double* cov, const CellBox& box,
                    double* gmin, double* covmax, ActiveRuns* spans, double* covered_min) {
  spans->Clear();
  double lo = kInf, hi = 0.0, lo_cov = kInf;
#if MJTOUCH_X86_SIMD
  __m128d lo01 = _mm_set1_pd(kInf), lo23 = lo01, hi01 = _mm_setzero_pd(), hi23 = hi01;
  __m128d all01 = lo01, all23 = lo01;
  const __m128d inf = _mm_set1_pd(kInf), zero = _mm_setzero_pd();
  const __m128d abs_mask = _mm_castsi128_pd(_mm_set1_epi64x(0x7fffffffffffffffLL));
  auto lanes = [&](const double* g, const double* w, __m128d* l, __m128d* h, __m128d* all) {
    const __m128d gv = _mm_loadu_pd(g), wv = _mm_loadu_pd(w);
    const __m128d covered = _mm_cmpgt_pd(wv, zero);
    const __m128d valid = _mm_and_pd(covered, _mm_cmplt_pd(_mm_and_pd(gv, abs_mask), inf));
    const __m128d gs = _mm_or_pd(_mm_and_pd(valid, gv), _mm_andnot_pd(valid, inf));
    *l = _mm_min_pd(gs, *l);                     // gs < l ? gs : l
    *h = _mm_max_pd(_mm_and_pd(valid, wv), *h);  // w > h ? w : h
    // (a NaN gap: minpd returns the second operand)
    *all = _mm_min_pd(_mm_or_pd(_mm_and_pd(covered, gv), _mm_andnot_pd(covered, inf)), *all);
  };
  auto lo_of = [](__m128d v) {
    return std::min(_mm_cvtsd_f64(v), _mm_cvtsd_f64(_mm_unpackhi_pd(v, v)));
  };
  auto hi_of = [](__m128d v) {
    return std::max(_mm_cvtsd_f64(v), _mm_cvtsd_f64(_mm_unpackhi_pd(v, v)));
  };
#else
  // The same selects and operand order in vector extensions (NEON on
  // aarch64): minpd(a, b) is a < b ? a : b, maxpd(a, b) a > b ? a : b.
  v2d lo01 = {kInf, kInf}, lo23 = lo01, hi01 = {0.0, 0.0}, hi23 = hi01;
  v2d all01 = lo01, all23 = lo01;
  const v2d inf = {kInf, kInf}, zero = {0.0, 0.0};
  auto lanes = [&](const double* g, const double* w, v2d* l, v2d* h, v2d* all) {
    v2d gv, wv;
    std::memcpy(&gv, g, sizeof(gv));
    std::memcpy(&wv, w, sizeof(wv));
    const v2l covered = wv > zero;
    const v2l valid = covered & (Abs(gv) < inf);
    const v2d gs = valid ? gv : inf;
    *l = gs < *l ? gs : *l;
    const v2d ws = reinterpret_cast<v2d>(reinterpret_cast<v2l>(wv) & valid);
    *h = ws > *h ? ws : *h;
    const v2d gc = covered ? gv : inf;
    *all = gc < *all ? gc : *all;
  };
  auto lo_of = [](v2d v) { return std::min(v[0], v[1]); };
  auto hi_of = [](v2d v) { return std::max(v[0], v[1]); };
#endif
  for (int j = box.j0; j < box.j0 + box.ny; ++j) {
    const double* g = gap + static_cast<size_t>(j) * grid.n;
    const double* w = cov + static_cast<size_t>(j) * grid.n;
    int a = box.i0, b = box.i0 + box.nx;
    for (; a < b && !Candidate(g[a], w[a]); ++a)
      if (w[a] > 0.0) lo_cov = std::min(lo_cov, g[a]);
    for (; b > a && !Candidate(g[b - 1], w[b - 1]); --b)
      if (w[b - 1] > 0.0) lo_cov = std::min(lo_cov, g[b - 1]);
    if (a == b) continue;
    spans->row.push_back(j);
    spans->begin.push_back(a);
    spans->end.push_back(b);
    int i = a;
    for (; i + 4 <= b; i += 4) {
      lanes(g + i, w + i, &lo01, &hi01, &all01);
      lanes(g + i + 2, w + i + 2, &lo23, &hi23, &all23);
    }
    for (; i < b; ++i) {
      if (w[i] > 0.0) lo_cov = std::min(lo_cov, g[i]);
      if (!Candidate(g[i], w[i])) continue;
      lo = std::min(lo, g[i]);
      hi = std::max(hi, w[i]);
    }
  }
  *gmin = std::min(lo, std::min(lo_of(lo01), lo_of(lo23)));
  *covmax = std::max(hi, std::max(hi_of(hi01), hi_of(hi23)));
  *covered_min = std::min(lo_cov, std::min(lo_of(all01), lo_of(all23)));
  if (*gmin == 0.0) {
    double m = kInf;
    for (size_t r = 0; r < spans->row.size(); ++r) {
      const size_t row = static_cast<size_t>(spans->row[r]) * grid.n;
      for (int i = spans->begin[r]; i < spans->end[r]; ++i)
        if (Candidate(gap[row + i], cov[row + i])) m = std::min(m, gap[row + i]);
    }
    *gmin = m;
  }
}

// The closed form's and the load's sums run in four lanes, lane k over the
// cells of columns i = k mod 4 in box order, added ((0 + 1) + (2 + 3)) at
// the end (WinklerLaneSum, which the reference uses too): four independent
// chains instead of one latency-bound one, the same bits from either clone.
// Cells outside the contact set add +0 to a lane, which changes no sum (a
// lane starts at +0, so it is never -0).
inline double LaneTotal(const v4d& v) {
  const double lane[4] = {v[0], v[1], v[2], v[3]};
  return WinklerLaneSum(lane);
}

// Per row span [a, e) of the box's columns [lo, hi): vectors of four cells
// at columns 4m .. 4m + 3 (column k of a vector is lane k), the span's
// ends widened to them where they stay in the box (the box's other cells
// of a span's row are no candidates: they add nothing), else cell by cell.
template <typename Cell, typename Quad>
inline void ForLanes(int a, int e, int lo, int hi, Cell&& cell, Quad&& quad) {
  int i = a & ~3;
  if (i < lo) {
    i = a;
    for (const int head = std::min(e, (a + 3) & ~3); i < head; ++i) cell(i);
  }
  const int end = ((e + 3) & ~3) <= hi ? (e + 3) & ~3 : e;
  for (; i + 4 <= end; i += 4) quad(i);
  for (; i < e; ++i) cell(i);
}

// The sums over the contact set at c, the candidates below c (c - g > 0):
// f(c) + target = sum cov (c - g) and its slope sum cov (Newton), sum cov g
// (with the slope, the closed form's sums, in WinklerLaneSum's order); the
// largest gap in the set and the smallest gap of the other candidates
// (exact, order-free). Branch-free in the vector body, so that it
// vectorises; the same bits from either clone (no FMA contraction).
struct SetSums {
  double f = 0, slope = 0, cov_g = 0, in_max = -kInf, out_min = kInf;
};

MJTOUCH_TARGET_CLONES
SetSums ContactSetSums(const double* gap, const double* cov, int n, const ActiveRuns& spans,
                       const CellBox& box, double c) {
  const v4d zero = {0, 0, 0, 0}, inf = {kInf, kInf, kInf, kInf}, ninf = -inf;
  const v4d cv = {c, c, c, c};
  v4d f = zero, sw = zero, swg = zero, hi = ninf, lo = inf;
  for (size_t r = 0; r < spans.row.size(); ++r) {
    const double* g = gap + static_cast<size_t>(spans.row[r]) * n;
    const double* w = cov + static_cast<size_t>(spans.row[r]) * n;
    ForLanes(
        spans.begin[r], spans.end[r], box.i0, box.i0 + box.nx,
        [&](int i) {
          if (!Candidate(g[i], w[i])) return;
          const int l = i & 3;
          const double d = c - g[i];
          if (d > 0.0) {
            f[l] += w[i] * d;
            sw[l] += w[i];
            swg[l] += w[i] * g[i];
            hi[l] = std::max(hi[l], g[i]);
          } else {
            lo[l] = std::min(lo[l], g[i]);
          }
        },
        [&](int i) {
          v4d gv, wv;
          std::memcpy(&gv, g + i, sizeof(gv));
          std::memcpy(&wv, w + i, sizeof(wv));
          const v4l cand = Candidates(gv, wv);
          const v4d d = cv - gv;
          const v4l below = d > zero;
          const v4l in = cand & below, out = cand & ~below;
          f += reinterpret_cast<v4d>(reinterpret_cast<v4l>(wv * d) & in);
          sw += reinterpret_cast<v4d>(reinterpret_cast<v4l>(wv) & in);
          swg += reinterpret_cast<v4d>(reinterpret_cast<v4l>(wv * gv) & in);
          const v4d gin = in ? gv : ninf, gout = out ? gv : inf;
          hi = gin > hi ? gin : hi;
          lo = gout < lo ? gout : lo;
        });
  }
  SetSums out;
  out.f = LaneTotal(f);
  out.slope = LaneTotal(sw);
  out.cov_g = LaneTotal(swg);
  out.in_max = std::max(std::max(hi[0], hi[1]), std::max(hi[2], hi[3]));
  out.out_min = std::min(std::min(lo[0], lo[1]), std::min(lo[2], lo[3]));
  return out;
}

// The loads cov (c - g) of the candidates below c (0 on the other cells of
// the spans) into load (by cell), their sum, and per span how many are
// nonzero.
MJTOUCH_TARGET_CLONES
double WinklerLoads(const double* gap, const double* cov, int n, const ActiveRuns& spans,
                    const CellBox& box, double c, double* load, int* nonzero) {
  const v4d zero = {0, 0, 0, 0};
  const v4d cv = {c, c, c, c};
  v4d total = zero;
  for (size_t r = 0; r < spans.row.size(); ++r) {
    const size_t row = static_cast<size_t>(spans.row[r]) * n;
    const double* g = gap + row;
    const double* w = cov + row;
    double* l = load + row;
    v4l count = {0, 0, 0, 0};
    ForLanes(
        spans.begin[r], spans.end[r], box.i0, box.i0 + box.nx,
        [&](int i) {
          const double d = c - g[i];
          const double li = Candidate(g[i], w[i]) && d > 0.0 ? w[i] * d : 0.0;
          l[i] = li;
          total[i & 3] += li;
          count[0] += li != 0.0;
        },
        [&](int i) {
          v4d gv, wv;
          std::memcpy(&gv, g + i, sizeof(gv));
          std::memcpy(&wv, w + i, sizeof(wv));
          const v4d d = cv - gv;
          const v4l in = Candidates(gv, wv) & (d > zero);
          const v4d li = reinterpret_cast<v4d>(reinterpret_cast<v4l>(wv * d) & in);
          std::memcpy(l + i, &li, sizeof(li));
          total += li;
          count -= li != zero;
        });
    nonzero[r] = static_cast<int>((count[0] + count[1]) + (count[2] + count[3]));
  }
  return LaneTotal(total);
}

// One run of touching cells: pressure = load x scale and its float copy
// (pressure_pa too if kDouble), as NormalizeLoad then SlipRun leave them.
// Returns whether some pressure is zero (underflow).
template <bool kDouble>
MJTOUCH_TARGET_CLONES bool ScaledPressureRun(const double* __restrict load, double scale, int len,
                                             double* __restrict p, float* __restrict fp) {
  const v4d sv = {scale, scale, scale, scale}, zero = {0, 0, 0, 0};
  v4l zeros = {0, 0, 0, 0};
  int k = 0;
  for (; k + 4 <= len; k += 4) {
    v4d lv;
    std::memcpy(&lv, load + k, sizeof(lv));
    const v4d pk = lv * sv;
    if (kDouble) std::memcpy(p + k, &pk, sizeof(pk));
    const v4f fpk = __builtin_convertvector(pk, v4f);
    std::memcpy(fp + k, &fpk, sizeof(fpk));
    zeros |= pk == zero;
  }
  bool zero_seen = (zeros[0] | zeros[1] | zeros[2] | zeros[3]) != 0;
  for (; k < len; ++k) {
    const double pk = load[k] * scale;
    if (kDouble) p[k] = pk;
    fp[k] = static_cast<float>(pk);
    zero_seen |= pk == 0.0;
  }
  return zero_seen;
}

// The shear of one run (double and float), ratio x pressure with pressure =
// load x scale, as SlipRun leaves it; a zero pressure (underflow) gets the
// zero shear ClearTraction leaves, not rx * 0 (-0 for rx < 0).
MJTOUCH_TARGET_CLONES
void ScaledShearRun(const double* __restrict load, double scale, double rx, double ry, int len,
                    double* __restrict sx, double* __restrict sy, float* __restrict fx,
                    float* __restrict fy) {
  const v4d sv = {scale, scale, scale, scale}, xv = {rx, rx, rx, rx}, yv = {ry, ry, ry, ry};
  const v4d zero = {0, 0, 0, 0};
  int k = 0;
  for (; k + 4 <= len; k += 4) {
    v4d lv;
    std::memcpy(&lv, load + k, sizeof(lv));
    const v4d pk = lv * sv;
    const v4l on = pk != zero;
    const v4d qx = reinterpret_cast<v4d>(reinterpret_cast<v4l>(xv * pk) & on);
    const v4d qy = reinterpret_cast<v4d>(reinterpret_cast<v4l>(yv * pk) & on);
    std::memcpy(sx + k, &qx, sizeof(qx));
    std::memcpy(sy + k, &qy, sizeof(qy));
    const v4f fqx = __builtin_convertvector(qx, v4f), fqy = __builtin_convertvector(qy, v4f);
    std::memcpy(fx + k, &fqx, sizeof(fqx));
    std::memcpy(fy + k, &fqy, sizeof(fqy));
  }
  for (; k < len; ++k) {
    const double pk = load[k] * scale;
    const bool on = pk != 0.0;
    const double qx = on ? rx * pk : 0.0, qy = on ? ry * pk : 0.0;
    sx[k] = qx;
    sy[k] = qy;
    fx[k] = static_cast<float>(qx);
    fy[k] = static_cast<float>(qy);
  }
}

}  // namespace

double ScanWinklerCandidates(const TaxelGrid& grid, const std::vector<double>& gap_m,
                             const std::vector<double>& coverage, const CellBox& box,
                             TractionField* out) {
  double covered_min;
  ScanCandidates(grid, gap_m.data(), coverage.data(), box, &out->scan_gmin, &out->scan_covmax,
                 &out->scratch_spans, &covered_min);
  return covered_min;
}

bool SolveWinkler(const TaxelGrid& grid, const std::vector<double>& gap_m,
                  const std::vector<double>& coverage, const CellBox& box, double k, double force,
                  double guess, TractionField* out, double* approach_m, bool scanned) {
  // WinklerPressureReference's approach with fewer passes: Newton from a
  // warm start right of the root (or one step from its left); a
  // closed-form pass whose contact set did not change would repeat the last
  // one exactly, so it is skipped. The closed form and the load sum keep
  // the reference's order (WinklerLaneSum's lanes), so the values
  // are its values.
  ActiveRuns& spans = out->scratch_spans;
  ActiveRuns& runs = out->solved_runs;
  runs.Clear();
  out->solved_total = 0.0;
  const int n = grid.n;
  const double* gap = gap_m.data();
  const double* cov = coverage.data();
  const double target = force / (k * grid.Area());
  if (!scanned) ScanWinklerCandidates(grid, gap_m, coverage, box, out);
  const double gmin = out->scan_gmin, covmax = out->scan_covmax;
  if (!std::isfinite(gmin) || !(force > 0.0)) return false;
  const bool warm = std::isfinite(guess);
  double c = gmin + target / std::max(covmax, 1e-12);
  // The last evaluation of the sums and its c: the closed form's first pass
  // reuses them when its contact set is the same.
  SetSums sums;
  double sums_c = std::nan("");
  auto eval = [&](double at) {
    sums = ContactSetSums(gap, cov, n, spans, box, at);
    sums_c = at;
    return sums.f - target;
  };
  double f = warm ? eval(guess) : 0.0;
  if (warm && guess > gmin && f >= 0.0) {
    c = guess;  // to the right of the root: Newton from there
  } else {
    // Left of the root (the load grew): f is convex, so one Newton step
    // from there lands right of the root, much nearer than the cold start
    // (the load on one cell), which needs many more steps.
    if (warm && guess > gmin && sums.slope > 0.0) {
      const double right = guess - f / sums.slope;
      if (right > guess && right < c) c = right;
    }
    f = eval(c);
  }
  for (int it = 0; it < 200; ++it) {
    if (f <= 0.0 || sums.slope <= 0.0) break;
    const double next = c - f / sums.slope;
    if (!(next < c)) break;
    c = next;
    // The contact set {g < c} did not change (every gap in it is below the
    // new c): the next step would be over the same set, at its root up to
    // round-off. The closed form below starts from that set either way.
    if (sums.in_max < c) break;
    if (it + 1 < 200) f = eval(c);
  }
  // Closed form from the converged contact set, as the reference. A pass
  // whose contact set {g < c} equals the last pass's would repeat its sums
  // and give next == c: it is skipped. The sets are compared through the
  // largest gap in the set and the smallest candidate outside it (c - g > 0
  // holds exactly when g < c). The first pass's set is the last Newton
  // evaluation's when c is at or below it and above all of that set's gaps
  // (the other candidates are at or above that evaluation's c): its sums
  // are taken from there, not from another pass.
  bool same_set = false;
  for (int pass = 0; pass < 4 && !same_set; ++pass) {
    if (!(pass == 0 && sums.in_max < c && c <= sums_c)) {
      sums = ContactSetSums(gap, cov, n, spans, box, c);
      sums_c = c;
    }
    if (!(sums.slope > 0.0)) break;
    const double next = (target + sums.cov_g) / sums.slope;
    if (next == c) break;
    same_set = sums.in_max < next && next <= sums.out_min;
    c = next;
  }
  // The loads cov (c - g) (by cell; zero on the spans' other cells) and
  // their sum as the reference's WinklerLaneSum takes it; the touching cells
  // as runs of nonzero load (a load that underflows to zero would give a
  // zero pressure, which the field leaves out of its runs either way).
  if (out->scratch_load.size() != grid.Size()) out->scratch_load.resize(grid.Size());
  double* load = out->scratch_load.data();
  std::vector<int>& nonzero = out->scratch_counts;
  nonzero.resize(spans.row.size());
  const double total = WinklerLoads(gap, cov, n, spans, box, c, load, nonzero.data());
  for (size_t r = 0; r < spans.row.size(); ++r) {
    const int j = spans.row[r];
    const double* l = load + static_cast<size_t>(j) * n;
    int b = spans.begin[r], e = spans.end[r];
    // (usually one run: the nonzero loads between the first and the last)
    while (b < e && l[b] == 0.0) ++b;
    while (e > b && l[e - 1] == 0.0) --e;
    if (b == e) continue;
    if (e - b == nonzero[r]) {
      runs.Add(j, b, e);
      continue;
    }
    for (int i = b; i < e;) {
      while (i < e && l[i] == 0.0) ++i;
      if (i == e) break;
      const int start = i;
      while (i + 4 <= e &&
             (l[i] != 0.0) & (l[i + 1] != 0.0) & (l[i + 2] != 0.0) & (l[i + 3] != 0.0))
        i += 4;
      while (i < e && l[i] != 0.0) ++i;
      runs.Add(j, start, i);
    }
  }
  out->solved_total = total;
  *approach_m = c;
  return total > 0.0;
}

bool WinklerPressure(const TaxelGrid& grid, const std::vector<double>& gap,
                     const std::vector<double>& cov, const CellBox& box, double k, double force,
                     double guess, TractionField* out) {
  ClearTraction(grid, out);
  double c;
  if (!SolveWinkler(grid, gap, cov, box, k, force, guess, out, &c)) return false;
  out->box = box;
  out->approach_m = c;
  // NormalizeLoad's scaling of the loads (the same product p * scale).
  const double scale = force / (grid.Area() * out->solved_total);
  const ActiveRuns& runs = out->solved_runs;
  for (size_t r = 0; r < runs.row.size(); ++r) {
    const size_t row = static_cast<size_t>(runs.row[r]) * grid.n;
    const double* load = out->scratch_load.data() + row;
    double* p = out->pressure_pa.data() + row;
    for (int i = runs.begin[r]; i < runs.end[r]; ++i) p[i] = load[i] * scale;
  }
  return true;
}

bool WriteWinklerSlipTraction(const TaxelGrid& grid, const CellBox& box, double c, double fn,
                              double fx, double fy, bool write_pressure_pa, TractionField* out) {
  const int n = grid.n;
  const double total = out->solved_total;
  if (!(total > 0.0)) {  // nothing solved: the cleared field
    ClearTraction(grid, out);
    return false;
  }
  if (!TractionSized(grid, *out)) ClearTraction(grid, out);  // no last support
  // The last support as row segments (ascending rows), cleared at the end
  // where the new runs do not cover it.
  ActiveRuns& last = out->scratch_runs;
  last.Clear();
  if (out->support_in_runs) {
    std::swap(last, out->runs);
  } else if (!out->box.empty()) {
    const CellBox& b = out->box;
    for (int j = b.j0; j < b.j0 + b.ny; ++j) last.Add(j, b.i0, b.i0 + b.nx);
  }
  const double scale = fn / (grid.Area() * total);
  SetUniformSlip(fn, fx, fy, out);
  // The arrays written now (the rest is left lazy, zero): those of them the
  // last field held are cleared outside the new runs, the other arrays it
  // held on all of its support.
  const unsigned held = HeldArrays(*out);
  const unsigned written = kPressureF | (write_pressure_pa ? kPressureD : 0u);
  const unsigned dropped = held & ~written, kept = held & written;
  out->runs = out->solved_runs;
  const ActiveRuns& now = out->runs;
  const double* load = out->scratch_load.data();
  bool zero = false;
  int active = 0;
  for (size_t r = 0; r < now.row.size(); ++r) {
    const size_t a = static_cast<size_t>(now.row[r]) * n + now.begin[r];
    const int len = now.end[r] - now.begin[r];
    zero |= write_pressure_pa
                ? ScaledPressureRun<true>(load + a, scale, len, out->pressure_pa.data() + a,
                                          out->pressure.data() + a)
                : ScaledPressureRun<false>(load + a, scale, len, nullptr, out->pressure.data() + a);
    active += len;
  }
  for (size_t r = 0; r < last.row.size() && dropped; ++r) {
    const size_t row = static_cast<size_t>(last.row[r]) * n;
    ZeroCells(out, row + last.begin[r], row + last.end[r], dropped);
  }
  // Clear the last support outside the cells just written.
  size_t q = 0;
  for (size_t r = 0; r < last.row.size() && kept; ++r) {
    const int j = last.row[r];
    const size_t row = static_cast<size_t>(j) * n;
    while (q < now.row.size() && now.row[q] < j) ++q;
    int x = last.begin[r];
    for (size_t s = q; s < now.row.size() && now.row[s] == j && x < last.end[r]; ++s) {
      ZeroCells(out, row + x, row + std::min(last.end[r], std::max(x, now.begin[s])), kept);
      x = std::max(x, now.end[s]);
    }
    ZeroCells(out, row + x, row + std::max(x, last.end[r]), kept);
  }
  if (zero) {  // (underflow) the runs of nonzero pressure only, as FinishUniformSlipTraction
    ActiveRuns split;
    active = 0;
    for (size_t r = 0; r < now.row.size(); ++r) {
      const double* l = load + static_cast<size_t>(now.row[r]) * n;
      ForEachRun(
          now.begin[r], now.end[r], [&](int i) { return l[i] * scale != 0.0; },
          [&](int begin, int end) {
            split.Add(now.row[r], begin, end);
            active += end - begin;
          });
    }
    // the zero-pressure cells hold zeros in every field already
    std::swap(out->runs, split);
  }
  out->lazy_pressure_pa = !write_pressure_pa;
  out->lazy_shear = true;
  out->lazy_scale = scale;
  out->box = box;
  out->approach_m = c;
  out->support_in_runs = true;
  out->active_cells = active;
  return true;
}

void MaterializeTraction(const TaxelGrid& grid, bool pressure_pa, bool shear, TractionField* f) {
  pressure_pa = pressure_pa && f->lazy_pressure_pa;
  shear = shear && f->lazy_shear;
  if (!pressure_pa && !shear) return;
  const ActiveRuns& runs = f->runs;
  const double* load = f->scratch_load.data();
  const double scale = f->lazy_scale;
  for (size_t r = 0; r < runs.row.size(); ++r) {
    const size_t a = static_cast<size_t>(runs.row[r]) * grid.n + runs.begin[r];
    const int len = runs.end[r] - runs.begin[r];
    if (pressure_pa)
      for (int k = 0; k < len; ++k) f->pressure_pa[a + k] = load[a + k] * scale;
    if (shear)
      ScaledShearRun(load + a, scale, f->slip_x, f->slip_y, len, f->shear_x_pa.data() + a,
                     f->shear_y_pa.data() + a, f->shear_x.data() + a, f->shear_y.data() + a);
  }
  if (pressure_pa) f->lazy_pressure_pa = false;
  if (shear) f->lazy_shear = false;
}

}  // namespace mjtouch
