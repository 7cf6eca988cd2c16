// Internal to contact/ (pressure.cc, winkler.cc): cell-range helpers on a
// TractionField's arrays, so that the clear of a support and the scan for
// runs of loaded cells are written once.
#ifndef MJTOUCH_CONTACT_TRACTION_CELLS_H_
#define MJTOUCH_CONTACT_TRACTION_CELLS_H_

#include <algorithm>
#include <cstddef>

#include "contact/pressure.h"

namespace mjtouch {

// Whether every array of f has the grid's size.
inline bool TractionSized(const TaxelGrid& grid, const TractionField& f) {
  const size_t N = grid.Size();
  return f.pressure_pa.size() == N && f.shear_x_pa.size() == N && f.shear_y_pa.size() == N &&
         f.pressure.size() == N && f.shear_x.size() == N && f.shear_y.size() == N;
}

// Groups of a TractionField's arrays (bit masks for ZeroCells).
enum : unsigned {
  kPressureD = 1,  // pressure_pa
  kPressureF = 2,  // pressure (float)
  kShearD = 4,     // shear_x_pa, shear_y_pa
  kShearF = 8,     // shear_x, shear_y (float)
  kAllArrays = 15
};

// The arrays of f that may hold nonzero values (not left lazily zero).
inline unsigned HeldArrays(const TractionField& f) {
  return kPressureF | (f.lazy_pressure_pa ? 0u : kPressureD) |
         (f.lazy_shear ? 0u : kShearD | kShearF);
}

// Zero the arrays of f in `arrays` on the cells [a, b) (flat indices; none if
// a >= b).
inline void ZeroCells(TractionField* f, size_t a, size_t b, unsigned arrays = kAllArrays) {
  if (a >= b) return;
  if (arrays & kPressureD) std::fill(f->pressure_pa.begin() + a, f->pressure_pa.begin() + b, 0.0);
  if (arrays & kPressureF) std::fill(f->pressure.begin() + a, f->pressure.begin() + b, 0.0f);
  if (arrays & kShearD)
    for (auto* v : {&f->shear_x_pa, &f->shear_y_pa}) std::fill(v->begin() + a, v->begin() + b, 0.0);
  if (arrays & kShearF)
    for (auto* v : {&f->shear_x, &f->shear_y}) std::fill(v->begin() + a, v->begin() + b, 0.0f);
}

// Marks f's shear as full slip (shear = ratio x pressure, ratio = tangential
// / normal force; zero without normal force) and sets the ratios.
inline void SetUniformSlip(double fn, double fx, double fy, TractionField* f) {
  f->uniform_slip = true;
  f->slip_x = fn > 0.0 ? fx / fn : 0.0;
  f->slip_y = fn > 0.0 ? fy / fn : 0.0;
}

// Calls run(begin, end) for each maximal run [begin, end) of the cells i in
// [i0, i1) with on(i), left to right. on must be pure: it may be called
// twice on a cell that ends a run.
template <typename On, typename Run>
inline void ForEachRun(int i0, int i1, On&& on, Run&& run) {
  for (int i = i0; i < i1;) {
    while (i < i1 && !on(i)) ++i;
    if (i == i1) break;
    const int begin = i;
    while (i < i1 && on(i)) ++i;
    run(begin, i);
  }
}

}  // namespace mjtouch

#endif  // MJTOUCH_CONTACT_TRACTION_CELLS_H_
