#include "vision/stress_score.hpp"

#include <cmath>
#include <cstdio>
#include <map>

#include "core/geometry.hpp"

namespace rilbed::vision {

namespace {

double signed_heading_error(double reported_deg, double true_deg) {
  double e = std::fmod(reported_deg - true_deg, 360.0);
  if (e <= -180.0) e += 360.0;
  if (e > 180.0) e -= 360.0;
  return e;
}

}  // namespace

void StressTally::add(const StressScene& scene, int frame, const std::vector<MarkerDetection>& found, int declined) {
  ++frames_;
  declined_ += declined;
  const auto& truth = scene.truth.at(static_cast<std::size_t>(frame));
  const StressConditions& c = scene.conditions;
  const double blur_px = std::sqrt(c.blur_sigma_px * c.blur_sigma_px + c.motion_blur_px * c.motion_blur_px / 12.0);
  std::vector<bool> used(found.size(), false);
  // The marker a point lies on (within half its diameter), or -1.
  auto marker_at = [&](double u, double v) {
    int best = -1;
    double best_d = 1e300;
    for (std::size_t i = 0; i < truth.size(); ++i) {
      const double d = std::hypot(u - truth[i].u, v - truth[i].v);
      if (d <= truth[i].diameter_px / 2 && d < best_d) {
        best = static_cast<int>(i);
        best_d = d;
      }
    }
    return best;
  };
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const StressTruth& t = truth[i];
    StressOutcome o;
    o.scene = scene.index;
    o.frame = frame;
    o.id = t.id;
    o.diameter_px = t.diameter_px;
    o.occluded = t.occluded;
    o.blur_px = blur_px;
    o.touching = t.touching;
    o.floor = c.floor;
    // Its own report: the nearest detection of its ID that lies on it.
    int mine = -1;
    double mine_d = 1e300;
    for (std::size_t k = 0; k < found.size(); ++k) {
      if (used[k] || found[k].id != t.id || marker_at(found[k].u, found[k].v) != static_cast<int>(i)) continue;
      const double d = std::hypot(found[k].u - t.u, found[k].v - t.v);
      if (d < mine_d) {
        mine = static_cast<int>(k);
        mine_d = d;
      }
    }
    if (mine >= 0) {
      used[static_cast<std::size_t>(mine)] = true;
      const double e = signed_heading_error(found[static_cast<std::size_t>(mine)].heading_deg, t.heading_deg);
      if (std::abs(e) > kStressWrongHeadingDeg) {
        mistakes_.push_back({StressMistake::Kind::kWrongHeading, scene.index, frame, t.id, t.id,
                             found[static_cast<std::size_t>(mine)].u, found[static_cast<std::size_t>(mine)].v, e});
      } else {
        o.found = true;
        o.centre_error_px = mine_d;
        o.heading_error_deg = e;
      }
    }
    if (t.visible) outcomes_.push_back(o);
  }
  for (std::size_t k = 0; k < found.size(); ++k) {
    if (used[k]) continue;
    const int on = marker_at(found[k].u, found[k].v);
    StressMistake m;
    m.scene = scene.index;
    m.frame = frame;
    m.id = found[k].id;
    m.u = found[k].u;
    m.v = found[k].v;
    if (on < 0) {
      m.kind = StressMistake::Kind::kFalseDetection;
    } else {
      m.true_id = truth[static_cast<std::size_t>(on)].id;
      m.kind = m.true_id == m.id ? StressMistake::Kind::kDuplicate : StressMistake::Kind::kWrongId;
    }
    mistakes_.push_back(m);
  }
}

int StressTally::count(StressMistake::Kind kind) const {
  int n = 0;
  for (const auto& m : mistakes_) n += m.kind == kind;
  return n;
}

StressStats summarise(const std::vector<StressOutcome>& outcomes,
                      const std::function<bool(const StressOutcome&)>& keep) {
  StressStats s;
  double centre2 = 0, heading2 = 0;
  std::map<int, std::pair<double, int>> by_id;  // id -> (sum of heading errors, count)
  for (const StressOutcome& o : outcomes) {
    if (!keep(o)) continue;
    ++s.markers;
    if (!o.found) continue;
    ++s.found;
    centre2 += o.centre_error_px * o.centre_error_px;
    heading2 += o.heading_error_deg * o.heading_error_deg;
    s.centre_max_px = std::max(s.centre_max_px, o.centre_error_px);
    s.heading_max_deg = std::max(s.heading_max_deg, std::abs(o.heading_error_deg));
    auto& b = by_id[o.id];
    b.first += o.heading_error_deg;
    ++b.second;
  }
  if (s.found) {
    s.centre_rms_px = std::sqrt(centre2 / s.found);
    s.heading_rms_deg = std::sqrt(heading2 / s.found);
  }
  for (const auto& [id, b] : by_id) {
    const double mean = b.first / b.second;
    if (std::abs(mean) > std::abs(s.worst_bias_deg) || s.worst_bias_id == 0) {
      s.worst_bias_id = id;
      s.worst_bias_deg = mean;
    }
  }
  return s;
}

const char* mistake_name(StressMistake::Kind kind) {
  switch (kind) {
    case StressMistake::Kind::kWrongId: return "wrong ID";
    case StressMistake::Kind::kFalseDetection: return "false detection";
    case StressMistake::Kind::kWrongHeading: return "heading > 10 deg off";
    case StressMistake::Kind::kDuplicate: return "duplicate";
  }
  return "?";
}

std::string list_mistakes(const StressTally& tally) {
  std::string out;
  for (const auto& m : tally.mistakes()) {
    char line[160];
    std::snprintf(line, sizeof line, "scene %d frame %d: %s, ID %d reported at (%.1f, %.1f) on marker %d\n", m.scene,
                  m.frame, mistake_name(m.kind), m.id, m.u, m.v, m.true_id);
    out += line;
  }
  return out;
}

}  // namespace rilbed::vision
