// batch.json: made from a batch's runs, written and read back as one type.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "run/batch_summary.hpp"

namespace rilbed::run {
namespace {

BatchRun ran(std::uint64_t seed, std::optional<double> formed_at_s, int collisions, std::string error = "") {
  BatchRun r;
  r.result.seed = seed;
  r.result.ended_by = error.empty() ? "duration" : "error";
  r.result.formed = formed_at_s.has_value();
  r.result.formation_time_s = formed_at_s;
  r.result.collisions = collisions;
  r.result.robot_collisions = collisions / 2;
  r.result.max_overlap_m = 0.001 * collisions;
  r.error = std::move(error);
  return r;
}

TEST(BatchSummary, CountsTheRunsThatTookPlace) {
  std::vector<BatchRun> runs = {ran(1, 10.0, 4), ran(2, std::nullopt, 2), ran(3, 20.0, 0, "link lost"), BatchRun{}};
  const BatchSummary b = summarise_batch("convoy", "central", runs, 12.5, 2);
  EXPECT_EQ(b.runs, 3);  // the fourth never ran (an interrupt)
  EXPECT_EQ(b.formed, 2);
  EXPECT_EQ(b.failed, 1);
  EXPECT_EQ(b.collisions, 6);
  EXPECT_EQ(b.robot_collisions, 3);
  EXPECT_DOUBLE_EQ(b.max_overlap_m, 0.004);
  ASSERT_TRUE(b.formation_time_median_s);
  EXPECT_DOUBLE_EQ(*b.formation_time_median_s, 15.0);
  EXPECT_EQ(b.seeds(), (std::vector<std::uint64_t>{1, 2, 3}));
  EXPECT_EQ(b.per_run[2]["error"], "link lost");
  EXPECT_NE(batch_table(b).find("| convoy | central | 3 | 2 | 15.0 |"), std::string::npos) << batch_table(b);
}

TEST(BatchSummary, WhatIsWrittenIsReadBack) {
  const BatchSummary b = summarise_batch("wander", "distributed", {ran(5, std::nullopt, 1)}, 1.0, 1);
  const auto path = std::filesystem::temp_directory_path() / ("rilbed_batch_" + std::to_string(::getpid()) + ".json");
  ASSERT_TRUE(write_batch_summary(path, b));
  std::string error;
  const auto read = read_batch_summary(path, error);
  ASSERT_TRUE(read) << error;
  EXPECT_EQ(to_json(*read), to_json(b));
  EXPECT_FALSE(read->formation_time_median_s);  // null: no run formed
  // A damaged one is named with what is wrong.
  std::ofstream(path) << R"({"scenario": "x", "mode": "central", "runs": "three"})";
  EXPECT_FALSE(read_batch_summary(path, error));
  EXPECT_NE(error.find("'runs' has the wrong type"), std::string::npos) << error;
  std::ofstream(path) << "not json";
  EXPECT_FALSE(read_batch_summary(path, error));
  EXPECT_NE(error.find("not JSON"), std::string::npos) << error;
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace rilbed::run
