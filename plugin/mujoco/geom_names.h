// Geom names written in a skin's attributes, as the compiled model spells
// them. MjSpec.attach(child, prefix=, suffix=) renames the child's geoms but
// not plugin config values; `pad_geom` records the pad's name as written
// beside `texture`, so the prefix and suffix the compiled pad name gained
// can be applied to each texture name too.
#ifndef MJTOUCH_MUJOCO_GEOM_NAMES_H_
#define MJTOUCH_MUJOCO_GEOM_NAMES_H_

#include <mujoco/mujoco.h>

#include <string>

namespace mjtouch {

// The geom `written` names in the compiled model: its id, or -1. With
// `pad_as_written` non-empty, every split of the pad's compiled name into
// prefix + pad_as_written + suffix is tried (nested attaches compose).
inline int ResolveWrittenGeom(const mjModel* m, int pad, const std::string& pad_as_written,
                              const std::string& written) {
  const char* pad_name = mj_id2name(m, mjOBJ_GEOM, pad);
  if (pad_as_written.empty() || !pad_name) return mj_name2id(m, mjOBJ_GEOM, written.c_str());
  const std::string compiled = pad_name;
  for (size_t at = compiled.find(pad_as_written); at != std::string::npos;
       at = compiled.find(pad_as_written, at + 1)) {
    const std::string name =
        compiled.substr(0, at) + written + compiled.substr(at + pad_as_written.size());
    const int g = mj_name2id(m, mjOBJ_GEOM, name.c_str());
    if (g >= 0) return g;
  }
  return -1;
}

}  // namespace mjtouch

#endif  // MJTOUCH_MUJOCO_GEOM_NAMES_H_
