// The generated character's look from its config: keys, colours, and what a typo gets.
#include <gtest/gtest.h>

#include "capture/character/default_character.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
using weft::capture::testing::expect_error;

TEST(AppearanceConfig, ReadsTexturedAndColours) {
  const DefaultCharacterConfig off = parse_default_character_config("name: x\n", "/cfg/a.yaml");
  EXPECT_FALSE(off.appearance.textured);  // no section: flat colours, as before
  const DefaultCharacterConfig c = parse_default_character_config(
      "appearance: {textured: true, shirt: [0.1, 0.2, 0.3], left_shoe: [1, 0, 0]}\n", "/cfg/a.yaml");
  EXPECT_TRUE(c.appearance.textured);
  EXPECT_EQ(c.appearance.shirt, Eigen::Vector3d(0.1, 0.2, 0.3));
  EXPECT_EQ(c.appearance.left_shoe, Eigen::Vector3d(1, 0, 0));
  EXPECT_EQ(c.appearance.hair, AppearanceConfig().hair);  // the rest keep their defaults
}

TEST(AppearanceConfig, BadKeysAndColoursNameKeyLineAndFile) {
  expect_error([] { parse_default_character_config("appearance: {textured: true, hat: [1, 0, 0]}\n", "a.yaml"); },
               {"a.yaml", "appearance.hat", "unknown key"});
  expect_error([] { parse_default_character_config("name: x\nappearance:\n  shirt: [0.1, 2, 0.3]\n", "b.yaml"); },
               {"b.yaml:3", "appearance.shirt", "[0, 1]"});
  expect_error([] { parse_default_character_config("appearance: {shirt: blue}\n", "c.yaml"); },
               {"c.yaml", "appearance.shirt", "[r, g, b]"});
  expect_error([] { parse_default_character_config("appearance: {textured: maybe}\n", "d.yaml"); },
               {"d.yaml", "appearance.textured", "true or false"});
  expect_error([] { parse_default_character_config("appearance: true\n", "e.yaml"); }, {"e.yaml", "appearance"});
}
