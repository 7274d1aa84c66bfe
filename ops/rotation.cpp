// Rotation parameterisations: Euler angles → matrices, rigid transforms → unit dual
// quaternions.
#include <Eigen/Core>
#include <cmath>

#include "ops/geometry.h"
#include "ops/ops.h"

namespace weft {
namespace {

template <class T>
using Mat3 = Eigen::Matrix<T, 3, 3, Eigen::RowMajor>;

template <class T>
Mat3<T> rot_x(T a) {
  Mat3<T> m;
  m << 1, 0, 0, 0, std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a);
  return m;
}
template <class T>
Mat3<T> rot_y(T b) {
  Mat3<T> m;
  m << std::cos(b), 0, std::sin(b), 0, 1, 0, -std::sin(b), 0, std::cos(b);
  return m;
}
template <class T>
Mat3<T> rot_z(T c) {
  Mat3<T> m;
  m << std::cos(c), -std::sin(c), 0, std::sin(c), std::cos(c), 0, 0, 0, 1;
  return m;
}
// Derivatives of the elementary rotations with respect to their angle.
template <class T>
Mat3<T> d_rot_x(T a) {
  Mat3<T> m;
  m << 0, 0, 0, 0, -std::sin(a), -std::cos(a), 0, std::cos(a), -std::sin(a);
  return m;
}
template <class T>
Mat3<T> d_rot_y(T b) {
  Mat3<T> m;
  m << -std::sin(b), 0, std::cos(b), 0, 0, 0, -std::cos(b), 0, -std::sin(b);
  return m;
}
template <class T>
Mat3<T> d_rot_z(T c) {
  Mat3<T> m;
  m << -std::sin(c), -std::cos(c), 0, std::cos(c), -std::sin(c), 0, 0, 0, 0;
  return m;
}

void check_last_dims(const char* op, const Tensor& t, const Shape& tail) {
  const Shape& s = t.shape();
  bool ok = s.size() >= tail.size();
  for (size_t i = 0; ok && i < tail.size(); ++i) ok = s[s.size() - tail.size() + i] == tail[i];
  if (!ok) fail(op, ": expected shape [..., ", shape_str(tail).substr(1), " got ", shape_str(s));
}

// Shepperd's method: the branch with the largest pivot d keeps the division stable.
// Row-major R entries r[0..8]; quaternion (w, x, y, z). For branch p the pivot component
// is ½√d with d = 1 + Σ σ_i R_ii, the others are (Σ c·R_ab)/(4·pivot).
struct QuatBranch {
  int sigma[3];
  double coef[4][9];  // numerator coefficients for each non-pivot component
};
constexpr QuatBranch kBranches[4] = {
    // pivot w
    {{1, 1, 1},
     {{0}, {0, 0, 0, 0, 0, -1, 0, 1, 0}, {0, 0, 1, 0, 0, 0, -1, 0, 0}, {0, -1, 0, 1, 0, 0, 0, 0, 0}}},
    // pivot x
    {{1, -1, -1},
     {{0, 0, 0, 0, 0, -1, 0, 1, 0}, {0}, {0, 1, 0, 1, 0, 0, 0, 0, 0}, {0, 0, 1, 0, 0, 0, 1, 0, 0}}},
    // pivot y
    {{-1, 1, -1},
     {{0, 0, 1, 0, 0, 0, -1, 0, 0}, {0, 1, 0, 1, 0, 0, 0, 0, 0}, {0}, {0, 0, 0, 0, 0, 1, 0, 1, 0}}},
    // pivot z
    {{-1, -1, 1},
     {{0, -1, 0, 1, 0, 0, 0, 0, 0}, {0, 0, 1, 0, 0, 0, 1, 0, 0}, {0, 0, 0, 0, 0, 1, 0, 1, 0}, {0}}},
};

template <class T>
int choose_branch(const T* r) {
  const T d[4] = {1 + r[0] + r[4] + r[8], 1 + r[0] - r[4] - r[8], 1 - r[0] + r[4] - r[8],
                  1 - r[0] - r[4] + r[8]};
  int best = 0;
  for (int b = 1; b < 4; ++b)
    if (d[b] > d[best]) best = b;
  return best;
}

// Quaternion of the rotation part of m (3×4 row-major), with w ≥ 0; also returns the
// branch and the sign applied, which the backward needs.
template <class T>
void matrix_to_quat(const T* m, T q[4], int& branch, T& sign) {
  const T r[9] = {m[0], m[1], m[2], m[4], m[5], m[6], m[8], m[9], m[10]};
  branch = choose_branch(r);
  const QuatBranch& br = kBranches[branch];
  const T d = 1 + br.sigma[0] * r[0] + br.sigma[1] * r[4] + br.sigma[2] * r[8];
  const T pivot = T(0.5) * std::sqrt(std::max(d, T(1e-30)));
  for (int c = 0; c < 4; ++c) {
    if (c == branch) {
      q[c] = pivot;
      continue;
    }
    T num = 0;
    for (int k = 0; k < 9; ++k) num += T(br.coef[c][k]) * r[k];
    q[c] = num / (4 * pivot);
  }
  sign = q[0] < 0 ? T(-1) : T(1);
  for (int c = 0; c < 4; ++c) q[c] *= sign;
}

}  // namespace

WEFT_REGISTER_OP(euler_to_rotation) {
  OpDef d;
  d.name = "euler_to_rotation";
  d.doc = "Euler angles [...,3] (x,y,z, radians) -> Rz*Ry*Rx [...,3,3]";
  d.num_inputs = 1;
  d.forward = [](const ForwardContext& c) {
    const Tensor& a = c.in(0);
    check_last_dims("euler_to_rotation", a, {3});
    Shape out_shape = a.shape();
    out_shape.push_back(3);
    Tensor out = Tensor::empty(out_shape, a.dtype());
    dispatch_float(a.dtype(), "euler_to_rotation", [&]<class T>() {
      const T* pa = a.data<T>();
      T* po = out.data<T>();
      const int64_t n = a.numel() / 3;
#pragma omp parallel for if (n > 4096)
      for (int64_t i = 0; i < n; ++i) {
        const Mat3<T> r = rot_z(pa[3 * i + 2]) * rot_y(pa[3 * i + 1]) * rot_x(pa[3 * i]);
        Eigen::Map<Mat3<T>>(po + 9 * i) = r;
      }
    });
    return out;
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    const Tensor& a = c.in(0);
    Tensor ga = Tensor::empty(a.shape(), a.dtype());
    dispatch_float(a.dtype(), "euler_to_rotation", [&]<class T>() {
      const T* pa = a.data<T>();
      const T* pg = c.grad_output.data<T>();
      T* po = ga.data<T>();
      const int64_t n = a.numel() / 3;
#pragma omp parallel for if (n > 4096)
      for (int64_t i = 0; i < n; ++i) {
        const T x = pa[3 * i], y = pa[3 * i + 1], z = pa[3 * i + 2];
        const Eigen::Map<const Mat3<T>> g(pg + 9 * i);
        const Mat3<T> rx = rot_x(x), ry = rot_y(y), rz = rot_z(z);
        po[3 * i] = (g.array() * (rz * ry * d_rot_x(x)).array()).sum();
        po[3 * i + 1] = (g.array() * (rz * d_rot_y(y) * rx).array()).sum();
        po[3 * i + 2] = (g.array() * (d_rot_z(z) * ry * rx).array()).sum();
      }
    });
    return {ga};
  };
  return d;
}

WEFT_REGISTER_OP(rigid_to_dual_quaternion) {
  OpDef d;
  d.name = "rigid_to_dual_quaternion";
  d.doc = "rigid transforms [...,3,4] -> unit dual quaternions [...,8] (w >= 0)";
  d.num_inputs = 1;
  d.forward = [](const ForwardContext& c) {
    const Tensor& m = c.in(0);
    check_last_dims("rigid_to_dual_quaternion", m, {3, 4});
    Shape out_shape(m.shape().begin(), m.shape().end() - 2);
    out_shape.push_back(8);
    Tensor out = Tensor::empty(out_shape, m.dtype());
    dispatch_float(m.dtype(), "rigid_to_dual_quaternion", [&]<class T>() {
      const T* pm = m.data<T>();
      T* po = out.data<T>();
      const int64_t n = m.numel() / 12;
      for (int64_t i = 0; i < n; ++i) {
        const T* mi = pm + 12 * i;
        T* q = po + 8 * i;
        int branch;
        T sign;
        matrix_to_quat(mi, q, branch, sign);
        // qe = ½ (0, t) ⊗ q0 = ½ (−t·v, w t + t × v)
        const T tx = mi[3], ty = mi[7], tz = mi[11];
        const T w = q[0], x = q[1], y = q[2], z = q[3];
        q[4] = T(-0.5) * (tx * x + ty * y + tz * z);
        q[5] = T(0.5) * (w * tx + ty * z - tz * y);
        q[6] = T(0.5) * (w * ty + tz * x - tx * z);
        q[7] = T(0.5) * (w * tz + tx * y - ty * x);
      }
    });
    return out;
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    const Tensor& m = c.in(0);
    Tensor gm = Tensor::zeros(m.shape(), m.dtype());
    dispatch_float(m.dtype(), "rigid_to_dual_quaternion", [&]<class T>() {
      const T* pm = m.data<T>();
      const T* pg = c.grad_output.data<T>();
      T* po = gm.data<T>();
      const int64_t n = m.numel() / 12;
      for (int64_t i = 0; i < n; ++i) {
        const T* mi = pm + 12 * i;
        const T* g = pg + 8 * i;
        T* gmi = po + 12 * i;
        T q[4];
        int branch;
        T sign;
        matrix_to_quat(mi, q, branch, sign);
        const T tx = mi[3], ty = mi[7], tz = mi[11];
        const T w = q[0], x = q[1], y = q[2], z = q[3];
        // Dual part: gradients to t and to the real quaternion.
        gmi[3] = T(0.5) * (-g[4] * x + g[5] * w - g[6] * z + g[7] * y);
        gmi[7] = T(0.5) * (-g[4] * y + g[5] * z + g[6] * w - g[7] * x);
        gmi[11] = T(0.5) * (-g[4] * z - g[5] * y + g[6] * x + g[7] * w);
        T gq[4] = {g[0] + T(0.5) * (g[5] * tx + g[6] * ty + g[7] * tz),
                   g[1] + T(0.5) * (-g[4] * tx + g[6] * tz - g[7] * ty),
                   g[2] + T(0.5) * (-g[4] * ty - g[5] * tz + g[7] * tx),
                   g[3] + T(0.5) * (-g[4] * tz + g[5] * ty - g[6] * tx)};
        // Undo the sign, then the branch formulas.
        for (int k = 0; k < 4; ++k) gq[k] *= sign;
        T qs[4];
        for (int k = 0; k < 4; ++k) qs[k] = q[k] * sign;  // before the sign flip
        const QuatBranch& br = kBranches[branch];
        const T pivot = qs[branch];
        T g_pivot = gq[branch];
        T gr[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
        for (int k = 0; k < 4; ++k) {
          if (k == branch) continue;
          // o_k = num_k / (4 pivot): ∂o_k/∂num = 1/(4 pivot), ∂o_k/∂pivot = −o_k/pivot
          g_pivot -= gq[k] * qs[k] / pivot;
          for (int e = 0; e < 9; ++e) gr[e] += gq[k] * T(br.coef[k][e]) / (4 * pivot);
        }
        // pivot = ½ √d: ∂pivot/∂d = 1/(4 √d) = 1/(8 pivot); ∂d/∂R_ii = σ_i
        const T g_d = g_pivot / (8 * pivot);
        gr[0] += g_d * T(br.sigma[0]);
        gr[4] += g_d * T(br.sigma[1]);
        gr[8] += g_d * T(br.sigma[2]);
        const int to_m[9] = {0, 1, 2, 4, 5, 6, 8, 9, 10};
        for (int e = 0; e < 9; ++e) gmi[to_m[e]] += gr[e];
      }
    });
    return {gm};
  };
  return d;
}

namespace ops {
Tensor euler_to_rotation(const Tensor& angles) { return apply("euler_to_rotation", {angles}); }
Tensor rigid_to_dual_quaternion(const Tensor& transforms) {
  return apply("rigid_to_dual_quaternion", {transforms});
}
}  // namespace ops

}  // namespace weft
