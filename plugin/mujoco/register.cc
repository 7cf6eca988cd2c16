#include <mujoco/mujoco.h>

#include "skin_plugin.h"

// Runs when the shared library is loaded. Loading the library twice (e.g. an
// editable build next to an installed one) must not register twice.
mjPLUGIN_LIB_INIT(mjtouch) {
  if (mjp_getPlugin(mjtouch::SkinPlugin::kName, nullptr) == nullptr) {
    mjtouch::SkinPlugin::RegisterPlugin();
  }
}
