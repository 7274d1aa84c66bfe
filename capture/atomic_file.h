#pragma once
// Atomic file output: write to a temporary file beside the target, then rename, so a
// crash or error never leaves a half-written file under the final name.
#include <functional>
#include <ostream>
#include <string>

namespace weft::capture {

// Calls `write` with a binary stream on a temporary file in the target's folder and
// renames it to `path` on success; on any failure the temporary is removed and a
// weft::Error naming `path` is thrown (exceptions from `write` propagate).
void write_file_atomically(const std::string& path,
                           const std::function<void(std::ostream&)>& write);

// Same, for bytes already in memory (e.g. an encoded PNG).
void write_bytes_atomically(const std::string& path, const void* data, size_t size);

}  // namespace weft::capture
