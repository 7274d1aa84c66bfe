#include "capture/studio/cloth_perturbation.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "capture/io/portable_random.h"
#include "graph/error.h"

namespace weft::capture {

namespace {

using physics::Positions;
using physics::Vec3;

// A uniformly distributed unit vector (normalised Gaussian triple; a zero draw cannot
// happen in practice, but fall back to x rather than divide by it).
Vec3 random_direction(PortableRandom& rng) {
  const Vec3 g(rng.gaussian(), rng.gaussian(), rng.gaussian());
  const double n = g.norm();
  return n > 0 ? Vec3(g / n) : Vec3::UnitX();
}

// A point uniformly distributed in the ball of radius r.
Vec3 random_in_ball(PortableRandom& rng, double r) { return random_direction(rng) * (r * std::cbrt(rng.uniform())); }

// Step 2's field: translations of length uniform in [0, bound] at random vertices, blended
// by normalised Gaussian weights of rest distance. Normalised, the weights form a
// partition of unity, so each vertex gets a convex combination of the translations and
// the bound holds exactly; the Gaussians make it smooth over node_sigma_m.
Positions smooth_field(const Positions& rest, int nodes, double sigma, double bound, PortableRandom& rng) {
  const int n = static_cast<int>(rest.size() / 3);
  std::vector<int> at(nodes);
  std::vector<Vec3> t(nodes);
  for (int k = 0; k < nodes; ++k) {
    at[k] = static_cast<int>(rng.uniform() * n) % n;
    t[k] = random_direction(rng) * (bound * rng.uniform());
  }
  Positions d(rest.size());
  const double inv2s2 = 1.0 / (2 * sigma * sigma);
  for (int i = 0; i < n; ++i) {
    const Vec3 p = rest.segment<3>(3 * i);
    // Weights relative to the nearest node, so that far from every node they do not all
    // underflow to zero (the nearest node's weight is then 1).
    double nearest = std::numeric_limits<double>::infinity();
    for (int k = 0; k < nodes; ++k) nearest = std::min(nearest, (rest.segment<3>(3 * at[k]) - p).squaredNorm());
    Vec3 sum = Vec3::Zero();
    double wsum = 0;
    for (int k = 0; k < nodes; ++k) {
      const double w = std::exp(-((rest.segment<3>(3 * at[k]) - p).squaredNorm() - nearest) * inv2s2);
      sum += w * t[k];
      wsum += w;
    }
    d.segment<3>(3 * i) = sum / wsum;
  }
  return d;
}

}  // namespace

PerturbedStart perturb_start(const Positions& x_before, const Positions& x, const Positions& rest,
                             const physics::BodyMesh& body, double h, const ClothPerturbationConfig& c,
                             uint64_t seed) {
  WEFT_CHECK(x.size() == x_before.size() && x.size() == rest.size() && x.size() % 3 == 0 && x.size() > 0,
             "perturb_start: states of ", x_before.size(), ", ", x.size(), " and rest of ", rest.size(),
             " coordinates");
  WEFT_CHECK(x.allFinite() && x_before.allFinite(), "perturb_start: non-finite ground truth");
  WEFT_CHECK(h > 0, "perturb_start: time step must be > 0 s, got ", h);
  WEFT_CHECK(c.max_stretch >= 0 && c.max_stretch < 1, "perturb_start: max_stretch must be in [0, 1), got ",
             c.max_stretch);
  WEFT_CHECK(c.nodes >= 1 && c.node_sigma_m > 0, "perturb_start: nodes must be >= 1 and node_sigma_m > 0");
  WEFT_CHECK(c.patches >= 0 && c.patch_radius_m > 0 && c.patch_depth_m >= 0,
             "perturb_start: patches >= 0, patch_radius_m > 0 and patch_depth_m >= 0 expected");
  const int n = static_cast<int>(x.size() / 3);
  PortableRandom rng(mix_seed(seed, 0x636c6f7468ull /* "cloth" */, static_cast<uint64_t>(n)));
  PerturbedStart out;
  ClothPerturbation& p = out.drawn;

  // 1. Stretch about the centroid.
  for (int i = 0; i < n; ++i) p.centroid += x.segment<3>(3 * i);
  p.centroid /= n;
  p.stretch_axis = random_direction(rng);
  p.axial_stretch = rng.uniform(1 - c.max_stretch, 1 + c.max_stretch);
  p.lateral_stretch = rng.uniform(1 - c.max_stretch, 1 + c.max_stretch);
  const Eigen::Matrix3d A = p.lateral_stretch * Eigen::Matrix3d::Identity() +
                            (p.axial_stretch - p.lateral_stretch) * p.stretch_axis * p.stretch_axis.transpose();
  Positions y(x.size());
  for (int i = 0; i < n; ++i) y.segment<3>(3 * i) = p.centroid + A * (x.segment<3>(3 * i) - p.centroid);

  // 2. Smooth displacement.
  p.displacement = smooth_field(rest, c.nodes, c.node_sigma_m, c.max_displacement_m, rng);
  y += p.displacement;

  // 3. Patches pushed into the body (of frame t), one after the other.
  std::vector<physics::ClosestPoint> closest(n);
  const double R2 = c.patch_radius_m * c.patch_radius_m;
  for (int k = 0; k < c.patches; ++k) {
    std::vector<int> candidates;
    for (int i = 0; i < n; ++i) {
      closest[i] = body.closest_point(y.segment<3>(3 * i));
      if (closest[i].face >= 0 && closest[i].distance < c.patch_candidate_distance_m) candidates.push_back(i);
    }
    // One draw per patch whether or not there is a candidate, so later draws stay aligned.
    const double pick = rng.uniform();
    if (candidates.empty()) continue;
    const int centre = candidates[std::min(candidates.size() - 1, static_cast<size_t>(pick * candidates.size()))];
    p.patch_centres.push_back(centre);
    const Vec3 pc = y.segment<3>(3 * centre);
    for (int i = 0; i < n; ++i) {
      const double r2 = (y.segment<3>(3 * i) - pc).squaredNorm();
      if (r2 >= R2 || closest[i].face < 0) continue;
      const double w = (1 - r2 / R2) * (1 - r2 / R2);
      const double move = w * (closest[i].distance + c.patch_depth_m);
      if (move > 0) y.segment<3>(3 * i) -= move * closest[i].normal;
    }
  }

  // 4. Noisy velocity.
  p.velocity_noise = smooth_field(rest, c.nodes, c.node_sigma_m, c.velocity_noise_smooth_mps, rng);
  for (int i = 0; i < n; ++i) p.velocity_noise.segment<3>(3 * i) += random_in_ball(rng, c.velocity_noise_vertex_mps);
  const Positions v = (x - x_before) / h + p.velocity_noise;
  out.x_prev = std::move(y);
  out.x_prev2 = out.x_prev - h * v;
  return out;
}

}  // namespace weft::capture
