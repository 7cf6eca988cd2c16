// The attribute table (plugin/core/pipeline/attributes.h) for documentation
// and tests: README's markdown table and the numeric ranges as JSON.
#include <cstring>
#include <sstream>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "pipeline/attributes.h"

namespace {

// Copies msg into buf (truncated, NUL-terminated); returns the full length + 1.
int CopyOut(const std::string& msg, char* buf, int len) {
  if (buf && len > 0) {
    std::strncpy(buf, msg.c_str(), len - 1);
    buf[len - 1] = '\0';
  }
  return static_cast<int>(msg.size()) + 1;
}

}  // namespace

extern "C" __attribute__((visibility("default"))) int mjtouch_attribute_table_markdown(
    char* buf, int len) {
  return CopyOut(mjtouch::AttributeTableMarkdown(), buf, len);
}

// [{"key", "kind", "lo", "hi", "lo_open", "hi_open", "units"}, ...] for the
// number, integer and per-class rows.
extern "C" __attribute__((visibility("default"))) int mjtouch_attribute_ranges_json(char* buf,
                                                                                   int len) {
  using mjtouch::AttributeKind;
  std::ostringstream js;
  js.precision(17);
  js << "[";
  bool first = true;
  for (const auto& row : mjtouch::SkinAttributes()) {
    const char* kind = row.kind == AttributeKind::kNumber    ? "number"
                       : row.kind == AttributeKind::kInteger ? "integer"
                       : row.kind == AttributeKind::kPerClass ? "per_class"
                                                              : nullptr;
    if (!kind) continue;
    js << (first ? "" : ", ") << "{\"key\": \"" << row.key << "\", \"kind\": \"" << kind
       << "\", \"lo\": " << row.lo << ", \"hi\": " << row.hi
       << ", \"lo_open\": " << (row.lo_open ? "true" : "false")
       << ", \"hi_open\": " << (row.hi_open ? "true" : "false") << ", \"units\": \"" << row.units
       << "\"}";
    first = false;
  }
  js << "]";
  return CopyOut(js.str(), buf, len);
}

// The model cache key of a configuration given as "key=value" lines (on a
// sphere pad of radius 8 mm), or "error: ..." (tests: every physics
// attribute must change the key).
extern "C" __attribute__((visibility("default"))) int mjtouch_config_cache_key(const char* text,
                                                                              char* buf,
                                                                              int len) {
  std::istringstream lines(text ? text : "");
  std::string line;
  std::vector<std::pair<std::string, std::string>> kv;
  while (std::getline(lines, line)) {
    const size_t eq = line.find('=');
    if (eq != std::string::npos) kv.emplace_back(line.substr(0, eq), line.substr(eq + 1));
  }
  mjtouch::SkinConfig cfg;
  std::string error;
  const bool ok = mjtouch::ParseSkinAttributes(
      [&](const char* key) -> std::optional<std::string> {
        for (const auto& [k, v] : kv)
          if (k == key) return v;
        return std::nullopt;
      },
      &cfg, &error);
  if (!ok) return CopyOut("error: " + error, buf, len);
  cfg.pad.shape = mjtouch::PadShape::kSphere;
  for (double& a : cfg.pad.semi_axes_m) a = 8e-3;
  return CopyOut(mjtouch::ConfigCacheKey(cfg), buf, len);
}
