// Standalone check of FmaFromDouble (plugin/core/common/exact_fma.h, the
// stress sums' fma on CPUs without FMA; scalar and vector forms) against
// std::fma, bit for bit: random
// finite triples over the exponent range, and products that fall exactly on
// a float midpoint with an addend far below double precision, where rounding
// the double sum to nearest (instead of to odd) rounds the wrong way.
//   ./test_exact_fma   # PASS/FAIL lines, exit status 1 on failure
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>

#include "common/exact_fma.h"

using mjtouch::FmaFromDouble;

namespace {

int bad = 0;
long checked = 0;

typedef float v4f __attribute__((vector_size(16)));

// The scalar and the vector form (the triple in lane k % 4 of zeros).
void Check(float a, float b, float c) {
  const float want = std::fma(a, b, c), got = FmaFromDouble(a, b, c);
  const int lane = static_cast<int>(checked % 4);
  v4f va{}, vb{}, vc{};
  va[lane] = a;
  vb[lane] = b;
  vc[lane] = c;
  const float got_v = FmaFromDouble(va, vb, vc)[lane];
  ++checked;
  if ((std::memcmp(&want, &got, sizeof want) != 0 ||
       std::memcmp(&want, &got_v, sizeof want) != 0) &&
      ++bad <= 10)
    std::printf("FAIL: fma(%a, %a, %a) = %a, FmaFromDouble gives %a (vector: %a)\n", a, b, c, want,
                got, got_v);
}

}  // namespace

int main() {
  std::mt19937_64 rng(1);
  std::uniform_int_distribution<int> expo(-60, 60), sign(0, 1);
  std::uniform_real_distribution<float> mant(1.0f, 2.0f);
  auto random_float = [&] {
    const float m = std::ldexp(mant(rng), expo(rng));
    return sign(rng) ? -m : m;
  };
  for (int k = 0; k < 2000000; ++k) Check(random_float(), random_float(), random_float());
  // Sums that cancel: c near -a b.
  for (int k = 0; k < 500000; ++k) {
    const float a = random_float(), b = random_float();
    Check(a, b, -static_cast<float>(static_cast<double>(a) * b) * (1.0f + 1e-7f * (k % 7)));
  }
  // a b = (1 + i 2^-12)(1 + j 2^-12) = 1 + (i + j) 2^-12 + i j 2^-24: for odd
  // i j, exactly half an ulp (2^-23) above a float; an addend of 2^-60 ..
  // 2^-100 of either sign decides the rounding, but is lost when the double
  // sum rounds to nearest.
  int midpoints = 0;
  for (int i = 1; i < 400; i += 2)
    for (int j = 1; j < 400; j += 2)
      for (int e = 60; e <= 100; e += 20)
        for (int sc = -8; sc <= 8; sc += 4) {
          const float a = std::ldexp(1.0f + std::ldexp(static_cast<float>(i), -12), sc);
          const float b = 1.0f + std::ldexp(static_cast<float>(j), -12);
          for (float s : {1.0f, -1.0f}) {
            const float c = s * std::ldexp(1.0f, sc - e);
            const float nearest = static_cast<float>(static_cast<double>(a) * b + c);
            midpoints += nearest != std::fma(a, b, c);
            Check(a, b, c);
            Check(-a, b, -c);
          }
        }
  std::printf(
      "%ld triples checked; %d of the midpoint cases are ones that double rounding "
      "gets wrong\n",
      checked, midpoints);
  if (midpoints == 0) {
    std::printf("FAIL: no midpoint case exercises the rounding to odd\n");
    ++bad;
  }
  std::printf("%s: %d failure(s)\n", bad ? "FAIL" : "PASS", bad);
  return bad ? 1 : 0;
}
