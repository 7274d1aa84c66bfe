#pragma once
// Learning-rate schedules as closed forms of the step number (0-based), so a resumed run
// needs only the step to continue the schedule. Set the optimiser's rate before each
// step: opt.set_lr(schedule.lr(step)).
#include <cstdint>
#include <memory>

namespace weft::nn {

class LRSchedule {
 public:
  virtual ~LRSchedule() = default;
  virtual double lr(int64_t step) const = 0;
};

class ConstantLR : public LRSchedule {
 public:
  explicit ConstantLR(double base_lr);
  double lr(int64_t step) const override;

 private:
  double base_;
};

// base · gamma^⌊step / step_size⌋ (torch.optim.lr_scheduler.StepLR).
class StepLR : public LRSchedule {
 public:
  StepLR(double base_lr, int64_t step_size, double gamma = 0.1);
  double lr(int64_t step) const override;

 private:
  double base_, gamma_;
  int64_t step_size_;
};

// min + (base − min)·(1 + cos(π·step/total))/2, then min after `total` steps
// (torch's CosineAnnealingLR over one half period).
class CosineLR : public LRSchedule {
 public:
  CosineLR(double base_lr, int64_t total_steps, double min_lr = 0.0);
  double lr(int64_t step) const override;

 private:
  double base_, min_;
  int64_t total_;
};

// Linear warm-up: for step < warmup_steps the rate is after.lr(0) scaled by
// start_factor + (1 − start_factor)·step/warmup_steps (torch's LinearLR); from then on
// after.lr(step − warmup_steps) (torch's SequentialLR).
class WarmupLR : public LRSchedule {
 public:
  WarmupLR(std::shared_ptr<const LRSchedule> after, int64_t warmup_steps,
           double start_factor = 0.0);
  double lr(int64_t step) const override;

 private:
  std::shared_ptr<const LRSchedule> after_;
  int64_t warmup_;
  double start_;
};

}  // namespace weft::nn
