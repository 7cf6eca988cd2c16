// Parse functions of the structured attributes (lists, per-class names, the
// layered stack) and the cross-attribute checks; referenced from the
// attribute table (attributes.cc). Each parses a present, non-empty value,
// and its Write*Key writes the parsed value to the model cache key.
#ifndef MJTOUCH_PIPELINE_ATTRIBUTE_PARSERS_H_
#define MJTOUCH_PIPELINE_ATTRIBUTE_PARSERS_H_

#include <ostream>
#include <string>
#include <vector>

#include "pipeline/attributes.h"

namespace mjtouch {

// Valid Young's moduli of `layers` and `base`, Pa, and layer thicknesses, m
// (attributes.cc says why).
constexpr double kMinLayerModulusPa = 100.0, kMaxLayerModulusPa = 2e10;
constexpr double kMinLayerThicknessM = 1e-6, kMaxLayerThicknessM = 1.0;

// The grammar of a one-entry composite value (`classes`, `outputs`,
// `quantity`, `sa1_merkel`, `base`, the per-class numbers): words separated
// by whitespace; ',' or ';' fails naming the attribute and `form`.
bool ListWords(AttributeParser* p, const char* key, const std::string& value, const char* form,
               std::vector<std::string>* words);

bool ParseTextureAttribute(const std::string& v, SkinConfig* cfg, AttributeParser* p);
bool ParseOversampleAttribute(const std::string& v, SkinConfig* cfg, AttributeParser* p);
bool ParseClassesAttribute(const std::string& v, SkinConfig* cfg, AttributeParser* p);
bool ParseQuantityAttribute(const std::string& v, SkinConfig* cfg, AttributeParser* p);
bool ParseOutputsAttribute(const std::string& v, SkinConfig* cfg, AttributeParser* p);
bool ParseShearAttribute(const std::string& v, SkinConfig* cfg, AttributeParser* p);
bool ParseMerkelAttribute(const std::string& v, SkinConfig* cfg, AttributeParser* p);
bool ParseSeedAttribute(const std::string& v, SkinConfig* cfg, AttributeParser* p);
bool ParseSitesAttribute(const std::string& v, SkinConfig* cfg, AttributeParser* p);
bool ParseLayersAttribute(const std::string& v, SkinConfig* cfg, AttributeParser* p);
bool ParseBaseAttribute(const std::string& v, SkinConfig* cfg, AttributeParser* p);

void WriteOversampleKey(const SkinConfig& cfg, std::ostream& out);
void WriteClassesKey(const SkinConfig& cfg, std::ostream& out);
void WriteQuantityKey(const SkinConfig& cfg, std::ostream& out);
void WriteOutputsKey(const SkinConfig& cfg, std::ostream& out);
void WriteShearKey(const SkinConfig& cfg, std::ostream& out);
void WriteMerkelKey(const SkinConfig& cfg, std::ostream& out);
void WriteSeedKey(const SkinConfig& cfg, std::ostream& out);
void WriteSitesKey(const SkinConfig& cfg, std::ostream& out);
void WriteLayersKey(const SkinConfig& cfg, std::ostream& out);
void WriteBaseKey(const SkinConfig& cfg, std::ostream& out);

// After every row: checks between attributes (oversample vs the contacts
// model, stress_theta vs the method, skin-specific keys, the elastic skin
// vs the depths, radius and ridge_pitch vs the grid) and the grid-fitted
// default radius.
bool CheckAttributeCombinations(const AttributeParser& p, SkinConfig* cfg, std::string* error);

}  // namespace mjtouch

#endif  // MJTOUCH_PIPELINE_ATTRIBUTE_PARSERS_H_
