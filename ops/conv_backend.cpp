#include "ops/conv_backend.h"

#include <atomic>
#include <cstdlib>

#include "graph/error.h"

namespace weft {

namespace {

ConvBackend initial_backend() {
  if (const char* env = std::getenv("WEFT_CONV_BACKEND"); env && *env)
    return parse_conv_backend(env, "WEFT_CONV_BACKEND");
  return ConvBackend::onednn;
}

std::atomic<ConvBackend>& current() {
  static std::atomic<ConvBackend> backend{initial_backend()};
  return backend;
}

}  // namespace

ConvBackend conv_backend() { return current().load(std::memory_order_relaxed); }

void set_conv_backend(ConvBackend backend) { current().store(backend); }

const char* conv_backend_name(ConvBackend backend) {
  switch (backend) {
    case ConvBackend::eigen: return "eigen";
    case ConvBackend::onednn: return "onednn";
    case ConvBackend::onednn_winograd: return "onednn-winograd";
  }
  return "?";
}

ConvBackend parse_conv_backend(const std::string& name, const std::string& where) {
  if (name == "eigen") return ConvBackend::eigen;
  if (name == "onednn") return ConvBackend::onednn;
  if (name == "onednn-winograd") return ConvBackend::onednn_winograd;
  fail(where, ": unknown convolution backend '", name,
       "' (expected eigen, onednn or onednn-winograd)");
}

int64_t preferred_channel_block() { return conv_backend() == ConvBackend::eigen ? 1 : 16; }

}  // namespace weft
