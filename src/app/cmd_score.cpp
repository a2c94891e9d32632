// `rilbed score`: compares `rilbed detect` output with ground truth.
#include <spdlog/spdlog.h>

#include <iostream>

#include "app/commands.hpp"
#include "vision/detection_score.hpp"

namespace rilbed::app {

void add_score_command(CLI::App& app) {
  struct Options {
    std::string truth, detections;
    double radius_px = 5.0;
  };
  auto opt = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("score", "Compare detections (rilbed detect --csv) with ground truth");
  cmd->add_option("--truth", opt->truth, "Ground-truth CSV (frame,id,u,v,heading_deg[,x_m,y_m,theta_deg])")->required();
  cmd->add_option("--detections", opt->detections, "Detections CSV from rilbed detect")->required();
  cmd->add_option("--radius-px", opt->radius_px, "Largest centre distance that still counts as found")
      ->capture_default_str();
  cmd->callback([opt] {
    const auto truth = vision::read_marker_csv(opt->truth);
    const auto det = vision::read_marker_csv(opt->detections);
    for (const auto* r : {&truth, &det}) {
      if (!r->ok()) {
        spdlog::error("{}", r->error);
        exit_code() = kExitFailure;
        return;
      }
    }
    std::cout << vision::format_score(vision::score_detections(truth.rows, det.rows, opt->radius_px));
  });
}

}  // namespace rilbed::app
