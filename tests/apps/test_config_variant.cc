// `--config SOURCE,KEY=VALUE,...` (config_variant.h): the split at commas outside a YAML list,
// the overrides applied as `--set` applies them, the variant's own name, and bad input naming
// the option and the key.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "config_variant.h"
#include "skerry/core/input_error.h"

namespace skerry::cli {
namespace {

TEST(ConfigVariant, SplitsAtCommasOutsideAYamlList) {
  const ConfigVariant v = ParseConfigVariant(
      "default,lidar_aerial.hull_min_b_m=[-1, -2, 0],solver.max_iterations=5", "--config");
  EXPECT_EQ(v.source, "default");
  ASSERT_EQ(v.overrides.size(), 2u);
  EXPECT_EQ(v.overrides[0], "lidar_aerial.hull_min_b_m=[-1, -2, 0]");
  EXPECT_EQ(v.overrides[1], "solver.max_iterations=5");
  EXPECT_TRUE(ParseConfigVariant("default", "--config").overrides.empty());
}

TEST(ConfigVariant, AFileWithACommaInItsNameIsThatFile) {
  const std::string path = testing::TempDir() + "/a,b.yaml";
  std::ofstream(path) << "name: ab\nwindow_keyframes: 7\n";
  const ConfigVariant v = ParseConfigVariant(path, "--config");
  EXPECT_EQ(v.source, path);
  EXPECT_TRUE(v.overrides.empty());
  EXPECT_EQ(LoadConfigVariant(path, "--config").window_keyframes, 7);
  std::filesystem::remove(path);
}

TEST(ConfigVariant, OverridesApplyAndNameTheVariant) {
  const EstimatorConfig plain = LoadConfigVariant("default", "--config");
  EXPECT_EQ(plain.name, "default");
  const EstimatorConfig v = LoadConfigVariant(
      "default,skyline.dem_sharpening_sigma=1,lidar_aerial.hull_min_b_m=[-1, -2, 0]", "--config");
  EXPECT_EQ(v.skyline.dem_sharpening_sigma, 1.0);
  EXPECT_EQ(v.lidar_aerial.hull_min_b_m, (std::vector<double>{-1.0, -2.0, 0.0}));
  // Characters a folder name cannot hold become '_'.
  EXPECT_EQ(v.name, "default-dem_sharpening_sigma-1-hull_min_b_m-_-1__-2__0_");
  // Everything else is the preset's.
  EXPECT_EQ(v.window_keyframes, plain.window_keyframes);
  EXPECT_EQ(v.ceres.max_iterations, plain.ceres.max_iterations);
  // A name given is kept.
  EXPECT_EQ(LoadConfigVariant("default,name=gain,skyline.dem_sharpening_sigma=1", "--config").name,
            "gain");
}

TEST(ConfigVariant, BadInputNamesTheOptionAndTheKey) {
  for (const char* bad : {",solver.max_iterations=5", "default,", "default,,x=1"}) {
    try {
      ParseConfigVariant(bad, "--config");
      ADD_FAILURE() << bad << " accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), "--config") << bad;
      EXPECT_NE(e.message().find("empty part"), std::string::npos) << e.what();
    }
  }
  try {
    LoadConfigVariant("default,solver.max_iterations=many", "--config");
    ADD_FAILURE() << "a word for a number accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), kCommandLine);
    EXPECT_EQ(e.field(), "--config solver.max_iterations") << e.what();
  }
  try {
    LoadConfigVariant("default,solver.max_iterations", "--config");
    ADD_FAILURE() << "an override without '=' accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("KEY=VALUE"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace skerry::cli
