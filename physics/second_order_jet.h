#pragma once
// A scalar carrying its gradient and (when Second) its Hessian with respect to N inputs:
// forward-mode differentiation for small element energies whose closed-form Hessians are
// long, e.g. the dihedral angle of a hinge. Jet2<N, false> skips the O(N²) Hessian work.
#include <Eigen/Core>
#include <cmath>
#include <type_traits>

namespace weft::physics {

template <int N, bool Second = true>
struct Jet2 {
  using Vec = Eigen::Matrix<double, N, 1>;
  // The Hessian's type is a dummy 1×1 when it is not carried.
  using Mat = std::conditional_t<Second, Eigen::Matrix<double, N, N>, Eigen::Matrix<double, 1, 1>>;
  double v = 0;
  Vec g = Vec::Zero();
  Mat h = Mat::Zero();

  static Jet2 variable(double value, int index) {
    Jet2 j;
    j.g.setZero();
    j.v = value;
    j.g[index] = 1.0;
    return j;
  }
};

template <int N, bool S>
Jet2<N, S> operator+(const Jet2<N, S>& a, const Jet2<N, S>& b) {
  Jet2<N, S> r;
  r.v = a.v + b.v;
  r.g = a.g + b.g;
  if constexpr (S) r.h = a.h + b.h;
  return r;
}

template <int N, bool S>
Jet2<N, S> operator-(const Jet2<N, S>& a, const Jet2<N, S>& b) {
  Jet2<N, S> r;
  r.v = a.v - b.v;
  r.g = a.g - b.g;
  if constexpr (S) r.h = a.h - b.h;
  return r;
}

template <int N, bool S>
Jet2<N, S> operator*(const Jet2<N, S>& a, const Jet2<N, S>& b) {
  Jet2<N, S> r;
  r.v = a.v * b.v;
  r.g = a.g * b.v + b.g * a.v;
  if constexpr (S) {
    const typename Jet2<N, S>::Mat cross = a.g * b.g.transpose();
    r.h = a.h * b.v + b.h * a.v + cross + cross.transpose();
  }
  return r;
}

template <int N, bool S>
Jet2<N, S> operator*(double k, const Jet2<N, S>& a) {
  Jet2<N, S> r;
  r.v = k * a.v;
  r.g = k * a.g;
  if constexpr (S) r.h = k * a.h;
  return r;
}

// f(a) for a scalar function with derivatives f1 = f'(a.v), f2 = f''(a.v).
template <int N, bool S>
Jet2<N, S> chain(const Jet2<N, S>& a, double f, double f1, double f2) {
  Jet2<N, S> r;
  r.v = f;
  r.g = f1 * a.g;
  if constexpr (S) r.h = f1 * a.h + f2 * a.g * a.g.transpose();
  return r;
}

template <int N, bool S>
Jet2<N, S> sqrt(const Jet2<N, S>& a) {
  const double s = std::sqrt(a.v);
  return chain(a, s, 0.5 / s, -0.25 / (s * a.v));
}

template <int N, bool S>
Jet2<N, S> inverse(const Jet2<N, S>& a) {
  const double i = 1.0 / a.v;
  return chain(a, i, -i * i, 2.0 * i * i * i);
}

// atan2(y, x); undefined at y = x = 0.
template <int N, bool S>
Jet2<N, S> atan2(const Jet2<N, S>& y, const Jet2<N, S>& x) {
  const double r2 = x.v * x.v + y.v * y.v;
  const double fy = x.v / r2, fx = -y.v / r2;
  const double fyy = -2.0 * x.v * y.v / (r2 * r2), fxx = -fyy;
  const double fxy = (y.v * y.v - x.v * x.v) / (r2 * r2);
  Jet2<N, S> r;
  r.v = std::atan2(y.v, x.v);
  r.g = fy * y.g + fx * x.g;
  if constexpr (S) {
    const typename Jet2<N, S>::Mat cross = y.g * x.g.transpose();
    r.h = fy * y.h + fx * x.h + fyy * y.g * y.g.transpose() + fxx * x.g * x.g.transpose() +
          fxy * (cross + cross.transpose());
  }
  return r;
}

}  // namespace weft::physics
