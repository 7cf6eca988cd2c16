#include <mujoco/mujoco.h>

#include "skin_plugin.h"

// The MuJoCo release whose headers this library was compiled against; struct
// layouts differ between releases, so a mismatch must refuse to register.
extern "C" __attribute__((visibility("default"))) int mjtouch_built_mujoco_version() {
  return mjVERSION_HEADER;
}

// Runs when the shared library is loaded. Loading the library twice (e.g. an
// editable build next to an installed one) must not register twice.
mjPLUGIN_LIB_INIT(mjtouch) {
  if (mj_version() != mjVERSION_HEADER) {
    mju_warning(
        "mjtouch: plugin built for MuJoCo %d but running MuJoCo %d; not registered. "
        "Reinstall mjtouch (pip install .) against this mujoco.",
        mjVERSION_HEADER, mj_version());
    return;
  }
  if (mjp_getPlugin(mjtouch::SkinPlugin::kName, nullptr) == nullptr) {
    mjtouch::SkinPlugin::RegisterPlugin();
  }
}
