// Stage 3b: layered elastic skin. A stack of welded, isotropic, linear-elastic
// layers over a rigid base (bone) or an elastic half-space. Pure C++: no
// MuJoCo types. Frame, signs and loads as in kernel.h (z into the skin,
// tension positive, `pressure` pushes into the skin).
//
// Method (REFERENCE.md sec. 4). Per 2D Fourier wavenumber k each layer's field
// is a Papkovich-Neuber solution 2 mu u = grad(phi + z psi) - 4 (1 - nu) psi e_z
// plus an antiplane part, with harmonic potentials that decay away from the
// layer's top face (exp(-k z')) or its bottom face (exp(k (z' - h))). Stresses
// are written with mu and nu only (no Lame lambda), so nu = 0.5 is exact, and
// every matrix entry is O(1): no overflow at any k h. The global system
// (surface tractions, welded interfaces, bottom condition) is solved by
// Gaussian elimination per k and is nonsingular at k = 0, so the k -> 0
// stresses are the exact limits; the k -> 0 surface compliance is a closed
// form (see SurfaceCompliance).
//
// Real space. Transfer functions at one receptor depth are tabulated on 1024
// log-spaced k (cubic in ln k; exact k = 0 value, linear below the first
// point), then radial Hankel transforms (orders 0-3, panel Gauss-Legendre)
// give the point-force response as 11 radial functions:
//  - LatticeTable: the radial functions are tabulated on a stretched r grid
//    and integrated over each source cell (uniform traction on the cell,
//    never a point force) by Gauss quadrature, in real space, so the slowly
//    decaying in-plane tails (1/r^2, 1/r^3) have no periodic images. In the
//    top layer the homogeneous half-space part (kernel.cc HalfSpace, exact
//    closed form, adaptive cell quadrature) is subtracted first, so what is
//    transformed is smooth on the scale 2 h1 - z.
//  - CellStress / PointStress / DiscStress: the same, with the Hankel
//    integrals done directly at each quadrature point (no r table): an
//    independent path used to check LatticeTable.
//
// Interfaces. s_xx, s_yy, s_xy jump across an interface (s_zz, s_xz, s_yz do
// not). A receptor whose depth is within 1e-9 x (stack depth) of an
// interface is evaluated on the side chosen at creation: kUpper (default: the
// layer above, e.g. the basal epidermis for Merkel cells at the
// epidermis/dermis interface) or kLower. The explicit-side overloads override.
#ifndef MJTOUCH_SUBSTRATE_LAYERED_H_
#define MJTOUCH_SUBSTRATE_LAYERED_H_

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "substrate/substrate.h"

namespace mjtouch {

struct ElasticLayer {
  double thickness_m = 0;
  double young_pa = 0;
  double poisson = 0;
};

// What lies under the stack: bone (rigid, zero displacement) or an elastic
// half-space.
struct LayeredBase {
  bool rigid = true;
  double young_pa = 0;  // half-space only
  double poisson = 0;   // half-space only
};

struct Material {
  double young_pa = 0;
  double poisson = 0;
};

enum class InterfaceSide { kUpper = 0, kLower = 1 };

// Point-force transfer functions at one depth and wavenumber k, in the frame
// (xi along the wavevector, eta across it, z). Fields go as exp(i k.x).
//  unit pressure p:     s_xixi = p_xixi, s_etaeta = p_etaeta, s_zz = p_zz,
//                       s_xiz = i p_xiz
//  unit shear q_xi:     s_xixi = i q_xixi, s_etaeta = i q_etaeta,
//                       s_zz = i q_zz, s_xiz = -q_xiz
//  unit shear q_eta:    s_etaz = a_etaz, s_xieta = i a_xieta
// Homogeneous half-space, e = exp(-k z): p_zz = -(1 + kz) e, q_xiz = (1 - kz) e,
// a_etaz = -e, ... (REFERENCE.md sec. 3).
struct LayerTransfer {
  double p_xixi = 0, p_etaeta = 0, p_zz = 0, p_xiz = 0;
  double q_xixi = 0, q_etaeta = 0, q_zz = 0, q_xiz = 0;
  double a_etaz = 0, a_xieta = 0;
};

// Strain (tensor shear components, Voigt order as Stress6) and strain energy
// density (J/m^3) of an isotropic material from its stress. Exact at nu = 0.5.
Stress6 StrainFromStress(const Stress6& stress_pa, const Material& material);
double StrainEnergyDensity(const Stress6& stress_pa, const Material& material);

class LayeredSubstrate : public Substrate {
 public:
  // Validates every field; on error returns null and sets *error to a message
  // naming the field and its valid range (E > 0, nu in (-1, 0.5],
  // thickness > 0, at least one layer). No exceptions.
  static std::unique_ptr<LayeredSubstrate> Create(const std::vector<ElasticLayer>& layers,
                                                  const LayeredBase& base, InterfaceSide side,
                                                  std::string* error);

  // Human fingertip of Shao et al. 2010 (Table 1): epidermis 0.7 mm (80 kPa,
  // 0.48), dermis 0.8 mm (50 kPa, 0.48), subcutis (24 kPa, 0.4) down to rigid
  // bone at 4 mm. Why bone at 4 mm: Shao's tip is a 14 mm-deep ellipse with
  // the distal phalanx inside; the palmar pulp between skin and bone is a few
  // mm, and contacts (6-13 mm wide at 0.5 N) are wider than that, so the deep
  // field feels the bone (17 GPa, i.e. rigid next to 24 kPa). A half-space
  // would make wide contacts far too compliant.
  static std::vector<ElasticLayer> ShaoFingertipLayers();
  static LayeredBase ShaoFingertipBase();

  // Substrate interface (interface side: the one chosen at creation). A depth
  // that CheckDepth rejects gives NaN stresses (NaN-filled tables).
  Stress6 CellStress(SurfaceLoad load, double x_m, double y_m, double z_m,
                     double pitch_m) const override;
  void LatticeTable(double z_m, double pitch_m, int n, const std::array<bool, kNumStress>& want,
                    std::vector<float>* table) const override;
  std::string Describe() const override;

  // Same, with an explicit interface side.
  Stress6 CellStress(SurfaceLoad load, double x_m, double y_m, double z_m, double pitch_m,
                     InterfaceSide side) const;
  void LatticeTable(double z_m, double pitch_m, int n, const std::array<bool, kNumStress>& want,
                    InterfaceSide side, std::vector<float>* table) const;

  // Stress (Pa) from a point force (1 N) at the origin, and from a unit (1 Pa)
  // uniform traction on a disc of radius radius_m centred at the origin.
  Stress6 PointStress(SurfaceLoad load, double x_m, double y_m, double z_m,
                      InterfaceSide side) const;
  Stress6 DiscStress(SurfaceLoad load, double x_m, double y_m, double z_m, double radius_m,
                     InterfaceSide side) const;

  // Surface normal displacement (m per Pa of pressure) at the centre of cell
  // (i, j) from unit pressure on cell (i + di, j + dj) of an n x n lattice of
  // pitch pitch_m: table[(dj + n - 1) * L + (di + n - 1)], L = 2 n - 1 (the
  // LatticeTable layout with one slab). The 1/r part (top layer) and the
  // base's long-wave part are closed forms over the cell; the remainder goes
  // the radial route.
  void SurfaceComplianceTable(double pitch_m, int n, std::vector<float>* table) const;

  // Direct (untabulated) transfer functions at wavenumber k_per_m >= 0.
  LayerTransfer TransferAt(double k_per_m, double z_m, InterfaceSide side) const;
  // Fourier surface compliance u_z / p (m/Pa) at k_per_m > 0; k_per_m = 0
  // gives the finite part: the closed-form limit for a rigid base, and
  // lim (C(k) - 2 (1 - nu_b^2) / (E_b k)) for a half-space base.
  double SurfaceCompliance(double k_per_m) const;

  // Material at depth z_m; on an interface, upper_side picks the layer above.
  // Inside a rigid base returns {0, 0}.
  Material MaterialAt(double z_m, bool upper_side) const;
  // Empty when z_m is a valid receptor depth (z > 0, not inside or on the
  // lower side of a rigid base), else the reason.
  std::string CheckDepth(double z_m, InterfaceSide side) const;

  const std::vector<ElasticLayer>& layers() const { return layers_; }
  const LayeredBase& base() const { return base_; }
  InterfaceSide interface_side() const { return side_; }
  double stack_depth_m() const { return interfaces_m_.back(); }

  // Per-k solution of the global system; public only for the implementation
  // file's helpers.
  struct Solution;

 private:
  LayeredSubstrate(std::vector<ElasticLayer> layers, LayeredBase base, InterfaceSide side);

  // Layer index at depth z (num layers = base half-space), local depth below
  // that layer's top face; -1 when invalid.
  int Locate(double z_m, InterfaceSide side, double* local_m) const;
  void Solve(double k, Solution* sol) const;
  struct Tab;
  void TabulateTransfer(int layer, double local_m, double z_m, bool subtract, double k_lo,
                        double k_hi, Tab* tab) const;
  double DecayLength(int layer, double z_m) const;
  double LowK(double z_m) const;

  LayerTransfer Evaluate(const Solution& sol, double k, int layer, double local_m) const;

  std::vector<ElasticLayer> layers_;
  LayeredBase base_;
  InterfaceSide side_;
  std::vector<double> interfaces_m_;          // depth of each layer's bottom face
  std::vector<double> mu_pa_;                 // shear modulus per layer (+ base)
  std::unique_ptr<HalfSpace> top_halfspace_;  // nu of layer 0
};

}  // namespace mjtouch

#endif  // MJTOUCH_SUBSTRATE_LAYERED_H_
