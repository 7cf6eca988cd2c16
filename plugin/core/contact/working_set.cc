#include "contact/working_set.h"

#include <cmath>
#include <cstring>
#include <limits>

#include "common/simd.h"

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
// The lanes of a comparison as bits 0-3.
MJTOUCH_LANES int Bits(v4l m) {
  return static_cast<int>((m[0] & 1) | (m[1] & 2) | (m[2] & 4) | (m[3] & 8));
}
// Sum4's end: the tail went into the first lane's partial sum s0.
MJTOUCH_LANES double Combine(v4d acc, double s0) { return (s0 + acc[1]) + (acc[2] + acc[3]); }
MJTOUCH_LANES size_t Count(v4l negated) {
  return static_cast<size_t>(-(negated[0] + negated[1] + negated[2] + negated[3]));
}

template <bool kAdd>
MJTOUCH_LANES double UpdateAndSumT(size_t B, double s, double tau, const double* __restrict r,
                                   const double* __restrict kd, const double* __restrict g0,
                                   const double* __restrict p, double* __restrict u,
                                   size_t* nc) {
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

template <bool kFloat>
MJTOUCH_LANES size_t BuildSetT(int bx, int by, int px, int hw, const double* __restrict g0,
                               const double* __restrict u, const double* __restrict p,
                               double gbar, double* __restrict gp, float* __restrict gpf,
                               int* __restrict S, double* __restrict gS,
                               double* __restrict pS) {
  const v4d zero = {0, 0, 0, 0}, inf = Splat(kInf), gbarv = Splat(gbar);
  size_t ns = 0;
  for (int j = 0; j < by; ++j) {
    const size_t row0 = static_cast<size_t>(j + hw) * px + hw;
    const size_t b0 = static_cast<size_t>(j) * bx;
    int i = 0;
    for (; i + 4 <= bx; i += 4) {
      const size_t b = b0 + i;
      const v4d gv = Load(g0 + b), pv = Load(p + b);
      const v4l finite = Abs(gv) < inf;
      const v4d gb = finite ? (gv + Load(u + b)) - gbarv : zero;
      const v4l in = (pv > zero) | (finite & (gb < zero));
      const v4d gin = in ? gb : zero;
      if constexpr (kFloat) {
        const v4f f = __builtin_convertvector(gin, v4f);
        std::memcpy(gpf + row0 + i, &f, sizeof(f));
      } else {
        Store(gp + row0 + i, gin);
      }
      const int m = Bits(in);
      if (m == 15) {
        const int c = static_cast<int>(b);
        S[ns] = c;
        S[ns + 1] = c + 1;
        S[ns + 2] = c + 2;
        S[ns + 3] = c + 3;
        Store(gS + ns, gb);
        Store(pS + ns, pv);
        ns += 4;
      } else if (m != 0) {
        for (int l = 0; l < 4; ++l) {  // kept only if in
          S[ns] = static_cast<int>(b) + l;
          gS[ns] = gb[l];
          pS[ns] = pv[l];
          ns += (m >> l) & 1;
        }
      }
    }
    for (; i < bx; ++i) {
      const size_t b = b0 + i;
      const bool finite = std::abs(g0[b]) < kInf;
      const double gb = finite ? g0[b] + u[b] - gbar : 0.0;
      const bool in = p[b] > 0.0 || (finite && gb < 0.0);
      if constexpr (kFloat) {
        gpf[row0 + i] = in ? static_cast<float>(gb) : 0.0f;
      } else {
        gp[row0 + i] = in ? gb : 0.0;
      }
      S[ns] = static_cast<int>(b);
      gS[ns] = gb;
      pS[ns] = p[b];
      ns += in;
    }
  }
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
double UpdateAndSum(size_t B, double s, double tau, const double* r, const double* kd,
                    const double* g0, const double* p, double* u, size_t* nc) {
  return kd ? UpdateAndSumT<true>(B, s, tau, r, kd, g0, p, u, nc)
            : UpdateAndSumT<false>(B, s, tau, r, kd, g0, p, u, nc);
}

MJTOUCH_TARGET_CLONES
size_t BuildSet(int bx, int by, int px, int hw, const double* g0, const double* u,
                const double* p, double gbar, double* gp, float* gpf, int* S, double* gS,
                double* pS) {
  return gp ? BuildSetT<false>(bx, by, px, hw, g0, u, p, gbar, gp, gpf, S, gS, pS)
            : BuildSetT<true>(bx, by, px, hw, g0, u, p, gbar, gp, gpf, S, gS, pS);
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

void Gather(size_t ns, const int* __restrict S, const double* __restrict x,
            double* __restrict xS) {
  for (size_t k = 0; k < ns; ++k) xS[k] = x[S[k]];
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

MJTOUCH_TARGET_CLONES
double CenterDot(size_t ns, double mean, double* __restrict xS, const double* __restrict gS) {
  const v4d mv = Splat(mean);
  v4d acc = {0, 0, 0, 0};
  size_t k = 0;
  for (; k + 4 <= ns; k += 4) {
    const v4d x = Load(xS + k) - mv;
    Store(xS + k, x);
    acc += Load(gS + k) * x;
  }
  double s0 = acc[0];
  for (; k < ns; ++k) {
    xS[k] -= mean;
    s0 += gS[k] * xS[k];
  }
  return Combine(acc, s0);
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
double StepProject(size_t ns, double tau, const double* __restrict pS,
                   const double* __restrict tS, const int* __restrict S, double* __restrict pnS,
                   double* __restrict delta, int* __restrict changed, size_t* nchg) {
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
double ScaleChange(size_t ns, double s, const double* __restrict pnS,
                   const double* __restrict pS, const int* __restrict S, double* __restrict p) {
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
