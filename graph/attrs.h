#pragma once
// Named, typed attributes of an op call (stride, axes, eps, ...).
#include <cstdint>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "graph/error.h"

namespace weft {

using AttrValue =
    std::variant<bool, int64_t, double, std::vector<int64_t>, std::vector<double>, std::string>;

class Attrs {
 public:
  Attrs() = default;
  Attrs(std::initializer_list<std::pair<std::string, AttrValue>> init) : items_(init) {}

  Attrs& set(const std::string& name, AttrValue v) {
    for (auto& [k, val] : items_)
      if (k == name) {
        val = std::move(v);
        return *this;
      }
    items_.emplace_back(name, std::move(v));
    return *this;
  }
  bool has(const std::string& name) const { return find(name) != nullptr; }

  int64_t get_int(const std::string& name) const { return get<int64_t>(name); }
  int64_t get_int(const std::string& name, int64_t fallback) const {
    return has(name) ? get<int64_t>(name) : fallback;
  }
  double get_float(const std::string& name) const {
    const AttrValue* v = require(name);
    if (auto* i = std::get_if<int64_t>(v)) return static_cast<double>(*i);
    return get<double>(name);
  }
  double get_float(const std::string& name, double fallback) const {
    return has(name) ? get_float(name) : fallback;
  }
  bool get_bool(const std::string& name, bool fallback = false) const {
    return has(name) ? get<bool>(name) : fallback;
  }
  std::vector<int64_t> get_ints(const std::string& name,
                                std::vector<int64_t> fallback = {}) const {
    if (!has(name)) return fallback;
    const AttrValue* v = find(name);
    if (auto* i = std::get_if<int64_t>(v)) return {*i};
    return get<std::vector<int64_t>>(name);
  }
  std::vector<double> get_floats(const std::string& name) const {
    return get<std::vector<double>>(name);
  }
  std::string get_string(const std::string& name, std::string fallback = "") const {
    return has(name) ? get<std::string>(name) : fallback;
  }
  const std::vector<std::pair<std::string, AttrValue>>& items() const { return items_; }

 private:
  const AttrValue* find(const std::string& name) const {
    for (auto& [k, v] : items_)
      if (k == name) return &v;
    return nullptr;
  }
  const AttrValue* require(const std::string& name) const {
    const AttrValue* v = find(name);
    if (!v) fail("missing attribute '", name, "'");
    return v;
  }
  template <class T>
  const T& get(const std::string& name) const {
    const AttrValue* v = require(name);
    const T* p = std::get_if<T>(v);
    if (!p) fail("attribute '", name, "' has the wrong type");
    return *p;
  }
  std::vector<std::pair<std::string, AttrValue>> items_;
};

}  // namespace weft
