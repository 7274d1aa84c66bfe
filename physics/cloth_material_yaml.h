#pragma once
// The cloth material as YAML: the `cloth.material` section of a `weft sim` scene
// (docs/SIMULATION.md) and the `simulation.material` section of a `weft synth` config
// (docs/DATASET.md) are read by this one parser, so both accept the same keys with the same
// ranges: those validate(ClothMaterial) enforces (cloth_model.h).
#include <string>

#include "files/strict_yaml.h"
#include "physics/cloth_model.h"

namespace weft::physics {

// Reads the keys present in the mapping `node` into `material`; absent keys keep the value
// `material` has. `key` names the section in messages ("cloth.material"). Unknown keys,
// wrong types and values out of range are one weft::Error naming the file, the line and the
// key (e.g. "scene.yaml:7: cloth.material.poisson_ratio: expected a number in [0, 0.5)").
//   density            kg/m², > 0
//   youngs_modulus     Pa, >= 0
//   poisson_ratio      [0, 0.5)
//   bending_stiffness  N·m, >= 0
//   thickness          m, > 0
//   membrane           stvk | tension_field
//   compression_ratio  [0, 1]
//   min_area_ratio     [0, 1)
void read_cloth_material(const StrictYaml& yaml, const YAML::Node& node, const std::string& key,
                         ClothMaterial& material);

// Every key of `material` as a YAML flow mapping ("{density: 0.15, youngs_modulus: 200000,
// ...}"), numbers in their shortest form that reads back to the same double, so
// read_cloth_material gives `material` back exactly.
std::string cloth_material_yaml(const ClothMaterial& material);

// The shortest text that reads back to the same double (std::to_chars), for YAML written
// to be read again.
std::string yaml_number(double value);

}  // namespace weft::physics
