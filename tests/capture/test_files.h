#pragma once
// Helpers for the capture tests: a scratch folder per test and small valid files.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "graph/error.h"
#include "tests/test_requirements.h"

namespace weft::capture::testing {

// The MakeHuman body of Debian's assimp-testmodels, which the generated character needs.
inline constexpr const char* kHuman = "/usr/share/assimp/models/Collada/human.zae";

// A file of the source tree (configs, data), from the test's build definitions.
inline std::string repo_file(const std::string& rel) { return std::string(WEFT_SOURCE_DIR) + "/" + rel; }

// Fails a test that needs kHuman when the package is not installed.
#define REQUIRE_HUMAN() REQUIRE_DEBIAN_FILE(::weft::capture::testing::kHuman, "assimp-testmodels")

// A fresh folder under the system temp dir, removed when the object dies.
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& tag) {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = std::filesystem::temp_directory_path() /
            ("weft_capture_" + tag + "_" + (info ? std::string(info->name()) : "x") + "_" +
             std::to_string(::getpid()));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  std::string file(const std::string& name) const { return (path_ / name).string(); }
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(file(name), std::ios::binary) << text;
    return file(name);
  }

 private:
  std::filesystem::path path_;
};

// The bytes of a file ("" when it cannot be read).
inline std::string slurp(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Expects `fn` to throw weft::Error whose message contains every one of `parts`.
template <class Fn>
void expect_error(Fn&& fn, std::initializer_list<std::string> parts) {
  try {
    fn();
    ADD_FAILURE() << "expected a weft::Error";
  } catch (const weft::Error& e) {
    const std::string msg = e.what();
    for (const auto& p : parts) EXPECT_NE(msg.find(p), std::string::npos) << "message: " << msg << "\nmissing: " << p;
  }
}

// A 4-joint skeleton in Skeletool form: root translation (weight 1000), a revolute
// chain and a marker; CRLF line ends as in real files.
inline std::string small_skeleton_text() {
  return "Skeletool Skeleton Definition V1.0\r\n"
         "joints: 4\r\n"
         "  root_tx   prismatic none     0 0 0   1 0 0  1.0\r\n"
         "  hip_rz    revolute  root_tx  0 1 0   0 0 1  1.0\r\n"
         "  knee_rz   revolute  hip_rz   0 -2 0  0 0 2  1.0\r\n"
         "  foot      revolute  knee_rz  0 -3 0  1 0 0  0.5\r\n"
         "markers: 1\r\n"
         "  toe  knee_rz  point  0.5 -4 0  0.1  1 0 0\r\n"
         "scaling joints: 0\r\n"
         "dofs: 3\r\n"
         "  tx 1\r\n"
         "      nolimits\r\n"
         "      root_tx 1000\r\n"
         "  bend 2\r\n"
         "      limits -1 1\r\n"
         "      hip_rz 1\r\n"
         "      knee_rz 0.5\r\n"
         "  knee 1\r\n"
         "      nolimits\r\n"
         "      knee_rz 1\r\n";
}

}  // namespace weft::capture::testing
