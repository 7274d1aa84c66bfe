#include "nn/schedule.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "graph/error.h"

namespace weft::nn {

namespace {
void check_step(int64_t step, const char* who) {
  if (step < 0) fail(who, ": step ", step, " is negative");
}
void check_rate(double lr, const char* who) {
  if (!(lr >= 0) || !std::isfinite(lr))
    fail(who, ": learning rate ", lr, " must be finite and non-negative");
}
}  // namespace

ConstantLR::ConstantLR(double base_lr) : base_(base_lr) { check_rate(base_lr, "ConstantLR"); }
double ConstantLR::lr(int64_t step) const {
  check_step(step, "ConstantLR");
  return base_;
}

StepLR::StepLR(double base_lr, int64_t step_size, double gamma)
    : base_(base_lr), gamma_(gamma), step_size_(step_size) {
  check_rate(base_lr, "StepLR");
  if (step_size <= 0) fail("StepLR: step_size ", step_size, " must be positive");
  if (!(gamma > 0)) fail("StepLR: gamma ", gamma, " must be positive");
}
double StepLR::lr(int64_t step) const {
  check_step(step, "StepLR");
  return base_ * std::pow(gamma_, static_cast<double>(step / step_size_));
}

CosineLR::CosineLR(double base_lr, int64_t total_steps, double min_lr)
    : base_(base_lr), min_(min_lr), total_(total_steps) {
  check_rate(base_lr, "CosineLR");
  check_rate(min_lr, "CosineLR");
  if (total_steps <= 0) fail("CosineLR: total_steps ", total_steps, " must be positive");
}
double CosineLR::lr(int64_t step) const {
  check_step(step, "CosineLR");
  const double t = static_cast<double>(std::min(step, total_)) / static_cast<double>(total_);
  return min_ + (base_ - min_) * 0.5 * (1.0 + std::cos(std::numbers::pi * t));
}

WarmupLR::WarmupLR(std::shared_ptr<const LRSchedule> after, int64_t warmup_steps,
                   double start_factor)
    : after_(std::move(after)), warmup_(warmup_steps), start_(start_factor) {
  if (!after_) fail("WarmupLR: no schedule to follow the warm-up");
  if (warmup_steps < 0) fail("WarmupLR: warmup_steps ", warmup_steps, " is negative");
  if (!(start_factor >= 0 && start_factor <= 1))
    fail("WarmupLR: start_factor ", start_factor, " must lie in [0, 1]");
}
double WarmupLR::lr(int64_t step) const {
  check_step(step, "WarmupLR");
  if (step >= warmup_) return after_->lr(step - warmup_);
  const double f = start_ + (1.0 - start_) * static_cast<double>(step) / static_cast<double>(warmup_);
  return after_->lr(0) * f;
}

}  // namespace weft::nn
