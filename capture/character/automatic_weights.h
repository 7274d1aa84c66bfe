#pragma once
// Skinning weights for meshes that come without them.
#include "geometry/mesh.h"
#include "capture/character/skeleton.h"
#include "capture/character/skinning.h"

namespace weft::capture {

// Each `target` vertex (e.g. a garment) takes the weights of the closest point on the
// `body` surface: the barycentric blend of that triangle's three vertex weight sets,
// keeping the `max_influences` largest, renormalised, sorted by decreasing weight.
// Both meshes in the same (bind) pose and units.
SkinningWeights transfer_weights_from_closest_point(const TriangleMesh& body,
                                                    const SkinningWeights& body_weights,
                                                    const TriangleMesh& target,
                                                    int max_influences = 8);

struct BoneDistanceOptions {
  int max_influences = 4;  // top-k bones per vertex
  double falloff = 4.0;    // w ∝ (d + ε)^−falloff, d the distance to the bone segment
  double epsilon = 1e-3;   // as a fraction of the skeleton's bounding-box diagonal
};

// Weights from distances to bone segments in the bind pose `bind` (global joint
// transforms): every joint whose origin is offset from its parent's defines the segment
// parent→joint, which moves with the parent joint. Each vertex takes the k nearest
// segments' joints with w ∝ (d + ε)^−falloff, normalised and sorted by decreasing weight.
// Smooth in the vertex position (no hard cut except at the top-k switch), deterministic.
SkinningWeights bone_distance_weights(const Vertices& V, const Skeleton& skeleton,
                                      const Transforms& bind, const BoneDistanceOptions& options = {});

}  // namespace weft::capture
