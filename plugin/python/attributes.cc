// The skin's attribute table (plugin/core/pipeline/attributes.h) for docs and
// tests: README's markdown table, the numeric ranges, and the model cache key
// of a configuration.
#include <optional>
#include <string>

#include <nanobind/nanobind.h>
#include <nanobind/stl/map.h>
#include <nanobind/stl/string.h>

#include "pipeline/attributes.h"
#include "python/convert.h"

namespace mjtouch::py {

void BindAttributes(nb::module_& m) {
  m.def("attribute_table_markdown", &AttributeTableMarkdown,
        "plugin/README.md's attribute table (markdown), one row per registered attribute.");

  m.def(
      "attribute_ranges",
      []() {
        nb::list rows;
        for (const auto& row : SkinAttributes()) {
          const char* kind = row.kind == AttributeKind::kNumber     ? "number"
                             : row.kind == AttributeKind::kInteger  ? "integer"
                             : row.kind == AttributeKind::kPerClass ? "per_class"
                                                                    : nullptr;
          if (!kind) continue;
          nb::dict r;
          r["key"] = row.key;
          r["kind"] = kind;
          r["lo"] = row.lo;
          r["hi"] = row.hi;
          r["lo_open"] = row.lo_open;
          r["hi_open"] = row.hi_open;
          r["units"] = row.units;
          rows.append(r);
        }
        return rows;
      },
      "Valid ranges of the number, integer and per-class attributes: dicts with key, kind, lo, "
      "hi, lo_open, hi_open, units.");

  m.def(
      "config_cache_key",
      [](const std::map<std::string, std::string>& attributes) {
        SkinConfig cfg;
        std::string error;
        const bool ok = ParseSkinAttributes(
            [&](const char* key) -> std::optional<std::string> {
              const auto it = attributes.find(key);
              if (it == attributes.end()) return std::nullopt;
              return it->second;
            },
            &cfg, &error);
        if (!ok) throw nb::value_error(error.c_str());
        cfg.pad.shape = PadShape::kSphere;  // a fixed pad: the key's attribute part
        for (double& a : cfg.pad.semi_axes_m) a = 8e-3;
        return ConfigCacheKey(cfg);
      },
      nb::arg("attributes"),
      "The model cache key of a skin configuration (attribute -> value) on a sphere pad of "
      "radius 8 mm: equal keys share one SkinModel. Raises ValueError on a bad attribute.");
}

}  // namespace mjtouch::py
