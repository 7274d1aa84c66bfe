#pragma once
// The capture layer's file writers use the engine's atomic writes (graph/atomic_file.h).
#include "graph/atomic_file.h"

namespace weft::capture {
using weft::write_bytes_atomically;
using weft::write_file_atomically;
}  // namespace weft::capture
