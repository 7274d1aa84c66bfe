#include "nn/safetensors.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "graph/error.h"

namespace weft::nn {
namespace {

namespace fs = std::filesystem;

class SafetensorsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("weft_safetensors_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  // Writes a file made of an explicit header and data section.
  std::string write_raw(const std::string& name, const std::string& header,
                        const std::string& data, int64_t length_override = -1) {
    const std::string p = path(name);
    std::ofstream out(p, std::ios::binary);
    const uint64_t n = length_override >= 0 ? static_cast<uint64_t>(length_override) : header.size();
    for (int i = 0; i < 8; ++i) out.put(static_cast<char>((n >> (8 * i)) & 0xff));
    out << header << data;
    return p;
  }

  // Expects load_safetensors to throw an Error whose message holds every `parts`.
  void expect_error(const std::string& p, const std::vector<std::string>& parts) {
    try {
      load_safetensors(p);
      ADD_FAILURE() << "no error for " << p;
    } catch (const Error& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(p), std::string::npos) << msg;
      for (const std::string& part : parts)
        EXPECT_NE(msg.find(part), std::string::npos) << "'" << part << "' not in: " << msg;
    }
  }

  fs::path dir_;
};

std::string floats(std::initializer_list<float> v) {
  std::string s(v.size() * 4, '\0');
  std::memcpy(s.data(), std::data(v), s.size());
  return s;
}

TEST_F(SafetensorsTest, RoundTripsEveryDtypeShapeAndMetadata) {
  TensorMap in;
  in["a.weight"] = Tensor::from_data({2, 3}, std::vector<double>{1, -2, 3.5, 4, 5, 6e-8});
  in["b"] = Tensor::from_data({3}, std::vector<double>{1.0 / 3, -1e300, 7}, DType::F64);
  in["count"] = Tensor::from_indices({}, {-9223372036854775807LL});
  in["empty"] = Tensor::zeros({0, 4});
  const Metadata meta{{"format", "pt"}, {"note", "quotes \" and \\ survive"}};
  const std::string p = path("rt.safetensors");
  save_safetensors(p, in, meta);

  const SafetensorsFile f = load_safetensors(p);
  EXPECT_EQ(f.metadata, meta);
  ASSERT_EQ(f.tensors.size(), in.size());
  for (const auto& [name, t] : in) {
    const Tensor& u = require_tensor(f, p, name);
    EXPECT_EQ(u.dtype(), t.dtype()) << name;
    EXPECT_EQ(u.shape(), t.shape()) << name;
    EXPECT_EQ(0, std::memcmp(u.raw_data(), t.raw_data(), t.nbytes())) << name;
  }
  // No temporary file is left beside the target.
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir_)) files += e.is_regular_file();
  EXPECT_EQ(files, 1);
}

TEST_F(SafetensorsTest, WritesTheSpecifiedLayout) {
  TensorMap in;
  in["x"] = Tensor::from_data({2}, std::vector<float>{1.5f, -2.0f});
  const std::string p = path("layout.safetensors");
  save_safetensors(p, in);
  std::ifstream f(p, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  uint64_t n = 0;
  for (int i = 7; i >= 0; --i) n = (n << 8) | static_cast<unsigned char>(bytes[i]);
  EXPECT_EQ(n % 8, 0u);  // data section 8-byte aligned
  ASSERT_EQ(bytes.size(), 8 + n + 8);
  const std::string header = bytes.substr(8, n);
  EXPECT_NE(header.find("\"dtype\":\"F32\""), std::string::npos) << header;
  EXPECT_NE(header.find("\"shape\":[2]"), std::string::npos) << header;
  EXPECT_NE(header.find("\"data_offsets\":[0,8]"), std::string::npos) << header;
  EXPECT_EQ(bytes.substr(8 + n), floats({1.5f, -2.0f}));
}

TEST_F(SafetensorsTest, ReadsAHandWrittenFileWithPaddingAndMetadata) {
  // As another writer may produce it: keys in any order, spaces after the JSON.
  const std::string header =
      R"({"__metadata__":{"format":"pt"},"w":{"dtype":"F32","shape":[1,2],"data_offsets":[4,12]},)"
      R"("s":{"dtype":"F32","shape":[],"data_offsets":[0,4]}}    )";
  const std::string p = write_raw("hand.safetensors", header, floats({9.0f, 1.0f, 2.0f}));
  const SafetensorsFile f = load_safetensors(p);
  EXPECT_EQ(f.metadata.at("format"), "pt");
  EXPECT_EQ(require_tensor(f, p, "s").item(), 9.0);
  EXPECT_EQ(require_tensor(f, p, "w").to_vector(), (std::vector<double>{1, 2}));
  EXPECT_EQ(require_tensor(f, p, "w").shape(), (Shape{1, 2}));
  try {
    require_tensor(f, p, "missing.weight");
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("missing.weight"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find(p), std::string::npos);
  }
}

TEST_F(SafetensorsTest, RejectsTruncatedAndCorruptFiles) {
  const std::string ok = R"({"w":{"dtype":"F32","shape":[2],"data_offsets":[0,8]}})";
  const std::string data = floats({1.0f, 2.0f});
  expect_error(write_raw("empty_header.st", "", ""), {"not valid JSON"});
  {  // fewer than 8 bytes
    std::ofstream(path("tiny.st"), std::ios::binary) << "abc";
    expect_error(path("tiny.st"), {"too short"});
  }
  expect_error(write_raw("trunc_header.st", ok.substr(0, 20), "", ok.size()), {"exceeds"});
  expect_error(write_raw("trunc_data.st", ok, data.substr(0, 6)), {"'w'", "run past"});
  expect_error(write_raw("json.st", "{\"w\": [1,", data), {"not valid JSON"});
  expect_error(write_raw("huge.st", ok, data, int64_t(1) << 40), {"implausible"});
  expect_error(write_raw("trailing.st", ok, data + "xx"), {"cover"});
  expect_error(write_raw("dtype.st", R"({"w":{"dtype":"BF16","shape":[2],"data_offsets":[0,4]}})",
                         data.substr(0, 4)),
               {"'w'", "BF16"});
  expect_error(write_raw("shape.st", R"({"w":{"dtype":"F32","shape":[3],"data_offsets":[0,8]}})",
                         data),
               {"'w'", "needs 12"});
  expect_error(write_raw("neg.st", R"({"w":{"dtype":"F32","shape":[-2],"data_offsets":[0,8]}})",
                         data),
               {"'w'", "shape"});
  expect_error(write_raw("rev.st", R"({"w":{"dtype":"F32","shape":[0],"data_offsets":[8,0]}})",
                         data),
               {"'w'", "reversed"});
  expect_error(write_raw("overlap.st",
                         R"({"a":{"dtype":"F32","shape":[2],"data_offsets":[0,8]},)"
                         R"("b":{"dtype":"F32","shape":[1],"data_offsets":[4,8]}})",
                         data),
               {"overlaps"});
  expect_error(write_raw("hole.st", R"({"a":{"dtype":"F32","shape":[1],"data_offsets":[4,8]}})",
                         data),
               {"belong to no tensor", "'a'"});
  expect_error(write_raw("meta.st", R"({"__metadata__":{"k":3}})", ""), {"'k'"});
  expect_error(path("does_not_exist.st"), {"cannot open"});
}

TEST_F(SafetensorsTest, FailedWriteLeavesNothingBehind) {
  TensorMap in;
  in["x"] = Tensor::ones({2});
  EXPECT_THROW(save_safetensors(path("no/such/dir/x.safetensors"), in), Error);
  EXPECT_THROW(save_safetensors(path("bad.safetensors"), {{"__metadata__", Tensor::ones({1})}}),
               Error);
  EXPECT_TRUE(fs::is_empty(dir_));
  // Overwriting replaces the file whole.
  save_safetensors(path("x.safetensors"), in);
  in["x"] = Tensor::full({3}, 2.0);
  save_safetensors(path("x.safetensors"), in);
  EXPECT_EQ(load_safetensors(path("x.safetensors")).tensors.at("x").to_vector(),
            (std::vector<double>{2, 2, 2}));
}

}  // namespace
}  // namespace weft::nn
