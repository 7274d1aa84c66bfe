#pragma once
// A scalar carrying its gradient and Hessian with respect to N inputs (forward-mode
// second-order differentiation). Used for small element energies whose closed-form
// Hessians are long, e.g. the dihedral angle of a hinge.
#include <Eigen/Core>
#include <cmath>

namespace weft::physics {

template <int N>
struct Jet2 {
  using Vec = Eigen::Matrix<double, N, 1>;
  using Mat = Eigen::Matrix<double, N, N>;
  double v = 0;
  Vec g = Vec::Zero();
  Mat h = Mat::Zero();

  static Jet2 variable(double value, int index) {
    Jet2 j;
    j.v = value;
    j.g[index] = 1.0;
    return j;
  }
};

template <int N>
Jet2<N> operator+(const Jet2<N>& a, const Jet2<N>& b) {
  Jet2<N> r;
  r.v = a.v + b.v;
  r.g = a.g + b.g;
  r.h = a.h + b.h;
  return r;
}

template <int N>
Jet2<N> operator-(const Jet2<N>& a, const Jet2<N>& b) {
  Jet2<N> r;
  r.v = a.v - b.v;
  r.g = a.g - b.g;
  r.h = a.h - b.h;
  return r;
}

template <int N>
Jet2<N> operator*(const Jet2<N>& a, const Jet2<N>& b) {
  Jet2<N> r;
  r.v = a.v * b.v;
  r.g = a.g * b.v + b.g * a.v;
  const typename Jet2<N>::Mat cross = a.g * b.g.transpose();
  r.h = a.h * b.v + b.h * a.v + cross + cross.transpose();
  return r;
}

template <int N>
Jet2<N> operator*(double s, const Jet2<N>& a) {
  Jet2<N> r;
  r.v = s * a.v;
  r.g = s * a.g;
  r.h = s * a.h;
  return r;
}

// f(a) for a scalar function with derivatives f1 = f'(a.v), f2 = f''(a.v).
template <int N>
Jet2<N> chain(const Jet2<N>& a, double f, double f1, double f2) {
  Jet2<N> r;
  r.v = f;
  r.g = f1 * a.g;
  r.h = f1 * a.h + f2 * a.g * a.g.transpose();
  return r;
}

template <int N>
Jet2<N> sqrt(const Jet2<N>& a) {
  const double s = std::sqrt(a.v);
  return chain(a, s, 0.5 / s, -0.25 / (s * a.v));
}

template <int N>
Jet2<N> inverse(const Jet2<N>& a) {
  const double i = 1.0 / a.v;
  return chain(a, i, -i * i, 2.0 * i * i * i);
}

// atan2(y, x); undefined at y = x = 0.
template <int N>
Jet2<N> atan2(const Jet2<N>& y, const Jet2<N>& x) {
  const double r2 = x.v * x.v + y.v * y.v;
  const double fy = x.v / r2, fx = -y.v / r2;
  const double fyy = -2.0 * x.v * y.v / (r2 * r2), fxx = -fyy;
  const double fxy = (y.v * y.v - x.v * x.v) / (r2 * r2);
  Jet2<N> r;
  r.v = std::atan2(y.v, x.v);
  r.g = fy * y.g + fx * x.g;
  const typename Jet2<N>::Mat cross = y.g * x.g.transpose();
  r.h = fy * y.h + fx * x.h + fyy * y.g * y.g.transpose() + fxx * x.g * x.g.transpose() +
        fxy * (cross + cross.transpose());
  return r;
}

}  // namespace weft::physics
