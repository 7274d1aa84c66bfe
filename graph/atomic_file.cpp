#include "graph/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>

#include "graph/error.h"

namespace weft {

namespace {

// Unique per process and call, in the target's folder (rename must not cross devices),
// hidden so that a folder listing during the write shows only finished files.
std::string temporary_name(const std::string& path) {
  static std::atomic<unsigned> counter{0};
  const std::filesystem::path target(path);
  return (target.parent_path() / ("." + target.filename().string() + ".tmp." +
                                  std::to_string(::getpid()) + "." + std::to_string(counter++)))
      .string();
}

// fsync of a file or folder by name; failures of the folder sync are ignored (some
// filesystems refuse it), those of the file are errors.
bool sync_path(const std::string& p, int flags) {
  const int fd = ::open(p.c_str(), flags);
  if (fd < 0) return false;
  const bool ok = ::fsync(fd) == 0;
  ::close(fd);
  return ok;
}

}  // namespace

void write_file_atomically(const std::string& path,
                           const std::function<void(std::ostream&)>& write) {
  const std::string tmp = temporary_name(path);
  try {
    {
      std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
      if (!out) fail(path, ": cannot open a temporary file for writing beside it");
      write(out);
      out.flush();
      if (!out) fail(path, ": write error (disk full?)");
    }
    if (!sync_path(tmp, O_RDONLY)) fail(path, ": cannot flush the temporary file to disk");
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec) fail(path, ": cannot rename the temporary file into place: ", ec.message());
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
    throw;
  }
  const std::filesystem::path dir = std::filesystem::path(path).parent_path();
  sync_path(dir.empty() ? "." : dir.string(), O_RDONLY | O_DIRECTORY);  // the rename itself
}

void write_bytes_atomically(const std::string& path, const void* data, size_t size) {
  write_file_atomically(path, [&](std::ostream& out) {
    out.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
  });
}

}  // namespace weft
