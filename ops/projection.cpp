// Pinhole projection with OpenCV's distortion model (k1, k2, p1, p2, k3).
#include <Eigen/Core>

#include "ops/geometry.h"
#include "ops/ops.h"

namespace weft {
namespace {

constexpr const char* kOp = "project_points";

ops::PinholeCamera camera_from(const Attrs& a) {
  ops::PinholeCamera cam;
  const std::vector<double> k = a.get_floats("intrinsics");    // fx fy cx cy
  const std::vector<double> d = a.get_floats("distortion");    // k1 k2 p1 p2 k3
  const std::vector<double> r = a.get_floats("rotation");      // 9, row-major
  const std::vector<double> t = a.get_floats("translation");   // 3
  cam.fx = k[0], cam.fy = k[1], cam.cx = k[2], cam.cy = k[3];
  cam.k1 = d[0], cam.k2 = d[1], cam.p1 = d[2], cam.p2 = d[3], cam.k3 = d[4];
  for (int i = 0; i < 9; ++i) cam.R[i] = r[i];
  for (int i = 0; i < 3; ++i) cam.t[i] = t[i];
  return cam;
}

// Distorted normalised coordinates of (x, y) and their 2×2 Jacobian.
struct Distorted {
  double xd, yd, j[2][2];
};
Distorted distort(const ops::PinholeCamera& c, double x, double y) {
  const double r2 = x * x + y * y;
  const double radial = 1 + r2 * (c.k1 + r2 * (c.k2 + r2 * c.k3));
  const double dradial = c.k1 + r2 * (2 * c.k2 + 3 * c.k3 * r2);  // d radial / d r2
  Distorted d;
  d.xd = x * radial + 2 * c.p1 * x * y + c.p2 * (r2 + 2 * x * x);
  d.yd = y * radial + c.p1 * (r2 + 2 * y * y) + 2 * c.p2 * x * y;
  d.j[0][0] = radial + 2 * x * x * dradial + 2 * c.p1 * y + 6 * c.p2 * x;
  d.j[0][1] = 2 * x * y * dradial + 2 * c.p1 * x + 2 * c.p2 * y;
  d.j[1][0] = 2 * x * y * dradial + 2 * c.p1 * x + 2 * c.p2 * y;
  d.j[1][1] = radial + 2 * y * y * dradial + 6 * c.p1 * y + 2 * c.p2 * x;
  return d;
}

constexpr double kMinDepth = 1e-9;

}  // namespace

WEFT_REGISTER_OP(project_points) {
  OpDef d;
  d.name = kOp;
  d.doc = "world points [...,3] -> pixels [...,2], pinhole + OpenCV distortion";
  d.num_inputs = 1;
  d.forward = [](const ForwardContext& c) {
    const Tensor& p = c.in(0);
    if (p.dim() < 1 || p.size(-1) != 3)
      fail(kOp, ": points must be [..., 3], got ", shape_str(p.shape()));
    const ops::PinholeCamera cam = camera_from(c.attrs);
    Shape out_shape = p.shape();
    out_shape.back() = 2;
    Tensor out = Tensor::empty(out_shape, p.dtype());
    dispatch_float(p.dtype(), kOp, [&]<class T>() {
      const T* pp = p.data<T>();
      T* po = out.data<T>();
      const int64_t n = p.numel() / 3;
      int64_t bad = -1;
      for (int64_t i = 0; i < n; ++i) {
        const double X = pp[3 * i], Y = pp[3 * i + 1], Z = pp[3 * i + 2];
        const double xc = cam.R[0] * X + cam.R[1] * Y + cam.R[2] * Z + cam.t[0];
        const double yc = cam.R[3] * X + cam.R[4] * Y + cam.R[5] * Z + cam.t[1];
        const double zc = cam.R[6] * X + cam.R[7] * Y + cam.R[8] * Z + cam.t[2];
        if (!(zc > kMinDepth)) {
          bad = i;
          break;
        }
        const Distorted dd = distort(cam, xc / zc, yc / zc);
        po[2 * i] = static_cast<T>(cam.fx * dd.xd + cam.cx);
        po[2 * i + 1] = static_cast<T>(cam.fy * dd.yd + cam.cy);
      }
      if (bad >= 0)
        fail(kOp, ": point ", bad, " of ", shape_str(p.shape()),
             " is at or behind the camera plane");
    });
    return out;
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    const Tensor& p = c.in(0);
    const ops::PinholeCamera cam = camera_from(c.attrs);
    Tensor gp = Tensor::empty(p.shape(), p.dtype());
    dispatch_float(p.dtype(), kOp, [&]<class T>() {
      const T* pp = p.data<T>();
      const T* go = c.grad_output.data<T>();
      T* pg = gp.data<T>();
      const int64_t n = p.numel() / 3;
      for (int64_t i = 0; i < n; ++i) {
        const double X = pp[3 * i], Y = pp[3 * i + 1], Z = pp[3 * i + 2];
        const double xc = cam.R[0] * X + cam.R[1] * Y + cam.R[2] * Z + cam.t[0];
        const double yc = cam.R[3] * X + cam.R[4] * Y + cam.R[5] * Z + cam.t[1];
        const double zc = cam.R[6] * X + cam.R[7] * Y + cam.R[8] * Z + cam.t[2];
        const double x = xc / zc, y = yc / zc;
        const Distorted dd = distort(cam, x, y);
        const double gu = go[2 * i] * cam.fx, gv = go[2 * i + 1] * cam.fy;
        // back through the distortion, then the perspective division, then R
        const double gx = gu * dd.j[0][0] + gv * dd.j[1][0];
        const double gy = gu * dd.j[0][1] + gv * dd.j[1][1];
        const double gxc = gx / zc, gyc = gy / zc, gzc = -(gx * x + gy * y) / zc;
        for (int a = 0; a < 3; ++a)
          pg[3 * i + a] =
              static_cast<T>(cam.R[a] * gxc + cam.R[3 + a] * gyc + cam.R[6 + a] * gzc);
      }
    });
    return {gp};
  };
  return d;
}

namespace ops {
Tensor project_points(const Tensor& points, const PinholeCamera& c) {
  Attrs a;
  a.set("intrinsics", std::vector<double>{c.fx, c.fy, c.cx, c.cy});
  a.set("distortion", std::vector<double>{c.k1, c.k2, c.p1, c.p2, c.k3});
  a.set("rotation", std::vector<double>(c.R, c.R + 9));
  a.set("translation", std::vector<double>(c.t, c.t + 3));
  return apply(kOp, {points}, a);
}
}  // namespace ops

}  // namespace weft
