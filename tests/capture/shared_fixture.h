#pragma once
// Folders several test processes share. ctest runs every test in a process of its own, so
// a dataset or training run that many tests read would otherwise be remade by each. A
// shared fixture is made once per build of the test program, under the build tree
// (WEFT_BINARY_DIR/test_fixtures/<name>_<program>), behind a file lock; a stamp with the
// program's modification time remakes it after a rebuild. Tests only read it.
#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <string>

#include "capture/studio/synthetic_studio.h"
#include "capture/training/trainer.h"
#include "tests/capture/test_files.h"

namespace weft::capture::testing {

inline std::filesystem::path shared_fixture(const std::string& name,
                                            const std::function<void(const std::filesystem::path&)>& make) {
  namespace fs = std::filesystem;
  const fs::path exe = fs::read_symlink("/proc/self/exe");
  const fs::path root = fs::path(WEFT_BINARY_DIR) / "test_fixtures";
  fs::create_directories(root);
  const fs::path dir = root / (name + "_" + exe.filename().string());
  const int lock = ::open((dir.string() + ".lock").c_str(), O_CREAT | O_RDWR, 0644);
  if (lock < 0 || ::flock(lock, LOCK_EX) != 0) throw weft::Error("cannot lock " + dir.string() + ".lock");
  struct Unlock {
    int fd;
    ~Unlock() { ::flock(fd, LOCK_UN), ::close(fd); }
  } unlock{lock};
  std::ostringstream stamp;
  stamp << exe.string() << " " << fs::last_write_time(exe).time_since_epoch().count() << "\n";
  const fs::path marker = dir / ".weft_fixture";
  if (fs::exists(marker) && slurp(marker) == stamp.str()) return dir;
  fs::remove_all(dir);
  fs::create_directories(dir);
  make(dir);
  std::ofstream(marker, std::ios::binary) << stamp.str();
  return dir;
}

// A scratch folder of this test process under the system temp dir, made on first use and
// removed when the process exits.
inline std::filesystem::path process_scratch(const std::string& tag) {
  namespace fs = std::filesystem;
  static std::map<std::string, fs::path> made;
  static struct Cleanup {
    ~Cleanup() {
      std::error_code ec;
      for (const auto& [t, dir] : made) fs::remove_all(dir, ec);
    }
  } cleanup;
  auto it = made.find(tag);
  if (it == made.end()) {
    const fs::path dir = fs::temp_directory_path() / ("weft_" + tag + "_test_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    it = made.emplace(tag, dir).first;
  }
  return it->second;
}

// The tiny dataset (configs/synth/tiny.yaml).
inline std::filesystem::path tiny_dataset() {
  return shared_fixture("tiny", [](const std::filesystem::path& dir) {
    synthesize_dataset(load_synth_config(repo_file("configs/synth/tiny.yaml")), dir.string());
  });
}

// An uninterrupted run of configs/train/tiny.yaml on tiny_dataset() (a model folder),
// with what its TrainSummary said in summary.txt: simulation windows, failures, the last
// validation's samples and silhouette IoU.
inline std::filesystem::path tiny_reference_run() {
  const std::filesystem::path data = tiny_dataset();
  return shared_fixture("tiny_reference_run", [&](const std::filesystem::path& dir) {
    TrainOptions o;
    o.config = repo_file("configs/train/tiny.yaml");
    o.data = data.string();
    o.run = dir.string();
    const TrainSummary s = train(o);
    std::ofstream(dir / "summary.txt") << s.simulation_windows << " " << s.simulation_failures << " "
                                       << s.last_validation.samples << " " << s.last_validation.silhouette_iou << "\n";
  });
}

}  // namespace weft::capture::testing
