// `weft nn forward`: one ResNet forward/backward pass on safetensors inputs, for parity
// checks against PyTorch (see nn/forward_pass.h and bench/resnet_torch_parity.py).
#include <iostream>

#include "apps/commands.h"
#include "nn/forward_pass.h"

namespace weft::apps {

void add_nn_command(CLI::App& app) {
  auto* nn = app.add_subcommand("nn", "Neural-network tools");
  nn->require_subcommand(1);
  auto* fwd = nn->add_subcommand(
      "forward", "Run a ResNet on tensor 'input' of a safetensors file and write 'output' "
                 "(and gradients, buffers) to another");
  auto o = std::make_shared<nn::ForwardPassOptions>();
  fwd->add_option("--arch", o->arch, "resnet18, resnet34 or resnet50")
      ->check(CLI::IsMember({"resnet18", "resnet34", "resnet50"}))
      ->capture_default_str();
  fwd->add_option("--outputs", o->outputs, "Size of the linear head")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  fwd->add_option("--weights", o->weights, "Weights (torchvision names), .safetensors")
      ->required();
  fwd->add_option("--input", o->input, "Holds tensor 'input', float32 [N, C, H, W]")->required();
  fwd->add_option("--output", o->output, "Written: 'output' (+ 'grad_input', 'grad.<name>', "
                                         "'buffer.<name>')")
      ->required();
  fwd->add_option("--grad-output", o->grad_output,
                  "Holds tensor 'grad_output' [N, outputs]: also run backward");
  fwd->add_flag("--train", o->train, "Batch norm in training mode; write updated buffers");
  auto dtype = std::make_shared<std::string>("float32");
  fwd->add_option("--dtype", *dtype, "Compute in float32 or float64 (inputs are widened)")
      ->check(CLI::IsMember({"float32", "float64"}))
      ->capture_default_str();
  fwd->callback([o, dtype] {
    o->dtype = *dtype == "float64" ? DType::F64 : DType::F32;
    const nn::ForwardPassSummary s = nn::run_forward_pass(*o);
    std::cout << o->arch << ": batch " << s.batch << ", " << s.parameters << " parameters, "
              << "forward " << s.forward_ms << " ms";
    if (!o->grad_output.empty()) std::cout << ", backward " << s.backward_ms << " ms";
    std::cout << "; wrote " << s.tensors_written << " tensors to " << o->output << '\n';
  });
}

}  // namespace weft::apps
