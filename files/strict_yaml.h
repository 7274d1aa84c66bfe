#pragma once
// Strict reading of hand-written YAML, the one YAML reader of weft (`weft sim` scenes,
// character.yaml, retarget mappings, motion specs, synth and training configs, model
// folders): unknown keys, wrong types and out-of-range values are errors that name the
// file, the line and the key, with what was expected.
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <type_traits>
#include <vector>

#include "graph/error.h"

namespace weft {

// A section's numeric key: the field it sets and the range it allows.
struct NumberKey {
  const char* key;
  double* value;
  double lo, hi;
};
struct IntegerKey {
  const char* key;
  int* value;
  double lo, hi;
};

struct StrictYaml {
  std::string file;            // display name used in messages
  std::filesystem::path dir;   // relative paths are resolved against this (path())

  // "file:line: key: msg" (the line when the node has one).
  [[noreturn]] void fail_at(const YAML::Node& node, const std::string& key, const std::string& msg) const;
  // `map` must be a mapping whose keys are all in `known`; `where` prefixes key names.
  void check_keys(const YAML::Node& map, const std::string& where,
                  const std::vector<const char*>& known) const;

  // The node as T; scalars must be scalars (a list where a number belongs is an error).
  template <class T>
  T get(const YAML::Node& node, const std::string& key, const char* what) const {
    constexpr bool scalar = std::is_arithmetic_v<T> || std::is_same_v<T, std::string>;
    if (scalar && !node.IsScalar()) fail_at(node, key, std::string("expected ") + what);
    try {
      return node.as<T>();
    } catch (const YAML::Exception&) {
      fail_at(node, key,
              std::string("expected ") + what +
                  (node.IsScalar() ? ", found '" + node.Scalar() + "'" : std::string()));
    }
  }
  double number(const YAML::Node& node, const std::string& key) const;  // finite
  double number(const YAML::Node& node, const std::string& key, double lo, double hi) const;
  double positive(const YAML::Node& node, const std::string& key) const;
  std::vector<std::string> strings(const YAML::Node& node, const std::string& key) const;
  // Checks that the section `n` holds only these keys and `other_keys` (which the caller
  // parses) and reads the numbers present into their fields; `where` prefixes key names.
  void numbers(const YAML::Node& n, const std::string& where, const std::vector<NumberKey>& numbers,
               const std::vector<IntegerKey>& integers, std::vector<const char*> other_keys) const;
  // A file path relative to `dir`; it must exist.
  std::string path(const YAML::Node& node, const std::string& key) const;
  // Parses YAML text; a syntax error names the file and line.
  YAML::Node parse(const std::string& text) const;
};

}  // namespace weft
