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

// Zero every array of f on the cells [a, b) (flat indices; none if a >= b).
inline void ZeroCells(TractionField* f, size_t a, size_t b) {
  if (a >= b) return;
  for (auto* v : {&f->pressure_pa, &f->shear_x_pa, &f->shear_y_pa})
    std::fill(v->begin() + a, v->begin() + b, 0.0);
  for (auto* v : {&f->pressure, &f->shear_x, &f->shear_y})
    std::fill(v->begin() + a, v->begin() + b, 0.0f);
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
