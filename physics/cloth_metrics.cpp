#include "physics/cloth_metrics.h"

#include "graph/error.h"

namespace weft::physics {

void measure_penetration(const ClothSimulator& sim, const Positions& x, FrameMetrics& m) {
  const int n = sim.mesh().num_vertices();
  WEFT_CHECK(x.size() == 3 * n, "metrics: frame has ", x.size(), " entries, expected ", 3 * n);
  double sum = 0;
  m.penetration_max = 0;
  m.penetrating_vertices = 0;
  m.min_signed_distance = std::numeric_limits<double>::infinity();
  for (int i = 0; i < n; ++i) {
    const double d = sim.signed_distance(x.segment<3>(3 * i));
    m.min_signed_distance = std::min(m.min_signed_distance, d);
    if (d < 0) {
      sum += -d;
      m.penetration_max = std::max(m.penetration_max, -d);
      ++m.penetrating_vertices;
    }
  }
  m.penetration_mean = m.penetrating_vertices > 0 ? sum / m.penetrating_vertices : 0.0;
}

void measure_out_of_balance(const ClothSimulator& sim, const Positions& x_prev2,
                            const Positions& x_prev, const Positions& x, double h,
                            FrameMetrics& m) {
  measure_out_of_balance(sim, x_prev2, x_prev, x, h, m, {});
}

void measure_out_of_balance(const ClothSimulator& sim, const Positions& x_prev2,
                            const Positions& x_prev, const Positions& x, double h,
                            FrameMetrics& m, const std::vector<int>& excluded) {
  summarize_out_of_balance(vertex_balance(sim, x_prev2, x_prev, x, h), m, excluded);
}

void summarize_out_of_balance(const VertexBalance& b, FrameMetrics& m, const std::vector<int>& excluded) {
  const int n = int(b.residual.size());
  std::vector<char> skip(n, 0);
  for (int i : excluded) {
    WEFT_CHECK(i >= 0 && i < n, "metrics: excluded vertex ", i, " is not in 0..", n - 1);
    skip[i] = 1;
  }
  double sum = 0, sum_rel = 0;
  int counted = 0;
  m.oob_force_max = m.oob_force_max_rel = 0;
  for (int i = 0; i < n; ++i) {
    if (skip[i]) continue;
    ++counted;
    const double r = b.residual[i];
    const double rel = b.weight[i] > 0 ? r / b.weight[i] : 0.0;
    sum += r;
    sum_rel += rel;
    m.oob_force_max = std::max(m.oob_force_max, r);
    m.oob_force_max_rel = std::max(m.oob_force_max_rel, rel);
  }
  m.oob_force_mean = counted ? sum / counted : 0.0;
  m.oob_force_mean_rel = counted ? sum_rel / counted : 0.0;
}

VertexBalance vertex_balance(const ClothSimulator& sim, const Positions& x_prev2, const Positions& x_prev,
                             const Positions& x, double h) {
  const int n = sim.mesh().num_vertices();
  WEFT_CHECK(x.size() == 3 * n && x_prev.size() == x.size() && x_prev2.size() == x.size(),
             "metrics: frames must have ", 3 * n, " entries");
  WEFT_CHECK(h > 0, "metrics: time step must be > 0 s, got ", h);
  const ClothSimulator::ForceParts f = sim.force_parts(x);
  const Positions friction = sim.friction_force(x_prev, x);
  const Positions a = (x - 2.0 * x_prev + x_prev2) / (h * h);
  const double g = sim.settings().gravity.norm();
  VertexBalance b;
  for (auto* v : {&b.residual, &b.inertia, &b.elastic, &b.external, &b.collision, &b.friction, &b.weight})
    v->resize(n);
  for (int i = 0; i < n; ++i) {
    const double mass = sim.mesh().mass[i];
    const Vec3 ma = mass * a.segment<3>(3 * i);
    const Vec3 sum = f.elastic.segment<3>(3 * i) + f.external.segment<3>(3 * i) + f.collision.segment<3>(3 * i) +
                     friction.segment<3>(3 * i);
    b.residual[i] = (ma - sum).norm();
    b.inertia[i] = ma.norm();
    b.elastic[i] = f.elastic.segment<3>(3 * i).norm();
    b.external[i] = f.external.segment<3>(3 * i).norm();
    b.collision[i] = f.collision.segment<3>(3 * i).norm();
    b.friction[i] = friction.segment<3>(3 * i).norm();
    b.weight[i] = mass * g;
  }
  return b;
}

FrameMetrics frame_metrics(const ClothSimulator& sim, const Positions& x_prev2,
                           const Positions& x_prev, const Positions& x, double h) {
  FrameMetrics m;
  measure_penetration(sim, x, m);
  measure_out_of_balance(sim, x_prev2, x_prev, x, h, m);
  return m;
}

}  // namespace weft::physics
