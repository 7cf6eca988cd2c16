// Standalone check of FftPlan::Transform (plugin/core/common/fft.*) on sizes
// whose plans use the fused radix-6 (2 x 3) and radix-9 (3 x 3) stages in
// every position (first with and without the half-input skip, middle, last
// in place and not), forward and inverse, float and double, against a
// naive DFT in long double:
// - normwise ||y - Y||_2 / ||Y||_2 <= 5 eps log2(n) (eps: T's unit
//   roundoff; Cooley-Tukey's error grows like eps log2 n with rounded
//   twiddles, the constant covering the twiddles' and butterflies' own
//   roundings; measured <= 0.5 eps log2 n);
// - `needed` (outputs k < needed) and `scale` (inputs times a real factor)
//   give the full transform's values;
// - each lane's bits do not depend on the batch (lane 0 of batch 1, the
//   scalar loop, equals lane 0 of batch 13, the vectorised one).
//   ./test_fft_radix   # PASS/FAIL lines, exit status 1 on failure
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "common/fft.h"

using namespace mjtouch;

namespace {

int failures = 0;
double worst_ratio = 0.0;  // measured error / (eps log2 n)

void Check(bool ok, const char* what, int n, const char* prec, bool inverse, double value = 0) {
  if (!ok) {
    ++failures;
    std::printf("FAIL: %s (n %d, %s, %s) %g\n", what, n, prec, inverse ? "inverse" : "forward",
                value);
  }
}

// X[k] = sum_j x[j] exp(-+2 pi i j k / n), long double, the exponent's
// j k reduced mod n (exact angles).
void NaiveDft(const std::vector<long double>& xr, const std::vector<long double>& xi, bool inverse,
              std::vector<long double>* yr, std::vector<long double>* yi) {
  const int n = static_cast<int>(xr.size());
  const long double pi = 3.141592653589793238462643383279502884L;
  yr->assign(n, 0.0L);
  yi->assign(n, 0.0L);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j) {
      const long double a = (inverse ? 2.0L : -2.0L) * pi *
                            static_cast<long double>((static_cast<long long>(j) * k) % n) / n;
      const long double c = std::cos(a), s = std::sin(a);
      (*yr)[k] += xr[j] * c - xi[j] * s;
      (*yi)[k] += xr[j] * s + xi[j] * c;
    }
}

template <typename T>
void CheckSize(int n, bool inverse, bool half, std::mt19937_64* rng, const char* prec) {
  const FftPlan plan(n);
  const int batch = 13, stride = 24;  // 13 lanes: vector body and scalar tail
  const int nonzero = half ? n / 2 : -1;
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  std::vector<T> re(static_cast<size_t>(n) * stride, T(0)), im(re.size(), T(0));
  std::vector<T> k(re.size());
  for (int e = 0; e < n; ++e)
    for (int b = 0; b < batch; ++b) {
      if (!half || e < n / 2) {
        re[static_cast<size_t>(e) * stride + b] = static_cast<T>(U(*rng));
        im[static_cast<size_t>(e) * stride + b] = static_cast<T>(U(*rng));
      }
      k[static_cast<size_t>(e) * stride + b] = static_cast<T>(U(*rng));
    }
  const std::vector<T> in_re = re, in_im = im;
  std::vector<T> sre(static_cast<size_t>(n) * stride), sim(sre.size());
  plan.Transform(re.data(), im.data(), batch, stride, inverse, sre.data(), sim.data(), nonzero);
  const double eps = std::numeric_limits<T>::epsilon() / 2;
  const double tol = 5.0 * eps * std::max(1.0, std::log2(static_cast<double>(n)));
  std::vector<long double> xr(n), xi(n), yr, yi;
  for (int b = 0; b < batch; ++b) {
    for (int e = 0; e < n; ++e) {
      xr[e] = in_re[static_cast<size_t>(e) * stride + b];
      xi[e] = in_im[static_cast<size_t>(e) * stride + b];
    }
    NaiveDft(xr, xi, inverse, &yr, &yi);
    long double err = 0.0L, norm = 0.0L;
    for (int e = 0; e < n; ++e) {
      const long double dr = re[static_cast<size_t>(e) * stride + b] - yr[e];
      const long double di = im[static_cast<size_t>(e) * stride + b] - yi[e];
      err += dr * dr + di * di;
      norm += yr[e] * yr[e] + yi[e] * yi[e];
    }
    const double rel = static_cast<double>(std::sqrt(err / norm));
    worst_ratio = std::max(worst_ratio, rel / (eps * std::max(1.0, std::log2(double(n)))));
    Check(rel <= tol, "differs from the naive DFT", n, prec, inverse, rel);
  }
  // Lane 0 alone (batch 1): the same bits.
  std::vector<T> r1(static_cast<size_t>(n) * 8), i1(r1.size());
  for (int e = 0; e < n; ++e) {
    r1[static_cast<size_t>(e) * 8] = in_re[static_cast<size_t>(e) * stride];
    i1[static_cast<size_t>(e) * 8] = in_im[static_cast<size_t>(e) * stride];
  }
  plan.Transform(r1.data(), i1.data(), 1, 8, inverse, sre.data(), sim.data(), nonzero);
  bool same = true;
  for (int e = 0; e < n; ++e)
    same = same &&
           std::memcmp(&r1[static_cast<size_t>(e) * 8], &re[static_cast<size_t>(e) * stride],
                       sizeof(T)) == 0 &&
           std::memcmp(&i1[static_cast<size_t>(e) * 8], &im[static_cast<size_t>(e) * stride],
                       sizeof(T)) == 0;
  Check(same, "batch 1 != lane 0 of batch 13", n, prec, inverse);
  if (half) return;
  // needed (outputs k < 2n/5, within every trailing stage's skip) and
  // scale: the values of the full transform of the scaled input.
  std::vector<T> pr = in_re, pi = in_im, qr = in_re, qi = in_im;
  const int needed = 2 * n / 5;
  plan.Transform(pr.data(), pi.data(), batch, stride, inverse, sre.data(), sim.data(), -1, needed);
  for (size_t e = 0; e < qr.size(); ++e) {
    qr[e] = in_re[e] * k[e];
    qi[e] = in_im[e] * k[e];
  }
  std::vector<T> sr2 = in_re, si2 = in_im;
  plan.Transform(qr.data(), qi.data(), batch, stride, inverse, sre.data(), sim.data());
  plan.Transform(sr2.data(), si2.data(), batch, stride, inverse, sre.data(), sim.data(), -1, -1,
                 k.data(), stride);
  bool part = true, scaled = true;
  for (int e = 0; e < n; ++e)
    for (int b = 0; b < batch; ++b) {
      const size_t i = static_cast<size_t>(e) * stride + b;
      if (e < needed) part = part && pr[i] == re[i] && pi[i] == im[i];
      scaled = scaled && sr2[i] == qr[i] && si2[i] == qi[i];
    }
  Check(part, "needed outputs differ from the full transform's", n, prec, inverse);
  Check(scaled, "scale differs from scaling beforehand", n, prec, inverse);
}

}  // namespace

int main() {
  std::mt19937_64 rng(11);
  // Plans (fft.cc): 6 [6], 9 [9], 18 [6 3], 27 [9 3], 36 [4 9],
  // 54 [6 9], 90 [6 3 5], 108 [4 9 3], 144 [4 4 9], 150 [6 5 5],
  // 162 [6 9 3], 180 [4 9 5]; 32 [4 8], 96 [4 8 3], 160 [4 8 5] (half
  // input: FirstStages4Half8) and 30 [6 5] for the others.
  const int sizes[] = {6, 9, 18, 27, 30, 32, 36, 54, 90, 96, 108, 144, 150, 160, 162, 180};
  int checked = 0;
  for (int n : sizes)
    for (int inverse = 0; inverse < 2; ++inverse)
      for (int half = 0; half < 2; ++half) {
        CheckSize<float>(n, inverse, half, &rng, "float");
        CheckSize<double>(n, inverse, half, &rng, "double");
        checked += 2;
      }
  std::printf("%d transforms against a naive DFT; worst error %.2f eps log2 n\n", checked,
              worst_ratio);
  std::printf("%s: %d failure(s)\n", failures ? "FAIL" : "PASS", failures);
  return failures ? 1 : 0;
}
