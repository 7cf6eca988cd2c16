#include "contact/working_set.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "common/simd.h"

#if MJTOUCH_X86_SIMD
#include <emmintrin.h>
#endif

// The vector types are only passed between inlined helpers; the
// by-value vector ABI never applies.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace mjtouch {
namespace working_set {
namespace {

// Four double lanes (one AVX2 vector, two SSE2 ones in the default clone;
// the lanes round alike in both).
typedef double v4d __attribute__((vector_size(32)));
typedef long long v4l __attribute__((vector_size(32)));
typedef float v4f __attribute__((vector_size(16)));
typedef int v4i __attribute__((vector_size(16)));
typedef int v8i __attribute__((vector_size(32)));

constexpr double kInf = std::numeric_limits<double>::infinity();

#define MJTOUCH_LANES inline __attribute__((always_inline))

MJTOUCH_LANES v4d Load(const double* x) {
  v4d v;
  std::memcpy(&v, x, sizeof(v));
  return v;
}
MJTOUCH_LANES void Store(double* x, v4d v) { std::memcpy(x, &v, sizeof(v)); }
MJTOUCH_LANES v4d Splat(double a) { return v4d{a, a, a, a}; }
MJTOUCH_LANES v4d Gather(const double* x, const int* S) {
  return v4d{x[S[0]], x[S[1]], x[S[2]], x[S[3]]};
}
// |x| by clearing the sign bit (std::abs's bits, NaN stays NaN).
MJTOUCH_LANES v4d Abs(v4d x) {
  const v4l mask = {0x7fffffffffffffffLL, 0x7fffffffffffffffLL, 0x7fffffffffffffffLL,
                    0x7fffffffffffffffLL};
  return reinterpret_cast<v4d>(reinterpret_cast<v4l>(x) & mask);
}
// The lanes of a comparison as bits 0-3 (SSE2's movmskpd on the halves:
// GCC's lane extractions cost several times more).
MJTOUCH_LANES int Bits(v4l m) {
#if MJTOUCH_X86_SIMD
  union {
    v4l v;
    __m128d h[2];
  } halves;
  halves.v = m;
  return _mm_movemask_pd(halves.h[0]) | (_mm_movemask_pd(halves.h[1]) << 2);
#else
  return static_cast<int>((m[0] & 1) | (m[1] & 2) | (m[2] & 4) | (m[3] & 8));
#endif
}
// Sum4's end: the tail went into the first lane's partial sum s0.
MJTOUCH_LANES double Combine(v4d acc, double s0) { return (s0 + acc[1]) + (acc[2] + acc[3]); }
MJTOUCH_LANES size_t Count(v4l negated) {
  return static_cast<size_t>(-(negated[0] + negated[1] + negated[2] + negated[3]));
}

template <bool kAdd>
MJTOUCH_LANES double UpdateAndSumT(size_t B, double s, double tau, const double* __restrict r,
                                   const double* __restrict kd, const double* __restrict g0,
                                   const double* __restrict p, double* __restrict u, size_t* nc) {
  const v4d zero = {0, 0, 0, 0}, sv = Splat(s), tv = Splat(tau);
  v4d acc = zero;
  v4l cnt = {0, 0, 0, 0};
  size_t b = 0;
  for (; b + 4 <= B; b += 4) {
    v4d v = Load(u + b) - tv * Load(r + b);
    if constexpr (kAdd) v += Load(kd + b);
    v *= sv;
    Store(u + b, v);
    const v4l c = Load(p + b) > zero;
    acc += c ? Load(g0 + b) + v : zero;
    cnt += c;
  }
  double s0 = acc[0];
  size_t n = Count(cnt);
  for (; b < B; ++b) {
    double v = u[b] - tau * r[b];
    if constexpr (kAdd) v += kd[b];
    v *= s;
    u[b] = v;
    const bool c = p[b] > 0.0;
    n += c;
    s0 += c ? g0[b] + v : 0.0;
  }
  *nc = n;
  return Combine(acc, s0);
}

// For the 4-bit lane mask m: kLane[m], the set lanes first, in order;
// kHalves[m], the same as 32-bit halves (one vpermd moves four doubles);
// kCount[m], how many.
constexpr v4i kLane[16] = {{0, 0, 0, 0}, {0, 0, 0, 0}, {1, 0, 0, 0}, {0, 1, 0, 0},
                           {2, 0, 0, 0}, {0, 2, 0, 0}, {1, 2, 0, 0}, {0, 1, 2, 0},
                           {3, 0, 0, 0}, {0, 3, 0, 0}, {1, 3, 0, 0}, {0, 1, 3, 0},
                           {2, 3, 0, 0}, {0, 2, 3, 0}, {1, 2, 3, 0}, {0, 1, 2, 3}};
constexpr v8i kHalves[16] = {
    {0, 1, 0, 1, 0, 1, 0, 1}, {0, 1, 0, 1, 0, 1, 0, 1}, {2, 3, 0, 1, 0, 1, 0, 1},
    {0, 1, 2, 3, 0, 1, 0, 1}, {4, 5, 0, 1, 0, 1, 0, 1}, {0, 1, 4, 5, 0, 1, 0, 1},
    {2, 3, 4, 5, 0, 1, 0, 1}, {0, 1, 2, 3, 4, 5, 0, 1}, {6, 7, 0, 1, 0, 1, 0, 1},
    {0, 1, 6, 7, 0, 1, 0, 1}, {2, 3, 6, 7, 0, 1, 0, 1}, {0, 1, 2, 3, 6, 7, 0, 1},
    {4, 5, 6, 7, 0, 1, 0, 1}, {0, 1, 4, 5, 6, 7, 0, 1}, {2, 3, 4, 5, 6, 7, 0, 1},
    {0, 1, 2, 3, 4, 5, 6, 7}};
constexpr int kCount[16] = {0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4};

// x's lanes in the order `halves` gives (bits moved, not converted).
MJTOUCH_LANES v4d Compact(v4d x, v8i halves) {
  return reinterpret_cast<v4d>(__builtin_shuffle(reinterpret_cast<v8i>(x), halves));
}

template <bool kFloat, bool kReadT>
MJTOUCH_LANES size_t BuildSetT(int bx, int by, int px, int hw, const double* __restrict g0,
                               const double* __restrict u, const double* __restrict p, double gbar,
                               double* __restrict gp, float* __restrict gpf, double* __restrict t,
                               int* __restrict S, double* __restrict gS, double* __restrict pS,
                               double* __restrict oS, size_t* __restrict row_first) {
  const v4d zero = {0, 0, 0, 0}, gbarv = Splat(gbar);
  // the padded array's border: zero (a periodic caller overwrites it)
  auto zero_pad = [&](size_t from, size_t n) {
    for (size_t k = from; k < from + n; ++k) {
      if constexpr (kFloat) {
        gpf[k] = 0.0f;
      } else {
        gp[k] = 0.0;
      }
    }
  };
  // a row's ends: the solver's stencil half width (2) as two stores, not
  // two memset calls per row
  auto zero_ends = [&](size_t from) {
    if (hw == 2) {
      if constexpr (kFloat) {
        gpf[from] = gpf[from + 1] = 0.0f;
      } else {
        gp[from] = gp[from + 1] = 0.0;
      }
    } else {
      zero_pad(from, hw);
    }
  };
  zero_pad(0, static_cast<size_t>(hw) * px);
  zero_pad(static_cast<size_t>(by + hw) * px, static_cast<size_t>(hw) * px);
  size_t ns = 0;
  for (int j = 0; j < by; ++j) {
    row_first[j] = ns;
    const size_t row0 = static_cast<size_t>(j + hw) * px + hw;
    zero_ends(row0 - hw);
    zero_ends(row0 + bx);
    const size_t b0 = static_cast<size_t>(j) * bx;
    // cells b0 + i .. b0 + i + 3, the first `done` of them classified already
    auto block = [&](int i, int done) {
      const size_t b = b0 + i;
      const v4d gv = Load(g0 + b), pv = Load(p + b);
      // g0 = +inf where not finite (LoadGuess): gb is then +inf or NaN, not
      // < 0, and p = 0 (such cells never join S; their gb goes unread)
      const v4d gb = (gv + Load(u + b)) - gbarv;
      const v4l in = (pv > zero) | (gb < zero);
      const int m = Bits(in) & (0xf << done);
      if (Bits(in) == 0) {  // none in S (most of the box): only zeros to write
        Store(t + b, zero);
        if constexpr (kFloat) {
          std::memset(gpf + row0 + i, 0, 4 * sizeof(float));
        } else {
          Store(gp + row0 + i, zero);
        }
        return;
      }
      v4d ov = zero;
      if constexpr (kReadT) ov = Load(t + b);
      Store(t + b, zero);
      const v4d gin = in ? gb : zero;
      if constexpr (kFloat) {
        const v4f f = __builtin_convertvector(gin, v4f);
        std::memcpy(gpf + row0 + i, &f, sizeof(f));
      } else {
        Store(gp + row0 + i, gin);
      }
      // the lanes in S moved to the front and stored whole (branch-free;
      // the lanes past the count are overwritten by the next cells)
#if MJTOUCH_X86_SIMD
      const v4i kept = kLane[m] + static_cast<int>(b);
      std::memcpy(S + ns, &kept, sizeof(kept));
      const v8i halves = kHalves[m];
      Store(gS + ns, Compact(gb, halves));
      Store(pS + ns, Compact(pv, halves));
      Store(oS + ns, Compact(ov, halves));
      ns += kCount[m];
#else
      // (variable shuffles lower to scalar code without AVX2: lane by lane)
      for (int l = 0; l < 4; ++l) {
        S[ns] = static_cast<int>(b) + l;
        gS[ns] = gb[l];
        pS[ns] = pv[l];
        oS[ns] = ov[l];
        ns += (m >> l) & 1;
      }
#endif
    };
    int i = 0;
    for (; i + 4 <= bx; i += 4) block(i, 0);
    // The row's last cells as the four ending the row (the ones already
    // classified masked off; t there is zero now and g_pad rewritten with
    // its value). Not on the last row: S's four-lane stores must stay
    // within B entries.
    if (i < bx && bx >= 4 && j + 1 < by) {
      block(bx - 4, 4 - (bx - i));
      i = bx;
    }
    for (; i < bx; ++i) {
      const size_t b = b0 + i;
      const double gb = g0[b] + u[b] - gbar;
      const bool in = p[b] > 0.0 || gb < 0.0;
      if constexpr (kFloat) {
        gpf[row0 + i] = in ? static_cast<float>(gb) : 0.0f;
      } else {
        gp[row0 + i] = in ? gb : 0.0;
      }
      S[ns] = static_cast<int>(b);
      gS[ns] = gb;
      pS[ns] = p[b];
      oS[ns] = kReadT ? t[b] : 0.0;
      t[b] = 0.0;
      ns += in;
    }
  }
  row_first[by] = ns;
  return ns;
}

}  // namespace

MJTOUCH_TARGET_CLONES
double ContactGapSum(size_t B, const double* __restrict g0, const double* __restrict u,
                     const double* __restrict p, size_t* nc) {
  const v4d zero = {0, 0, 0, 0};
  v4d acc = zero;
  v4l cnt = {0, 0, 0, 0};
  size_t b = 0;
  for (; b + 4 <= B; b += 4) {
    const v4l c = Load(p + b) > zero;
    acc += c ? Load(g0 + b) + Load(u + b) : zero;
    cnt += c;
  }
  double s0 = acc[0];
  size_t n = Count(cnt);
  for (; b < B; ++b) {
    const bool c = p[b] > 0.0;
    n += c;
    s0 += c ? g0[b] + u[b] : 0.0;
  }
  *nc = n;
  return Combine(acc, s0);
}

MJTOUCH_TARGET_CLONES
double ScaleStart(size_t B, double scale, double* __restrict p, const double* u_from, double* u,
                  const double* __restrict g0, size_t* nc) {
  const v4d zero = {0, 0, 0, 0}, sv = Splat(scale);
  v4d acc = zero;
  v4l cnt = {0, 0, 0, 0};
  size_t b = 0;
  for (; b + 4 <= B; b += 4) {
    const v4d pv = Load(p + b) * sv, uv = Load(u_from + b) * sv;
    Store(p + b, pv);
    Store(u + b, uv);
    const v4l c = pv > zero;
    acc += c ? Load(g0 + b) + uv : zero;
    cnt += c;
  }
  double s0 = acc[0];
  size_t n = Count(cnt);
  for (; b < B; ++b) {
    p[b] *= scale;
    u[b] = u_from[b] * scale;
    const bool c = p[b] > 0.0;
    n += c;
    s0 += c ? g0[b] + u[b] : 0.0;
  }
  *nc = n;
  return Combine(acc, s0);
}

MJTOUCH_TARGET_CLONES
double UpdateAndSum(size_t B, double s, double tau, const double* r, const double* kd,
                    const double* g0, const double* p, double* u, size_t* nc) {
  return kd ? UpdateAndSumT<true>(B, s, tau, r, kd, g0, p, u, nc)
            : UpdateAndSumT<false>(B, s, tau, r, kd, g0, p, u, nc);
}

MJTOUCH_TARGET_CLONES
size_t BuildSet(int bx, int by, int px, int hw, const double* g0, const double* u, const double* p,
                double gbar, double* gp, float* gpf, double* t, bool read_t, int* S, double* gS,
                double* pS, double* oS, size_t* row_first) {
  if (gp) {
    return read_t ? BuildSetT<false, true>(bx, by, px, hw, g0, u, p, gbar, gp, gpf, t, S, gS, pS,
                                           oS, row_first)
                  : BuildSetT<false, false>(bx, by, px, hw, g0, u, p, gbar, gp, gpf, t, S, gS, pS,
                                            oS, row_first);
  }
  return read_t ? BuildSetT<true, true>(bx, by, px, hw, g0, u, p, gbar, gp, gpf, t, S, gS, pS, oS,
                                        row_first)
                : BuildSetT<true, false>(bx, by, px, hw, g0, u, p, gbar, gp, gpf, t, S, gS, pS, oS,
                                         row_first);
}

MJTOUCH_TARGET_CLONES
double LoadGuess(int bx, int by, size_t stride, const double* __restrict gap,
                 const double* __restrict given, double* __restrict g0, double* __restrict p,
                 size_t* ncand, int* __restrict changed, size_t* nchanged) {
  [[maybe_unused]] const v4d zero = {0, 0, 0, 0}, inf = Splat(kInf);
  double sum = 0.0;
  v4l cand_n = {0, 0, 0, 0};
  size_t nc = 0, nch = 0;
  for (int j = 0; j < by; ++j) {
    const double* gr = gap + static_cast<size_t>(j) * stride;
    const double* qr = given + static_cast<size_t>(j) * stride;
    double* g0r = g0 + static_cast<size_t>(j) * bx;
    double* pr = p + static_cast<size_t>(j) * bx;
    const int b0 = j * bx;
    int i = 0;
#if MJTOUCH_X86_SIMD  // (elsewhere the scalar loop below: one running sum)
    for (; i + 4 <= bx; i += 4) {
      const v4d gv = Load(gr + i), qv = Load(qr + i);
      const v4l cand = Abs(gv) < inf;
      Store(g0r + i, cand ? gv : inf);
      cand_n += cand;
      // std::max(0, q) on candidates, 0 if not finite
      const v4d v = (cand & (qv > zero) & (Abs(qv) < inf)) ? qv : zero;
      Store(pr + i, v);
      const int ch = Bits(v != qv);
      if (ch != 0) {
        for (int l = 0; l < 4; ++l)
          if ((ch >> l) & 1) changed[nch++] = b0 + i + l;
      }
      // in order; zeros skipped (v >= +0 and sum >= +0: adding +0 is exact)
      if (Bits(v != zero) != 0) {
        sum += v[0];
        sum += v[1];
        sum += v[2];
        sum += v[3];
      }
    }
#endif
    for (; i < bx; ++i) {
      const bool cand = std::abs(gr[i]) < kInf;
      g0r[i] = cand ? gr[i] : kInf;
      nc += cand;
      double v = cand ? std::max(0.0, qr[i]) : 0.0;
      if (!(std::abs(v) < kInf)) v = 0.0;
      pr[i] = v;
      if (v != qr[i]) changed[nch++] = b0 + i;
      sum += v;
    }
  }
  *ncand = nc + Count(cand_n);
  *nchanged = nch;
  return sum;
}

MJTOUCH_TARGET_CLONES
double ContactSummary(size_t B, const double* __restrict g0, const double* __restrict u,
                      const double* __restrict p, size_t* nc, double* max_g0) {
  [[maybe_unused]] const v4d zero = {0, 0, 0, 0}, ninf = Splat(-kInf);
  double sum = 0.0;
  v4d mx = ninf;
  v4l cnt = {0, 0, 0, 0};
  size_t b = 0;
#if MJTOUCH_X86_SIMD  // (elsewhere the scalar loop below)
  for (; b + 4 <= B; b += 4) {
    const v4l c = Load(p + b) > zero;
    if (Bits(c) == 0) continue;
    cnt += c;
    const v4d gv = Load(g0 + b);
    // in order; a cell off the contact adds +0 (sum is never -0): exact
    const v4d a = c ? gv + Load(u + b) : zero;
    sum += a[0];
    sum += a[1];
    sum += a[2];
    sum += a[3];
    const v4d m = c ? gv : ninf;
    mx = m > mx ? m : mx;
  }
#endif
  size_t n = Count(cnt);
  double m0 = std::max(std::max(mx[0], mx[1]), std::max(mx[2], mx[3]));
  for (; b < B; ++b) {
    if (p[b] > 0.0) {
      sum += g0[b] + u[b];
      m0 = std::max(m0, g0[b]);
      ++n;
    }
  }
  // The largest of finite values does not depend on the order, but for
  // the sign of a zero (std::max keeps the first of equals): then again in
  // box order.
  if (m0 == 0.0) {
    m0 = -kInf;
    for (b = 0; b < B; ++b)
      if (p[b] > 0.0) m0 = std::max(m0, g0[b]);
  }
  *nc = n;
  *max_g0 = m0;
  return sum;
}

MJTOUCH_TARGET_CLONES
double GatherSum(size_t ns, const int* __restrict S, const double* __restrict x,
                 double* __restrict xS) {
  v4d acc = {0, 0, 0, 0};
  size_t k = 0;
  for (; k + 4 <= ns; k += 4) {
    const v4d v = Gather(x, S + k);
    Store(xS + k, v);
    acc += v;
  }
  double s0 = acc[0];
  for (; k < ns; ++k) {
    xS[k] = x[S[k]];
    s0 += xS[k];
  }
  return Combine(acc, s0);
}

MJTOUCH_TARGET_CLONES
double GatherDot(size_t ns, const int* __restrict S, const double* __restrict x,
                 const double* __restrict yS) {
  v4d acc = {0, 0, 0, 0};
  size_t k = 0;
  for (; k + 4 <= ns; k += 4) acc += Gather(x, S + k) * Load(yS + k);
  double s0 = acc[0];
  for (; k < ns; ++k) s0 += x[S[k]] * yS[k];
  return Combine(acc, s0);
}

namespace {

template <bool kScatter>
MJTOUCH_LANES double CenterDotT(size_t ns, double mean, double* __restrict xS,
                                const double* __restrict gS, const int* __restrict S,
                                double* __restrict x_box) {
  const v4d mv = Splat(mean);
  v4d acc = {0, 0, 0, 0};
  size_t k = 0;
  for (; k + 4 <= ns; k += 4) {
    const v4d x = Load(xS + k) - mv;
    Store(xS + k, x);
    if constexpr (kScatter) {
      x_box[S[k]] = x[0];
      x_box[S[k + 1]] = x[1];
      x_box[S[k + 2]] = x[2];
      x_box[S[k + 3]] = x[3];
    }
    acc += Load(gS + k) * x;
  }
  double s0 = acc[0];
  for (; k < ns; ++k) {
    xS[k] -= mean;
    if constexpr (kScatter) x_box[S[k]] = xS[k];
    s0 += gS[k] * xS[k];
  }
  return Combine(acc, s0);
}

}  // namespace

MJTOUCH_TARGET_CLONES
double CenterDot(size_t ns, double mean, double* xS, const double* gS, const int* S,
                 double* x_box) {
  return x_box ? CenterDotT<true>(ns, mean, xS, gS, S, x_box)
               : CenterDotT<false>(ns, mean, xS, gS, S, x_box);
}

MJTOUCH_TARGET_CLONES
double AxpySum(size_t ns, double beta, const double* __restrict zS, const double* __restrict oS,
               double* __restrict tS) {
  const v4d bv = Splat(beta);
  v4d acc = {0, 0, 0, 0};
  size_t k = 0;
  for (; k + 4 <= ns; k += 4) {
    const v4d t = Load(zS + k) + bv * Load(oS + k);
    Store(tS + k, t);
    acc += t;
  }
  double s0 = acc[0];
  for (; k < ns; ++k) {
    tS[k] = zS[k] + beta * oS[k];
    s0 += tS[k];
  }
  return Combine(acc, s0);
}

MJTOUCH_TARGET_CLONES
double StepProject(size_t ns, double tau, const double* __restrict pS, const double* __restrict tS,
                   const int* __restrict S, double* __restrict pnS, double* __restrict delta,
                   int* __restrict changed, size_t* nchg) {
  const v4d zero = {0, 0, 0, 0}, tv = Splat(tau);
  v4d acc = zero;
  size_t n = 0;
  size_t k = 0;
  for (; k + 4 <= ns; k += 4) {
    const v4d v = Load(pS + k) - tv * Load(tS + k);
    const v4l neg = v < zero;
    const int m = Bits(neg);
    if (m != 0) {
      for (int l = 0; l < 4; ++l) {
        if ((m >> l) & 1) {
          delta[S[k + l]] = -v[l];
          changed[n++] = S[k + l];
        }
      }
    }
    const v4d vp = neg ? zero : v;
    Store(pnS + k, vp);
    acc += vp;
  }
  double s0 = acc[0];
  for (; k < ns; ++k) {
    double v = pS[k] - tau * tS[k];
    if (v < 0.0) {
      delta[S[k]] = -v;
      changed[n++] = S[k];
      v = 0.0;
    }
    pnS[k] = v;
    s0 += v;
  }
  *nchg = n;
  return Combine(acc, s0);
}

MJTOUCH_TARGET_CLONES
double ScaleChange(size_t ns, double s, const double* __restrict pnS, const double* __restrict pS,
                   const int* __restrict S, double* __restrict p) {
  const v4d sv = Splat(s);
  v4d acc = {0, 0, 0, 0};
  size_t k = 0;
  for (; k + 4 <= ns; k += 4) {
    const v4d v = sv * Load(pnS + k);
    acc += Abs(v - Load(pS + k));
    p[S[k]] = v[0];
    p[S[k + 1]] = v[1];
    p[S[k + 2]] = v[2];
    p[S[k + 3]] = v[3];
  }
  double s0 = acc[0];
  for (; k < ns; ++k) {
    const double v = s * pnS[k];
    s0 += std::abs(v - pS[k]);
    p[S[k]] = v;
  }
  return Combine(acc, s0);
}

}  // namespace working_set
}  // namespace mjtouch
