// AdaDelta (Zeiler 2012), the optimiser the study trained its U-Net with.
// LibTorch's C++ API has no AdaDelta, so it is written here following
// PyTorch's torch.optim.Adadelta update (same defaults).
#pragma once

#include <torch/torch.h>

namespace orchard::nn {

struct AdadeltaOptions : public torch::optim::OptimizerCloneableOptions<AdadeltaOptions> {
  AdadeltaOptions(double lr = 1.0) : lr_(lr) {}
  TORCH_ARG(double, lr) = 1.0;    // scales the update (AdaDelta's own step size is adaptive)
  TORCH_ARG(double, rho) = 0.9;   // decay of the running averages
  TORCH_ARG(double, eps) = 1e-6;  // keeps the square roots away from zero
  TORCH_ARG(double, weight_decay) = 0;

 public:
  void serialize(torch::serialize::InputArchive& archive) override;
  void serialize(torch::serialize::OutputArchive& archive) const override;
  double get_lr() const override { return lr(); }
  void set_lr(const double value) override { lr(value); }
};

struct AdadeltaParamState : public torch::optim::OptimizerCloneableParamState<AdadeltaParamState> {
  TORCH_ARG(torch::Tensor, square_avg);  // running average of squared gradients
  TORCH_ARG(torch::Tensor, acc_delta);   // running average of squared updates
  TORCH_ARG(int64_t, step) = 0;

 public:
  void serialize(torch::serialize::InputArchive& archive) override;
  void serialize(torch::serialize::OutputArchive& archive) const override;
};

class Adadelta : public torch::optim::Optimizer {
 public:
  explicit Adadelta(std::vector<torch::Tensor> params, AdadeltaOptions defaults = {});
  torch::Tensor step(LossClosure closure = nullptr) override;
  void save(torch::serialize::OutputArchive& archive) const override;
  void load(torch::serialize::InputArchive& archive) override;

 private:
  template <typename Self, typename Archive>
  static void serialize(Self& self, Archive& archive) {
    _TORCH_OPTIM_SERIALIZE_WITH_TEMPLATE_ARG(Adadelta);
  }
};

}  // namespace orchard::nn
