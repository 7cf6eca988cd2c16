// fma(a, b, c) of floats, exactly, from double arithmetic: for CPUs without
// an FMA unit, where fmaf is a library call per element. a * b is exact in
// double, and p + c rounded to odd in double, then rounded to float, is the
// correctly rounded fma, as double carries more than 2 x 24 + 1 bits (Boldo
// and Melquiond 2008, "Emulation of FMA and correctly rounded sums: proved
// algorithms using rounding to odd", IEEE Trans. Computers 57(4)). Round to
// odd: the nearest sum s, moved one ulp towards the exact error e (TwoSum)
// where the sum is inexact and s's last bit is even. Finite inputs (the
// sum then is too); needs IEEE double arithmetic without contraction
// (-ffp-contract=off) or x87.
// Checked against std::fma by tests/cpp/test_exact_fma.cc.
#ifndef MJTOUCH_COMMON_EXACT_FMA_H_
#define MJTOUCH_COMMON_EXACT_FMA_H_

// Inlined into each ISA's copy, so the by-value vector ABI never applies.
#pragma GCC diagnostic ignored "-Wpsabi"

#include <cstdint>
#include <cstring>

namespace mjtouch {

inline __attribute__((always_inline)) float FmaFromDouble(float a, float b, float c) {
  const double p = static_cast<double>(a) * b, cd = c;
  double s = p + cd;
  const double t = s - p, e = (p - (s - t)) + (cd - t);
  uint64_t bits;
  std::memcpy(&bits, &s, sizeof(s));
  // Without branches (the lanes' parities are random): + or - 1 where needed.
  const uint64_t move = static_cast<uint64_t>(e != 0) & ~bits & 1;
  const uint64_t away = static_cast<uint64_t>((e > 0) == (s > 0));
  bits += move * (2 * away - 1);
  std::memcpy(&s, &bits, sizeof(s));
  return static_cast<float>(s);
}

// The same, lane by lane, on a GCC vector of floats (the lanes elementwise,
// in double vectors: what a CPU without FMA runs; ~10 instructions a lane).
template <typename VF>
inline __attribute__((always_inline)) VF FmaFromDouble(VF a, VF b, VF c) {
  constexpr int n = static_cast<int>(sizeof(VF) / sizeof(float));
  typedef double VD __attribute__((vector_size(n * sizeof(double))));
  typedef unsigned long long VU __attribute__((vector_size(n * sizeof(double))));
  const VD p = __builtin_convertvector(a, VD) * __builtin_convertvector(b, VD);
  const VD cd = __builtin_convertvector(c, VD);
  const VD s = p + cd;
  const VD t = s - p, e = (p - (s - t)) + (cd - t);
  // Only operations SSE2 has on 64-bit lanes (no 64-bit compares or
  // arithmetic shifts): the double compare, and, xor, logical shifts, add.
  const VU bits = reinterpret_cast<VU>(s);
  const VU move = reinterpret_cast<VU>(e != 0) & ~bits & 1;  // inexact, last bit even
  const VU same_sign = ~(reinterpret_cast<VU>(e) ^ bits) >> 63;
  const VU step = (same_sign << 1) - 1;  // +1 away from zero, else -1
  const VU odd = bits + (step & (0 - move));
  return __builtin_convertvector(reinterpret_cast<VD>(odd), VF);
}

}  // namespace mjtouch

#endif  // MJTOUCH_COMMON_EXACT_FMA_H_
