// Internal to the surface stage (not part of its interface): RenderGap's
// fast path for faces whose axes are the pad's (aligned_face.cc), and the
// helpers it shares with render.cc and primitives.cc.
#ifndef MJTOUCH_SURFACE_ALIGNED_FACE_H_
#define MJTOUCH_SURFACE_ALIGNED_FACE_H_

#include <algorithm>
#include <limits>
#include <vector>

#include "surface/surface.h"

namespace mjtouch {
namespace surface_detail {

inline double Overlap1D(double a0, double a1, double b0, double b1) {
  return std::max(0.0, std::min(a1, b1) - std::max(a0, b0));
}

// Integral from 0 to s (grid units, 0 <= s <= ncol - 1) of row r's linear
// interpolant, from the running integrals.
inline double RowIntegral(const CounterSurface& s, int r, double x) {
  const float* h = s.samples + static_cast<size_t>(r) * s.ncol;
  const double* P = s.row_prefix + static_cast<size_t>(r) * s.ncol;
  int c = static_cast<int>(x);
  c = std::clamp(c, 0, s.ncol - 2);
  const double f = x - c;
  return P[c] + f * h[c] + 0.5 * f * f * (double(h[c + 1]) - h[c]);
}

// Fast path for a face (plane, rectangle, height field) whose x and y axes
// are the pad's up to sign and scale (R = S^T P mixes no axes in its first
// two rows): a pad sliding over a level texture. A cell's footprint in the
// surface frame then depends on its column alone in x and on its row alone
// in y, so the coverage factors and, for a height field whose rows are all
// equal (gratings), the texture's cell mean are computed once per column or
// row and broadcast. Values equal the general path's bit for bit: the terms
// left out are exact zeros (0 * finite), which can change only the sign of
// a zero, and the next subtraction of a nonzero half width removes it.
bool IsAlignedFace(const CounterSurface& s, const double R[9], double hx, double hy);

struct AlignedFace {
  const CounterSurface& s;
  const double* R;  // pad frame -> surface frame
  const double* t;  // pad origin in the surface frame
  double hx, hy;    // half extents of a cell's footprint (surface frame)
  double cull;      // cells whose gap lower bound exceeds it are skipped
  // The per-column and per-row values; those of a face are reused by the
  // next call on it in the same RenderGap call (which resets the key).
  RenderScratch* scratch;
};

struct Extent {
  CellBounds cells;
  bool wrote = false;  // some cell written
};

// Running extrema of the covered cells (coverage > 0, finite gap), in four
// lanes (RenderSummary).
struct Extrema {
  static constexpr double kInf = std::numeric_limits<double>::infinity();
  double lo[4] = {kInf, kInf, kInf, kInf}, hi[4] = {0, 0, 0, 0};
};

// Renders the face into gap_m / coverage; `covers_only`: renders nothing
// and returns whether every cell mean within reach is known per column and
// >= 0 (so the texture's gap is at most its base plane's everywhere).
bool RenderAlignedFace(const TaxelGrid& grid, const std::vector<double>& skin_z,
                       const AlignedFace& f, const SkinBlocks& blocks, const double* block_lb,
                       double* gap_m, double* coverage, Extent* ext, bool covers_only = false,
                       Extrema* extrema = nullptr, ActiveRuns* spans = nullptr,
                       CellBox* overwrite = nullptr);

}  // namespace surface_detail
}  // namespace mjtouch

#endif  // MJTOUCH_SURFACE_ALIGNED_FACE_H_
