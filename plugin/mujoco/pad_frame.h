// The skin's frame in the world: the pad geom's frame turned by `facing`
// (PadGeometry::rotation, geom from skin).
#ifndef MJTOUCH_MUJOCO_PAD_FRAME_H_
#define MJTOUCH_MUJOCO_PAD_FRAME_H_

#include <mujoco/mujoco.h>

#include "surface/surface.h"

namespace mjtouch {

// World-from-skin rotation (row-major) of pad geom g: geom_xmat itself when
// the pad is not rotated (the same bits), else geom_xmat * rotation.
inline const mjtNum* PadFrameMat(const mjData* d, int g, const PadGeometry& pad, mjtNum out[9]) {
  const mjtNum* gmat = d->geom_xmat + 9 * g;
  if (!pad.rotated) return gmat;
  mju_mulMatMat(out, gmat, pad.rotation, 3, 3, 3);
  return out;
}

}  // namespace mjtouch

#endif  // MJTOUCH_MUJOCO_PAD_FRAME_H_
