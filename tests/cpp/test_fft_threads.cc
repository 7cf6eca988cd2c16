// Standalone check of Fft2D::ConvolveReal (plugin/core/common/fft.*), the
// compliance operator's convolution that the `elastic` solve runs on the
// `threads` pool: on box shapes even and odd (1 to 3 parts per pass, inputs
// pruned to fewer rows / columns as the box check does), float and double,
// - threads 2, 3 and 4 give the bits of threads 1 (the parts write disjoint
//   memory and each lane's arithmetic does not depend on the split);
// - the result is the linear (non-wrapping) convolution with the kernel,
//   against a direct sum: relative to the output's largest value 1e-13
//   (double; measured <= 8e-15) and 2e-6 (float spectra; measured <= 3e-7).
//   ./test_fft_threads   # PASS/FAIL lines, exit status 1 on failure
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <vector>

#include "common/fft.h"

using namespace mjtouch;

namespace {

// A real kernel even in both axes (the compliance's symmetry), decaying
// like 1 / r.
double Kernel(int dx, int dy) { return 1.0 / std::sqrt(1.0 + dx * dx + dy * dy); }

int failures = 0;

void Check(bool ok, const char* what, int bx, int by, int rows, int cols, const char* prec,
           double value = 0) {
  if (!ok) {
    ++failures;
    std::printf("FAIL: %s (box %d x %d, input %d x %d, %s) %g\n", what, bx, by, rows, cols, prec,
                value);
  }
}

template <typename T>
void CheckShape(int bx, int by, int rows, int cols, std::mt19937_64* rng, const char* prec) {
  const int mx = NextFftSize(2 * bx - 1), my = NextFftSize(2 * by - 1);
  const Fft2D fft(mx, my);
  // The kernel on the mx x my torus and its half spectrum (normalised).
  std::vector<double> kr(static_cast<size_t>(mx) * my);
  for (int y = 0; y < my; ++y)
    for (int x = 0; x < mx; ++x)
      kr[static_cast<size_t>(y) * mx + x] =
          Kernel(x <= mx / 2 ? x : x - mx, y <= my / 2 ? y : y - my);
  std::vector<double> sre(fft.spectrum_size()), sim(fft.spectrum_size()), scratch;
  fft.ForwardReal(kr.data(), mx, my, mx, sre.data(), sim.data(), &scratch);
  std::vector<T> k_hat(fft.spectrum_size());
  for (size_t k = 0; k < k_hat.size(); ++k)
    k_hat[k] = static_cast<T>(sre[k] / (static_cast<double>(mx) * my));
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::vector<double> in(static_cast<size_t>(bx) * by, 0.0);
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < cols; ++x) in[static_cast<size_t>(y) * bx + x] = U(*rng);
  std::vector<T> spec_re(fft.spectrum_size()), spec_im(fft.spectrum_size()), work;
  std::vector<std::vector<double>> out(5, std::vector<double>(in.size(), -1.0));
  for (int threads = 1; threads <= 4; ++threads)
    fft.ConvolveReal(in.data(), bx, rows, cols, k_hat.data(), by, bx, out[threads].data(), bx,
                     spec_re.data(), spec_im.data(), &work, threads);
  for (int threads = 2; threads <= 4; ++threads)
    Check(std::memcmp(out[1].data(), out[threads].data(), in.size() * sizeof(double)) == 0,
          threads == 2   ? "threads 2 != threads 1"
          : threads == 3 ? "threads 3 != threads 1"
                         : "threads 4 != threads 1",
          bx, by, rows, cols, prec);
  // The direct sum.
  double worst = 0.0, scale = 0.0;
  for (int y = 0; y < by; ++y)
    for (int x = 0; x < bx; ++x) {
      double s = 0.0;
      for (int v = 0; v < rows; ++v)
        for (int u = 0; u < cols; ++u)
          s += in[static_cast<size_t>(v) * bx + u] * Kernel(x - u, y - v);
      scale = std::max(scale, std::abs(s));
      worst = std::max(worst, std::abs(s - out[1][static_cast<size_t>(y) * bx + x]));
    }
  const double tol = sizeof(T) == 8 ? 1e-13 : 2e-6;
  Check(worst <= tol * scale, "differs from the direct convolution", bx, by, rows, cols, prec,
        worst / scale);
}

}  // namespace

int main() {
  std::mt19937_64 rng(7);
  // (bx, by, input rows, input cols): the solve's boxes, odd sizes, a
  // pruned input (the box check), boxes too small to split
  const int shapes[][4] = {{79, 74, 74, 79}, {76, 70, 70, 76}, {75, 71, 71, 75},
                           {33, 20, 20, 33}, {40, 50, 37, 29}, {92, 82, 74, 79},
                           {7, 9, 9, 7},     {3, 2, 2, 3},     {1, 5, 5, 1}};
  int checked = 0;
  for (const auto& s : shapes) {
    CheckShape<float>(s[0], s[1], s[2], s[3], &rng, "float");
    CheckShape<double>(s[0], s[1], s[2], s[3], &rng, "double");
    checked += 2;
  }
  std::printf("%d shapes x 2 precisions, threads 1-4 against each other and a direct sum\n",
              checked / 2);
  std::printf("%s: %d failure(s)\n", failures ? "FAIL" : "PASS", failures);
  return failures ? 1 : 0;
}
