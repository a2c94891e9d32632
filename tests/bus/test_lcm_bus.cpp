// The run on an LCM bus: a whole run published on the in-process bus (memq://) and read
// back by a subscriber, message by message: the world first, a poses message per control
// step, every event as events.csv has it, the status every second and at the end.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "bus/lcm_bus.hpp"
#include "bus/lcm_conversion.hpp"
#include "bus/lcm_log_reader.hpp"
#include "bus/report_decoder.hpp"
#include "bus/run_publisher.hpp"
#include "run/simulation.hpp"

namespace rilbed::bus {
namespace {

struct Collector {
  std::vector<std::string> order;  // channel of each message, in arrival order
  std::vector<rilbed::poses_t> poses;
  std::vector<rilbed::event_t> events;
  std::vector<rilbed::status_t> status;
  std::vector<rilbed::world_t> worlds;
  std::vector<rilbed::wheels_t> wheels;
  std::vector<rilbed::sensors_t> sensors;
  // Decodes each message as its channel's type (a test does not need the checks).
  template <typename Message>
  LcmSubscription::Handler into(std::vector<Message>& out) {
    return [this, &out](const std::string& c, const void* data, std::size_t size) {
      Message m;
      ASSERT_EQ(m.decode(data, 0, static_cast<int>(size)), static_cast<int>(size)) << c;
      order.push_back(c);
      out.push_back(m);
    };
  }
};

run::Scenario convoy_sim() {
  return run::load_scenario(std::filesystem::path(RILBED_SOURCE_DIR) / "scenarios" / "convoy_sim.yaml");
}

std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(LcmBus, ARunOnTheInProcessBusIsWhatItsFolderHolds) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  const Channels channels = Channels::with_prefix("T1_");
  Collector got;
  LcmRunPublisher publisher(lcm, channels, true);
  const auto poses = publisher.subscribe(channels.poses, got.into(got.poses));
  const auto events = publisher.subscribe(channels.events, got.into(got.events));
  const auto status = publisher.subscribe(channels.status, got.into(got.status));
  const auto worlds = publisher.subscribe(channels.world, got.into(got.worlds));
  const auto wheels = publisher.subscribe(channels.wheels, got.into(got.wheels));
  const auto sensors = publisher.subscribe(channels.sensors, got.into(got.sensors));

  const auto dir = std::filesystem::temp_directory_path() / ("rilbed_lcm_bus_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  run::RunOptions o;
  o.seed = 3;
  o.stop_when_formed = true;
  o.out_dir = dir;
  o.observer = &publisher;
  const run::RunResult r = run::run_scenario(convoy_sim(), o);
  ASSERT_TRUE(r.formed);

  ASSERT_FALSE(got.order.empty());
  EXPECT_EQ(got.order.front(), "T1_RILBED_WORLD");  // a viewer can draw before the first poses
  ASSERT_FALSE(got.worlds.empty());
  EXPECT_EQ(got.worlds.front().scenario, "convoy_sim");
  EXPECT_DOUBLE_EQ(got.worlds.front().width_m, 1.5);
  EXPECT_EQ(got.worlds.front().num_robots, 8);
  // One poses message per control step, every robot in each.
  const auto steps = static_cast<std::size_t>(std::llround(r.simulated_s / 0.1)) + 1;
  EXPECT_NEAR(static_cast<double>(got.poses.size()), static_cast<double>(steps), 1.0);
  for (const auto& p : got.poses) ASSERT_EQ(p.num_robots, 8);
  // Every robot's wheels and sensors at every step; the convoy's Kheperas carry 8 IR sensors.
  ASSERT_EQ(got.wheels.size(), got.poses.size());
  ASSERT_EQ(got.sensors.size(), got.poses.size());
  bool moved = false;
  for (std::size_t i = 0; i < got.wheels.size(); ++i) {
    ASSERT_EQ(got.wheels[i].utime, got.poses[i].utime);
    ASSERT_EQ(got.wheels[i].num_robots, 8);
    for (const auto& w : got.wheels[i].robots) {
      ASSERT_LE(std::abs(w.left_units), 127);
      EXPECT_DOUBLE_EQ(w.left_mps, w.left_units * 0.008);
      moved = moved || w.left_units != 0 || w.right_units != 0;
    }
    ASSERT_EQ(got.sensors[i].num_robots, 8);
    for (const auto& r : got.sensors[i].robots) {
      ASSERT_EQ(r.num_proximity, i == 0 ? r.num_proximity : 8);  // before the first step nothing was read
      for (const auto v : r.proximity) ASSERT_TRUE(v >= 0 && v <= 1023) << v;
    }
  }
  EXPECT_TRUE(moved);
  EXPECT_EQ(got.sensors.back().robots[0].num_proximity, 8);
  // The poses are the trajectories' rows.
  const std::string trajectories = slurp(dir / "trajectories.csv");
  const auto& last = got.poses.back();
  char row[128];
  std::snprintf(row, sizeof row, "%.3f,%d,%.5f,%.5f,", static_cast<double>(last.utime) * 1e-6, last.robots[0].id,
                last.robots[0].x_m, last.robots[0].y_m);
  EXPECT_NE(trajectories.find(row), std::string::npos) << row;
  // Every event, as events.csv has it, in order.
  std::istringstream csv(slurp(dir / "events.csv"));
  std::string line;
  std::getline(csv, line);  // header
  std::size_t k = 0;
  while (std::getline(csv, line)) {
    ASSERT_LT(k, got.events.size()) << line;
    const auto& e = got.events[k++];
    std::snprintf(row, sizeof row, "%.3f,", static_cast<double>(e.utime) * 1e-6);
    EXPECT_EQ(
        line.rfind(std::string(row) + e.kind + "," + std::to_string(e.id) + "," + std::to_string(e.other) + ",", 0), 0u)
        << line;
  }
  EXPECT_EQ(k, got.events.size());
  // The status every simulated second, then once more at the end.
  ASSERT_GE(got.status.size(), static_cast<std::size_t>(r.simulated_s));
  EXPECT_EQ(got.status.front().state, "running");
  const auto& end = got.status.back();
  EXPECT_EQ(end.state, "ended");
  EXPECT_EQ(end.ended_by, "formed");
  EXPECT_TRUE(end.formed);
  EXPECT_NEAR(end.formation_time_s, *r.formation_time_s, 1e-9);
  EXPECT_EQ(end.seed, 3);
  EXPECT_EQ(end.num_robots, 8);
  // What the publisher counted is what arrived.
  const auto counts = publisher.counts();
  EXPECT_EQ(counts.at("T1_RILBED_POSES").messages, got.poses.size());
  EXPECT_EQ(counts.at("T1_RILBED_EVENTS").messages, got.events.size());
  EXPECT_EQ(counts.at("T1_RILBED_POSES").failures, 0u);
  EXPECT_GT(counts.at("T1_RILBED_POSES").bytes, 100u * got.poses.size());
  std::filesystem::remove_all(dir);
}

// A run nobody hears (the in-process bus, no subscriber, no log) costs no encoding; a
// local subscriber gets exactly what a bus subscriber gets, without the bus.
TEST(LcmBus, NothingIsEncodedForNobodyAndLocalSubscribersHearAll) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  run::RunOptions o;
  o.seed = 5;
  o.duration_s = 3.0;
  {
    LcmRunPublisher unheard(lcm, Channels{}, true);
    o.observer = &unheard;
    run::run_scenario(convoy_sim(), o);
    EXPECT_TRUE(unheard.counts().empty());
  }
  struct Counter final : run::RunObserver {
    int worlds = 0, poses = 0, wheels = 0, sensors = 0, statuses = 0, summaries = 0;
    void on_world(TimeUs, const run::WorldReport&) override { ++worlds; }
    void on_poses(TimeUs, std::span<const run::PoseReport>) override { ++poses; }
    void on_wheels(TimeUs, std::span<const run::WheelReport>) override { ++wheels; }
    void on_sensors(TimeUs, std::span<const run::SensorReport>) override { ++sensors; }
    void on_status(const run::StatusReport&) override { ++statuses; }
    void on_summary(TimeUs, const nlohmann::json&) override { ++summaries; }
  } local;
  Collector bus;
  LcmRunPublisher heard(lcm, Channels{}, true);
  heard.add_local_subscriber(local);
  const auto poses = heard.subscribe(Channels{}.poses, bus.into(bus.poses));
  o.observer = &heard;
  run::run_scenario(convoy_sim(), o);
  EXPECT_EQ(static_cast<std::size_t>(local.poses), bus.poses.size());
  EXPECT_GT(local.poses, 25);
  EXPECT_EQ(local.wheels, local.poses);
  EXPECT_EQ(local.sensors, local.poses);
  EXPECT_GE(local.worlds, 3);
  EXPECT_GE(local.statuses, 4);  // every second and the end
  EXPECT_EQ(local.summaries, 1);
  EXPECT_EQ(heard.counts().at("RILBED_POSES").messages, bus.poses.size());
}

TEST(LcmBus, ChecksChannelPrefixesAndUrls) {
  EXPECT_EQ(check_channel_prefix(""), std::nullopt);
  EXPECT_EQ(check_channel_prefix("LAB_2_"), std::nullopt);
  EXPECT_NE(check_channel_prefix("LAB 2"), std::nullopt);
  EXPECT_NE(check_channel_prefix("a.b"), std::nullopt);
  EXPECT_NE(check_channel_prefix(std::string(60, 'A')), std::nullopt);
  EXPECT_EQ(Channels::with_prefix("X_").status, "X_RILBED_STATUS");
  std::string error;
  EXPECT_EQ(open_lcm("nosuch://here", error), nullptr);
  EXPECT_NE(error.find("nosuch://here"), std::string::npos) << error;
  EXPECT_NE(open_lcm("memq://", error), nullptr);
}

TEST(LcmBus, MessagesRoundTripThroughTheirEncoding) {
  run::PoseReport p{4, true, false, Pose2{{0.5, 0.25}, -1.0}, "follow", "unseen"};
  const rilbed::poses_t poses = to_lcm(1'500'000, std::span<const run::PoseReport>(&p, 1));
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(poses.getEncodedSize()));
  ASSERT_EQ(poses.encode(bytes.data(), 0, static_cast<int>(bytes.size())), static_cast<int>(bytes.size()));
  rilbed::poses_t back;
  ASSERT_EQ(back.decode(bytes.data(), 0, static_cast<int>(bytes.size())), static_cast<int>(bytes.size()));
  ASSERT_EQ(back.num_robots, 1);
  EXPECT_EQ(back.utime, 1'500'000);
  EXPECT_EQ(back.robots[0].id, 4);
  EXPECT_TRUE(back.robots[0].real);
  EXPECT_FALSE(back.robots[0].seen);
  EXPECT_DOUBLE_EQ(back.robots[0].theta_rad, -1.0);
  EXPECT_EQ(back.robots[0].behaviour, "follow");
  EXPECT_EQ(back.robots[0].health, "unseen");
  // Cut short, it does not decode.
  EXPECT_LT(back.decode(bytes.data(), 0, static_cast<int>(bytes.size()) - 3), 0);
}

}  // namespace
}  // namespace rilbed::bus

namespace rilbed::bus {
namespace {

std::vector<std::uint8_t> from_hex(const std::string& hex) {
  std::vector<std::uint8_t> bytes;
  for (std::size_t i = 0; i + 1 < hex.size(); i += 2)
    bytes.push_back(static_cast<std::uint8_t>(std::stoi(hex.substr(i, 2), nullptr, 16)));
  return bytes;
}

// Inputs the fuzz targets found: each once crashed or exhausted memory; now each is a
// message (or a log) refused with a reason.
TEST(LcmBus, HostileMessagesAndLogsAreRefusedNotDecoded) {
  run::RunObserver nobody;
  RunReportDecoder decoder(Channels::with_prefix(""), nobody);
  // A world whose obstacle count asks for 144 GB.
  const auto world = from_hex("333e0b631fa8361d000000000000000000000001003ff80000000000003ff3333333333333017fffffff");
  const auto problem = decoder.decode("RILBED_WORLD", world.data(), world.size());
  ASSERT_TRUE(problem.has_value());
  EXPECT_NE(problem->find("not a rilbed.world_t"), std::string::npos) << *problem;
  // An event whose string length is 0x80000000 (lcm-gen's decoder wraps it and reads 2 GB
  // past the buffer).
  const auto log_bytes = from_hex(
      "eda1da01000000000000000000000000000000010000000d0000002752494c4245445f4556454e5453b0cb1efb6b9edf8400000000"
      "00000001800000006e6f7465000000000100000000000000027800");
  const auto dir = std::filesystem::temp_directory_path() / ("rilbed_hostile_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "event.lcm", std::ios::binary)
      .write(reinterpret_cast<const char*>(log_bytes.data()), static_cast<std::streamsize>(log_bytes.size()));
  LcmLogReader reader((dir / "event.lcm").string());
  ASSERT_TRUE(reader.good());
  const auto event = reader.next();
  ASSERT_TRUE(event.has_value());
  EXPECT_EQ(event->channel, "RILBED_EVENTS");
  EXPECT_TRUE(decoder.decode(event->channel, event->data.data(), event->data.size()).has_value());
  EXPECT_FALSE(reader.next().has_value());
  // A log event that claims 2 GB of data (liblcm's reader wrote through a null pointer).
  const auto huge =
      from_hex("eda1da01000000000000000000000000000000010000000d7fffffff52494c4245445f4556454e5453736f6d652064617461");
  std::ofstream(dir / "huge.lcm", std::ios::binary)
      .write(reinterpret_cast<const char*>(huge.data()), static_cast<std::streamsize>(huge.size()));
  LcmLogReader cut((dir / "huge.lcm").string());
  EXPECT_FALSE(cut.next().has_value());
  EXPECT_TRUE(cut.truncated());
  EXPECT_EQ(cut.skipped_bytes(), huge.size());
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rilbed::bus

namespace rilbed::bus {
namespace {

// Each report, encoded as the publisher encodes it and decoded as every subscriber
// decodes it, is the report again.
TEST(LcmBus, WheelsSensorsAndDetectionsSurviveTheBus) {
  struct Got final : run::RunObserver {
    std::vector<run::WheelReport> wheels;
    std::vector<std::pair<int, environment::SensorReadings>> sensors;
    std::vector<run::DetectionReport> detections;
    run::StatusReport status;
    std::int64_t frame = 0;
    cv::Mat image;
    bool wants_frame_images() const override { return true; }
    void on_wheels(TimeUs, std::span<const run::WheelReport> w) override { wheels.assign(w.begin(), w.end()); }
    void on_sensors(TimeUs, std::span<const run::SensorReport> s) override {
      for (const auto& r : s) sensors.emplace_back(r.id, *r.readings);
    }
    void on_detections(const run::FrameReport& f) override {
      frame = f.frame;
      detections.assign(f.detections.begin(), f.detections.end());
    }
    void on_frame_image(TimeUs, std::int64_t, const cv::Mat& m) override { image = m.clone(); }
    void on_status(const run::StatusReport& s) override { status = s; }
  } got;
  const Channels channels;
  RunReportDecoder decoder(channels, got);
  auto through = [&](const std::string& channel, const auto& message) {
    std::vector<std::uint8_t> bytes(static_cast<std::size_t>(message.getEncodedSize()));
    ASSERT_EQ(message.encode(bytes.data(), 0, static_cast<int>(bytes.size())), static_cast<int>(bytes.size()));
    ASSERT_EQ(decoder.decode(channel, bytes.data(), bytes.size()), std::nullopt) << channel;
  };
  const std::vector<run::WheelReport> wheels = {{1, {127, -127}}, {7, {0, 3}}};
  rilbed::wheels_t w;
  fill(w, 500'000, wheels);
  EXPECT_DOUBLE_EQ(w.robots[0].left_mps, 127 * 0.008);
  through(channels.wheels, w);
  ASSERT_EQ(got.wheels.size(), 2u);
  EXPECT_EQ(got.wheels[0].wheels, (agents::WheelCommand{127, -127}));
  EXPECT_EQ(got.wheels[1].id, 7);

  environment::SensorReadings full;
  full.proximity = environment::ProximityValues{0, 1, 2, 3, 1020, 1021, 1022, 1023};
  full.ranges = {{true, 0.25}, {false, 1.5}};
  full.beacons = {{3, -1.0}};
  full.track = {0, 255, 17};
  full.odometry = environment::OdometryReading{-5, 123456789012};
  const environment::SensorReadings none;  // a robot that carries no sensor
  const std::vector<run::SensorReport> sensors = {{2, &full}, {9, &none}};
  rilbed::sensors_t s;
  fill(s, 600'000, sensors);
  through(channels.sensors, s);
  ASSERT_EQ(got.sensors.size(), 2u);
  const environment::SensorReadings& back = got.sensors[0].second;
  EXPECT_EQ(got.sensors[0].first, 2);
  EXPECT_EQ(back.t_us, 600'000);
  EXPECT_EQ(back.proximity, full.proximity);
  ASSERT_EQ(back.ranges.size(), 2u);
  EXPECT_TRUE(back.ranges[0].hit);
  EXPECT_EQ(back.ranges[1].distance_m, 1.5);
  ASSERT_EQ(back.beacons.size(), 1u);
  EXPECT_EQ(back.beacons[0].bearing_rad, -1.0);
  EXPECT_EQ(back.track, full.track);
  ASSERT_TRUE(back.odometry.has_value());
  EXPECT_EQ(back.odometry->right_pulses, 123456789012);
  const environment::SensorReadings& empty = got.sensors[1].second;
  EXPECT_FALSE(empty.proximity || empty.odometry);
  EXPECT_TRUE(empty.ranges.empty() && empty.beacons.empty() && empty.track.empty());

  const std::vector<run::DetectionReport> found = {{4, 812.5, 90.25, 359.5, 0.97, 31.0, Pose2{{0.4, 1.1}, -2.0}}};
  through(channels.detections, to_lcm(run::FrameReport{700'000, 21, 0.4, found}));
  EXPECT_EQ(got.frame, 21);
  ASSERT_EQ(got.detections.size(), 1u);
  EXPECT_EQ(got.detections[0].u_px, 812.5);
  EXPECT_EQ(got.detections[0].heading_deg, 359.5);
  EXPECT_EQ(got.detections[0].pose.heading_rad, -2.0);

  // A frame goes as JPEG and comes back as an image of its size, close to the original.
  cv::Mat image(48, 64, CV_8UC1, cv::Scalar(180));
  cv::rectangle(image, {10, 10}, {30, 30}, cv::Scalar(20), -1);
  const rilbed::frame_t f = to_lcm(800'000, 22, image, 90);
  EXPECT_EQ(f.size, static_cast<std::int32_t>(f.data.size()));
  through(channels.frames, f);
  ASSERT_EQ(got.image.size(), image.size());
  EXPECT_LT(cv::norm(got.image, image, cv::NORM_INF), 40.0);
  EXPECT_LT(cv::norm(got.image, image, cv::NORM_L1) / image.total(), 2.0);
  // Not JPEG: refused, saying why.
  rilbed::frame_t png = f;
  png.format = "png";
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(png.getEncodedSize()));
  png.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  const auto problem = decoder.decode(channels.frames, bytes.data(), bytes.size());
  ASSERT_TRUE(problem.has_value());
  EXPECT_NE(problem->find("not jpeg"), std::string::npos) << *problem;

  run::StatusReport st;
  st.state = "paused";
  st.loop_latency_ms = 3.5;
  st.camera_fps = 29.9;
  st.frames = 1234;
  through(channels.status, to_lcm(st));
  EXPECT_EQ(got.status.state, "paused");
  EXPECT_EQ(got.status.loop_latency_ms, 3.5);
  EXPECT_EQ(got.status.camera_fps, 29.9);
  EXPECT_EQ(got.status.frames, 1234);
}

}  // namespace
}  // namespace rilbed::bus

namespace rilbed::bus {
namespace {

template <typename Message>
std::vector<std::uint8_t> encoded(const Message& m) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

// Robots' bodies reach a viewer with the next world_t; one that cannot be drawn is refused.
TEST(LcmBus, RobotBodiesTravelBeforeTheWorldAndBadOnesAreRefused) {
  struct Got final : run::RunObserver {
    run::WorldReport world;
    int worlds = 0;
    void on_world(TimeUs, const run::WorldReport& w) override {
      world = w;
      ++worlds;
    }
  } got;
  const Channels channels;
  RunReportDecoder decoder(channels, got);
  run::WorldReport w;
  w.robot_ids = {1, 2, 3};
  w.bodies = {run::BodyDrawing{},
              run::BodyDrawing{
                  "square", 0.0, {{0.035, 0.035}, {-0.035, 0.035}, {-0.035, -0.035}, {0.035, -0.035}}, 0.06, 0.016}};
  w.body_of = {{1, 0}, {2, 1}, {3, 1}};
  const auto bodies = encoded(robot_bodies(5, w));
  ASSERT_FALSE(decoder.decode(channels.robot_bodies, bodies.data(), bodies.size()));
  const auto world = encoded(to_lcm(5, w));
  ASSERT_FALSE(decoder.decode(channels.world, world.data(), world.size()));
  ASSERT_EQ(got.worlds, 1);
  ASSERT_EQ(got.world.bodies.size(), 2u);
  EXPECT_EQ(got.world.bodies[1].name, "square");
  EXPECT_EQ(got.world.bodies[1].outline_m, w.bodies[1].outline_m);
  EXPECT_NEAR(got.world.bodies[1].radius_m, 0.035 * std::sqrt(2.0), 1e-15);  // the outline's bounding disc
  EXPECT_EQ(got.world.bodies[0], w.bodies[0]);
  EXPECT_EQ(got.world.body_of, w.body_of);

  rilbed::robot_bodies_t bad = robot_bodies(6, w);
  std::swap(bad.bodies[1].outline_x_m[0], bad.bodies[1].outline_x_m[1]);  // a bow tie
  auto bytes = encoded(bad);
  auto problem = decoder.decode(channels.robot_bodies, bytes.data(), bytes.size());
  ASSERT_TRUE(problem);
  EXPECT_NE(problem->find("RILBED_ROBOT_BODIES: body 1: outline crosses itself"), std::string::npos) << *problem;
  bad = robot_bodies(6, w);
  bad.body_of[2] = 2;
  bytes = encoded(bad);
  problem = decoder.decode(channels.robot_bodies, bytes.data(), bytes.size());
  ASSERT_TRUE(problem);
  EXPECT_NE(problem->find("robot 3 has body 2 of 2"), std::string::npos) << *problem;
  bad = robot_bodies(6, w);
  bad.bodies[0].radius_m = -1.0;
  bytes = encoded(bad);
  EXPECT_TRUE(decoder.decode(channels.robot_bodies, bytes.data(), bytes.size()));
}

}  // namespace
}  // namespace rilbed::bus

namespace rilbed::bus {
namespace {

// Sensor models' readings and marks travel just before their step's sensors_t and come back
// on the robots they belong to; a bad one is left out, said so, and the step still arrives.
TEST(LcmBus, SensorModelReadingsAndMarksJoinTheirStep) {
  struct Got final : run::RunObserver {
    std::vector<std::pair<int, environment::SensorReadings>> sensors;
    void on_sensors(TimeUs, std::span<const run::SensorReport> s) override {
      sensors.clear();
      for (const auto& r : s) sensors.emplace_back(r.id, *r.readings);
    }
  } got;
  const Channels channels;
  RunReportDecoder decoder(channels, got);
  environment::SensorReadings seeing;
  seeing.track = {40};
  seeing.models.push_back({"to_goal", {0.25, -3.0}});
  seeing.marks.push_back({environment::SensorMark::Shape::kCircle, {0.02, 0.0}, {}, 0.004, 0x20c0f0ffu});
  seeing.marks.push_back({environment::SensorMark::Shape::kLine, {0.0, 0.0}, {0.1, 0.05}, 0.0, 0xff0000ffu});
  const environment::SensorReadings plain;
  const std::vector<run::SensorReport> step = {{1, &plain}, {4, &seeing}};
  rilbed::sensor_models_t models;
  ASSERT_TRUE(fill(models, 900'000, step));
  ASSERT_EQ(models.num_robots, 1);  // robot 1 has none
  rilbed::sensors_t sensors;
  fill(sensors, 900'000, step);
  auto send = [&](const std::string& channel, const auto& message) {
    const auto bytes = encoded(message);
    return decoder.decode(channel, bytes.data(), bytes.size());
  };
  ASSERT_FALSE(send(channels.sensor_models, models));
  ASSERT_FALSE(send(channels.sensors, sensors));
  ASSERT_EQ(got.sensors.size(), 2u);
  EXPECT_TRUE(got.sensors[0].second.models.empty());
  const environment::SensorReadings& back = got.sensors[1].second;
  ASSERT_EQ(back.models.size(), 1u);
  EXPECT_EQ(back.models[0].name, "to_goal");
  EXPECT_EQ(back.models[0].values, seeing.models[0].values);
  ASSERT_EQ(back.marks.size(), 2u);
  EXPECT_EQ(back.marks[1].shape, environment::SensorMark::Shape::kLine);
  EXPECT_EQ(back.marks[1].b_m.y, 0.05);
  EXPECT_EQ(back.marks[0].rgba, 0x20c0f0ffu);
  EXPECT_EQ(back.track, seeing.track);
  // The next step without models has none: they belong to their utime only.
  fill(sensors, 1'000'000, step);
  ASSERT_FALSE(send(channels.sensors, sensors));
  EXPECT_TRUE(got.sensors[1].second.models.empty() && got.sensors[1].second.marks.empty());
  // A value that is not finite: that robot's models are left out, the step still arrives.
  fill(models, 1'100'000, step);
  models.robots[0].readings[0].values[1] = std::nan("");
  fill(sensors, 1'100'000, step);
  ASSERT_FALSE(send(channels.sensor_models, models));
  const auto problem = send(channels.sensors, sensors);
  ASSERT_TRUE(problem);
  EXPECT_NE(problem->find("RILBED_SENSOR_MODELS: robot 4: model 'to_goal' has a value that is not finite"),
            std::string::npos)
      << *problem;
  ASSERT_EQ(got.sensors.size(), 2u);
  EXPECT_TRUE(got.sensors[1].second.models.empty());
  EXPECT_EQ(got.sensors[1].second.track, seeing.track);
}

}  // namespace
}  // namespace rilbed::bus
