#pragma once
// What a test needs from outside the repository. Each is installed by scripts/setup.sh (a
// Debian package) or laid beside the clone (../shared/data); a test that finds one missing
// fails with a message naming what is missing and how to get it, instead of skipping
// quietly: a suite that skips on a fresh machine hides a missing install step.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace weft::testing {

// The ddc subject (Skeletool character, skin, 300 frames of motion), laid beside the
// clone as ../shared/data/ddc; its README gives the licence.
inline const std::string kDdcDir = std::string(WEFT_SOURCE_DIR) + "/../shared/data/ddc";

// Debian's assimp-testmodels: the MakeHuman body and the CMU clips.
inline constexpr const char* kAssimpModels = "/usr/share/assimp/models";

}  // namespace weft::testing

// Fails the test (and returns from it) when `path` is missing, naming the Debian package
// that provides it.
#define REQUIRE_DEBIAN_FILE(path, package)                                                          \
  if (!std::filesystem::exists(path))                                                               \
  GTEST_FAIL() << (path) << " is missing: it comes with Debian's " << (package)                     \
               << "; install it with scripts/setup.sh (or apt-get install " << (package) << ")"

// Fails the test when the ddc subject is not beside the clone.
#define REQUIRE_DDC_DATA()                                                                           \
  if (!std::filesystem::exists(::weft::testing::kDdcDir + "/ddc.skeleton"))                          \
  GTEST_FAIL() << "the ddc subject is missing: " << ::weft::testing::kDdcDir                         \
               << "/ddc.skeleton not found; the tests read it from ../shared/data/ddc beside the clone " \
                  "(its README gives the files and their licence)"
