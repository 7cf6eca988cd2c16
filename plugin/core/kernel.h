// Stage 3: elastic kernel. Surface tractions on the taxel grid -> stress tensor
// at receptor sites. Pure C++: no MuJoCo types.
//
// Frame: x, y in the skin's tangent plane (the taxel grid's u, v axes), z
// pointing INTO the skin (depth). Tension positive. Tractions are the force per
// area that the counter-surface exerts on the skin: `pressure` pushes into the
// skin (+z), shear along +x / +y.
#ifndef MJTOUCH_CORE_KERNEL_H_
#define MJTOUCH_CORE_KERNEL_H_

#include <array>
#include <memory>
#include <string>
#include <vector>

namespace mjtouch {

// Stress components, Voigt order.
enum StressComponent { kSxx = 0, kSyy, kSzz, kSxy, kSxz, kSyz, kNumStress };
// Surface loads: normal pressure into the skin, shear along +x, shear along +y.
enum SurfaceLoad { kLoadPressure = 0, kLoadShearX, kLoadShearY, kNumLoads };

using Stress6 = std::array<double, kNumStress>;

// Influence of surface tractions on the stress below the surface. Every
// implementation loads a whole square cell (side `pitch_m`) uniformly, never a
// point, so that stress near the surface stays finite.
class Substrate {
 public:
  virtual ~Substrate() = default;

  // Stress (Pa) at offset (x_m, y_m) from the centre of a square cell of side
  // pitch_m and at depth z_m > 0, for a unit (1 Pa) uniform traction `load` on
  // that cell.
  virtual Stress6 CellStress(SurfaceLoad load, double x_m, double y_m,
                             double z_m, double pitch_m) const = 0;

  // Lattice influence table at depth z_m for cells of side pitch_m on a grid
  // of n x n cells: table[((load * 6 + comp) * L + (dj + n - 1)) * L +
  // (di + n - 1)], L = 2n - 1, is the stress at the receptor under the centre
  // of cell (i, j) from unit traction on cell (i + di, j + dj), i.e. indexed
  // by source minus receptor so that sums over a row of sources run forward
  // in memory; i runs along x, j along y. Only components with want[comp] are
  // filled (others left 0).
  // The default samples CellStress; substrates may override with a faster
  // method (e.g. FFT of a Hankel-tabulated transfer function).
  virtual void LatticeTable(double z_m, double pitch_m, int n,
                            const std::array<bool, kNumStress>& want,
                            std::vector<float>* table) const;

  // A short human-readable description for logs and build reports.
  virtual std::string Describe() const = 0;
};

// Homogeneous, isotropic, linear-elastic half-space: Boussinesq (normal) and
// Cerruti (tangential) point solutions integrated over the cell by adaptive
// Gauss-Legendre quadrature. Stress under prescribed traction depends on nu
// only, not on E.
class HalfSpace : public Substrate {
 public:
  explicit HalfSpace(double poisson) : nu_(poisson) {}

  Stress6 CellStress(SurfaceLoad load, double x_m, double y_m, double z_m,
                     double pitch_m) const override;
  std::string Describe() const override;

  // Point-force solutions (force 1 N), exposed for tests. z_m > 0.
  Stress6 Boussinesq(double x_m, double y_m, double z_m) const;
  Stress6 CerrutiX(double x_m, double y_m, double z_m) const;
  Stress6 CerrutiY(double x_m, double y_m, double z_m) const;

 private:
  double nu_;
};

// Lattice tables for a set of depths, shared read-only by every MjData of one
// model (built once per distinct configuration).
struct KernelTables {
  int n = 0;            // taxel grid is n x n
  double pitch_m = 0;   // taxel pitch
  std::vector<double> depths_m;               // one table per depth
  std::vector<std::vector<float>> tables;     // layout as Substrate::LatticeTable
  std::array<bool, kNumStress> components{};  // components filled
  double build_seconds = 0;

  const float* At(int depth_index, SurfaceLoad load, StressComponent comp) const {
    const int L = 2 * n - 1;
    return tables[depth_index].data() +
           static_cast<size_t>(load * kNumStress + comp) * L * L;
  }
};

std::shared_ptr<const KernelTables> BuildKernelTables(
    const Substrate& substrate, int n, double pitch_m,
    const std::vector<double>& depths_m,
    const std::array<bool, kNumStress>& components);

// Stress at one receptor (grid cell index ri, rj, table `depth_index`) from
// the tractions of the active cells. Direct summation over the active cells'
// row runs. pressure/shear arrays are n*n, row-major (j * n + i), Pa.
struct ActiveRuns {
  // For each grid row j with contact: [i_begin, i_end) of active cells.
  std::vector<int> row, begin, end;
  void Clear() { row.clear(); begin.clear(); end.clear(); }
  int Count() const {
    int c = 0;
    for (size_t k = 0; k < row.size(); ++k) c += end[k] - begin[k];
    return c;
  }
};

void StressAtReceptor(const KernelTables& kt, int depth_index, int ri, int rj,
                      const ActiveRuns& runs, const float* pressure,
                      const float* shear_x, const float* shear_y,
                      const std::array<bool, kNumStress>& want, Stress6* out);

}  // namespace mjtouch

#endif  // MJTOUCH_CORE_KERNEL_H_
