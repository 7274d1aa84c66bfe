#include "physics/newton_solver.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "graph/error.h"

namespace weft::physics {

namespace {
double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

const char* to_string(StepStatus s) {
  switch (s) {
    case StepStatus::converged: return "converged";
    case StepStatus::max_iterations: return "max_iterations";
    case StepStatus::line_search_failed: return "line_search_failed";
    case StepStatus::non_finite: return "non_finite";
  }
  return "unknown";
}

NewtonSolver::NewtonSolver(int num_vertices, std::vector<Energy*> energies, NewtonOptions options)
    : n_(num_vertices), energies_(std::move(energies)), options_(options) {
  WEFT_CHECK(options_.max_iterations >= 1, "newton: max_iterations must be >= 1, got ",
             options_.max_iterations);
  WEFT_CHECK(options_.tolerance > 0, "newton: tolerance must be > 0, got ", options_.tolerance);
  std::vector<std::array<int, 2>> pairs;
  for (const Energy* e : energies_) e->add_pattern(pairs);
  hessian_ = SparseHessian(n_, pairs);
  exact_hessian_ = hessian_;
  inv_force_scale_ = Eigen::VectorXd::Ones(n_);
  if (options_.factor_without_weak_pairs) {
    WEFT_CHECK(options_.linear_solver == LinearSolverKind::direct,
               "newton: factor_without_weak_pairs needs the direct linear solver");
    std::vector<std::array<int, 2>> weak;
    for (const Energy* e : energies_) e->add_weak_pairs(weak);
    auto ordered = [](std::array<int, 2> p) { return p[0] < p[1] ? p : std::array<int, 2>{p[1], p[0]}; };
    for (auto& p : weak) p = ordered(p);
    std::sort(weak.begin(), weak.end());
    std::vector<std::array<int, 2>> strong;
    for (const auto& p : pairs)
      if (!std::binary_search(weak.begin(), weak.end(), ordered(p))) strong.push_back(p);
    coarse_ = SparseHessian(n_, strong);
  }
  cholmod_ = std::make_unique<CholmodSolver>(coarse_.num_vertices() > 0 ? coarse_ : hessian_,
                                             options_.cholesky, options_.ordering, options_.amalgamation);
}

void NewtonSolver::set_force_scale(Eigen::VectorXd f) {
  WEFT_CHECK(f.size() == n_, "newton: ", f.size(), " force scales for ", n_, " vertices");
  WEFT_CHECK(f.allFinite() && f.minCoeff() > 0, "newton: force scales must be finite and > 0 N");
  inv_force_scale_ = f.cwiseInverse();
}

double NewtonSolver::residual(const Eigen::VectorXd& g) const {
  double r = 0;
  for (int i = 0; i < n_; ++i) r = std::max(r, g.segment<3>(3 * i).norm() * inv_force_scale_[i]);
  return r;
}

double NewtonSolver::evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* g, SparseHessian* h,
                              std::vector<double>* ms) const {
  if (g) g->setZero(3 * n_);
  if (h) h->set_zero();
  double e = 0;
  for (size_t k = 0; k < energies_.size(); ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    e += energies_[k]->evaluate(x, g, h);
    if (ms) (*ms)[k] += ms_since(t0);
  }
  return e;
}

double NewtonSolver::energy(const Eigen::VectorXd& x) const {
  return evaluate(x, nullptr, nullptr, nullptr);
}

double NewtonSolver::gradient(const Eigen::VectorXd& x, Eigen::VectorXd& g) const {
  return evaluate(x, &g, nullptr, nullptr);
}

const SparseHessian& NewtonSolver::hessian(const Eigen::VectorXd& x) {
  evaluate(x, nullptr, &hessian_, nullptr);
  return hessian_;
}

NewtonSolver::CgOutcome NewtonSolver::preconditioned_cg(const SparseHessian& H, const Eigen::VectorXd& g,
                                                        Eigen::VectorXd& d, NewtonReport& report) {
  // CG on (H + δI) d = −g from d = 0, preconditioned by the (possibly older) Cholesky
  // factor, to a residual of cg_relative_tolerance·‖g‖. On non-positive curvature d keeps
  // the last iterate (every iterate before it is a descent direction).
  Eigen::VectorXd r = -g;
  d.setZero(r.size());
  const double target = (cg_forcing_ > 0 ? cg_forcing_ : options_.cg_relative_tolerance) * r.norm();
  return projected_cg(H, r, d, target, {}, &negative_direction_, report);
}

void NewtonSolver::project_onto_held(const std::vector<HeldComponent>& held, Eigen::VectorXd& v) {
  for (const auto& [i, u] : held) v.segment<3>(3 * i) -= u * u.dot(v.segment<3>(3 * i));
}

NewtonSolver::CgOutcome NewtonSolver::projected_cg(const SparseHessian& H, Eigen::VectorXd& r, Eigen::VectorXd& d,
                                                   double target, const std::vector<HeldComponent>& held,
                                                   Eigen::VectorXd* curvature_direction, NewtonReport& report) {
  auto project = [&](Eigen::VectorXd& v) { project_onto_held(held, v); };
  project(r);
  Eigen::VectorXd z = cholmod_->solve(r);
  project(z);
  Eigen::VectorXd p = z;
  double rz = r.dot(z);
  for (int k = 0; k < options_.cg_max_iterations; ++k) {
    Eigen::VectorXd hp = H.multiply(p);
    hp += delta_ * p;
    project(hp);
    const double php = p.dot(hp);
    if (!(php > 0)) {
      if (curvature_direction) *curvature_direction = p;
      return CgOutcome::negative_curvature;
    }
    const double alpha = rz / php;
    d += alpha * p;
    r -= alpha * hp;
    ++report.cg_iterations;
    if (r.norm() <= target) return CgOutcome::converged;
    z = cholmod_->solve(r);
    project(z);
    const double rz_new = r.dot(z);
    p = z + (rz_new / rz) * p;
    rz = rz_new;
  }
  return CgOutcome::too_slow;
}

void NewtonSolver::exact_direction(const SparseHessian& H, const Eigen::VectorXd& g, Eigen::VectorXd& d,
                                   NewtonReport& report) {
  // Truncated CG on (H + δI) d = −g (H the exact Hessian), preconditioned by the factor
  // of the corrected H + δI or of its bound without the weak pairs. If the very first
  // direction has non-positive curvature, the preconditioned step is used.
  const int before = report.cg_iterations;
  last_cg_outcome_ = preconditioned_cg(H, g, d, report);
  if (report.cg_iterations == before) d = cholmod_->solve(-g);
}

void NewtonSolver::refine_limited_direction(const Eigen::VectorXd& x, const Eigen::VectorXd& g,
                                            const Eigen::VectorXd& d, Eigen::VectorXd& limited, NewtonReport& report) {
  // The constraints: vertex i's move along u_i (the unit direction of what the filter took
  // from it) stays what the filter left.
  std::vector<HeldComponent> held;
  for (int i = 0; i < n_; ++i) {
    const Eigen::Vector3d cut = limited.segment<3>(3 * i) - d.segment<3>(3 * i);
    const double length = cut.norm();
    if (length > 0) held.push_back({i, cut / length});
  }
  if (held.empty() || !cholmod_->has_factor()) return;
  // Projected PCG on the model gᵀy + ½yᵀ(H + δI)y from y = limited (H the factorised,
  // corrected Hessian: positive semi-definite), to 1e-2 of the projected residual.
  Eigen::VectorXd y = limited;
  Eigen::VectorXd r = -g - hessian_.multiply(y) - delta_ * y;
  Eigen::VectorXd projected = r;
  project_onto_held(held, projected);
  projected_cg(hessian_, r, y, 1e-2 * projected.norm(), held, nullptr, report);
  // The other vertices' new moves meet the filter too.
  clip_vertex_steps(x, y);
  if (y.allFinite() && g.dot(y) < 0) limited.swap(y);
}

bool NewtonSolver::correct_hessian(const Eigen::VectorXd& x, NewtonReport& report) {
  if (hessian_corrected_) return false;
  hessian_corrected_ = true;
  bool any = false;
  for (const Energy* e : energies_) any |= e->add_hessian_correction(x, hessian_);
  if (any) ++report.corrections;
  return any;
}

bool NewtonSolver::direction(const Eigen::VectorXd& x, const Eigen::VectorXd& g,
                             Eigen::VectorXd& d, NewtonReport& report) {
  const auto t0 = std::chrono::steady_clock::now();
  bool ok = false;
  const bool reuse = options_.linear_solver == LinearSolverKind::reused_factor;
  for (int attempt = 0; attempt < 40 && !ok; ++attempt) {
    if (reuse && !factor_stale_ && cholmod_->has_factor()) {
      const CgOutcome cg = preconditioned_cg(hessian_, g, d, report);
      if (cg == CgOutcome::converged && g.dot(d) < 0 && d.allFinite()) {
        ok = true;
        break;
      }
      // Negative curvature of the exact Hessian: switch to the PSD-corrected one and keep
      // the factor; otherwise (CG too slow) refresh the factor.
      if (cg == CgOutcome::negative_curvature && correct_hessian(x, report)) continue;
      factor_stale_ = true;
      continue;
    }
    if (!reuse && options_.precondition_exact_hessian && !hessian_corrected_) {
      // Factorise the corrected Hessian, which is positive definite, and reach the exact
      // one by CG (exact_direction): one factorisation per iteration instead of a failed
      // one on the indefinite exact Hessian followed by the corrected one.
      exact_hessian_.values() = hessian_.values();
      exact_differs_ = correct_hessian(x, report);
    }
    const bool coarse = coarse_.num_vertices() > 0;
    bool factored;
    if (coarse) {
      hessian_.bound_into(coarse_);
      coarse_.add_to_diagonal(delta_);
      factored = cholmod_->factorize(coarse_);
    } else {
      hessian_.add_to_diagonal(delta_);
      factored = cholmod_->factorize(hessian_);
      hessian_.add_to_diagonal(-delta_);
    }
    ++report.factorizations;
    if (factored) {
      if (exact_differs_)
        exact_direction(exact_hessian_, g, d, report);
      else if (coarse)
        exact_direction(hessian_, g, d, report);
      else
        d = -cholmod_->solve(g);
      factor_stale_ = false;
      if (d.allFinite() && g.dot(d) < 0) {
        ok = true;
        break;
      }
    } else {
      factor_stale_ = true;
    }
    // Not positive definite: first switch the energies with an indefinite exact Hessian
    // to their PSD projection, and only then regularise with δI.
    if (correct_hessian(x, report)) continue;
    delta_ = delta_ == 0 ? delta_floor_ : 10.0 * delta_;
  }
  report.linear_solve_ms += ms_since(t0);
  return ok;
}

double NewtonSolver::max_step(const Eigen::VectorXd& x, const Eigen::VectorXd& dx) const {
  double alpha = 1.0;
  for (const Energy* en : energies_) alpha = std::min(alpha, en->max_step(x, dx));
  return alpha;
}

void NewtonSolver::clip_vertex_steps(const Eigen::VectorXd& x, Eigen::VectorXd& dx) const {
  for (const Energy* en : energies_) en->clip_vertex_steps(x, dx);
}

double NewtonSolver::search_negative_curvature(const Eigen::VectorXd& g, double reach, Eigen::VectorXd& x_new,
                                              double& e_new, Eigen::VectorXd& x_trial,
                                              NewtonReport& report) const {
  // CG stopped at a direction p of non-positive curvature of the exact Hessian (a buckling
  // mode of the compressed membrane), so the accepted step left it out. The energy falls
  // along p before the membrane stiffens again: from the accepted point, try p scaled to
  // move a vertex as far as the accepted step did (reach, m), doubling while the energy
  // keeps falling or halving until it falls, and keep the lowest energy found. Energy
  // evaluations only; the step filter applies.
  Eigen::VectorXd p = negative_direction_;
  if (g.dot(p) > 0) p = -p;
  const double p_max = p.lpNorm<Eigen::Infinity>();
  if (!(p_max > 0) || !(reach > 0) || !p.allFinite()) return 0;
  auto admissible = [&](double tau) { return max_step(x_new, tau * p); };
  double tau = reach / p_max;
  tau *= admissible(tau);
  double best_tau = 0, best_e = e_new;
  for (int k = 0; k < 12 && tau > 0; ++k) {
    x_trial = x_new + tau * p;
    const double et = evaluate(x_trial, nullptr, nullptr, &report.energy_ms);
    if (std::isfinite(et) && et < best_e) {
      best_e = et;
      best_tau = tau;
      if (admissible(2.0 * tau) < 1.0) break;
      tau *= 2.0;
    } else if (best_tau > 0) {
      break;
    } else {
      tau *= 0.5;
    }
  }
  if (best_tau == 0) return 0;
  x_new += best_tau * p;
  e_new = best_e;
  return best_tau * p_max;
}

void NewtonSolver::print_trace(int it, const Eigen::VectorXd& x, const Eigen::VectorXd& g, double e,
                               const Eigen::VectorXd& x_new, const Eigen::VectorXd& d,
                               double alpha, const IterationTrace& t,
                               const NewtonReport& report) const {
  // One line per accepted iteration (WEFT_NEWTON_TRACE): the energy decrease against the
  // exact quadratic model's prediction for the step taken, the step filter's cap, the
  // line search (back-tracks, doublings), CG (iterations and how it ended), and the vertex
  // with the largest residual with each energy's share of the force there (relative to
  // its force scale): where the out-of-balance force sits.
  const Eigen::VectorXd step = x_new - x;
  const SparseHessian& h = exact_differs_ ? exact_hessian_ : hessian_;
  const double predicted = -(g.dot(step) + 0.5 * step.dot(h.multiply(step)));
  const double actual = e - energy(x_new);
  int worst = 0;
  double worst_r = -1;
  for (int i = 0; i < n_; ++i) {
    const double r = g.segment<3>(3 * i).norm() * inv_force_scale_[i];
    if (r > worst_r) {
      worst_r = r;
      worst = i;
    }
  }
  std::string shares;
  char buf[96];
  for (const Energy* en : energies_) {
    Eigen::VectorXd ge = Eigen::VectorXd::Zero(3 * n_);
    en->evaluate(x, &ge, nullptr);
    const double r = ge.segment<3>(3 * worst).norm() * inv_force_scale_[worst];
    if (r < 1e-3 * worst_r) continue;
    std::snprintf(buf, sizeof buf, " %s %.3g", en->name().c_str(), r);
    shares += buf;
  }
  for (const Energy* en : energies_) {
    const std::string about = en->describe_vertex(x, worst);
    if (!about.empty()) shares += " " + en->name() + " " + about;
  }
  // Where the full (filtered) step met more curvature than the quadratic model: per energy,
  // its change along α₀·d minus the linear prediction α₀·∇E_k·d, against the model's total
  // ½α₀²·dᵀHd. Only for iterations that back-tracked.
  std::string curvature;
  if (t.backtracks > 0) {
    const double a0 = t.filter;
    const Eigen::VectorXd x_full = x + a0 * d;
    const SparseHessian& hm = exact_differs_ ? exact_hessian_ : hessian_;
    std::snprintf(buf, sizeof buf, " | full step %.3g: model %.3e;", a0, 0.5 * a0 * a0 * d.dot(hm.multiply(d)));
    curvature = buf;
    for (const Energy* en : energies_) {
      Eigen::VectorXd ge = Eigen::VectorXd::Zero(3 * n_);
      const double e0 = en->evaluate(x, &ge, nullptr);
      const double c = en->evaluate(x_full, nullptr, nullptr) - e0 - a0 * ge.dot(d);
      if (std::abs(c) < 1e-12) continue;
      std::snprintf(buf, sizeof buf, " %s %.3e", en->name().c_str(), c);
      curvature += buf;
    }
  }
  static const char* outcomes[] = {"converged", "negative_curvature", "too_slow"};
  std::fprintf(stderr,
               "it %d E %.12g res %.3e |d| %.2e filter %.3g limited %d alpha %g backtracks %d "
               "curvature_step %.2e decrease %.3e predicted %.3e ratio %.3f cg %d %s delta %.2e "
               "fact %d corr %d worst v%d |dx| %.2e m:%s%s\n",
               it, e, worst_r, d.lpNorm<Eigen::Infinity>(), t.filter, t.limited_vertices, alpha, t.backtracks,
               t.curvature_step, actual, predicted,
               predicted != 0 ? actual / predicted : 0.0, report.cg_iterations - t.cg_before,
               exact_differs_ ? outcomes[static_cast<int>(last_cg_outcome_)] : "none", delta_,
               report.factorizations, report.corrections, worst, step.segment<3>(3 * worst).norm(),
               shares.c_str(), curvature.c_str());
}

NewtonReport NewtonSolver::minimize(Eigen::VectorXd& x) {
  WEFT_CHECK(x.size() == 3 * n_, "newton: x has ", x.size(), " entries, expected ", 3 * n_);
  const auto t_start = std::chrono::steady_clock::now();
  NewtonReport report;
  report.energy_ms.assign(energies_.size(), 0.0);
  Eigen::VectorXd g(3 * n_), g_new(3 * n_), d(3 * n_), x_new(3 * n_), x_trial(3 * n_);
  double e = x.allFinite() ? evaluate(x, &g, nullptr, &report.energy_ms) : NAN;
  auto finish = [&](StepStatus s) {
    report.status = s;
    report.energy = e;
    report.gradient_norm = g.allFinite() ? g.lpNorm<Eigen::Infinity>() : NAN;
    report.residual = g.allFinite() ? residual(g) : NAN;
    report.regularization = delta_;
    report.total_ms = ms_since(t_start);
    if (std::isfinite(report.residual) &&  // the returned iterate's, if not recorded yet
        report.residual_history.size() < static_cast<size_t>(report.iterations) + 1) {
      report.residual_history.push_back(report.residual);
      report.residual_ms.push_back(report.total_ms);
    }
    return report;
  };
  if (!std::isfinite(e) || !g.allFinite()) return finish(StepStatus::non_finite);
  report.accepted_energies.push_back(e);
  const bool trace_on = std::getenv("WEFT_NEWTON_TRACE") != nullptr;
  cg_forcing_ = options_.cg_relative_tolerance;
  const double phi = 0.5 * (1.0 + std::sqrt(5.0));
  for (int it = 0; it < options_.max_iterations; ++it) {
    report.residual_history.push_back(residual(g));
    report.residual_ms.push_back(ms_since(t_start));
    if (report.residual_history.back() <= options_.tolerance) return finish(StepStatus::converged);
    // The accepted iterate's Hessian came with its gradient (one pass over the energies);
    // only the start's is assembled here.
    if (it == 0) evaluate(x, nullptr, &hessian_, &report.energy_ms);
    for (const Energy* en : energies_) en->adjust_hessian(x, g, hessian_);
    hessian_corrected_ = false;
    exact_differs_ = false;
    last_cg_outcome_ = CgOutcome::converged;
    if (delta_floor_ == 0) {
      // Regularisation starts from a tiny fraction of the Hessian's scale (N/m).
      double diag = 0;
      for (int c = 0; c < hessian_.rows(); ++c)
        diag += std::abs(hessian_.values()[hessian_.column_starts()[c + 1] - 1]);
      delta_floor_ = std::max(1e-8 * diag / hessian_.rows(), 1e-12);
    }
    bool accepted = false;
    double last_alpha = 0;
    IterationTrace trace;
    trace.cg_before = report.cg_iterations;
    for (int retry = 0; retry < 4 && !accepted; ++retry) {
      if (!direction(x, g, d, report)) break;
      double alpha = 1.0;
      trace.limited_vertices = 0;
      if (options_.per_vertex_step_limits) {
        Eigen::VectorXd limited = d;
        clip_vertex_steps(x, limited);
        for (int i = 0; i < n_; ++i)
          if (limited.segment<3>(3 * i) != d.segment<3>(3 * i)) ++trace.limited_vertices;
        if (trace.limited_vertices > 0 && options_.refine_limited_steps && g.dot(limited) < 0)
          refine_limited_direction(x, g, d, limited, report);
        if (trace.limited_vertices > 0) {
          if (g.dot(limited) < 0)
            d.swap(limited);
          else
            alpha = max_step(x, d);  // not a descent direction: the global filter
        }
        // Friction's clamp does not cap the whole step (FrictionEnergy::max_step), the
        // collision's does: the limited move already meets it.
      } else {
        alpha = max_step(x, d);
      }
      const double slope = g.dot(d);
      trace.filter = alpha;
      trace.backtracks = 0;
      double e_accept = 0;
      for (int b = 0; b < options_.max_backtracks; ++b, alpha *= 0.5, ++trace.backtracks) {
        x_new = x + alpha * d;
        const double e_new = evaluate(x_new, nullptr, nullptr, &report.energy_ms);
        if (std::isfinite(e_new) && e_new <= e + options_.armijo * alpha * slope) {
          accepted = true;
          e_accept = e_new;
          break;
        }
      }
      if (accepted && options_.negative_curvature_search &&
          last_cg_outcome_ == CgOutcome::negative_curvature) {
        trace.curvature_step = search_negative_curvature(g, (alpha * d).lpNorm<Eigen::Infinity>(),
                                                         x_new, e_accept, x_trial, report);
        if (trace.curvature_step > 0) ++report.curvature_steps;
      }
      last_alpha = alpha;
      if (!accepted) {
        // No sufficient decrease along the Newton direction: bend it toward −∇E.
        delta_ = std::max(10.0 * delta_, 1e3 * delta_floor_);
        factor_stale_ = true;
      }
    }
    if (!accepted) return finish(StepStatus::line_search_failed);
    if (trace_on) print_trace(it, x, g, e, x_new, d, last_alpha, trace, report);
    // The linear model's gradient after the step taken, before hessian_ moves on to x_new.
    double model_gradient = 0;
    if (options_.adaptive_cg_tolerance) {
      const Eigen::VectorXd step = x_new - x;
      model_gradient = (g + (exact_differs_ ? exact_hessian_ : hessian_).multiply(step)).norm();
    }
    // Gradient and Hessian at the new iterate in one pass: the Hessian is wasted only on
    // the iterate that converges, and each iteration saves a pass (the energies share
    // their per-element work between both).
    const double e_new = evaluate(x_new, &g_new, &hessian_, &report.energy_ms);
    if (!std::isfinite(e_new) || !g_new.allFinite()) return finish(StepStatus::non_finite);
    if (options_.adaptive_cg_tolerance) {
      const double g_norm = g.norm();
      double eta = g_norm > 0 ? std::abs(g_new.norm() - model_gradient) / g_norm : options_.cg_relative_tolerance;
      const double previous = std::pow(cg_forcing_, phi);
      if (previous > 0.1) eta = std::max(eta, previous);
      cg_forcing_ = std::clamp(eta, options_.cg_min_relative_tolerance, options_.cg_relative_tolerance);
      // A step that has used half its iterations gets exact directions from then on.
      if (2 * (it + 1) >= options_.max_iterations) cg_forcing_ = options_.cg_min_relative_tolerance;
    }
    x.swap(x_new);
    g.swap(g_new);
    e = e_new;
    report.accepted_energies.push_back(e);
    report.iterations = it + 1;
    delta_ = delta_ <= delta_floor_ ? 0.0 : 0.1 * delta_;
  }
  if (residual(g) <= options_.tolerance) return finish(StepStatus::converged);
  return finish(StepStatus::max_iterations);
}

}  // namespace weft::physics
