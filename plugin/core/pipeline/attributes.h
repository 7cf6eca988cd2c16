// The MJCF attributes of mjtouch.skin as one table (attributes.cc). Each row
// gives the key, its kind, valid range and units, the default and meaning
// shown in plugin/README.md, and where the parsed value lives in SkinConfig.
// From the table come: the keys registered with MuJoCo, parsing and range
// checks (messages name the attribute, its value and valid range with
// units), the model cache key, and README's attribute table.
#ifndef MJTOUCH_PIPELINE_ATTRIBUTES_H_
#define MJTOUCH_PIPELINE_ATTRIBUTES_H_

#include <functional>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "pipeline/config.h"

namespace mjtouch {

enum class AttributeKind {
  kNumber,    // one finite number in [lo, hi] (ends open or closed)
  kInteger,   // one integer in [lo, hi]
  kBool,      // true / false / 1 / 0
  kChoice,    // one word of `choices` (its index is the parsed value)
  kPerClass,  // one number per receptor class (SA1 RA PC), each in [lo, hi]
  kCustom,    // parsed by `parse`; `range_text` says what is valid
};

// Whether an attribute's parsed value goes into the model cache key.
enum class AttributeScope {
  kModel,    // physics: part of the key (two models differing here never share)
  kDrawing,  // drawing only (`visual`): not part of the physics
  kAdapter,  // read by the MuJoCo adapter, not stored in SkinConfig (`texture`)
};

class AttributeParser;

struct AttributeRow {
  const char* key;
  AttributeKind kind;
  double lo, hi;  // kNumber, kInteger, kPerClass
  bool lo_open, hi_open;
  const char* units;  // "" when dimensionless
  const char* default_text;
  const char* meaning;
  // kChoice: the words, space-separated; kCustom: the valid values in words.
  const char* choices_or_range;
  // The parsed value: kNumber / kInteger / kBool / kChoice (index 0) and
  // kPerClass (index = class). Set only from a valid, present value.
  double (*get)(const SkinConfig& cfg, int index);
  void (*set)(SkinConfig* cfg, int index, double value);
  // kCustom: parse a present, non-empty value (false after p->Fail) and
  // write the parsed value to the cache key.
  bool (*parse)(const std::string& value, SkinConfig* cfg, AttributeParser* p);
  void (*cache_key)(const SkinConfig& cfg, std::ostream& out);
  AttributeScope scope;
};

// Every attribute, in parsing order (later rows may read earlier ones).
const std::vector<AttributeRow>& SkinAttributes();
// The valid values of a row as messages and README show them, e.g.
// "(0, 0.01] m", "[4, 512]", "sine triangle square".
std::string ValidRangeText(const AttributeRow& row);

// Looks up an attribute's raw value: nullopt when unset. (MuJoCo stores an
// unset attribute and value="" alike, as ""; whitespace is kept and is an
// error here.)
using AttributeLookup = std::function<std::optional<std::string>(const char* key)>;
// Returns "" when unset (and so cannot tell value="" from unset).
using AttributeGetter = std::function<std::string(const char* key)>;

// Parses and checks every attribute; false with a message naming the
// attribute, its value and its valid range (with units).
bool ParseSkinAttributes(const AttributeLookup& lookup, SkinConfig* cfg, std::string* error);
bool ParseSkinConfig(const AttributeGetter& get, SkinConfig* cfg, std::string* error);

// All attribute keys, for plugin registration.
const std::vector<const char*>& SkinAttributeKeys();

// Canonical text of every physics attribute's parsed value plus the pad
// geometry: equal keys <=> models that may share one SkinModel.
std::string ConfigCacheKey(const SkinConfig& cfg);

// plugin/README.md's attribute table (markdown), generated from the rows.
std::string AttributeTableMarkdown();

// State of one ParseSkinConfig call, for the custom parse functions.
class AttributeParser {
 public:
  explicit AttributeParser(std::string* error) : error_(error) {}
  bool ok() const { return ok_; }
  // Records the first failure ("mjtouch.skin: " + msg); returns false.
  bool Fail(const std::string& msg);
  // Whether `key` was given (set before its row's parse function runs).
  bool Present(const char* key) const;
  void MarkPresent(const char* key) { present_.push_back(key); }

 private:
  std::string* error_;
  bool ok_ = true;
  std::vector<std::string> present_;
};

}  // namespace mjtouch

#endif  // MJTOUCH_PIPELINE_ATTRIBUTES_H_
