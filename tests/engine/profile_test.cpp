#include <gtest/gtest.h>

#include "engine/profile.hpp"
#include "io/error.hpp"

namespace topotrack {
namespace {

TEST(Profile, DefaultFileMatchesCodeDefaults) {
  // profiles/default.json states the paper's values; the structs carry them too. They must agree.
  EXPECT_EQ(to_json(load_profile("default")), to_json(TrackerParams{}));
}

TEST(Profile, PaperValues) {
  const TrackerParams p = load_profile("default");
  EXPECT_EQ(p.improve.ratio, 4);
  EXPECT_EQ(p.improve.min_angle_deg, 10);
  EXPECT_EQ(p.improve.min_dihedral_deg, 45);
  EXPECT_EQ(p.coarse_params.node_spacing_factor, 4);
  EXPECT_EQ(p.coarse_params.k, 4);
  EXPECT_EQ(p.coarse_params.alpha_point, 0.1);
  EXPECT_EQ(p.coarse_params.alpha_plane, 1.0);
  EXPECT_EQ(p.coarse_params.alpha_fit, 0.1);
  EXPECT_EQ(p.coarse_params.alpha_reg_start, 1000);
  EXPECT_EQ(p.coarse_params.max_normal_angle_deg, 60);
  EXPECT_EQ(p.coarse_params.max_closest_ratio, 3);
  EXPECT_EQ(p.fine_params.sigma, 0.1);
}

TEST(Profile, EveryBundledProfileLoads) {
  const auto names = profile_names();
  for (const char* n : {"default", "fluid", "morph", "capture", "preview"})
    EXPECT_NE(std::find(names.begin(), names.end(), n), names.end()) << n;
  for (const auto& n : names) EXPECT_NO_THROW(load_profile(n)) << n;
  EXPECT_EQ(load_profile("preview").coarse_params.graph_density, 0.25);
  EXPECT_EQ(load_profile("capture").coarse_params.alpha_reg_start, 1000);  // the paper's (10000 drifted more)
  // A denser graph for squashing bodies (tests/kernels/registration/coarse_drift_test.cpp).
  EXPECT_EQ(load_profile("capture").coarse_params.node_spacing_factor, 2);
  EXPECT_EQ(load_profile("capture").coarse_params.max_iterations_per_level_after_pass, 8);  // 3 drifted more
  // Voxels half an edge length keep parts one edge length thick (tests/engine/tracker_real_data_test.cpp).
  EXPECT_EQ(load_profile("capture").voxel_size_factor, 0.5);
  EXPECT_EQ(load_profile("default").voxel_size_factor, 1.0);  // the paper's
  // A finer lattice where the topology differs (tests/engine/tracker_test.cpp); the paper has one lattice.
  EXPECT_EQ(load_profile("capture").topology_refinements, 2);
  EXPECT_EQ(load_profile("fluid").topology_refinements, 1);
  // The lattice on the grid a capture was extracted on, where there is one (tracker_real_data_test.cpp).
  EXPECT_TRUE(load_profile("capture").extraction_grid);
  EXPECT_FALSE(load_profile("default").extraction_grid);
  EXPECT_FALSE(load_profile("fluid").extraction_grid);
  EXPECT_EQ(load_profile("default").topology_refinements, 0);
  EXPECT_EQ(load_profile("default").coarse_params.max_iterations_per_level_after_pass, 3);
  EXPECT_EQ(load_profile("default").coarse_params.node_spacing_factor, 4);  // the paper's
}

TEST(Profile, UnknownNamesAndBadValuesAreRejected) {
  TrackerParams p;
  EXPECT_THROW(apply_profile(p, nlohmann::json{{"coarse", {{"alpha_nope", 1}}}}, "x.json"), InvalidInput);
  EXPECT_THROW(apply_profile(p, nlohmann::json{{"coarse", {{"k", "four"}}}}, "x.json"), InvalidInput);
  EXPECT_THROW(apply_profile(p, nlohmann::json{{"coarse", {{"k", 2.5}}}}, "x.json"), InvalidInput);
  EXPECT_THROW(apply_profile(p, nlohmann::json{{"improve", {{"min_angle_deg", -1}}}}, "x.json"), InvalidInput);
  EXPECT_THROW(apply_profile(p, nlohmann::json::array(), "x.json"), InvalidInput);
  EXPECT_THROW(load_profile("no-such-profile"), UsageError);
  try {
    apply_profile(p, nlohmann::json{{"fine", {{"sigma", "a"}}}}, "my.json");
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("my.json"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("fine.sigma"), std::string::npos);
  }
}

TEST(Profile, CommandLineSettings) {
  TrackerParams p;
  apply_setting(p, "coarse.alpha_reg_start=100");
  apply_setting(p, "tracker.topology=false");
  apply_setting(p, "voxel_size_factor=0.5");  // tracker.* may omit the section
  EXPECT_EQ(p.coarse_params.alpha_reg_start, 100);
  EXPECT_FALSE(p.topology);
  EXPECT_EQ(p.voxel_size_factor, 0.5);
  EXPECT_THROW(apply_setting(p, "coarse.alpha_reg_start"), UsageError);
  EXPECT_THROW(apply_setting(p, "coarse.alpha_reg_start=abc"), UsageError);
  EXPECT_THROW(apply_setting(p, "nope=1"), UsageError);
  EXPECT_THROW(apply_setting(p, "coarse.k=0"), UsageError);
}

TEST(Profile, JsonRoundTrip) {
  TrackerParams p;
  apply_setting(p, "fine.sigma=0.05");
  apply_setting(p, "improve.enable_flips=false");
  TrackerParams q;
  apply_profile(q, to_json(p), "dump");
  EXPECT_EQ(to_json(p), to_json(q));
}

}  // namespace
}  // namespace topotrack
