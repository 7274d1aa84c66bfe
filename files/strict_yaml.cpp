#include "files/strict_yaml.h"

#include <algorithm>
#include <sstream>

namespace weft {

void StrictYaml::fail_at(const YAML::Node& node, const std::string& key, const std::string& msg) const {
  const YAML::Mark m = node.Mark();
  if (m.line >= 0) weft::fail(file, ":", m.line + 1, ": ", key, ": ", msg);
  weft::fail(file, ": ", key, ": ", msg);
}

void StrictYaml::check_keys(const YAML::Node& map, const std::string& where,
                            const std::vector<const char*>& known) const {
  if (!map.IsMap()) fail_at(map, where.empty() ? "(top level)" : where, "expected a mapping");
  for (const auto& kv : map) {
    const std::string key = kv.first.as<std::string>();
    if (std::none_of(known.begin(), known.end(), [&](const char* k) { return key == k; })) {
      std::string list;
      for (const char* k : known) list += std::string(list.empty() ? "" : ", ") + k;
      // `where` is a section ("body") or a key prefix ending in a dot ("cameras.").
      const std::string full = where.empty() || where.back() == '.' ? where + key : where + "." + key;
      fail_at(kv.first, full, "unknown key (expected one of: " + list + ")");
    }
  }
}

double StrictYaml::number(const YAML::Node& node, const std::string& key) const {
  const double v = get<double>(node, key, "a number");
  if (!std::isfinite(v)) fail_at(node, key, "expected a finite number");
  return v;
}

double StrictYaml::number(const YAML::Node& node, const std::string& key, double lo,
                          double hi) const {
  const double v = number(node, key);
  if (v < lo || v > hi) {
    std::ostringstream range;  // shortest form: [0.01, 1e+06], not [0.010000, 1000000.000000]
    range << "[" << lo << ", " << hi << "]";
    fail_at(node, key, "expected a number in " + range.str() + ", found " + node.Scalar());
  }
  return v;
}

void StrictYaml::numbers(const YAML::Node& n, const std::string& where, const std::vector<NumberKey>& numbers,
                         const std::vector<IntegerKey>& integers, std::vector<const char*> other_keys) const {
  for (const NumberKey& k : numbers) other_keys.push_back(k.key);
  for (const IntegerKey& k : integers) other_keys.push_back(k.key);
  check_keys(n, where, other_keys);
  for (const NumberKey& k : numbers)
    if (n[k.key]) *k.value = number(n[k.key], where + k.key, k.lo, k.hi);
  for (const IntegerKey& k : integers)
    if (n[k.key]) *k.value = static_cast<int>(number(n[k.key], where + k.key, k.lo, k.hi));
}

double StrictYaml::positive(const YAML::Node& node, const std::string& key) const {
  const double v = number(node, key);
  if (!(v > 0)) fail_at(node, key, "expected a number > 0");
  return v;
}

std::vector<std::string> StrictYaml::strings(const YAML::Node& node, const std::string& key) const {
  if (!node.IsSequence()) fail_at(node, key, "expected a list of names");
  std::vector<std::string> out;
  for (const auto& n : node) out.push_back(get<std::string>(n, key, "a name"));
  return out;
}

std::string StrictYaml::path(const YAML::Node& node, const std::string& key) const {
  const std::string p = get<std::string>(node, key, "a file path");
  if (p.empty()) fail_at(node, key, "empty path");
  const std::filesystem::path full = (dir / p).lexically_normal();
  if (!std::filesystem::exists(full)) fail_at(node, key, "file not found: " + full.string());
  return full.string();
}

YAML::Node StrictYaml::parse(const std::string& text) const {
  try {
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {
    weft::fail(file, ":", e.mark.line + 1, ": invalid YAML: ", e.msg);
  }
}

}  // namespace weft
