#include "graph/atomic_file.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "graph/error.h"

namespace weft {
namespace {

namespace fs = std::filesystem;

class AtomicFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("weft_atomic_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
            "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  int entries() const {
    int n = 0;
    for (const auto& e : fs::directory_iterator(dir_)) n += static_cast<int>(e.exists());
    return n;
  }
  static std::string read(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }
  fs::path dir_;
};

TEST_F(AtomicFileTest, ReplacesTheTargetAndLeavesNoTemporary) {
  const fs::path p = dir_ / "a.txt";
  write_text_atomically(p.string(), "first");
  write_text_atomically(p.string(), "second, longer");
  EXPECT_EQ(read(p), "second, longer");
  EXPECT_EQ(entries(), 1);
}

TEST_F(AtomicFileTest, AFailedWriteKeepsTheOldFileAndRemovesTheTemporary) {
  const fs::path p = dir_ / "b.txt";
  write_text_atomically(p.string(), "old");
  EXPECT_THROW(write_file_atomically(p.string(),
                                     [](std::ostream& out) {
                                       out << "half of the new";
                                       fail("the writer gave up");
                                     }),
               Error);
  EXPECT_EQ(read(p), "old");
  EXPECT_EQ(entries(), 1);
}

TEST_F(AtomicFileTest, AMissingFolderIsAnErrorNamingThePath) {
  const std::string p = (dir_ / "no" / "such" / "c.txt").string();
  try {
    write_text_atomically(p, "x");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace weft
