#pragma once
// The method's optional final collision-resolution pass at test time: cloth vertices a
// network predicted inside the body are pushed out by a few quasi-static Newton steps on
//   E(x) = W_membrane(x; x₀) + W_bend(x; x₀) + E_collision(x; obstacles) + E_pins(x)
//          + k/2 ‖x − x₀‖²_M,
// x₀ the predicted positions, M the cloth's lumped masses, k the proximal stiffness
// (1/s²). No gravity and no inertia beyond the proximal term: the pass corrects the
// prediction's contacts, it does not simulate.
//
// The elastic energies are the simulator's (the same classes, material and collision
// penalty) but measured from the prediction: the membrane and bending take x₀ as their
// rest state, so the prediction's own shape exerts no force, and where vertices are pushed
// out their neighbours follow as an elastic sheet would, by a displacement that decays
// over the length sqrt(E·t / (k·ρ)) (E·t the membrane stiffness, ρ the areal density:
// 3.7 cm for the synthetic studio's skirt at the default k). Measured from the template's
// rest shape instead, the membrane would also pull every stretched part of the prediction
// back, moving cloth far from any contact.
//
// Because the correction decays away from the penetrations, only a region is solved: the
// vertices within `region_radius` (geodesic along the predicted cloth's edges) of a vertex
// inside an obstacle (signed distance < 0), plus the ring of vertices around it, held at x₀
// by stiff pins. Everything else is returned exactly at x₀, including vertices that rest
// in the collision band (0 ≤ d < thickness) away from any penetration: the pass resolves
// penetrations, it does not re-balance contact. A prediction with no vertex inside is
// returned unchanged without a Newton iteration. The Newton solver is the simulator's
// (CHOLMOD, regularisation, step filter, Armijo line search), on that region.
//
// Guarantees: the returned x is finite; every accepted Newton iterate lowers E (the
// report's energies); vertices outside the region are not moved. Not guaranteed: that
// nothing stays inside — a vertex ends where the penalty balances the elastic and proximal
// forces, normally in the band outside the surface (on the 3k skirt nothing was left
// inside, docs/BENCHMARKS.md); the stats report what is left inside after the pass.
#include <limits>
#include <string>
#include <vector>

#include "physics/body_mesh.h"
#include "physics/cloth_model.h"
#include "physics/collision_energy.h"
#include "physics/newton_solver.h"

namespace weft::physics {

struct CollisionResolutionOptions {
  ClothMaterial material;              // the simulator's cloth material (density unused: masses from the mesh)
  double collision_thickness = 0.005;  // m, the penalty's band δ (SimulationSettings' meaning)
  double collision_stiffness = 1.0e4;  // N/m
  double pin_stiffness = 1.0e4;        // N/m: the held vertices and the region's border ring
  // k of the proximal term k/2 ‖x − x₀‖²_M, in 1/s² (N/m per kg of vertex mass). Larger
  // keeps the correction more local (decay length sqrt(E·t/(k·ρ))).
  double proximal_stiffness = 1.0e6;
  // Geodesic radius (m) of the solved region around the vertices inside; infinity solves
  // the whole cloth (connected to a vertex inside; those resting in the band then move too).
  double region_radius = 0.06;
  int max_iterations = 20;
  // Converged when every vertex's force residual is below the proximal force of this
  // displacement, ‖∇_i E‖ ≤ k·m_i·tolerance_m (m; the Hessian is at least k·M), or when a
  // Newton iteration moves no vertex farther than it: where the body's distance field has
  // a kink (concave creases, edges of the left-out faces) the penalty is not smooth and
  // Newton's line search stalls next to the minimiser with the residual above the test.
  double tolerance_m = 1.0e-4;
  // Also converged when an iteration lowered E by at most this fraction of E and no solved
  // vertex is inside any more: measured on the skirt, E then has settled to 0.1 % while
  // the position test above would take as many iterations again for sub-millimetre
  // refinements. 0 switches this test off.
  double energy_tolerance = 1.0e-3;
  // A predicted triangle whose area fell below this fraction of its rest area has no
  // usable shape to measure elasticity from; it is left out of the membrane and bending.
  double min_reference_area_ratio = 1.0e-3;
};
// Throws weft::Error naming the field if a value is out of range.
void validate(const CollisionResolutionOptions& options);

// Cloth vertices inside the obstacles: depth = −signed distance (m) of those with a
// negative one.
struct PenetrationStats {
  double max_depth = 0;   // m, 0 when none is inside
  double mean_depth = 0;  // m, over the vertices inside; 0 when none is
  int vertices_inside = 0;
};

struct CollisionResolutionResult {
  Positions x;                       // 3n, metres
  PenetrationStats before, after;
  StepStatus status = StepStatus::converged;
  int iterations = 0;                // Newton iterations (0: nothing to resolve)
  int region_vertices = 0;           // vertices solved (without the held border ring)
  std::vector<double> energies;      // E after each accepted Newton iterate (first: at x₀), J
  double distance_ms = 0;            // signed distances before and after, ms
  double setup_ms = 0;               // region, energies, symbolic factorisation, ms
  double newton_ms = 0;              // the Newton solve, ms, of which:
  std::vector<std::string> energy_names;  //   the energies (proximal = "inertia", membrane, ...)
  std::vector<double> energy_ms;          //   evaluating each (values, gradients, Hessians), ms
  double linear_solve_ms = 0;             //   factorisations and solves, ms
  double total_ms = 0;               // wall time of the whole pass, ms
};

// The obstacles the cloth is pushed out of (non-owning; bodies must outlive the call).
struct CollisionObstacles {
  std::vector<SphereObstacle> spheres;
  std::vector<const BodyMesh*> bodies;
};

// Signed-distance penetration of `x` (3n, m) into the obstacles (the simulator's distance).
PenetrationStats measure_penetration(const Positions& x, const CollisionObstacles& obstacles);

// The pass. `mesh`: the cloth (rest positions, triangles; its lumped masses weigh the
// proximal term); `x0`: the predicted positions (3n, metres, finite); `held`: vertices
// pinned at x₀ (e.g. anchors; may be empty). Throws weft::Error on a wrong vertex count,
// non-finite positions, a held vertex out of range or bad options.
CollisionResolutionResult resolve_collisions(const ClothMesh& mesh, const Positions& x0,
                                             const CollisionObstacles& obstacles,
                                             const CollisionResolutionOptions& options,
                                             const std::vector<int>& held = {});

}  // namespace weft::physics
