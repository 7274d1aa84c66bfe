#pragma once
// Perturbed cloth starts for simulation windows: the method's simulation loss starts its
// windows from network predictions, which are stretched or compressed, off by centimetres
// and partly inside the body, with velocities from the difference of two such states.
// perturb_start makes such a start from a ground-truth pair (x_{t−1}, x_t), seeded and
// deterministic (PortableRandom: the same on every platform), with every part bounded:
//   1. stretch: x ← c + A(x − c) about the centroid c, A = λ_⊥ I + (λ_a − λ_⊥) a aᵀ with a
//      random unit axis a and λ_a, λ_⊥ uniform in [1 − max_stretch, 1 + max_stretch], so
//      every length changes by a factor in that range (0.3: 30 % compressed to 30 %
//      stretched);
//   2. smooth displacement, embedded-graph-like: random translations t_k (uniform
//      direction, length uniform in [0, max_displacement_m]) at `nodes` random vertices,
//      blended by normalised Gaussian weights of each vertex's rest distance to the nodes,
//      d(x_i) = Σ w_k t_k / Σ w_k: a convex combination, so ‖d‖ ≤ max_displacement_m;
//   3. patches pushed into the body: at `patches` random vertices within
//      patch_candidate_distance_m of the body, every vertex within patch_radius_m moves
//      along minus its closest body normal by w(r)·(d_i + patch_depth_m) (w = (1 − r²/R²)²,
//      d_i its signed distance, moves only inwards), so the centre ends patch_depth_m
//      inside and no vertex deeper than that (on a locally flat body) unless it was;
//   4. velocity: v = (x_t − x_{t−1})/h + noise, the noise a smooth field like 2. of at
//      most velocity_noise_smooth_mps plus a per-vertex uniform ball of radius
//      velocity_noise_vertex_mps; x_prev2 = x_prev − h·v.
// Distances in metres, velocities in m/s.
#include <cstdint>
#include <vector>

#include "physics/body_mesh.h"
#include "physics/cloth_model.h"

namespace weft::capture {

struct ClothPerturbationConfig {
  double max_stretch = 0.3;            // principal stretches in [1 − this, 1 + this]
  int nodes = 32;                      // smooth displacement: translation nodes
  double max_displacement_m = 0.03;    // bound on each vertex's smooth displacement
  double node_sigma_m = 0.1;           // Gaussian width of a node's weight (smoothness scale)
  int patches = 2;                     // patches pushed into the body
  double patch_depth_m = 0.02;         // depth of a patch's centre below the body surface
  double patch_radius_m = 0.05;        // support of a patch
  double patch_candidate_distance_m = 0.03;  // patch centres: vertices this close to the body
  double velocity_noise_smooth_mps = 0.5;    // smooth velocity noise bound
  double velocity_noise_vertex_mps = 0.05;   // per-vertex velocity noise bound
};

// What one draw did (reports, tests).
struct ClothPerturbation {
  physics::Vec3 centroid = physics::Vec3::Zero();  // m
  physics::Vec3 stretch_axis = physics::Vec3::UnitX();
  double axial_stretch = 1, lateral_stretch = 1;    // λ_a, λ_⊥
  physics::Positions displacement;     // step 2's d(x_i) per vertex (3n, m)
  std::vector<int> patch_centres;      // vertex ids (fewer than `patches` if no candidate)
  physics::Positions velocity_noise;   // step 4's noise (3n, m/s)
};

struct PerturbedStart {
  physics::Positions x_prev2, x_prev;  // m, one time step h apart
  ClothPerturbation drawn;
};

// x_before, x: ground truth at t − 1 and t (3n, m); rest: the cloth's rest positions
// (3n, m; the displacement's weights use rest distances, so the field is smooth on the
// cloth however it is posed); body: the body at frame t (for the patches' normals); h: the
// time step (s). Deterministic for (inputs, config, seed).
PerturbedStart perturb_start(const physics::Positions& x_before, const physics::Positions& x,
                             const physics::Positions& rest, const physics::BodyMesh& body, double h,
                             const ClothPerturbationConfig& config, uint64_t seed);

}  // namespace weft::capture
