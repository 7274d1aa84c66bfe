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
  return backend == ConvBackend::eigen ? "eigen" : "onednn";
}

ConvBackend parse_conv_backend(const std::string& name, const std::string& where) {
  if (name == "eigen") return ConvBackend::eigen;
  if (name == "onednn") return ConvBackend::onednn;
  fail(where, ": unknown convolution backend '", name, "' (expected eigen or onednn)");
}

int64_t preferred_channel_block() { return conv_backend() == ConvBackend::onednn ? 16 : 1; }

}  // namespace weft
