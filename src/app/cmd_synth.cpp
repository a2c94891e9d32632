// `rilbed synth`: renders footage of marked robots with the synthetic overhead camera
// and writes it with its ground truth and calibration, as datasets/ holds it.
#include <spdlog/spdlog.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include <cstdint>
#include <filesystem>
#include <fstream>

#include "app/commands.hpp"
#include "vision/field_mapping.hpp"
#include "vision/lab_footage.hpp"
#include "vision/stress_scene.hpp"
#include "vision/synthetic_scene.hpp"

namespace rilbed::app {
namespace {

struct SynthOptions {
  std::string preset = "nominal";
  std::string out = "synth_out";
  int frames = 150;
  double fps = 15.0;
  int robots = 8;
  std::uint64_t seed = 1;  // 64 bits: bench_stress draws its sets' seeds from the whole range
  int width = 1280;
  int height = 720;
  std::string format = "avi";
  int first_scene = 0;       // stress: the first scene written
  int frames_per_scene = 4;  // stress: each scene's clip
};

// `--preset stress` and `--preset lab`: scenes of the vision stress set (each its own camera,
// floor, light and clutter, src/vision/stress_scene.hpp) or of the second generator's lab
// footage (src/vision/lab_footage.hpp), as PNG frames (each already through JPEG at its
// scene's quality), with per-scene conditions and calibration.
int run_stress_synth(const SynthOptions& opt, const std::filesystem::path& dir) {
  const bool lab = opt.preset == "lab";
  std::error_code ec;
  std::filesystem::create_directories(dir / "frames", ec);
  std::filesystem::create_directories(dir / "calibration", ec);
  if (ec) {
    spdlog::error("cannot create '{}': {}", (dir / "frames").string(), ec.message());
    return kExitFailure;
  }
  vision::StressOptions stress;
  stress.frames_per_scene = opt.frames_per_scene;
  stress.image_size = {opt.width, opt.height};
  vision::LabFootageOptions lab_options;
  lab_options.frames_per_scene = opt.frames_per_scene;
  lab_options.image_size = {opt.width, opt.height};
  lab_options.fps = opt.fps;
  std::ofstream truth(dir / "ground_truth.csv");
  truth << "frame,id,u,v,heading_deg,scene,diameter_px,occluded,touching\n";
  std::ofstream scenes(dir / "scenes.csv");
  scenes
      << "scene,first_frame,frames,marker_diameter_px,blur_sigma_px,motion_blur_px,motion_blur_angle_deg,noise_sigma,"
         "jpeg_quality,light_ratio,vignetting,tilt_deg,k1,floor,floor_source,floor_grey,clutter_items,robots\n";
  char line[512];
  int frame = 0;
  for (int k = opt.first_scene; frame < opt.frames; ++k) {
    const vision::StressScene scene =
        lab ? vision::make_lab_scene(opt.seed, k, lab_options) : vision::make_stress_scene(opt.seed, k, stress);
    const vision::StressConditions& c = scene.conditions;
    std::snprintf(line, sizeof line, "%d,%d,%zu,%.2f,%.3f,%.3f,%.1f,%.2f,%d,%.3f,%.3f,%.2f,%.4f,%s,%s,%.1f,%d,%d\n", k,
                  frame, scene.frames.size(), c.marker_diameter_px, c.blur_sigma_px, c.motion_blur_px,
                  c.motion_blur_angle_deg, c.noise_sigma, c.jpeg_quality, c.light_ratio, c.vignetting, c.tilt_deg, c.k1,
                  vision::floor_name(c.floor), c.floor_source.c_str(), c.floor_grey, c.clutter_items, c.robots);
    scenes << line;
    std::snprintf(line, sizeof line, "scene_%04d.yaml", k);
    if (const std::string err =
            vision::save_field_calibration(scene.calibration, (dir / "calibration" / line).string());
        !err.empty()) {
      spdlog::error("{}", err);
      return kExitFailure;
    }
    for (std::size_t f = 0; f < scene.frames.size() && frame < opt.frames; ++f, ++frame) {
      std::snprintf(line, sizeof line, "frame_%04d.png", frame);
      if (!cv::imwrite((dir / "frames" / line).string(), scene.frames[f])) {
        spdlog::error("cannot write '{}'", (dir / "frames" / line).string());
        return kExitFailure;
      }
      for (const auto& t : scene.truth[f]) {
        std::snprintf(line, sizeof line, "%d,%d,%.3f,%.3f,%.3f,%d,%.2f,%.4f,%d\n", frame, t.id, t.u, t.v, t.heading_deg,
                      k, t.diameter_px, t.occluded, t.touching ? 1 : 0);
        truth << line;
      }
    }
  }
  std::ofstream about(dir / "scene.txt");
  about << "rendered by: rilbed synth --preset " << opt.preset << " --frames " << opt.frames << " --seed " << opt.seed
        << " --scene " << opt.first_scene << " --frames-per-scene " << opt.frames_per_scene << " --width " << opt.width
        << " --height " << opt.height
        << "\nfamily 6ucp, IDs 1..8; each scene's conditions in scenes.csv, its calibration in "
           "calibration/scene_NNNN.yaml\n";
  std::printf("wrote %d frames (frames/*.png), ground_truth.csv, scenes.csv, calibration/ and scene.txt to %s\n",
              opt.frames, opt.out.c_str());
  return 0;
}

int run_synth(const SynthOptions& opt) {
  if (opt.preset == "stress" || opt.preset == "lab") return run_stress_synth(opt, opt.out);
  vision::ScenePreset preset;
  try {
    preset = vision::scene_preset(opt.preset, {opt.width, opt.height});
  } catch (const std::invalid_argument& e) {
    spdlog::error("--preset: {}", e.what());
    return kExitUsage;
  }
  std::error_code ec;
  std::filesystem::create_directories(opt.out, ec);
  if (ec) {
    spdlog::error("--out: cannot create '{}': {}", opt.out, ec.message());
    return kExitFailure;
  }
  const std::filesystem::path dir(opt.out);
  // The MJPG writer does the compression, once, at the preset's quality: exactly what a
  // camera streaming MJPG delivers.
  const int quality = preset.conditions.jpeg_quality > 0 ? preset.conditions.jpeg_quality : 95;
  preset.conditions.jpeg_quality = 0;
  vision::SyntheticCamera camera(preset.camera, vision::MarkerFamily::six_ucp(), preset.conditions, preset.clutter);

  cv::VideoWriter video;
  const bool images = opt.format != "avi";
  if (!images) {
    const auto path = (dir / "video.avi").string();
    video.open(path, cv::CAP_OPENCV_MJPEG, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), opt.fps,
               preset.camera.image_size);
    if (!video.isOpened()) {
      spdlog::error("cannot write '{}'", path);
      return kExitFailure;
    }
    video.set(cv::VIDEOWRITER_PROP_QUALITY, quality);
  } else {
    std::filesystem::create_directories(dir / "frames", ec);
    if (ec) {
      spdlog::error("cannot create '{}': {}", (dir / "frames").string(), ec.message());
      return kExitFailure;
    }
  }
  std::ofstream truth(dir / "ground_truth.csv");
  truth << "frame,id,u,v,heading_deg,x_m,y_m,theta_deg\n";
  cv::RNG rng(opt.seed);
  char line[256];
  for (int f = 0; f < opt.frames; ++f) {
    const auto robots = vision::robots_at(f / opt.fps, opt.robots, preset, static_cast<unsigned>(opt.seed));
    const cv::Mat frame = camera.render(robots, rng);
    if (images) {
      // JPEG frames at the camera's quality are byte for byte what an MJPG stream carries.
      std::snprintf(line, sizeof line, "frame_%04d.%s", f, opt.format.c_str());
      if (!cv::imwrite((dir / "frames" / line).string(), frame, {cv::IMWRITE_JPEG_QUALITY, quality})) {
        spdlog::error("cannot write '{}'", (dir / "frames" / line).string());
        return kExitFailure;
      }
    } else {
      video.write(frame);
    }
    for (const auto& t : camera.truth(robots)) {
      if (!t.visible) continue;
      std::snprintf(line, sizeof line, "%d,%d,%.3f,%.3f,%.3f,%.5f,%.5f,%.3f\n", f, t.id, t.u, t.v, t.heading_deg, t.x_m,
                    t.y_m, t.theta_deg);
      truth << line;
    }
  }

  const vision::FieldCalibration calib = preset.camera.field_calibration(preset.field_width_m, preset.field_height_m);
  if (const std::string err = vision::save_field_calibration(calib, (dir / "calibration.yaml").string());
      !err.empty()) {
    spdlog::error("{}", err);
    return kExitFailure;
  }
  std::ofstream about(dir / "scene.txt");
  about << "rendered by: rilbed synth --preset " << opt.preset << " --frames " << opt.frames << " --fps " << opt.fps
        << " --robots " << opt.robots << " --seed " << opt.seed << " --width " << opt.width << " --height "
        << opt.height << " --format " << opt.format << "\njpeg quality: " << quality
        << "\nmarker diameter: " << preset.marker_diameter_m << " m, family 6ucp, IDs 1.." << opt.robots
        << "\nfield: " << preset.field_width_m << " x " << preset.field_height_m << " m\n";
  std::printf("wrote %d frames (%s), ground_truth.csv, calibration.yaml and scene.txt to %s\n", opt.frames,
              images ? ("frames/*." + opt.format).c_str() : "video.avi", opt.out.c_str());
  return 0;
}

}  // namespace

void add_synth_command(CLI::App& app) {
  auto opt = std::make_shared<SynthOptions>();
  CLI::App* cmd = app.add_subcommand("synth", "Render footage with ground truth from the synthetic overhead camera");
  cmd->add_option("--preset", opt->preset,
                  "nominal, hard, stress (every scene's conditions drawn at random from wide ranges; PNG frames, "
                  "per-scene conditions and calibration) or lab (the second generator: light traced from lamp to "
                  "JPEG, scenes plain, hard and harsh in turn; frames as stress's)")
      ->capture_default_str();
  cmd->add_option("--scene", opt->first_scene, "stress, lab: the first scene written (scene K of the seed's set)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--frames-per-scene", opt->frames_per_scene, "stress, lab: frames of each scene's clip")
      ->capture_default_str()
      ->check(CLI::Range(1, 64));
  cmd->add_option("--out", opt->out, "Output directory")->capture_default_str();
  cmd->add_option("--frames", opt->frames, "Number of frames")->capture_default_str()->check(CLI::PositiveNumber);
  cmd->add_option("--fps", opt->fps, "Frames per second")->capture_default_str()->check(CLI::PositiveNumber);
  cmd->add_option("--robots", opt->robots, "Robots (IDs 1..N, N <= 8)")->capture_default_str()->check(CLI::Range(1, 8));
  cmd->add_option("--seed", opt->seed, "Seed of paths and noise")->capture_default_str();
  cmd->add_option("--width", opt->width, "Image width")->capture_default_str()->check(CLI::Range(160, 4096));
  CLI::Option* height = cmd->add_option("--height", opt->height, "Image height (stress: 960 unless given)")
                            ->capture_default_str()
                            ->check(CLI::Range(120, 4096));
  cmd->add_option("--format", opt->format,
                  "avi (MJPG video.avi), jpg (frames/frame_%04d.jpg at the preset's MJPG quality) or png")
      ->capture_default_str()
      ->check(CLI::IsMember({"avi", "jpg", "png"}));
  cmd->callback([opt, height] {
    // The stress set's and the lab footage's frames are 1280x960.
    if ((opt->preset == "stress" || opt->preset == "lab") && height->count() == 0) opt->height = 960;
    exit_code() = run_synth(*opt);
  });
}

}  // namespace rilbed::app
