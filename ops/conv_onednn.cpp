#include "ops/conv_onednn.h"

#include <dnnl.hpp>
#include <map>
#include <memory>
#include <mutex>
#include <tuple>
#include <vector>

#include "graph/error.h"
#include "ops/conv_backend.h"

namespace weft {

namespace {

using dnnl::memory;
using Tag = memory::format_tag;

dnnl::engine& cpu_engine() {
  static dnnl::engine engine(dnnl::engine::kind::cpu, 0);
  return engine;
}

dnnl::stream& thread_stream() {
  thread_local dnnl::stream stream(cpu_engine());
  return stream;
}

// The primitives of one geometry, made once (creating a primitive descriptor walks
// oneDNN's implementation list: tens of microseconds, against a few milliseconds to run).
struct ConvPrimitives {
  dnnl::algorithm algorithm = dnnl::algorithm::convolution_direct;
  memory::desc x_md, w_plain_md, y_md, b_md;  // weft's tensors as they are
  dnnl::convolution_forward::primitive_desc fwd_pd;
  dnnl::convolution_forward fwd;
  // Backward, made on first use.
  std::once_flag bwd_once;
  dnnl::convolution_backward_data::primitive_desc bwd_data_pd;
  dnnl::convolution_backward_data bwd_data;
  dnnl::convolution_backward_weights::primitive_desc bwd_weights_pd;
  dnnl::convolution_backward_weights bwd_weights;
};

// The geometry, bias, Winograd, and the epilogue's kind (0: none; else 1 + 2·residual +
// 4·relu).
using Key = std::tuple<int64_t, int64_t, int64_t, int64_t, int64_t, int64_t, int64_t, int64_t,
                       int64_t, int64_t, int64_t, int64_t, int64_t, int64_t, int64_t, bool,
                       bool, int>;

memory::dims dims(std::initializer_list<int64_t> v) { return memory::dims(v.begin(), v.end()); }

// Activations: blocked tensors are given to oneDNN as they are (nChw16c / nChw8c); NCHW
// ones are reordered to the layout the kernels choose, as PyTorch does (oneDNN's
// kernels on plain NCHW sum each output in one long chain, about 1.5× further from
// float64 than PyTorch's own float32 run; nhwc ones, 4–5× further). Weights: always the
// kernels' choice, reordered per call.
Tag blocked_tag(int64_t block) { return block == 16 ? Tag::nChw16c : Tag::nChw8c; }

memory::desc activation_md(const memory::dims& d, int64_t block) {
  return memory::desc(d, memory::data_type::f32, block > 1 ? blocked_tag(block) : Tag::any);
}

struct ConvDescs {
  memory::desc x, w, b, y;
  memory::dims stride, dil, pad;
};

ConvDescs conv_descs(const ConvGeometry& g, bool bias) {
  ConvDescs d;
  d.x = activation_md(dims({g.N, g.C, g.H, g.W}), g.in_block);
  d.y = activation_md(dims({g.N, g.O, g.Ho, g.Wo}), g.block);
  d.w = memory::desc(dims({g.O, g.C, g.kh, g.kw}), memory::data_type::f32, Tag::any);
  if (bias) d.b = memory::desc(dims({g.O}), memory::data_type::f32, Tag::x);
  d.stride = dims({g.sh, g.sw});
  d.dil = dims({g.dh - 1, g.dw - 1});
  d.pad = dims({g.ph, g.pw});
  return d;
}

// Where oneDNN-winograd uses Winograd: 3×3, stride 1, no dilation, and at least 16×16
// output pixels (below that, its kernels were no faster than the direct ones, and at 4×4
// 2.7× slower: docs/BENCHMARKS.md).
bool winograd_suits(const ConvGeometry& g) {
  return g.kh == 3 && g.kw == 3 && g.sh == 1 && g.sw == 1 && g.dh == 1 && g.dw == 1 &&
         g.Ho * g.Wo >= 256;
}

int epilogue_kind(const ConvEpilogue* e) {
  return e ? 1 + 2 * e->residual.defined() + 4 * e->relu : 0;
}

// The epilogue as oneDNN post-ops: × scale and + shift per channel (binary ops on a
// [1, O, 1, 1] operand), + residual (a binary add on a tensor of the output's layout),
// then ReLU.
dnnl::primitive_attr epilogue_attr(int kind, const memory::desc& y_md, int64_t O) {
  dnnl::primitive_attr attr;
  if (kind == 0) return attr;
  const memory::desc channel(dims({1, O, 1, 1}), memory::data_type::f32, Tag::abcd);
  dnnl::post_ops ops;
  ops.append_binary(dnnl::algorithm::binary_mul, channel);
  ops.append_binary(dnnl::algorithm::binary_add, channel);
  if (kind & 2) ops.append_binary(dnnl::algorithm::binary_add, y_md);
  if (kind & 4) ops.append_eltwise(1.0f, dnnl::algorithm::eltwise_relu, 0.0f, 0.0f);
  attr.set_post_ops(ops);
  return attr;
}

std::shared_ptr<ConvPrimitives> make_primitives(const ConvGeometry& g, bool bias, bool winograd,
                                                int epilogue) {
  auto p = std::make_shared<ConvPrimitives>();
  using dt = memory::data_type;
  p->x_md = memory::desc(dims({g.N, g.C, g.H, g.W}), dt::f32,
                         g.in_block > 1 ? blocked_tag(g.in_block) : Tag::nchw);
  p->y_md = memory::desc(dims({g.N, g.O, g.Ho, g.Wo}), dt::f32,
                         g.block > 1 ? blocked_tag(g.block) : Tag::nchw);
  p->w_plain_md = memory::desc(dims({g.O, g.C, g.kh, g.kw}), dt::f32, Tag::oihw);
  if (bias) p->b_md = memory::desc(dims({g.O}), dt::f32, Tag::x);
  const ConvDescs d = conv_descs(g, bias);
  const auto prop = epilogue ? dnnl::prop_kind::forward_inference
                             : dnnl::prop_kind::forward_training;
  const dnnl::primitive_attr attr = epilogue_attr(epilogue, p->y_md, g.O);
  auto forward_pd = [&](dnnl::algorithm algorithm) {
    const auto desc =
        bias ? dnnl::convolution_forward::desc(prop, algorithm, d.x, d.w, d.b, d.y, d.stride,
                                               d.dil, d.pad, d.pad)
             : dnnl::convolution_forward::desc(prop, algorithm, d.x, d.w, d.y, d.stride, d.dil,
                                               d.pad, d.pad);
    return dnnl::convolution_forward::primitive_desc(desc, attr, cpu_engine());
  };
  if (winograd) {
    try {  // oneDNN has Winograd kernels only for some shapes and machines
      p->fwd_pd = forward_pd(dnnl::algorithm::convolution_winograd);
      p->algorithm = dnnl::algorithm::convolution_winograd;
    } catch (const dnnl::error&) {
    }
  }
  if (p->algorithm != dnnl::algorithm::convolution_winograd)
    p->fwd_pd = forward_pd(dnnl::algorithm::convolution_direct);
  p->fwd = dnnl::convolution_forward(p->fwd_pd);
  return p;
}

void make_backward(ConvPrimitives& p, const ConvGeometry& g, bool bias) {
  const ConvDescs d = conv_descs(g, bias);
  const auto data_desc = dnnl::convolution_backward_data::desc(
      p.algorithm, d.x, d.w, d.y, d.stride, d.dil, d.pad, d.pad);
  p.bwd_data_pd =
      dnnl::convolution_backward_data::primitive_desc(data_desc, cpu_engine(), p.fwd_pd);
  p.bwd_data = dnnl::convolution_backward_data(p.bwd_data_pd);
  // The weight gradient always runs the direct kernels: oneDNN 2.6's Winograd backward-
  // weights kernel crashed on ResNet-18's shapes (segfault inside its JIT code).
  const auto direct = dnnl::algorithm::convolution_direct;
  const auto weights_desc =
      bias ? dnnl::convolution_backward_weights::desc(direct, d.x, d.w, d.b, d.y, d.stride,
                                                      d.dil, d.pad, d.pad)
           : dnnl::convolution_backward_weights::desc(direct, d.x, d.w, d.y, d.stride, d.dil,
                                                      d.pad, d.pad);
  dnnl::convolution_forward::primitive_desc hint = p.fwd_pd;
  if (p.algorithm != direct) {
    const auto fwd_desc =
        bias ? dnnl::convolution_forward::desc(dnnl::prop_kind::forward_training, direct, d.x,
                                               d.w, d.b, d.y, d.stride, d.dil, d.pad, d.pad)
             : dnnl::convolution_forward::desc(dnnl::prop_kind::forward_training, direct, d.x,
                                               d.w, d.y, d.stride, d.dil, d.pad, d.pad);
    hint = dnnl::convolution_forward::primitive_desc(fwd_desc, cpu_engine());
  }
  p.bwd_weights_pd =
      dnnl::convolution_backward_weights::primitive_desc(weights_desc, cpu_engine(), hint);
  p.bwd_weights = dnnl::convolution_backward_weights(p.bwd_weights_pd);
}

std::string geometry_text(const ConvGeometry& g) {
  return "input [" + std::to_string(g.N) + "," + std::to_string(g.C) + "," +
         std::to_string(g.H) + "," + std::to_string(g.W) + "]" +
         (g.block > 1 ? " to channel blocks of " + std::to_string(g.block) : "") + ", weight [" + std::to_string(g.O) + "," +
         std::to_string(g.C) + "," + std::to_string(g.kh) + "," + std::to_string(g.kw) + "]";
}

ConvPrimitives& primitives(const ConvGeometry& g, bool bias, bool backward, int epilogue = 0) {
  static std::mutex mutex;
  static std::map<Key, std::shared_ptr<ConvPrimitives>> cache;
  const bool winograd = conv_backend() == ConvBackend::onednn_winograd && winograd_suits(g);
  const Key key{g.N, g.C, g.H, g.W, g.O, g.kh, g.kw, g.sh, g.sw, g.ph, g.pw, g.dh, g.dw,
                g.block, g.in_block, bias, winograd, epilogue};
  std::shared_ptr<ConvPrimitives> p;
  try {
    {
      std::lock_guard<std::mutex> lock(mutex);
      auto& slot = cache[key];
      if (!slot) slot = make_primitives(g, bias, winograd, epilogue);
      p = slot;
    }
    if (backward) std::call_once(p->bwd_once, [&] { make_backward(*p, g, bias); });
  } catch (const dnnl::error& e) {
    fail("conv2d (oneDNN): no convolution for ", geometry_text(g), ": ", e.what(),
         " (WEFT_CONV_BACKEND=eigen selects weft's own kernels)");
  }
  return *p;  // entries are never removed
}

// Reusable per-thread buffers for tensors in a oneDNN layout, one per use (slot).
enum Slot { kX, kW, kY, kGy, kGx, kGw, kSlots };
void* scratch(Slot slot, size_t bytes) {
  thread_local std::vector<float> buffers[kSlots];
  std::vector<float>& buffer = buffers[slot];
  const size_t n = (bytes + sizeof(float) - 1) / sizeof(float);
  if (buffer.size() < n) {
    buffer.clear();
    buffer.shrink_to_fit();
    buffer.resize(n);
  }
  return buffer.data();
}

memory wrap(const memory::desc& md, const Tensor& t) {
  return memory(md, cpu_engine(), const_cast<float*>(t.data<float>()));
}

// A weft tensor (plain layout `plain`) as the kernels want it (`md`): the tensor itself,
// or a reordered copy in scratch.
memory input_as(const memory::desc& md, const memory::desc& plain, const Tensor& t, Slot slot) {
  memory m = wrap(plain, t);
  if (md == plain) return m;
  memory out(md, cpu_engine(), scratch(slot, md.get_size()));
  dnnl::reorder(m, out).execute(thread_stream(), m, out);
  return out;
}

// Where the kernel writes a result for tensor t: t itself, or scratch to reorder from.
memory output_as(const memory::desc& md, const memory::desc& plain, const Tensor& t, Slot slot) {
  if (md == plain) return wrap(plain, t);
  return memory(md, cpu_engine(), scratch(slot, md.get_size()));
}

void finish_output(const memory& written, const memory::desc& plain, const Tensor& t) {
  if (written.get_desc() == plain) return;
  memory m = wrap(plain, t);
  dnnl::reorder(written, m).execute(thread_stream(), const_cast<memory&>(written), m);
}

}  // namespace

Tensor onednn_conv_forward(const Tensor& x, const Tensor& w, const Tensor& bias,
                           const ConvGeometry& g, const ConvEpilogue* epilogue) {
  if (epilogue && g.block == 1)
    fail("conv2d_affine (oneDNN): the epilogue needs a blocked output");
  ConvPrimitives& p = primitives(g, bias.defined(), false, epilogue_kind(epilogue));
  Tensor y = Tensor::empty(g.output_shape(), DType::F32);
  dnnl::stream& s = thread_stream();
  const memory out = output_as(p.fwd_pd.dst_desc(), p.y_md, y, kY);
  std::unordered_map<int, memory> args{
      {DNNL_ARG_SRC, input_as(p.fwd_pd.src_desc(), p.x_md, x, kX)},
      {DNNL_ARG_WEIGHTS, input_as(p.fwd_pd.weights_desc(), p.w_plain_md, w, kW)},
      {DNNL_ARG_DST, out}};
  if (bias.defined()) args.emplace(DNNL_ARG_BIAS, wrap(p.b_md, bias));
  if (epilogue) {
    const memory::desc channel(dims({1, g.O, 1, 1}), memory::data_type::f32, Tag::abcd);
    args.emplace(DNNL_ARG_ATTR_MULTIPLE_POST_OP(0) | DNNL_ARG_SRC_1, wrap(channel, epilogue->scale));
    args.emplace(DNNL_ARG_ATTR_MULTIPLE_POST_OP(1) | DNNL_ARG_SRC_1, wrap(channel, epilogue->shift));
    if (epilogue->residual.defined())
      args.emplace(DNNL_ARG_ATTR_MULTIPLE_POST_OP(2) | DNNL_ARG_SRC_1,
                   wrap(p.y_md, epilogue->residual));
  }
  p.fwd.execute(s, args);
  finish_output(out, p.y_md, y);
  s.wait();
  return y;
}

ConvGradients onednn_conv_backward(const Tensor& x, const Tensor& w, const Tensor& gy,
                                   const ConvGeometry& g, bool want_x, bool want_w,
                                   bool want_bias) {
  ConvPrimitives& p = primitives(g, want_bias, true);
  dnnl::stream& s = thread_stream();
  ConvGradients out;
  // Both backward kernels take dy in the same layout (they share the forward's hint).
  const memory gy_m = input_as(p.bwd_data_pd.diff_dst_desc(), p.y_md, gy, kGy);
  if (want_x) {
    out.x = Tensor::empty(g.input_shape(), DType::F32);
    const memory gx = output_as(p.bwd_data_pd.diff_src_desc(), p.x_md, out.x, kGx);
    p.bwd_data.execute(s, {{DNNL_ARG_DIFF_DST, gy_m},
                           {DNNL_ARG_WEIGHTS, input_as(p.bwd_data_pd.weights_desc(),
                                                       p.w_plain_md, w, kW)},
                           {DNNL_ARG_DIFF_SRC, gx}});
    finish_output(gx, p.x_md, out.x);
  }
  if (want_w || want_bias) {
    out.w = Tensor::empty({g.O, g.C, g.kh, g.kw}, DType::F32);
    const memory gy_w = p.bwd_weights_pd.diff_dst_desc() == gy_m.get_desc()
                            ? gy_m
                            : input_as(p.bwd_weights_pd.diff_dst_desc(), p.y_md, gy, kGx);
    const memory gw = output_as(p.bwd_weights_pd.diff_weights_desc(), p.w_plain_md, out.w, kGw);
    std::unordered_map<int, memory> args{
        {DNNL_ARG_SRC, input_as(p.bwd_weights_pd.src_desc(), p.x_md, x, kX)},
        {DNNL_ARG_DIFF_DST, gy_w},
        {DNNL_ARG_DIFF_WEIGHTS, gw}};
    if (want_bias) {
      out.bias = Tensor::empty({g.O}, DType::F32);
      args.emplace(DNNL_ARG_DIFF_BIAS, wrap(p.b_md, out.bias));
    }
    p.bwd_weights.execute(s, args);
    finish_output(gw, p.w_plain_md, out.w);
    if (!want_w) out.w = Tensor();
  }
  s.wait();
  return out;
}

}  // namespace weft
