// The elastic skin as a substrate: the stress below the surface from a unit
// uniform traction on one square cell (Green's functions integrated over the
// cell). Used by the stress stage's tables. Pure C++: no MuJoCo types.
//
// Frame: x, y in the skin's tangent plane (the taxel grid's u, v axes), z
// pointing INTO the skin (depth). Tension positive. Tractions are the force per
// area that the counter-surface exerts on the skin: `pressure` pushes into the
// skin (+z), shear along +x / +y.
#ifndef MJTOUCH_SUBSTRATE_SUBSTRATE_H_
#define MJTOUCH_SUBSTRATE_SUBSTRATE_H_

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
  virtual Stress6 CellStress(SurfaceLoad load, double x_m, double y_m, double z_m,
                             double pitch_m) const = 0;

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

// Normal surface displacement (m per Pa) of a homogeneous, isotropic
// half-space at the centre of cell (i, j) of an n x n lattice of pitch
// pitch_m from unit uniform pressure on cell (i + di, j + dj):
// table[(dj + n - 1) * L + (di + n - 1)], L = 2n - 1 (the layout of
// LayeredSubstrate::SurfaceComplianceTable). The substrate's surface Green's
// function over a cell, closed form (Love 1929; Johnson, Contact Mechanics,
// eq. 3.25): u = p / (pi E*) sum over the corners of
// +-[X asinh(Y/|X|) + Y asinh(X/|Y|)], E* = E / (1 - nu^2).
void HalfSpaceSurfaceComplianceTable(double young_pa, double poisson, double pitch_m, int n,
                                     std::vector<float>* table);

}  // namespace mjtouch

#endif  // MJTOUCH_SUBSTRATE_SUBSTRATE_H_
