// Internal to afferents/: the receptor state's slots (kReceptorStateSize
// doubles, receptors.h) and the per-step drive ReceptorStepper's per-class
// paths share (receptors.cc, receptor_batch.cc).
#ifndef MJTOUCH_AFFERENTS_RECEPTOR_STATE_H_
#define MJTOUCH_AFFERENTS_RECEPTOR_STATE_H_

#include "afferents/receptors.h"

namespace mjtouch {
namespace receptor_state {

enum {
  kU0 = 0,
  kU1,
  kU2,
  kU3,          // membranes over threshold (SA1: one per heminode)
  kRefractory,  // refractory time left, s
  kPrevQ,       // q at the end of the previous step
  kHasPrev,     // 1 once primed
  kRate,        // exponentially smoothed rate, Hz
  kNoise,       // Ornstein-Uhlenbeck noise, units of threshold
  kCount,       // steps drawn from the noise generator
  kF0,
  kF1,
  kF2,
  kF3,      // filter states (SA1, RA: 2, PC: 4)
  kAdapt,   // adaptation current, threshold units
  kVariant  // population variant index
};
static_assert(kVariant + 1 == kReceptorStateSize, "receptor state layout");
constexpr int kMaxNodes = 4;  // SA1 heminodes

}  // namespace receptor_state

// The drive of one receptor over a step, before the rectification kinks.
struct ReceptorStepper::Drive {
  int nodes;
  int variant;
  double l0[receptor_state::kMaxNodes], l1[receptor_state::kMaxNodes];  // at the step ends
  double x_start[4];  // filter state at the step start
  double v;           // dq/dt over the step
  double n0, n1;      // noise at the step ends
};

}  // namespace mjtouch

#endif  // MJTOUCH_AFFERENTS_RECEPTOR_STATE_H_
