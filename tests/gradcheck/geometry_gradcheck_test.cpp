// Gradient checks of the differentiable geometry ops (ops/geometry.h).
#include <algorithm>
#include <cmath>

#include "graph/autograd.h"
#include "ops/geometry.h"
#include "ops/ops.h"
#include "tests/gradcheck/cases.h"

namespace weft::testing {
namespace {

// int64 [rows, per_row] with entries in [0, count), distinct within a row.
Tensor random_index(Generator& g, int64_t rows, int64_t per_row, int64_t count) {
  std::vector<int64_t> v;
  for (int64_t r = 0; r < rows; ++r) {
    std::vector<int64_t> row;
    while (static_cast<int64_t>(row.size()) < per_row) {
      const int64_t k = g.integer(0, count - 1);
      if (std::find(row.begin(), row.end(), k) == row.end()) row.push_back(k);
    }
    v.insert(v.end(), row.begin(), row.end());
  }
  return Tensor::from_indices({rows, per_row}, v);
}

// Positive weights normalised per row.
Tensor random_weights(Generator& g, int64_t rows, int64_t per_row) {
  Tensor w = uniform64(g, {rows, per_row}, 0.2, 1.0);
  double* p = w.data<double>();
  for (int64_t r = 0; r < rows; ++r) {
    double s = 0;
    for (int64_t j = 0; j < per_row; ++j) s += p[r * per_row + j];
    for (int64_t j = 0; j < per_row; ++j) p[r * per_row + j] /= s;
  }
  return w;
}

// Rigid transforms [B,J,3,4] from random Euler angles (scaled) and translations.
Tensor random_rigid(Generator& g, int64_t B, int64_t J, double angle_scale) {
  NoGradGuard no_grad;
  Tensor angles = ops::scale(uniform64(g, {B, J, 3}), angle_scale);
  Tensor R = ops::euler_to_rotation(angles);
  Tensor out = Tensor::empty({B, J, 3, 4}, DType::F64);
  for (int64_t i = 0; i < B * J; ++i)
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) out.data<double>()[i * 12 + r * 4 + c] = R.data<double>()[i * 9 + r * 3 + c];
      out.data<double>()[i * 12 + r * 4 + 3] = g.uniform(-1, 1);
    }
  return out;
}

}  // namespace

WEFT_GRADCHECK_CASES(euler_to_rotation) {
  return {uniform_case("euler_to_rotation", "[2,3,3] angles in [-3,3]", {{2, 3, 3}}, {}, -3, 3),
          uniform_case("euler_to_rotation", "single [3]", {{3}}, {}, -1, 1)};
}

WEFT_GRADCHECK_CASES(rigid_to_dual_quaternion) {
  GradcheckCase near_identity;
  near_identity.op = "rigid_to_dual_quaternion";
  near_identity.name = "small rotations (w pivot)";
  near_identity.make_inputs = [](Generator& g) {
    return std::vector<Tensor>{random_rigid(g, 2, 2, 0.5)};
  };
  GradcheckCase half_turns = near_identity;
  half_turns.name = "near half turns about x, y, z (x, y, z pivots)";
  half_turns.make_inputs = [](Generator& g) {
    NoGradGuard no_grad;
    Tensor angles = Tensor::from_data(
        {1, 3, 3}, std::vector<double>{3.0, 0.1, -0.2, 0.1, 3.0, 0.2, -0.1, 0.2, 3.0}, DType::F64);
    Tensor R = ops::euler_to_rotation(angles);
    Tensor out = Tensor::empty({1, 3, 3, 4}, DType::F64);
    for (int i = 0; i < 3; ++i)
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c)
          out.data<double>()[i * 12 + r * 4 + c] = R.data<double>()[i * 9 + r * 3 + c];
        out.data<double>()[i * 12 + r * 4 + 3] = g.uniform(-1, 1);
      }
    return std::vector<Tensor>{out};
  };
  return {near_identity, half_turns};
}

WEFT_GRADCHECK_CASES(embedded_deformation) {
  GradcheckCase c;
  c.op = "embedded_deformation";
  c.name = "B=2 V=5 K=4 n=3";
  c.make_inputs = [](Generator& g) {
    return std::vector<Tensor>{uniform64(g, {5, 3}), uniform64(g, {4, 3}),
                               uniform64(g, {2, 4, 3, 3}), uniform64(g, {2, 4, 3}),
                               random_index(g, 5, 3, 4), random_weights(g, 5, 3)};
  };
  return {c};
}

WEFT_GRADCHECK_CASES(linear_blend_skinning) {
  GradcheckCase shared;
  shared.op = "linear_blend_skinning";
  shared.name = "shared vertices B=2 V=4 J=3 m=2";
  shared.make_inputs = [](Generator& g) {
    return std::vector<Tensor>{uniform64(g, {4, 3}), uniform64(g, {2, 3, 3, 4}),
                               random_index(g, 4, 2, 3), random_weights(g, 4, 2)};
  };
  GradcheckCase per_frame = shared;
  per_frame.name = "per-frame vertices B=2 V=3 J=2 m=1";
  per_frame.make_inputs = [](Generator& g) {
    return std::vector<Tensor>{uniform64(g, {2, 3, 3}), uniform64(g, {2, 2, 3, 4}),
                               random_index(g, 3, 1, 2), random_weights(g, 3, 1)};
  };
  return {shared, per_frame};
}

WEFT_GRADCHECK_CASES(dual_quaternion_skinning) {
  // Unit dual quaternions from rigid transforms; joint 1 is negated so the
  // antipodality sign flip is exercised (q and −q are the same rotation).
  auto make = [](int64_t B, int64_t V, int64_t J, int64_t m, bool shared) {
    return [=](Generator& g) {
      NoGradGuard no_grad;
      Tensor dq = ops::rigid_to_dual_quaternion(random_rigid(g, B, J, 0.6)).clone();
      for (int64_t b = 0; b < B; ++b)
        for (int k = 0; k < 8; ++k) dq.data<double>()[(b * J + 1) * 8 + k] *= -1;
      Tensor verts = shared ? uniform64(g, {V, 3}) : uniform64(g, {B, V, 3});
      return std::vector<Tensor>{verts, dq, random_index(g, V, m, J), random_weights(g, V, m)};
    };
  };
  GradcheckCase shared;
  shared.op = "dual_quaternion_skinning";
  shared.name = "shared vertices B=2 V=4 J=3 m=3 (one antipodal joint)";
  shared.make_inputs = make(2, 4, 3, 3, true);
  GradcheckCase per_frame = shared;
  per_frame.name = "per-frame vertices B=1 V=3 J=2 m=2";
  per_frame.make_inputs = make(1, 3, 2, 2, false);
  return {shared, per_frame};
}

WEFT_GRADCHECK_CASES(project_points) {
  GradcheckCase c;
  c.op = "project_points";
  c.name = "[2,3,3] points, rotated camera, radial and tangential distortion";
  c.make_inputs = [](Generator& g) {
    Tensor p = uniform64(g, {2, 3, 3}, -0.5, 0.5);
    for (int64_t i = 0; i < 6; ++i) p.data<double>()[3 * i + 2] += 3.0;  // in front
    return std::vector<Tensor>{p};
  };
  ops::PinholeCamera cam;
  cam.fx = 800, cam.fy = 780, cam.cx = 320, cam.cy = 240;
  cam.k1 = -0.2, cam.k2 = 0.05, cam.p1 = 0.001, cam.p2 = -0.002, cam.k3 = 0.01;
  const double a = 0.1;
  const double R[9] = {std::cos(a), 0, std::sin(a), 0, 1, 0, -std::sin(a), 0, std::cos(a)};
  c.function = [cam, R](const std::vector<Tensor>& in) mutable {
    for (int i = 0; i < 9; ++i) cam.R[i] = R[i];
    cam.t[0] = 0.1, cam.t[1] = -0.2, cam.t[2] = 0.3;
    return ops::project_points(in[0], cam);
  };
  return {c};
}

}  // namespace weft::testing

namespace weft::testing {

// A branching 5-joint chain: a prismatic root, revolute joints with skewed axes, two
// children of joint 2; with and without inverse bind transforms.
static ops::KinematicChain test_chain(bool with_bind) {
  ops::KinematicChain c;
  c.parents = {-1, 0, 1, 2, 2};
  c.prismatic = {1, 0, 0, 0, 1};
  c.offsets = {0.1, 0.2, 0.0, 0.0, 1.0, 0.0, 0.3, 0.5, -0.2, 0.0, 0.4, 0.1, -0.2, 0.1, 0.3};
  const double s = 1 / std::sqrt(3.0);
  c.axes = {0, 1, 0, 1, 0, 0, s, s, s, 0, 0, 1, s, -s, s};
  if (with_bind) {
    Generator g(5);
    for (int j = 0; j < 5; ++j) {
      Tensor R = ops::euler_to_rotation(Tensor::rand({3}, g, DType::F64, -1, 1));
      for (int r = 0; r < 3; ++r) {
        for (int k = 0; k < 3; ++k) c.bind_inverse.push_back(R.at({r, k}));
        c.bind_inverse.push_back(g.uniform(-1, 1));
      }
    }
  }
  return c;
}

WEFT_GRADCHECK_CASES(forward_kinematics) {
  GradcheckCase c = uniform_case("forward_kinematics", "branching chain, B=2", {{2, 5}}, {}, -2, 2);
  c.function = [](const std::vector<Tensor>& in) {
    return ops::forward_kinematics(in[0], test_chain(false));
  };
  GradcheckCase bind = c;
  bind.name = "branching chain with inverse bind transforms, B=1";
  bind.make_inputs = [](Generator& g) { return std::vector<Tensor>{uniform64(g, {1, 5}, -2, 2)}; };
  bind.function = [](const std::vector<Tensor>& in) {
    return ops::forward_kinematics(in[0], test_chain(true));
  };
  return {c, bind};
}

}  // namespace weft::testing

namespace weft::testing {

WEFT_GRADCHECK_CASES(image_sample_bilinear) {
  GradcheckCase c;
  c.op = "image_sample_bilinear";
  c.name = "B=2 5x6 images, interior and clamped points";
  c.make_inputs = [](Generator& g) {
    Tensor pts = uniform64(g, {2, 4, 2}, 0.3, 3.7);
    // keep points off the pixel grid lines (kinks of bilinear interpolation)
    double* p = pts.data<double>();
    for (int64_t i = 0; i < pts.numel(); ++i) p[i] = std::floor(p[i]) + 0.2 + 0.6 * (p[i] - std::floor(p[i]));
    p[0] = -1.3;  // clamped in x: gradient in x is zero there
    p[3] = 7.6;   // clamped in y (H = 5)
    return std::vector<Tensor>{uniform64(g, {2, 5, 6}), pts};
  };
  return {c};
}

WEFT_GRADCHECK_CASES(arap_energy) {
  GradcheckCase c;
  c.op = "arap_energy";
  c.name = "K=4 nodes, 4 edges, B=2";
  c.make_inputs = [](Generator& g) {
    return std::vector<Tensor>{uniform64(g, {4, 3}), uniform64(g, {2, 4, 3, 3}),
                               uniform64(g, {2, 4, 3}),
                               Tensor::from_indices({4, 2}, {0, 1, 1, 2, 2, 3, 0, 3}),
                               uniform64(g, {4}, 0.1, 1.0)};
  };
  return {c};
}

}  // namespace weft::testing
