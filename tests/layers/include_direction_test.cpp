// Dependencies point down (docs/DESIGN.md, "Layers and their rules"): every source file of
// a layer includes only its own layer and the layers this table lets it include. A new
// include across layers fails here until the table (and DESIGN.md's) says it may.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

// Layer → the other layers it may include. capture/ is one layer per sub-folder.
const std::map<std::string, std::set<std::string>>& may_include() {
  static const std::set<std::string> floor = {"graph", "files", "geometry"};
  auto with_floor = [&](std::set<std::string> s) {
    s.insert(floor.begin(), floor.end());
    return s;
  };
  static const std::map<std::string, std::set<std::string>> table = {
      {"graph", {}},
      {"files", {"graph"}},
      {"geometry", {"files", "graph"}},
      {"ops", {"graph"}},
      {"nn", {"ops", "graph"}},
      {"physics", with_floor({})},
      {"capture/io", with_floor({})},
      {"capture/render", with_floor({"capture/io"})},
      {"capture/plots", with_floor({"capture/io"})},
      {"capture/character", with_floor({"capture/io"})},
      {"capture/motion", with_floor({"capture/character", "capture/io"})},
      {"capture/deformation", with_floor({"capture/character", "capture/io", "ops"})},
      {"capture/dataset", with_floor({"capture/io", "capture/render"})},
      {"capture/detection", with_floor({"capture/dataset", "capture/io", "nn", "ops"})},
      {"capture/model", with_floor({"capture/garment", "capture/deformation", "capture/dataset", "capture/detection", "capture/character",
                                    "capture/io", "nn", "ops"})},
      {"capture/garment", with_floor({"capture/character", "capture/dataset", "capture/io", "physics"})},
      {"capture/studio", with_floor({"capture/garment", "capture/character", "capture/motion", "capture/dataset",
                                     "capture/render", "capture/io", "physics"})},
      {"capture/evaluation", with_floor({"capture/model", "capture/garment", "capture/dataset", "capture/character",
                                         "capture/render", "capture/plots", "capture/io", "physics"})},
      {"capture/inference", with_floor({"capture/model", "capture/garment", "capture/dataset", "capture/detection", "capture/character",
                                        "capture/motion", "capture/render", "capture/io", "nn"})},
      {"capture/training",
       with_floor({"capture/model", "capture/studio", "capture/garment", "capture/evaluation", "capture/deformation",
                   "capture/dataset", "capture/detection", "capture/character", "capture/motion", "capture/render", "capture/plots",
                   "capture/io", "nn", "ops", "physics"})},
      {"capture/adaptation", with_floor({"capture/training", "capture/inference", "capture/model", "capture/dataset",
                                         "capture/io"})},
  };
  return table;
}

// The layer of an include path ("capture/io/camera.h" → "capture/io", "graph/error.h" →
// "graph"), or "" for a path outside the layers (a third-party header in quotes).
std::string layer_of(const std::string& include) {
  const size_t a = include.find('/');
  if (a == std::string::npos) return "";
  const std::string top = include.substr(0, a);
  if (top == "capture") {
    const size_t b = include.find('/', a + 1);
    return b == std::string::npos ? "" : include.substr(0, b);
  }
  return top;
}

TEST(IncludeDirection, EveryLayerIncludesOnlyTheLayersBelowIt) {
  const fs::path root = WEFT_SOURCE_DIR;
  const std::regex include_line(R"re(^\s*#\s*include\s*"([^"]+)")re");
  int files = 0;
  for (const auto& [layer, allowed] : may_include()) {
    ASSERT_TRUE(fs::is_directory(root / layer)) << layer;
    for (const auto& entry : fs::directory_iterator(root / layer)) {
      const std::string ext = entry.path().extension().string();
      if (ext != ".h" && ext != ".cpp") continue;
      ++files;
      std::ifstream in(entry.path());
      std::string line;
      int number = 0;
      while (std::getline(in, line)) {
        ++number;
        std::smatch m;
        if (!std::regex_search(line, m, include_line)) continue;
        const std::string other = layer_of(m[1].str());
        if (other.empty() || other == layer) continue;
        EXPECT_TRUE(allowed.count(other)) << entry.path().string() << ":" << number << ": " << layer
                                          << " includes " << m[1] << " (layer " << other
                                          << "), which it may not (docs/DESIGN.md)";
      }
    }
  }
  EXPECT_GT(files, 100);
}

// Every folder with sources under capture/ is in the table (a new one must say where it sits).
TEST(IncludeDirection, EveryCaptureFolderIsALayerOfTheTable) {
  const fs::path root = fs::path(WEFT_SOURCE_DIR) / "capture";
  for (const auto& entry : fs::directory_iterator(root))
    if (entry.is_directory())
      EXPECT_TRUE(may_include().count("capture/" + entry.path().filename().string()))
          << entry.path().string() << " is not in the table of layers";
}

}  // namespace
