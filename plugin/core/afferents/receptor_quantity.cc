// Stage 4's receptor quantities: the stress measures that drive each class
// (ReceptorQuantity) and the class and quantity names.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "afferents/receptors.h"

namespace mjtouch {
namespace {

// Eigenvalues of a symmetric 3x3 (Smith 1961), ascending; l2 and l3 may be
// null when only the smallest is wanted (skips a cosine).
void Principal(const double s[6], double* l1, double* l2, double* l3) {
  const double xx = s[0], yy = s[1], zz = s[2], xy = s[3], xz = s[4], yz = s[5];
  const double p1 = xy * xy + xz * xz + yz * yz;
  const double q = (xx + yy + zz) / 3.0;
  if (p1 <= 1e-30 * (xx * xx + yy * yy + zz * zz + 1e-300)) {
    double e[3] = {xx, yy, zz};
    std::sort(e, e + 3);
    *l1 = e[0];
    if (l3) {
      *l2 = e[1];
      *l3 = e[2];
    }
    return;
  }
  const double p2 = (xx - q) * (xx - q) + (yy - q) * (yy - q) + (zz - q) * (zz - q) + 2 * p1;
  const double p = std::sqrt(p2 / 6.0);
  const double b00 = (xx - q) / p, b11 = (yy - q) / p, b22 = (zz - q) / p;
  const double b01 = xy / p, b02 = xz / p, b12 = yz / p;
  const double det =
      b00 * (b11 * b22 - b12 * b12) - b01 * (b01 * b22 - b12 * b02) + b02 * (b01 * b12 - b11 * b02);
  const double r = std::clamp(det / 2.0, -1.0, 1.0);
  const double phi = std::acos(r) / 3.0;
  const double e1 = q + 2 * p * std::cos(phi + 2.0943951023931957);
  *l1 = e1;
  if (!l3) return;
  const double e3 = q + 2 * p * std::cos(phi);
  *l3 = e3;
  *l2 = 3 * q - e1 - e3;
}

}  // namespace

const char* ClassName(ReceptorClass c) {
  switch (c) {
    case ReceptorClass::kSA1: return "SA1";
    case ReceptorClass::kRA: return "RA";
    default: return "PC";
  }
}

const char* QuantityName(Quantity q) {
  switch (q) {
    case Quantity::kCompressiveSzz: return "szz";
    case Quantity::kMaxCompressive: return "maxcomp";
    case Quantity::kVonMises: return "vonmises";
    case Quantity::kStrainEnergy: return "sed";
    case Quantity::kCompressiveStrain: return "strain";
    default: return "maxshear";
  }
}

bool ParseQuantity(const std::string& s, Quantity* q) {
  if (s == "szz") {
    *q = Quantity::kCompressiveSzz;
    return true;
  }
  if (s == "maxcomp") {
    *q = Quantity::kMaxCompressive;
    return true;
  }
  if (s == "vonmises") {
    *q = Quantity::kVonMises;
    return true;
  }
  if (s == "maxshear") {
    *q = Quantity::kMaxShear;
    return true;
  }
  if (s == "sed") {
    *q = Quantity::kStrainEnergy;
    return true;
  }
  if (s == "strain") {
    *q = Quantity::kCompressiveStrain;
    return true;
  }
  return false;
}

double ReceptorQuantity(Quantity q, const double s[6]) {
  switch (q) {
    case Quantity::kCompressiveSzz: return -s[2];
    case Quantity::kStrainEnergy:
    case Quantity::kCompressiveStrain:
      return std::numeric_limits<double>::quiet_NaN();  // needs the material (pipeline/step.cc)
    case Quantity::kVonMises: {
      const double a = s[0] - s[1], b = s[1] - s[2], c = s[2] - s[0];
      return std::sqrt(0.5 * (a * a + b * b + c * c) +
                       3.0 * (s[3] * s[3] + s[4] * s[4] + s[5] * s[5]));
    }
    default: {
      double l1, l2, l3;
      if (q == Quantity::kMaxCompressive) {
        Principal(s, &l1, nullptr, nullptr);
        return std::max(0.0, -l1);
      }
      Principal(s, &l1, &l2, &l3);
      return 0.5 * (l3 - l1);
    }
  }
}

}  // namespace mjtouch
