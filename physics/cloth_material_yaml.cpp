#include "physics/cloth_material_yaml.h"

#include <charconv>
#include <cmath>
#include <limits>
#include <sstream>

namespace weft::physics {

namespace {

// A finite number in [lo, hi] (hi_open: [lo, hi)); the message names the range.
double number_in(const StrictYaml& y, const YAML::Node& n, const std::string& key, double lo, double hi,
                 bool hi_open, const char* unit) {
  const double v = y.number(n, key);
  if (v < lo || v > hi || (hi_open && v == hi)) {
    std::ostringstream msg;
    msg << "expected a number";
    if (std::isinf(hi)) msg << " >= " << lo;
    else msg << " in [" << lo << ", " << hi << (hi_open ? ")" : "]");
    msg << unit << ", found " << n.Scalar();
    y.fail_at(n, key, msg.str());
  }
  return v;
}

}  // namespace

void read_cloth_material(const StrictYaml& y, const YAML::Node& n, const std::string& key, ClothMaterial& m) {
  y.check_keys(n, key,
               {"density", "youngs_modulus", "poisson_ratio", "bending_stiffness", "thickness", "membrane",
                "compression_ratio", "min_area_ratio"});
  const double inf = std::numeric_limits<double>::infinity();
  auto full = [&](const char* k) { return key + "." + k; };
  if (n["density"]) m.density = y.positive(n["density"], full("density"));
  if (n["youngs_modulus"])
    m.youngs_modulus = number_in(y, n["youngs_modulus"], full("youngs_modulus"), 0, inf, false, " Pa");
  if (n["poisson_ratio"])
    m.poisson_ratio = number_in(y, n["poisson_ratio"], full("poisson_ratio"), 0, 0.5, true, "");
  if (n["bending_stiffness"])
    m.bending_stiffness = number_in(y, n["bending_stiffness"], full("bending_stiffness"), 0, inf, false, " N·m");
  if (n["thickness"]) m.thickness = y.positive(n["thickness"], full("thickness"));
  if (n["membrane"]) {
    const std::string model = y.get<std::string>(n["membrane"], full("membrane"), "a string");
    if (model != "stvk" && model != "tension_field")
      y.fail_at(n["membrane"], full("membrane"), "expected stvk or tension_field, found '" + model + "'");
    m.membrane = model == "stvk" ? MembraneModel::stvk : MembraneModel::tension_field;
  }
  if (n["compression_ratio"])
    m.compression_ratio = number_in(y, n["compression_ratio"], full("compression_ratio"), 0, 1, false, "");
  if (n["min_area_ratio"])
    m.min_area_ratio = number_in(y, n["min_area_ratio"], full("min_area_ratio"), 0, 1, true, "");
}

std::string yaml_number(double value) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, value);
  return std::string(buf, r.ptr);
}

std::string cloth_material_yaml(const ClothMaterial& m) {
  return "{density: " + yaml_number(m.density) + ", youngs_modulus: " + yaml_number(m.youngs_modulus) +
         ", poisson_ratio: " + yaml_number(m.poisson_ratio) + ", bending_stiffness: " +
         yaml_number(m.bending_stiffness) + ", thickness: " + yaml_number(m.thickness) +
         ", membrane: " + to_string(m.membrane) + ", compression_ratio: " + yaml_number(m.compression_ratio) +
         ", min_area_ratio: " + yaml_number(m.min_area_ratio) + "}";
}

}  // namespace weft::physics
