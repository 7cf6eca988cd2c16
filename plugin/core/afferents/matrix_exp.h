// Internal to afferents/: the matrix exponential the receptor filters'
// exact propagators are built from (ReceptorStepper).
#ifndef MJTOUCH_AFFERENTS_MATRIX_EXP_H_
#define MJTOUCH_AFFERENTS_MATRIX_EXP_H_

namespace mjtouch {

// exp(A) of an m x m row-major matrix (m <= 5): scaling and squaring with a
// 16-term Taylor series (||A|| <= 1/4 after scaling: error < 1e-24).
void Expm(int m, const double* A, double* E);

}  // namespace mjtouch

#endif  // MJTOUCH_AFFERENTS_MATRIX_EXP_H_
