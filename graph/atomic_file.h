#pragma once
// Atomic, durable file output for every layer: the bytes go to a temporary file beside
// the target, are flushed to disk (fsync), and the temporary is renamed over the target,
// so a crash or an error never leaves a half-written file under the final name.
#include <cstddef>
#include <functional>
#include <ostream>
#include <string>

namespace weft {

// Calls `write` with a binary stream on a temporary file in the target's folder and
// renames it to `path` on success; on any failure the temporary is removed and a
// weft::Error naming `path` is thrown (exceptions from `write` propagate).
void write_file_atomically(const std::string& path,
                           const std::function<void(std::ostream&)>& write);
// Same, for bytes already in memory (e.g. an encoded PNG or a text).
void write_bytes_atomically(const std::string& path, const void* data, size_t size);
inline void write_text_atomically(const std::string& path, const std::string& text) {
  write_bytes_atomically(path, text.data(), text.size());
}

}  // namespace weft
