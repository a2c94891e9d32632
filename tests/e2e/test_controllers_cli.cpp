// `rilbed controllers`: the one registry of controllers as the CLI prints it, against the
// scenario reference (scenarios/README.md) and the scenarios that name them.
#include <gtest/gtest.h>

#include <set>

#include <nlohmann/json.hpp>

#include "run_command.hpp"

namespace rilbed::e2e {
namespace {

TEST(ControllersCli, TheScenarioReferenceShowsWhatTheCommandPrints) {
  const CommandResult r = run_rilbed("controllers");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string readme = read_file(std::filesystem::path(RILBED_SOURCE_DIR) / "scenarios" / "README.md");
  const std::string begin = "<!-- BEGIN rilbed controllers -->\n", end = "<!-- END rilbed controllers -->";
  const auto from = readme.find(begin), to = readme.find(end);
  ASSERT_NE(from, std::string::npos);
  ASSERT_NE(to, std::string::npos);
  EXPECT_EQ(readme.substr(from + begin.size(), to - from - begin.size()), r.out)
      << "scenarios/README.md's controller tables differ from `rilbed controllers`: paste its output between the "
         "markers";
}

TEST(ControllersCli, JsonListsEveryControllerWithItsParameters) {
  const CommandResult r = run_rilbed("controllers --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json list = nlohmann::json::parse(r.out);
  ASSERT_TRUE(list.is_array());
  std::set<std::string> names;
  for (const auto& c : list) {
    ASSERT_TRUE(c.contains("name") && c.contains("summary") && c.contains("sensors") && c.contains("params")) << c;
    names.insert(c["name"].get<std::string>());
    for (const auto& p : c["params"]) {
      for (const char* key : {"name", "unit", "default", "min", "max", "summary"}) {
        EXPECT_TRUE(p.contains(key)) << c["name"] << " " << p << " lacks " << key;
      }
    }
  }
  for (const char* wanted : {"convoy", "wander", "track_follow", "beacon_homing", "goto", "c:braitenberg", "none"}) {
    EXPECT_TRUE(names.contains(wanted)) << wanted;
  }
  // A parameter out of its range is refused where it stands in the file.
  const auto dir = scratch_dir("controllers");
  std::ofstream(dir / "fast.yaml") << "robots:\n  - id: 1\n    controller: wander\n    params: {speed_mps: 3}\n";
  std::string args = "run '";  // piece by piece: GCC 12's false -Wrestrict (PR 105329)
  args += (dir / "fast.yaml").string();
  args += "'";
  const CommandResult bad = run_rilbed(args);
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("fast.yaml:4: robots[0].params.speed_mps: must be 0 to 1.016 (m/s), not 3"), std::string::npos)
      << bad.err;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rilbed::e2e
