#pragma once
// Physical plausibility metrics of a cloth sequence, for simulated and predicted frames.
//  - Out-of-balance force per vertex: r_i = m_i a_i − f_i(x_t), a from the centred
//    difference (x_t − 2x_{t−1} + x_{t−2})/h² of three consecutive frames, f the sum of
//    internal (membrane, bending), external (gravity, pins, rays) and collision forces at
//    the newest frame x_t (the implicit Euler convention, so a converged simulated step
//    has r ≈ Newton's residual), plus friction over the frame x_{t−1} → x_t
//    (ClothSimulator::friction_force): without it a cloth held still on a slope by static
//    friction would show its whole tangential weight as out of balance. Reported in
//    newtons and relative to m_i‖g‖.
//  - Penetration: over cloth vertices with negative signed distance to an obstacle, the
//    mean and max depth (m); 0 when none penetrates.
#include "physics/cloth_simulator.h"

namespace weft::physics {

struct FrameMetrics {
  double oob_force_mean = 0, oob_force_max = 0;          // N
  double oob_force_mean_rel = 0, oob_force_max_rel = 0;  // ÷ (m_i ‖g‖)
  double penetration_mean = 0, penetration_max = 0;      // m
  int penetrating_vertices = 0;
  double min_signed_distance = std::numeric_limits<double>::infinity();  // m
};

// Penetration metrics of one frame against the simulator's obstacles as they are now.
void measure_penetration(const ClothSimulator& sim, const Positions& x, FrameMetrics& m);

// Out-of-balance force of frame x_t given the two frames before it, h seconds apart.
void measure_out_of_balance(const ClothSimulator& sim, const Positions& x_prev2,
                            const Positions& x_prev, const Positions& x, double h,
                            FrameMetrics& m);
// The same over every vertex but `excluded` (e.g. vertices held by an attachment whose
// reaction force is not modelled); every vertex excluded gives zeros.
void measure_out_of_balance(const ClothSimulator& sim, const Positions& x_prev2,
                            const Positions& x_prev, const Positions& x, double h,
                            FrameMetrics& m, const std::vector<int>& excluded);

// The out-of-balance force of frame x_t per vertex, and the size of each term it balances
// (N): r_i = m_i a_i − (elastic + external + collision + friction)_i. Which term is large
// tells a prediction that hangs wrong (inertia, elastic) from one inside the body
// (collision: the penalty's force grows with the depth, so its maximum restates the
// deepest penetration).
struct VertexBalance {
  std::vector<double> residual;   // ‖r_i‖
  std::vector<double> inertia;    // ‖m_i a_i‖
  std::vector<double> elastic;    // ‖membrane + bending‖
  std::vector<double> external;   // ‖gravity + pins + rays‖
  std::vector<double> collision;  // ‖collision penalty‖
  std::vector<double> friction;   // ‖friction over x_{t−1} → x_t‖
  std::vector<double> weight;     // m_i ‖g‖ (the scale of the relative figures)
};
VertexBalance vertex_balance(const ClothSimulator& sim, const Positions& x_prev2, const Positions& x_prev,
                             const Positions& x, double h);
// measure_out_of_balance's figures from a vertex balance, over every vertex but `excluded`.
void summarize_out_of_balance(const VertexBalance& balance, FrameMetrics& m, const std::vector<int>& excluded = {});

// Both of the above.
FrameMetrics frame_metrics(const ClothSimulator& sim, const Positions& x_prev2,
                           const Positions& x_prev, const Positions& x, double h);

}  // namespace weft::physics
