#include "nn/forward_pass.h"

#include <chrono>

#include "graph/error.h"
#include "nn/checkpoint.h"
#include "nn/resnet.h"

namespace weft::nn {

namespace {
double ms_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}
}  // namespace

ForwardPassSummary run_forward_pass(const ForwardPassOptions& o) {
  const SafetensorsFile weights = load_safetensors(o.weights);
  const Tensor& conv1 = require_tensor(weights, o.weights, "conv1.weight");
  if (conv1.dim() != 4)
    fail("weights '", o.weights, "': tensor 'conv1.weight' is ", describe(conv1),
         ", expected [64, C, 7, 7]");
  const SafetensorsFile input_file = load_safetensors(o.input);
  Tensor input = require_tensor(input_file, o.input, "input");
  if (input.dtype() != DType::F32 || input.dim() != 4 || input.size(1) != conv1.size(1))
    fail("input '", o.input, "': tensor 'input' is ", describe(input), ", expected float32 [N, ",
         conv1.size(1), ", H, W] (C from the weights' conv1.weight)");
  Tensor grad_output;
  if (!o.grad_output.empty()) {
    const SafetensorsFile g = load_safetensors(o.grad_output);
    grad_output = require_tensor(g, o.grad_output, "grad_output");
    if (grad_output.dtype() != DType::F32 || grad_output.shape() != Shape{input.size(0), o.outputs})
      fail("grad-output '", o.grad_output, "': tensor 'grad_output' is ", describe(grad_output),
           ", expected float32 [", input.size(0), ", ", o.outputs, "]");
  }

  if (o.dtype == DType::I64) fail("nn forward: dtype must be float32 or float64");
  auto widen = [&](const Tensor& t) { return t.dtype() == DType::I64 ? t : t.to(o.dtype); };
  TensorMap weight_tensors;
  for (const auto& [name, t] : weights.tensors) weight_tensors[name] = widen(t);
  input = widen(input);
  if (grad_output.defined()) grad_output = widen(grad_output);

  ResNetOptions ro;
  ro.dtype = o.dtype;
  ro.in_channels = conv1.size(1);
  ro.outputs = o.outputs;
  ro.initialise = false;  // every value comes from the file
  auto net = make_resnet(o.arch, ro);
  net->load_state_dict(weight_tensors, "weights '" + o.weights + "'");
  net->train(o.train);

  ForwardPassSummary summary;
  summary.batch = input.size(0);
  summary.parameters = net->num_parameters();
  if (grad_output.defined()) input.set_requires_grad();
  auto t0 = std::chrono::steady_clock::now();
  const Tensor output = net->forward(input);
  summary.forward_ms = ms_since(t0);

  TensorMap out;
  out["output"] = output.detach();
  if (grad_output.defined()) {
    t0 = std::chrono::steady_clock::now();
    output.backward(grad_output);
    summary.backward_ms = ms_since(t0);
    out["grad_input"] = input.grad();
    for (const NamedTensor& p : net->named_parameters()) {
      if (!p.tensor.grad().defined())
        fail("nn forward: parameter '", p.name, "' received no gradient");
      out["grad." + p.name] = p.tensor.grad();
    }
  }
  if (o.train)
    for (const NamedTensor& b : net->named_buffers()) out["buffer." + b.name] = b.tensor;
  save_safetensors(o.output, out, {{"weft.arch", o.arch}, {"weft.train", o.train ? "1" : "0"}});
  summary.tensors_written = static_cast<int64_t>(out.size());
  return summary;
}

}  // namespace weft::nn
