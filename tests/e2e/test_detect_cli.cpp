// End-to-end tests of `rilbed detect` (and `synth`, `score`): the real binary replays the
// recorded footage of datasets/ and its output is checked against the ground truth.
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include <filesystem>
#include <fstream>

#include "run_command.hpp"
#include "vision/detection_score.hpp"
#include "vision/stress_scene.hpp"
#include "vision/synthetic_scene.hpp"

namespace fs = std::filesystem;
using namespace rilbed;
using rilbed::e2e::read_file;
using rilbed::e2e::run_rilbed;
using rilbed::e2e::scratch_dir;

namespace {

const fs::path kDatasets = fs::path(RILBED_SOURCE_DIR) / "datasets";

vision::DetectionScore detect_and_score(const fs::path& dataset, const std::string& extra, const fs::path& out) {
  const auto csv = out / (dataset.filename().string() + ".csv");
  const auto r = run_rilbed("detect '" + (dataset / "frames").string() + "' --calib '" +
                            (dataset / "calibration.yaml").string() + "' --csv '" + csv.string() + "' " + extra);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  const auto truth = vision::read_marker_csv((dataset / "ground_truth.csv").string());
  const auto det = vision::read_marker_csv(csv.string());
  EXPECT_TRUE(truth.ok()) << truth.error;
  EXPECT_TRUE(det.ok()) << det.error;
  return vision::score_detections(truth.rows, det.rows);
}

int data_rows(const std::string& csv) {
  int lines = 0;
  for (char c : csv) lines += c == '\n';
  return lines - 1;  // header
}

}  // namespace

TEST(DetectCli, NominalFootageMatchesGroundTruth) {
  const auto out = scratch_dir("detect_nominal");
  const auto s = detect_and_score(kDatasets / "nominal", "", out);
  SCOPED_TRACE(vision::format_score(s));
  EXPECT_EQ(s.truth_markers, 360);
  EXPECT_EQ(s.found, s.truth_markers);
  EXPECT_EQ(s.wrong_id, 0);
  EXPECT_EQ(s.duplicates, 0);
  EXPECT_LT(s.centre_rms_px, 0.3);
  EXPECT_LT(s.heading_rms_deg, 1.5);
  EXPECT_EQ(s.field_pairs, s.found);
  EXPECT_LT(s.field_rms_mm, 1.0);
  EXPECT_LT(s.theta_rms_deg, 1.5);
  fs::remove_all(out);
}

TEST(DetectCli, HardFootageMatchesGroundTruth) {
  const auto out = scratch_dir("detect_hard");
  const auto s = detect_and_score(kDatasets / "hard", "", out);
  SCOPED_TRACE(vision::format_score(s));
  EXPECT_GE(s.recall(), 0.99);
  EXPECT_EQ(s.wrong_id, 0);
  EXPECT_EQ(s.duplicates, 0);
  EXPECT_LT(s.centre_rms_px, 0.3);
  EXPECT_LT(s.heading_rms_deg, 1.5);
  EXPECT_LT(s.field_rms_mm, 2.0);
  fs::remove_all(out);
}

TEST(DetectCli, FullFrameSearchAgreesWithTracking) {
  const auto out = scratch_dir("detect_notrack");
  const auto s = detect_and_score(kDatasets / "hard", "--no-track", out);
  EXPECT_GE(s.recall(), 0.99);
  EXPECT_EQ(s.wrong_id, 0);
  fs::remove_all(out);
}

// Only the listed IDs are given out, and a marker of an unlisted ID never takes one.
TEST(DetectCli, OnlyListedIdsAndNoLookalikes) {
  const auto out = scratch_dir("detect_ids");
  const auto s = detect_and_score(kDatasets / "hard", "--ids 2,5,7", out);
  EXPECT_EQ(s.found, 3 * 45);
  EXPECT_EQ(s.wrong_id, 0);
  fs::remove_all(out);
}

TEST(DetectCli, CsvColumnsFollowTheContract) {
  const auto out = scratch_dir("detect_csv");
  const auto frames = (kDatasets / "nominal" / "frames").string();
  auto r = run_rilbed("detect '" + frames + "' --max-frames 2 --csv - -q");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.substr(0, r.out.find('\n')), "frame,id,u,v,heading_deg,score");
  EXPECT_EQ(data_rows(r.out), 16);
  r = run_rilbed("detect '" + frames + "' --max-frames 1 --calib '" +
                 (kDatasets / "nominal" / "calibration.yaml").string() + "' -q");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.substr(0, r.out.find('\n')), "frame,id,u,v,heading_deg,score,x_m,y_m,theta_deg");
  EXPECT_NE(r.err.find("summary: 1 frames read"), std::string::npos) << r.err;
  fs::remove_all(out);
}

// A video file: rendered here as MJPG AVI, then cut in half; the frames before the cut
// are still reported and the run ends cleanly.
TEST(DetectCli, VideoAndTruncatedVideo) {
  const auto out = scratch_dir("detect_video");
  auto r = run_rilbed("synth --preset nominal --frames 12 --seed 5 --format avi --out '" + out.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto video = out / "video.avi";
  r = run_rilbed("detect '" + video.string() + "' --csv '" + (out / "full.csv").string() + "' -q");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto truth = vision::read_marker_csv((out / "ground_truth.csv").string());
  const auto full = vision::read_marker_csv((out / "full.csv").string());
  ASSERT_TRUE(full.ok()) << full.error;
  const auto s = vision::score_detections(truth.rows, full.rows);
  EXPECT_EQ(s.found, 96);
  EXPECT_EQ(s.wrong_id, 0);

  const auto cut = out / "cut.avi";
  fs::copy_file(video, cut);
  fs::resize_file(cut, fs::file_size(video) / 2);
  r = run_rilbed("detect '" + cut.string() + "' --csv '" + (out / "cut.csv").string() + "' -q");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("cut.avi"), std::string::npos) << r.err;
  const auto part = vision::read_marker_csv((out / "cut.csv").string());
  ASSERT_TRUE(part.ok());
  EXPECT_GT(part.rows.size(), 8u);
  EXPECT_LT(part.rows.size(), 96u);
  EXPECT_EQ(vision::score_detections(truth.rows, part.rows).wrong_id, 0);
  fs::remove_all(out);
}

// `synth --preset stress` writes a scene's clip as the contract says (PNG frames, the truth
// with its extra columns, each scene's conditions and calibration), the same pair of seed
// and scene gives the same frames, and `detect` on those frames with that calibration
// names no marker wrongly.
TEST(DetectCli, StressScenesAsTheContractSays) {
  const auto out = scratch_dir("detect_stress");
  auto r = run_rilbed("synth --preset stress --seed 11 --scene 3 --frames 4 --out '" + out.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string truth_text = read_file(out / "ground_truth.csv");
  EXPECT_EQ(truth_text.substr(0, truth_text.find('\n')),
            "frame,id,u,v,heading_deg,scene,diameter_px,occluded,touching");
  const std::string scenes = read_file(out / "scenes.csv");
  EXPECT_EQ(scenes.rfind("scene,first_frame,frames,marker_diameter_px,", 0), 0u) << scenes;
  EXPECT_NE(scenes.find("\n3,0,4,"), std::string::npos) << scenes;
  ASSERT_TRUE(fs::exists(out / "calibration" / "scene_0003.yaml"));
  for (int f = 0; f < 4; ++f) EXPECT_TRUE(fs::exists(out / "frames" / ("frame_000" + std::to_string(f) + ".png")));
  const cv::Mat first = cv::imread((out / "frames" / "frame_0000.png").string());
  EXPECT_EQ(first.cols, 1280);
  EXPECT_EQ(first.rows, 960);
  // Again: the same frames, byte for byte.
  const auto again = scratch_dir("detect_stress_again");
  r = run_rilbed("synth --preset stress --seed 11 --scene 3 --frames 1 --out '" + again.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(read_file(again / "frames" / "frame_0000.png"), read_file(out / "frames" / "frame_0000.png"));
  r = run_rilbed("detect '" + (out / "frames").string() + "' --calib '" +
                 (out / "calibration" / "scene_0003.yaml").string() + "' --csv '" + (out / "found.csv").string() +
                 "' -q");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("  declined: "), std::string::npos) << r.err;  // the summary counts ambiguous markers
  const auto truth = vision::read_marker_csv((out / "ground_truth.csv").string());
  const auto found = vision::read_marker_csv((out / "found.csv").string());
  ASSERT_TRUE(truth.ok()) << truth.error;
  ASSERT_TRUE(found.ok()) << found.error;
  const auto s = vision::score_detections(truth.rows, found.rows);
  EXPECT_GT(s.truth_markers, 0);
  EXPECT_EQ(s.wrong_id, 0);
  EXPECT_EQ(s.duplicates, 0);
  fs::remove_all(out);
  fs::remove_all(again);
}

// bench_stress draws 64-bit seeds and names them for `synth` to show its mistakes: synth
// takes them whole and renders the very frame the bench scored.
TEST(DetectCli, StressSynthTakesTheBenchsSixtyFourBitSeeds) {
  const auto out = scratch_dir("detect_stress_seed64");
  const std::uint64_t seed = 2822153290125956176ULL;
  auto r = run_rilbed("synth --preset stress --seed " + std::to_string(seed) + " --scene 5 --frames 1 --out '" +
                      out.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const cv::Mat written = cv::imread((out / "frames" / "frame_0000.png").string());
  const vision::StressScene scene = vision::make_stress_scene(seed, 5);
  ASSERT_EQ(written.size(), scene.frames[0].size());
  EXPECT_EQ(cv::norm(written, scene.frames[0], cv::NORM_INF), 0.0);
  fs::remove_all(out);
}

// Bad frames in a directory are named and skipped; the good ones keep their frame numbers.
TEST(DetectCli, CorruptAndOddSizedFramesAreSkipped) {
  const auto out = scratch_dir("detect_bad_frames");
  const auto dir = out / "frames";
  fs::create_directories(dir);
  for (int f = 0; f < 4; ++f) {
    const std::string name = "frame_000" + std::to_string(f) + ".jpg";
    fs::copy_file(kDatasets / "nominal" / "frames" / name, dir / name);
  }
  std::ofstream(dir / "frame_0001.jpg", std::ios::trunc) << "this is not a JPEG";
  cv::imwrite((dir / "frame_0002.jpg").string(), cv::Mat(100, 100, CV_8UC3, cv::Scalar(128, 128, 128)));
  const auto r = run_rilbed("detect '" + dir.string() + "' --csv - -q");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("frame_0001.jpg"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("frame_0002.jpg"), std::string::npos) << r.err;
  EXPECT_EQ(data_rows(r.out), 16);  // frames 0 and 3
  EXPECT_NE(r.out.find("\n3,1,"), std::string::npos);
  fs::remove_all(out);
}

TEST(DetectCli, UnreadableInputsFailClearly) {
  const auto out = scratch_dir("detect_unreadable");
  auto r = run_rilbed("detect '" + (out / "missing.avi").string() + "' -q");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("missing.avi"), std::string::npos) << r.err;

  const auto dir = out / "junk";
  fs::create_directories(dir);
  std::ofstream(dir / "a.png") << "junk";
  r = run_rilbed("detect '" + dir.string() + "' -q");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("no frame could be read"), std::string::npos) << r.err;

  r = run_rilbed("detect --ids 0-3 '" + dir.string() + "'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("0-3"), std::string::npos) << r.err;
  r = run_rilbed("detect --family 4ucp '" + dir.string() + "'");
  EXPECT_EQ(r.exit_code, 2);
  r = run_rilbed("detect");
  EXPECT_NE(r.exit_code, 0);
  r = run_rilbed("detect --calib '" + (dir / "a.png").string() + "' '" + dir.string() + "'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("a.png"), std::string::npos) << r.err;
  fs::remove_all(out);
}

// Clutter alone (discs and rings the size of markers, tape, a chessboard, text) never
// gets an ID.
TEST(DetectCli, ClutterNeverGetsAnId) {
  const auto out = scratch_dir("detect_clutter");
  const auto preset = vision::scene_preset("hard");
  vision::SyntheticCamera camera(preset.camera, vision::MarkerFamily::six_ucp(), preset.conditions, preset.clutter);
  cv::RNG rng(9);
  for (int f = 0; f < 5; ++f) {
    cv::imwrite((out / ("empty_" + std::to_string(f) + ".png")).string(), camera.render({}, rng));
  }
  const auto r = run_rilbed("detect '" + out.string() + "' --csv - -q");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(data_rows(r.out), 0) << r.out;
  fs::remove_all(out);
}

TEST(DetectCli, MissingCameraFailsClearly) {
  const auto r = run_rilbed("detect --camera 57 -q");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("camera 57"), std::string::npos) << r.err;
  EXPECT_NE(run_rilbed("detect --camera 0 somefile.avi").exit_code, 0);  // one input only
}

TEST(ScoreCli, ReportsRecallAndErrors) {
  const auto truth = (kDatasets / "nominal" / "ground_truth.csv").string();
  const auto r = run_rilbed("score --truth '" + truth + "' --detections '" + truth + "'");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("recall 1.0000 (360 of 360), wrong IDs 0"), std::string::npos) << r.out;
  const auto bad = run_rilbed("score --truth '" + truth + "' --detections /nonexistent.csv");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("/nonexistent.csv"), std::string::npos);
}
