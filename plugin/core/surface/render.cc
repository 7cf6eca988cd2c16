// Stage 1's rendering: the gap between each taxel cell of the skin and the
// counter-surfaces (RenderGap), over blocks of skin cells (MakeSkinBlocks)
// culled by lower bounds; aligned faces through aligned_face.cc, the rest
// through the general per-cell code.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "surface/aligned_face.h"
#include "surface/mesh_surface.h"
#include "surface/primitives.h"
#include "surface/surface.h"

namespace mjtouch {

using namespace surface_detail;

SkinBlocks MakeSkinBlocks(const TaxelGrid& grid, const std::vector<double>& skin_z) {
  SkinBlocks sb;
  const int B = SkinBlocks::kSide;
  sb.n = grid.n;
  sb.nb = (grid.n + B - 1) / B;
  sb.zmin.assign(static_cast<size_t>(sb.nb) * sb.nb, kInf);
  sb.zmax.assign(static_cast<size_t>(sb.nb) * sb.nb, -kInf);
  for (int j = 0; j < grid.n; ++j)
    for (int i = 0; i < grid.n; ++i) {
      const double z = skin_z[static_cast<size_t>(j) * grid.n + i];
      if (!std::isfinite(z)) continue;
      const size_t b = static_cast<size_t>(j / B) * sb.nb + i / B;
      sb.zmin[b] = std::min(sb.zmin[b], z);
      sb.zmax[b] = std::max(sb.zmax[b], z);
    }
  return sb;
}

namespace {

// A counter-surface's frame seen from the pad.
struct SurfaceFrame {
  double R[9], t[3], hx, hy;
  double centre_pad[3];  // surface origin in the pad frame (line types)
  double radius;         // bounding sphere (line types)
  char path = 0;         // 0: not rendered, 1: aligned-face path, 2: general
};

SurfaceFrame FrameOf(const CounterSurface& s, const Pose& pad, double h) {
  SurfaceFrame F;
  // R = S^T P maps pad-frame vectors into the surface frame.
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      F.R[3 * r + c] = s.pose.mat[0 + r] * pad.mat[0 + c] + s.pose.mat[3 + r] * pad.mat[3 + c] +
                       s.pose.mat[6 + r] * pad.mat[6 + c];
  for (int r = 0; r < 3; ++r) {  // pad origin in the surface frame
    F.t[r] = 0.0;
    for (int c = 0; c < 3; ++c) F.t[r] += s.pose.mat[3 * c + r] * (pad.pos[c] - s.pose.pos[c]);
  }
  for (int c = 0; c < 3; ++c) {  // -R^T t
    F.centre_pad[c] = 0.0;
    for (int r = 0; r < 3; ++r) F.centre_pad[c] -= F.R[3 * r + c] * F.t[r];
  }
  F.radius = BoundRadius(s);
  // Axis-aligned half extents of a cell's footprint in the surface frame.
  F.hx = 0.5 * h * (std::abs(F.R[0]) + std::abs(F.R[1]));
  F.hy = 0.5 * h * (std::abs(F.R[3]) + std::abs(F.R[4]));
  return F;
}

// Lower bound of a cell's gap to surface s (+inf: cannot touch). Face
// types: the surface's highest point; line types: the top of the bounding
// sphere on the cell's line (h: the grid pitch).
inline __attribute__((always_inline)) double CellLowerBound(const CounterSurface& s,
                                                            const SurfaceFrame& F, double h,
                                                            double u, double v, double z) {
  if (IsLineType(s.type)) {
    const double dx = u - F.centre_pad[0], dy = v - F.centre_pad[1];
    const double e = F.radius + h;  // the whole cell, not only its centre
    const double q = e * e - dx * dx - dy * dy;
    if (q < 0.0) return kInf;
    return z - (F.centre_pad[2] + std::sqrt(q));
  }
  const double qz = F.t[2] + F.R[6] * u + F.R[7] * v + F.R[8] * z;
  return qz - s.max_height_m;
}

// f(i, j, index, u, v, z) for the skin cells of block b (nb blocks a side).
template <typename F>
inline __attribute__((always_inline)) void ForBlockCells(const TaxelGrid& grid,
                                                         const std::vector<double>& skin_z, int nb,
                                                         int b, F&& f) {
  const int B = SkinBlocks::kSide;
  const int bi = b % nb, bj = b / nb;
  for (int j = bj * B; j < std::min(grid.n, bj * B + B); ++j) {
    const double v = grid.Centre(j);
    for (int i = bi * B; i < std::min(grid.n, bi * B + B); ++i) {
      const size_t idx = static_cast<size_t>(j) * grid.n + i;
      const double z = skin_z[idx];
      if (std::isfinite(z)) f(i, j, idx, grid.Centre(i), v, z);
    }
  }
}

// Whether no cell of a block (centres u0..u1 x v0..v1, heights zmin..zmax)
// has a footprint overlapping a bounded face's extent along the face's axis
// `axis` (0: x, half extent `half`): its cells' coverage is then 0 and
// they take nothing (a parked texture beside the pad). The range of the
// footprint's centre widened by its half extent and kOffFaceMarginM, far
// above the rounding of the per-cell coordinates.
constexpr double kOffFaceMarginM = 1e-9;

bool OffFace(const SurfaceFrame& F, int axis, double half, double u0, double u1, double v0,
             double v1, double zmin, double zmax) {
  const double* r = F.R + 3 * axis;
  const double lo = F.t[axis] + std::min(r[0] * u0, r[0] * u1) + std::min(r[1] * v0, r[1] * v1) +
                    std::min(r[2] * zmin, r[2] * zmax);
  const double hi = F.t[axis] + std::max(r[0] * u0, r[0] * u1) + std::max(r[1] * v0, r[1] * v1) +
                    std::max(r[2] * zmin, r[2] * zmax);
  const double reach = (axis == 0 ? F.hx : F.hy) + kOffFaceMarginM;
  return hi + reach <= -half || lo - reach >= half;
}

// Per surface k and block b, a lower bound of the block's cells' lower
// bounds (block_lb[k * nb^2 + b]; +inf: no skin cell or out of reach), so
// that whole blocks out of reach are skipped.
void BlockLowerBounds(const TaxelGrid& grid, const SkinBlocks& blocks,
                      const std::vector<CounterSurface>& surfaces,
                      const std::vector<SurfaceFrame>& frames, std::vector<double>* block_lb) {
  const double h = grid.pitch_m;
  const int B = SkinBlocks::kSide, nb = blocks.nb;
  block_lb->assign(surfaces.size() * nb * nb, kInf);
  for (size_t k = 0; k < surfaces.size(); ++k) {
    const SurfaceFrame& F = frames[k];
    const bool line = IsLineType(surfaces[k].type);
    const bool bounded = surfaces[k].type == CounterSurface::Type::kRectangle ||
                         surfaces[k].type == CounterSurface::Type::kHeightField;
    for (int bj = 0; bj < nb; ++bj)
      for (int bi = 0; bi < nb; ++bi) {
        const size_t b = static_cast<size_t>(bj) * nb + bi;
        const double zmin = blocks.zmin[b], zmax = blocks.zmax[b];
        if (!std::isfinite(zmin)) continue;
        const double u0 = grid.Centre(bi * B), u1 = grid.Centre(std::min(grid.n, bi * B + B) - 1);
        const double v0 = grid.Centre(bj * B), v1 = grid.Centre(std::min(grid.n, bj * B + B) - 1);
        double lb;
        if (line) {
          const double dx = std::max({0.0, u0 - F.centre_pad[0], F.centre_pad[0] - u1});
          const double dy = std::max({0.0, v0 - F.centre_pad[1], F.centre_pad[1] - v1});
          const double e = F.radius + h;
          const double q = e * e - dx * dx - dy * dy;
          lb = q < 0.0 ? kInf : zmin - (F.centre_pad[2] + std::sqrt(q));
        } else {
          lb = F.t[2] + std::min(F.R[6] * u0, F.R[6] * u1) + std::min(F.R[7] * v0, F.R[7] * v1) +
               (F.R[8] >= 0.0 ? F.R[8] * zmin : F.R[8] * zmax) - surfaces[k].max_height_m;
          if (bounded && OffFace(F, 0, surfaces[k].half_x_m, u0, u1, v0, v1, zmin, zmax)) lb = kInf;
          if (bounded && OffFace(F, 1, surfaces[k].half_y_m, u0, u1, v0, v1, zmin, zmax)) lb = kInf;
        }
        (*block_lb)[k * nb * nb + b] = lb;
      }
  }
}

// The smallest lower bound of any cell's gap: exact over the blocks whose
// bound could hold it, best block first.
double SmallestLowerBound(const RenderRequest& req, const std::vector<SurfaceFrame>& frames, int nb,
                          const std::vector<double>& block_lb) {
  double lb_min = kInf;
  size_t first = 0;
  for (size_t e = 1; e < block_lb.size(); ++e)
    if (block_lb[e] < block_lb[first]) first = e;
  for (size_t pass = 0; pass <= block_lb.size(); ++pass) {
    const size_t e = pass == 0 ? first : pass - 1;
    if (pass > 0 && e == first) continue;
    if (!(block_lb[e] < lb_min)) continue;
    const size_t k = e / (nb * nb);
    ForBlockCells(req.grid, req.skin_z, nb, static_cast<int>(e % (nb * nb)),
                  [&](int, int, size_t, double u, double v, double z) {
                    lb_min = std::min(lb_min, CellLowerBound(req.surfaces[k], frames[k],
                                                             req.grid.pitch_m, u, v, z));
                  });
  }
  return lb_min;
}

// Whether surface k + 1 is a height field on rectangle k: the same frame
// (bit for bit), extents and reach, equal rows (per-column means).
bool TextureOnFace(const std::vector<CounterSurface>& surfaces,
                   const std::vector<SurfaceFrame>& frames, size_t k) {
  const CounterSurface &a = surfaces[k], &b = surfaces[k + 1];
  const SurfaceFrame &Fa = frames[k], &Fb = frames[k + 1];
  return a.type == CounterSurface::Type::kRectangle &&
         b.type == CounterSurface::Type::kHeightField && b.rows_identical && b.row_prefix &&
         b.elevation_m >= 0.0 && a.half_x_m == b.half_x_m && a.half_y_m == b.half_y_m &&
         a.max_height_m <= b.max_height_m && std::memcmp(Fa.R, Fb.R, sizeof(Fa.R)) == 0 &&
         std::memcmp(Fa.t, Fb.t, sizeof(Fa.t)) == 0 && Fa.hx == Fb.hx && Fa.hy == Fb.hy;
}

// Surface k through the general per-cell code: each cell within reach of
// the cull level whose gap is below the one held takes this surface's gap
// and coverage (and extends *cells). Returns whether any cell was written.
bool RenderGeneralSurface(const RenderRequest& req, size_t k, const SurfaceFrame& F, int nb,
                          const double* block_lb, double cull, double* gap_m, double* coverage,
                          CellBounds* cells) {
  const CounterSurface& s = req.surfaces[k];
  const bool area_average = req.area_average;
  const double h = req.grid.pitch_m;
  const double g = area_average ? 0.5 * h / std::sqrt(3.0) : 0.0;
  const double* R = F.R;
  const double area = 4.0 * F.hx * F.hy;
  const bool line = IsLineType(s.type);
  bool wrote = false;
  // The pad's z axis in the surface frame.
  const double d_loc[3] = {R[2], R[5], R[8]};
  for (int b = 0; b < nb * nb; ++b) {
    if (!(block_lb[b] <= cull)) continue;
    ForBlockCells(
        req.grid, req.skin_z, nb, b, [&](int i, int j, size_t idx, double u, double v, double z) {
          if (CellLowerBound(s, F, h, u, v, z) > cull) return;
          double cov = 1.0, gap;
          if (line) {
            if (s.type == CounterSurface::Type::kRay) {  // mesh_surface.cc
              if (!RayCellGap(s, req.pad_pose, u, v, z, h, area_average ? kRayCellSide : 1, &gap,
                              &cov))
                return;
            } else {
              double top_sum = 0.0;
              int hits = 0;
              const int np = area_average ? 2 : 1;
              for (int a = 0; a < np; ++a) {
                for (int b = 0; b < np; ++b) {
                  const double x = u + (area_average ? (a ? g : -g) : 0.0);
                  const double y = v + (area_average ? (b ? g : -g) : 0.0);
                  const double o[3] = {F.t[0] + R[0] * x + R[1] * y, F.t[1] + R[3] * x + R[4] * y,
                                       F.t[2] + R[6] * x + R[7] * y};
                  // The body indents the skin here only if it reaches the
                  // skin's surface along the column (lo <= z): one lying
                  // wholly above it is inside the pad beside the patch (on
                  // the fingertip's side or back), where the skin is not,
                  // and MuJoCo's contact with it is off the patch.
                  double lo, hi;
                  if (LineInterval(s, o, d_loc, &lo, &hi) && lo <= z) {
                    top_sum += hi;
                    ++hits;
                  }
                }
              }
              if (hits == 0) return;
              cov = static_cast<double>(hits) / (np * np);
              gap = z - top_sum / hits;
            }
          } else {
            const double qz = F.t[2] + R[6] * u + R[7] * v + R[8] * z;
            const double qx = F.t[0] + R[0] * u + R[1] * v + R[2] * z;
            const double qy = F.t[1] + R[3] * u + R[4] * v + R[5] * z;
            gap = qz;
            if (s.type != CounterSurface::Type::kPlane) {
              const double hx = area_average ? F.hx : 0.0, hy = area_average ? F.hy : 0.0;
              if (area_average) {
                const double ox = Overlap1D(qx - hx, qx + hx, -s.half_x_m, s.half_x_m);
                const double oy = Overlap1D(qy - hy, qy + hy, -s.half_y_m, s.half_y_m);
                cov = area > 0 ? ox * oy / area : 0.0;
              } else {
                cov = (std::abs(qx) <= s.half_x_m && std::abs(qy) <= s.half_y_m) ? 1.0 : 0.0;
              }
              if (cov <= 0.0) return;
              if (s.type == CounterSurface::Type::kHeightField) {
                const double x0 = std::max(qx - hx, -s.half_x_m);
                const double x1 = std::min(qx + hx, s.half_x_m);
                const double y0 = std::max(qy - hy, -s.half_y_m);
                const double y1 = std::min(qy + hy, s.half_y_m);
                gap = qz - HeightFieldBoxMean(s, x0, x1, y0, y1);
              }
            }
          }
          if (gap < gap_m[idx]) {
            gap_m[idx] = gap;
            coverage[idx] = cov;
            wrote = true;
            cells->Add(i, j);
          }
        });
  }
  return wrote;
}

}  // namespace

double RenderGap(const RenderRequest& req, const RenderOutput& out) {
  const TaxelGrid& grid = req.grid;
  const std::vector<double>& skin_z = req.skin_z;
  const std::vector<CounterSurface>& surfaces = req.surfaces;
  std::vector<double>* gap_m = out.gap_m;
  std::vector<double>* coverage = out.coverage;
  RenderSummary* summary = out.summary;
  RenderScratch local_scratch;
  RenderScratch& scratch = out.scratch ? *out.scratch : local_scratch;
  scratch.columns_key = RenderScratch::ColumnKey{};  // column values reused within a call only
  const size_t N = grid.Size();
  Extrema extrema;
  int writers = 0, aligned_writers = 0;  // surfaces that wrote cells (RenderSummary)
  if (summary) {
    summary->valid = false;
    summary->spans.Clear();
  }
  // Cells [i0, i1) x [j0, j1) of the last result's box (`written`) back to
  // +inf / 0 (the rest of the grid holds them already).
  const bool reuse = out.written && gap_m->size() == N && coverage->size() == N;
  const CellBox last = reuse ? *out.written : CellBox{};
  auto clear_last = [&](int i0, int i1, int j0, int j1) {
    i0 = std::max(i0, last.i0);
    i1 = std::min(i1, last.i0 + last.nx);
    for (int j = std::max(j0, last.j0); j < std::min(j1, last.j0 + last.ny) && i0 < i1; ++j) {
      const size_t a = static_cast<size_t>(j) * grid.n;
      std::fill(gap_m->begin() + a + i0, gap_m->begin() + a + i1, kInf);
      std::fill(coverage->begin() + a + i0, coverage->begin() + a + i1, 0.0);
    }
  };
  if (!reuse) {
    gap_m->assign(N, kInf);
    coverage->assign(N, 0.0);
  }
  std::vector<SurfaceFrame> frames(surfaces.size());
  for (size_t k = 0; k < surfaces.size(); ++k)
    frames[k] = FrameOf(surfaces[k], req.pad_pose, grid.pitch_m);
  SkinBlocks local_blocks;
  const SkinBlocks* blocks = req.blocks;
  if (!blocks || blocks->n != grid.n) {
    local_blocks = MakeSkinBlocks(grid, skin_z);
    blocks = &local_blocks;
  }
  const int nb = blocks->nb;
  std::vector<double>& block_lb = scratch.block_lb;
  BlockLowerBounds(grid, *blocks, surfaces, frames, &block_lb);
  // The cull level is relative to the smallest lower bound of any cell.
  const double cull = std::isfinite(req.cull_above_m)
                          ? SmallestLowerBound(req, frames, nb, block_lb) + req.cull_above_m
                          : kInf;
  // Which surfaces render (0: none, 1: aligned-face path, 2: general) and
  // how many have cells within reach. If one alone does, through the
  // aligned path, it overwrites its rectangle and only the rest of the last
  // box is cleared (exclusive); else the last box is cleared first.
  int reaching = 0, exclusive = -1;
  for (size_t k = 0; k < surfaces.size(); ++k) {
    const SurfaceFrame& F = frames[k];
    const bool aligned =
        req.fast_paths && req.area_average && IsAlignedFace(surfaces[k], F.R, F.hx, F.hy);
    if (aligned && k + 1 < surfaces.size() && TextureOnFace(surfaces, frames, k)) {
      // A texture on this face (the plate proxy under its height field,
      // next in the list) whose cell means are all >= 0: its gap is never
      // above the face's and equal only with the same coverage, so the
      // face would change no cell's result.
      const SurfaceFrame& T = frames[k + 1];
      Extent none;
      if (RenderAlignedFace(grid, skin_z,
                            AlignedFace{surfaces[k + 1], T.R, T.t, T.hx, T.hy, cull, &scratch},
                            *blocks, &block_lb[(k + 1) * nb * nb], nullptr, nullptr, &none, true))
        continue;
    }
    frames[k].path = aligned ? 1 : 2;
    bool reach = false;
    for (int b = 0; b < nb * nb && !reach; ++b) reach = block_lb[k * nb * nb + b] <= cull;
    if (!reach) continue;
    ++reaching;
    exclusive = aligned ? static_cast<int>(k) : -1;
  }
  if (!(reuse && reaching == 1 && exclusive >= 0)) exclusive = -1;
  if (reuse && exclusive < 0) clear_last(0, grid.n, 0, grid.n);
  CellBounds cells;  // written
  for (size_t k = 0; k < surfaces.size(); ++k) {
    const SurfaceFrame& F = frames[k];
    if (F.path == 0) continue;
    if (F.path == 2) {
      writers += RenderGeneralSurface(req, k, F, nb, &block_lb[k * nb * nb], cull, gap_m->data(),
                                      coverage->data(), &cells);
      continue;
    }
    Extent ext{cells};
    CellBox rect;
    const bool own = static_cast<int>(k) == exclusive;
    RenderAlignedFace(grid, skin_z, AlignedFace{surfaces[k], F.R, F.t, F.hx, F.hy, cull, &scratch},
                      *blocks, &block_lb[k * nb * nb], gap_m->data(), coverage->data(), &ext, false,
                      summary && aligned_writers == 0 ? &extrema : nullptr,
                      summary ? &summary->spans : nullptr, own ? &rect : nullptr);
    if (own) {  // the last box outside the rectangle written
      const int ri1 = rect.i0 + rect.nx, rj1 = rect.j0 + rect.ny;
      if (rect.empty()) {
        clear_last(0, grid.n, 0, grid.n);
      } else {
        clear_last(0, grid.n, 0, rect.j0);
        clear_last(0, grid.n, rj1, grid.n);
        clear_last(0, rect.i0, rect.j0, rj1);
        clear_last(ri1, grid.n, rect.j0, rj1);
      }
    }
    cells = ext.cells;
    writers += ext.wrote;
    aligned_writers += ext.wrote;
  }
  if (summary && writers == 1 && aligned_writers == 1) {
    summary->valid = true;
    summary->gap_min_m =
        std::min(std::min(extrema.lo[0], extrema.lo[1]), std::min(extrema.lo[2], extrema.lo[3]));
    summary->coverage_max =
        std::max(std::max(extrema.hi[0], extrema.hi[1]), std::max(extrema.hi[2], extrema.hi[3]));
  }
  // Every cell written above is in this box (a write takes a gap below the
  // cell's, and extends the box).
  const CellBox box = cells.Box();
  if (out.rendered) *out.rendered = box;
  if (out.written) *out.written = box;
  return cull;
}

PatchFootprint MakePatchFootprint(const TaxelGrid& patch, const std::vector<double>& patch_z,
                                  const PadGeometry& pad, int cells) {
  const double* ax = pad.semi_axes_m;
  double bound;  // a sphere about the geom's centre (the skin's origin) holding the shape
  switch (pad.shape) {
    case PadShape::kCapsule: bound = ax[2]; break;
    case PadShape::kBox: bound = std::sqrt(ax[0] * ax[0] + ax[1] * ax[1] + ax[2] * ax[2]); break;
    case PadShape::kMesh: bound = pad.mesh ? pad.mesh->bound_radius_m : 0.0; break;
    default: bound = std::max({ax[0], ax[1], ax[2]});
  }
  // Cells of about 2 bound / cells whose edges fall on the patch's square
  // (a footprint cell lies wholly on or off it), and enough of them.
  const double half = patch.HalfExtent();
  bound = std::max(bound, half);
  const int per_half = std::max(1, static_cast<int>(std::ceil(half * cells / (2.0 * bound))));
  PatchFootprint fp;
  fp.grid.pitch_m = half / per_half;
  fp.grid.n = 2 * static_cast<int>(std::ceil(bound / fp.grid.pitch_m - 1e-9));
  fp.grid.offset_m = patch.offset_m;
  cells = fp.grid.n;
  Ridges smooth;
  smooth.enabled = false;
  fp.skin_z = SkinSurface(fp.grid, pad, smooth);
  fp.on_patch.assign(fp.grid.Size(), 0);
  for (int j = 0; j < cells; ++j)
    for (int i = 0; i < cells; ++i) {
      const double u = fp.grid.Centre(i) - patch.offset_m, v = fp.grid.Centre(j) - patch.offset_m;
      if (!(std::abs(u) < half && std::abs(v) < half)) continue;
      const int pi = std::min(patch.n - 1, static_cast<int>((u + half) / patch.pitch_m));
      const int pj = std::min(patch.n - 1, static_cast<int>((v + half) / patch.pitch_m));
      fp.on_patch[static_cast<size_t>(j) * cells + i] =
          std::isfinite(patch_z[static_cast<size_t>(pj) * patch.n + pi]);
    }
  return fp;
}

double PatchShare(PatchFootprint* fp, const Pose& pad_pose, const CounterSurface& s) {
  fp->one.assign(1, s);
  RenderRequest request{fp->grid, fp->skin_z, pad_pose, fp->one};
  RenderOutput out{&fp->gap, &fp->coverage};
  out.scratch = &fp->scratch;
  RenderGap(request, out);
  double on = 0.0, off = 0.0;
  bool seen = false;
  for (size_t k = 0; k < fp->gap.size(); ++k) {
    seen = seen || fp->coverage[k] > 0.0;
    const double w = fp->coverage[k] * std::max(-fp->gap[k], 0.0);
    if (!(w > 0.0)) continue;
    (fp->on_patch[k] ? on : off) += w;
  }
  if (!seen) return 0.0;  // no column of the pad meets the body
  if (!(on + off > 0.0)) return -1.0;
  return off == 0.0 ? 1.0 : on / (on + off);
}

}  // namespace mjtouch
