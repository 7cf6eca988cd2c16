// The matrix exponential of a small matrix (matrix_exp.h).
#include "afferents/matrix_exp.h"

#include <algorithm>
#include <cmath>

namespace mjtouch {

void Expm(int m, const double* A, double* E) {
  double norm = 0.0;
  for (int i = 0; i < m; ++i) {
    double row = 0.0;
    for (int j = 0; j < m; ++j) row += std::abs(A[i * m + j]);
    norm = std::max(norm, row);
  }
  int squarings = 0;
  while (norm > 0.25 && squarings < 1000) {
    norm *= 0.5;
    ++squarings;
  }
  const double scale = std::ldexp(1.0, -squarings);
  double X[25], T[25], tmp[25];
  for (int i = 0; i < m * m; ++i) X[i] = A[i] * scale;
  for (int i = 0; i < m * m; ++i) T[i] = E[i] = (i % (m + 1) == 0) ? 1.0 : 0.0;
  auto mul = [m](const double* P, const double* Q, double* R) {
    for (int i = 0; i < m; ++i)
      for (int j = 0; j < m; ++j) {
        double acc = 0.0;
        for (int k = 0; k < m; ++k) acc += P[i * m + k] * Q[k * m + j];
        R[i * m + j] = acc;
      }
  };
  for (int k = 1; k <= 16; ++k) {
    mul(T, X, tmp);
    for (int i = 0; i < m * m; ++i) {
      T[i] = tmp[i] / k;
      E[i] += T[i];
    }
  }
  for (int s = 0; s < squarings; ++s) {
    mul(E, E, tmp);
    std::copy(tmp, tmp + m * m, E);
  }
}

}  // namespace mjtouch
