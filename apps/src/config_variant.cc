#include "config_variant.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "skerry/core/input_error.h"

namespace skerry::cli {

ConfigVariant ParseConfigVariant(const std::string& text, const std::string& field) {
  ConfigVariant v;
  if (std::filesystem::is_regular_file(text)) {
    v.source = text;
    return v;
  }
  std::vector<std::string> parts(1);
  int depth = 0;
  for (const char c : text) {
    if (c == '[' || c == '{') ++depth;
    if ((c == ']' || c == '}') && depth > 0) --depth;
    if (c == ',' && depth == 0) {
      parts.emplace_back();
    } else {
      parts.back() += c;
    }
  }
  for (const std::string& p : parts) {
    if (p.empty()) {
      throw InputError(kCommandLine, 0, field,
                       "'" + text + "': an empty part (expected SOURCE[,KEY=VALUE...])");
    }
  }
  v.source = parts.front();
  v.overrides.assign(parts.begin() + 1, parts.end());
  return v;
}

EstimatorConfig LoadConfigVariant(const std::string& text, const std::string& field) {
  const ConfigVariant v = ParseConfigVariant(text, field);
  EstimatorConfig config;
  try {
    config = LoadPreset(v.source, v.overrides);
  } catch (const InputError& e) {
    // LoadPreset names a bad override `--set KEY`; here it came in as part of `field`.
    const std::string set = "--set ";
    if (e.file() != kCommandLine || e.field().rfind(set, 0) != 0) throw;
    throw InputError(kCommandLine, 0, field + " " + e.field().substr(set.size()), e.message());
  }
  const auto key_of = [](const std::string& o) { return o.substr(0, o.find('=')); };
  const bool named = std::any_of(v.overrides.begin(), v.overrides.end(),
                                 [&](const std::string& o) { return key_of(o) == "name"; });
  if (named || v.overrides.empty()) return config;
  std::string name = config.name;
  for (const std::string& o : v.overrides) {  // LoadPreset has checked each has an '='
    const std::string key = key_of(o);
    name += "-" + key.substr(key.rfind('.') + 1) + "-" + o.substr(o.find('=') + 1);
  }
  for (char& c : name) {
    const bool ok = std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-';
    if (!ok) c = '_';
  }
  config.name = name;
  return config;
}

}  // namespace skerry::cli
