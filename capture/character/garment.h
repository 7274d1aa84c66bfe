#pragma once
// Garments generated around a body in its bind pose: a tube of rings (a skirt from the
// waist, a dress from under the arms) whose radius, per angle and height, clears the
// body by a margin and only grows downward (the cloth hangs; it never dips between the
// legs). The top ring is the waistband: its vertices are the anchors tied to the body.
#include <Eigen/Core>
#include <vector>

#include "geometry/mesh.h"

namespace weft::capture {

struct TubeGarmentOptions {
  double top_y = 0;        // height of the top ring (units)
  double length = 0.5;     // from the top ring down to the hem (units)
  double flare = 0.3;      // radius gained per unit of drop beyond what the body needs
  double clearance = 0.01; // minimum distance to the body in the bind pose (units)
  int segments = 64;       // vertices around each ring
  int rings = 48;          // rings from top to hem (≥ 2)
  double mid_x = 0;        // the body's midline plane x = mid_x (units): the axis is found there
};

struct TubeGarment {
  TriangleMesh mesh;          // rings × segments vertices, outward-facing triangles
  std::vector<int> anchors;   // the top ring (cloth vertex indices)
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();  // the tube's axis (x, z)
  double min_distance = 0;    // smallest unsigned distance to the body (units)
  int inside = 0;             // garment vertices inside the body (0 when generation succeeded)
};

// `excluded` (per body vertex, may be empty) marks vertices the garment may ignore when it
// sizes itself (the arms and hands: the skirt goes under the hands in the A-pose). The
// axis passes through the centroid of the largest body cross-section at top_y that
// crosses the midline plane x = mid_x (Y up, the body facing ±z). After sizing,
// every garment vertex closer than `clearance` to the non-excluded body is pushed
// outward until it clears it. Deterministic.
TubeGarment generate_tube_garment(const TriangleMesh& body, const std::vector<char>& excluded,
                                  const TubeGarmentOptions& options);

// Adds a shoulder strap to a tube garment (a dress): a band two vertices wide that leaves
// the top ring at the front where x is closest to `x`, runs over the shoulder `clearance`
// outside the body's cross-section by the plane x = const, and rejoins the top ring at
// the back (its end vertices are top-ring vertices, so the strap is sewn to the dress).
// Strap vertices higher than `anchor_y` become anchors. Throws weft::Error if the plane
// does not reach over the body above the top ring.
void add_shoulder_strap(TubeGarment& garment, const TriangleMesh& body, double x, double clearance,
                        double anchor_y, int segments);

// Signed distance of each point to a closed body mesh: the distance to the closest
// triangle, negative inside (generalised winding number). Multithreaded (TBB).
Eigen::VectorXd signed_distances(const TriangleMesh& body, const Vertices& points);

}  // namespace weft::capture
