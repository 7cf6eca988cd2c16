// Stage 1: surface rendering. The skin's surface (pad shape plus fingerprint
// ridge relief) sampled on the taxel grid, and the gap between each taxel's
// cell and the counter-surfaces it faces. Every sample is an exact average over
// the cell's area (anti-aliased), so a texture sliding under the grid varies
// smoothly and adds no spurious line at V / pitch.
#ifndef MJTOUCH_SURFACE_SURFACE_H_
#define MJTOUCH_SURFACE_SURFACE_H_

#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "common/grid.h"

namespace mjtouch {

// Pad shape in its own frame (the fingertip geom's); the skin that touches
// is the -z side: the pole of a sphere or ellipsoid, the -z end cap of a
// capsule (a hemisphere), the -z face of a box, the near side of a mesh.
enum class PadShape { kSphere, kEllipsoid, kCapsule, kBox, kMesh };

class MeshRayCaster;

// A kMesh pad's surface: a closed convex triangle mesh in the geom frame
// (MuJoCo collides a mesh geom as its convex hull, so the adapter gives the
// hull: the surface MuJoCo's contacts lie on). MakePadMesh (mesh_surface.h).
struct PadMesh {
  std::vector<float> vertices_m;  // 3 per vertex
  std::vector<int> faces;         // 3 vertex indices per triangle
  std::string key;                // the data's hash: equal meshes, equal keys
  double bound_radius_m = 0;      // largest vertex distance from the origin
  std::shared_ptr<const MeshRayCaster> caster;
};

struct PadGeometry {
  PadShape shape = PadShape::kEllipsoid;
  // Half extents along x, y, z: sphere (r, r, r), ellipsoid (a, b, c),
  // capsule (r, r, r + half length), box (MuJoCo's size), mesh (the largest
  // |vertex coordinate| per axis).
  double semi_axes_m[3] = {0, 0, 0};
  std::shared_ptr<const PadMesh> mesh;  // kMesh only
  // The skin's frame in the geom's (`facing`): row-major, columns the skin's
  // x, y, z axes in the geom frame; the skin faces its -z. Identity unless
  // `rotated`: the shape above stays in the geom frame, and the skin's
  // surface is the shape's near side seen along the skin's z.
  bool rotated = false;
  double rotation[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
};

// Sets pad->rotation to the smallest rotation taking the skin's -z to the
// unit vector `facing` (geom frame); facing = +z: a half turn about x.
// `rotated` is false exactly for facing = (0, 0, -1).
void SetPadFacing(const double facing[3], PadGeometry* pad);
// The smaller half extent of the pad's shape along the skin's x and y; a
// mesh: the radius of the largest disc about the skin's centre inside its
// outline seen along the skin's z (the minimum of its support function).
double PadFootprintSemiAxis(const PadGeometry& pad);

// Ridge relief across the ridge direction s (period pitch, crest at s = 0,
// mean zero): sine (H/2) cos(2 pi s / pitch); triangle (sharp crests and
// valleys, linear flanks); square (crests of width pitch / 2, flat).
enum class RidgeProfile { kSine = 0, kTriangle, kSquare };
const char* RidgeProfileName(RidgeProfile p);

struct Ridges {
  bool enabled = true;
  double pitch_m = 0.45e-3;   // ridge period (Shao et al. 2010)
  double height_m = 0.05e-3;  // crest-to-valley relief (Shao et al. 2010)
  double angle_rad = 0.0;     // ridge lines vs pad y axis (0: perpendicular to x)
  RidgeProfile profile = RidgeProfile::kSine;
};

// Cell-averaged skin surface height z (pad frame, m) at every taxel; +inf
// where the cell lies outside the pad's footprint (a cell is inside if its
// four 2x2 Gauss points are). Ridges protrude towards -z around the pad's
// mean surface. The pad shape is averaged by 2x2 Gauss quadrature (smooth);
// the ridge relief exactly: sine in closed form (cell mean of cos(k.r) is
// cos(k.r_c) sinc(k_x h/2) sinc(k_y h/2)), the piecewise-linear profiles by
// integrating them against the cell's projection onto the ridge direction
// (a trapezoid density) piece by piece with 2-point Gauss, exact for the
// piecewise-quadratic product.
std::vector<double> SkinSurface(const TaxelGrid& grid, const PadGeometry& pad,
                                const Ridges& ridges);

// Ridge relief (m, protrusion positive) at s, and its exact mean over the
// cell of side h at s_c for ridges at angle_rad (exposed for tests).
double RidgeRelief(const Ridges& ridges, double s_m);
double RidgeCellMean(const Ridges& ridges, double s_centre_m, double h_m);

// Rigid transform, local -> world: world = pos + mat * local (mat row-major).
struct Pose {
  double pos[3] = {0, 0, 0};
  double mat[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
};

// A counter-surface described in its own frame.
//  - kPlane, kRectangle, kHeightField: local +z is the outward normal of the
//    face the skin touches; the gap is measured along it, and a cell's
//    coverage of a rectangle or height field is its exact overlap fraction.
//  - kSphere, kEllipsoid, kCapsule, kCylinder, kBox (MuJoCo's geom frames
//    and sizes) and kRay (any geom, through a ray query, e.g. MuJoCo meshes):
//    the gap is measured along the pad's z axis, from the skin down to the
//    body's top where the cell's line (pad frame x, y fixed) meets it;
//    analytic bodies are averaged over the cell at 2x2 Gauss points
//    (coverage: the fraction that hit), kRay over 4x4 rays (mesh_surface.h).
struct CounterSurface {
  enum class Type {
    kPlane,
    kRectangle,
    kHeightField,
    kSphere,
    kEllipsoid,
    kCapsule,
    kCylinder,
    kRay,
    kBox  // MuJoCo's box (size_m: half sizes) as a body, for contact on its edges or corners
  };
  Type type = Type::kPlane;
  Pose pose;
  // kRectangle: half sizes of the face (x, y); kPlane ignores them.
  double half_x_m = 0, half_y_m = 0;
  // kSphere (r), kEllipsoid (a, b, c), kCapsule / kCylinder (r, half length
  // of the axis along local z): MuJoCo's geom size.
  double size_m[3] = {0, 0, 0};
  // kRay: distance along the unit direction `dir` (world) from `origin` to
  // the first surface hit, or < 0 for none. Must be thread-compatible.
  std::function<double(const double origin[3], const double dir[3])> ray;
  // kRay (and the analytic bodies, filled by the renderer): radius of a
  // sphere about the local origin that contains the body (culling, misses).
  double bound_radius_m = 0;
  // kHeightField (MuJoCo semantics): nrow x ncol samples in [0, 1], row r at
  // y = -half_y + 2 half_y r / (nrow - 1), column c at x likewise;
  // height = elevation_m * sample.
  int nrow = 0, ncol = 0;
  const float* samples = nullptr;
  double elevation_m = 0;
  // Optional per-row running integrals of the samples (HeightFieldRowPrefix):
  // makes a cell average O(rows) instead of O(rows x columns).
  const double* row_prefix = nullptr;
  // Every row equal (a 1D texture): cell means need one row only.
  bool rows_identical = false;
  double max_height_m = 0;  // highest point above the local z = 0 plane
  int id = -1;              // caller's tag (e.g. MuJoCo geom id)
};

struct SkinBlocks;
struct RenderSummary;
struct RenderScratch;

// What RenderGap renders: the skin (heights skin_z on the grid, pad at
// pad_pose) against the counter-surfaces.
struct RenderRequest {
  const TaxelGrid& grid;
  const std::vector<double>& skin_z;
  const Pose& pad_pose;
  const std::vector<CounterSurface>& surfaces;
  // Cells whose gap is provably above this (m, relative to the smallest
  // lower bound of any cell) are skipped and left at +inf; +inf renders all.
  double cull_above_m = std::numeric_limits<double>::infinity();
  const SkinBlocks* blocks = nullptr;  // MakeSkinBlocks(grid, skin_z); null: built per call
  // false: each cell sampled at its centre (point sampling; for tests that
  // show what the averaging removes).
  bool area_average = true;
  // false: every surface through the general per-cell code (the reference
  // the fast paths are tested and benchmarked against; the same bits).
  bool fast_paths = true;
};

// Where RenderGap writes. gap_m and coverage are resized to the grid.
struct RenderOutput {
  std::vector<double>* gap_m;
  std::vector<double>* coverage;
  CellBox* rendered = nullptr;  // if given: the box of the cells with coverage > 0
  // If given, in: a box outside which gap_m / coverage (already grid-sized)
  // hold +inf / 0, so only it is reset (not the whole grid); out: the same
  // for this call's result (the cells it rendered).
  CellBox* written = nullptr;
  // If given: filled when one surface alone wrote cells, through the
  // aligned-face fast path (else summary->valid = false).
  RenderSummary* summary = nullptr;
  RenderScratch* scratch = nullptr;  // reused between calls; null: one per call
};

// Gap (m) between each taxel cell of the skin and the nearest
// counter-surface, measured along each surface's normal; coverage is the
// fraction of the cell over a surface (0: no surface, gap = +inf). Returns
// the absolute cull level used (+inf if none), so a caller whose contact
// reaches above it can render again without culling.
double RenderGap(const RenderRequest& request, const RenderOutput& out);

// RenderGap's scratch, kept by a caller between calls (Workspace: one per
// simulation) so that no call allocates; the results do not depend on it.
struct RenderScratch {
  std::vector<double> block_lb;       // per surface and skin block: a lower bound of the gap
  std::vector<double> columns, rows;  // the aligned-face path's per-column / per-row values
  // The face whose per-column values `columns` holds, reused within one
  // RenderGap call (the covers-only test, then the render); reset per call.
  struct ColumnKey {
    const CounterSurface* face = nullptr;
    int c0 = 0, c1 = 0;
    bool per_cell = false, negative = false;
  };
  ColumnKey columns_key;
};

// The covered cells (coverage > 0, finite gap) of a RenderGap call, taken
// while the rows are rendered (a later pass over them would read them from
// farther than L1): their smallest gap (in four running minima: for a zero
// the sign may differ from a row-by-row minimum's) and largest coverage,
// and per row with any the span from the first to the last (ascending rows).
struct RenderSummary {
  bool valid = false;
  double gap_min_m = 0, coverage_max = 0;
  ActiveRuns spans;
};

// Bounds of the skin's height over blocks of kSide x kSide cells, so that
// RenderGap skips whole blocks out of reach. +inf / -inf: no skin cell.
struct SkinBlocks {
  static constexpr int kSide = 8;
  int n = 0, nb = 0;
  std::vector<double> zmin, zmax;  // nb x nb, row-major
};
SkinBlocks MakeSkinBlocks(const TaxelGrid& grid, const std::vector<double>& skin_z);

// Which share of a counter-body's contact the skin's patch carries. MuJoCo
// gives each contact a point and a force, not its extent: a body pressing
// across the patch's edge (a block along a fingertip, a neighbour near the
// grid's rim) would put all its force on the few cells it reaches. The
// footprint is the pad's whole near side (the shape seen along the skin's
// z, no ridges) on a coarse grid in the skin's frame; a body's overlap with
// it (depth x coverage per cell, the render's own rule) is split into the
// cells over the patch (covered taxels) and the rest.
struct PatchFootprint {
  TaxelGrid grid;
  std::vector<double> skin_z;
  std::vector<char> on_patch;         // per footprint cell: its centre over a covered taxel
  std::vector<double> gap, coverage;  // scratch, one render
  RenderScratch scratch;
  std::vector<CounterSurface> one;  // the surface rendered
};
// cells: about this many footprint cells a side (their edges on the
// patch's square); patch_z: SkinSurface(patch, pad, ...).
PatchFootprint MakePatchFootprint(const TaxelGrid& patch, const std::vector<double>& patch_z,
                                  const PadGeometry& pad, int cells);
// The share in [0, 1] of surface s's overlap with the pad that lies on the
// patch (exactly 1 when none lies off it); 0 if no column of the footprint
// meets the body (the render cannot see it); -1 if the body lies under the
// pad but overlaps no cell (a contact within MuJoCo's margin).
double PatchShare(PatchFootprint* fp, const Pose& pad_pose, const CounterSurface& s);

// Radius of a sphere about the surface's origin containing the body
// (analytic bodies from size_m; kRay: bound_radius_m).
double BoundRadius(const CounterSurface& s);

// Running integrals along x of each row of a height field's samples (grid
// units, trapezoid rule, which is exact for the linear interpolant).
std::vector<double> HeightFieldRowPrefix(int nrow, int ncol, const float* samples);

// Exact average of a bilinear height field over the axis-aligned box
// [x0, x1] x [y0, y1] (surface frame), exposed for tests.
double HeightFieldBoxMean(const CounterSurface& s, double x0, double x1, double y0, double y1);

}  // namespace mjtouch

#endif  // MJTOUCH_SURFACE_SURFACE_H_
