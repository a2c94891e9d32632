#include "agents/track_features.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace rilbed::agents {

TrackArray TrackArray::of(std::span<const environment::TrackSensorConfig> elements) {
  TrackArray array;
  for (const environment::TrackSensorConfig& config : elements) {
    const environment::TrackFootprint footprint = environment::track_footprint(config);
    Vec2 centre{};
    for (const Vec2& p : footprint.points_m) centre = centre + p;
    if (!footprint.points_m.empty()) centre = centre / static_cast<double>(footprint.points_m.size());
    array.points_m.push_back(centre);
    for (const Vec2& p : footprint.points_m)
      array.footprint_radius_m = std::max(array.footprint_radius_m, (p - centre).norm());
  }
  return array;
}

int TrackArray::centre_element() const {
  int best = -1;
  for (int i = 0; i < static_cast<int>(points_m.size()); ++i) {
    const Vec2 p = points_m[static_cast<std::size_t>(i)];
    if (best < 0) {
      best = i;
      continue;
    }
    const Vec2 b = points_m[static_cast<std::size_t>(best)];
    if (std::abs(p.y) < std::abs(b.y) - 1e-6 || (std::abs(std::abs(p.y) - std::abs(b.y)) <= 1e-6 && p.x < b.x))
      best = i;
  }
  return best;
}

std::vector<int> arm_sides(const TrackArray& array, const TrackReadingConfig& config) {
  std::vector<int> sides;
  const double reach = 0.5 * config.tape_width_m + array.footprint_radius_m + config.arm_clearance_m;
  for (const Vec2& p : array.points_m) sides.push_back(p.y >= reach ? 1 : p.y <= -reach ? -1 : 0);
  return sides;
}

TrackArrayReading read_track_array(const TrackArray& array, std::span<const int> track,
                                   const TrackReadingConfig& config, std::span<const int> sides, double near_m) {
  TrackArrayReading r;
  const double on = config.on_fraction * config.max_value;
  const std::size_t n = std::min({track.size(), array.points_m.size(), sides.size()});
  bool middle_on = false, left_on = false, right_on = false;
  for (std::size_t i = 0; i < n; ++i) {
    if (track[i] < on) continue;
    ++r.elements_on;
    r.offset_m += array.points_m[i].y;
    if (sides[i] > 0) left_on = true;
    if (sides[i] < 0) right_on = true;
    if (sides[i] == 0) middle_on = true;
  }
  r.on_track = r.elements_on > 0;
  if (r.on_track) r.offset_m /= r.elements_on;
  if (r.on_track) {
    // Runs of elements that see tape, neighbours across the front (by lateral place).
    std::vector<std::size_t> order(n);
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::sort(order.begin(), order.end(), [&](auto a, auto b) { return array.points_m[a].y < array.points_m[b].y; });
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < n;) {
      if (track[order[k]] < on) {
        ++k;
        continue;
      }
      double sum = 0.0;
      int count = 0;
      for (; k < n && track[order[k]] >= on; ++k, ++count) sum += array.points_m[order[k]].y;
      const double centre = sum / count;
      if (std::abs(centre - near_m) < best) {
        best = std::abs(centre - near_m);
        r.run_offset_m = centre;
      }
    }
  }
  // An arm is tape beyond the tape's own edge joined to tape in the middle; an outer
  // element alone is the robot far off the tape's centre.
  r.arm_left = left_on && middle_on;
  r.arm_right = right_on && middle_on;
  return r;
}

std::string_view track_feature_name(TrackFeatureKind kind) {
  switch (kind) {
    case TrackFeatureKind::kNone: return "none";
    case TrackFeatureKind::kEnd: return "end";
    case TrackFeatureKind::kCornerLeft: return "corner_left";
    case TrackFeatureKind::kCornerRight: return "corner_right";
    case TrackFeatureKind::kTee: return "tee";
    case TrackFeatureKind::kCross: return "cross";
  }
  return "?";
}

TrackFeatureKind classify_ways(std::span<const double> ways_rad, double arrival_heading_rad,
                               const BranchScanConfig& config, int* way_in) {
  int in = -1;
  double nearest = 1e9;
  for (int k = 0; k < static_cast<int>(ways_rad.size()); ++k) {
    const double off = std::abs(wrap_rad_pi(ways_rad[static_cast<std::size_t>(k)] - arrival_heading_rad - kPi));
    if (off < nearest) {
      nearest = off;
      in = k;
    }
  }
  if (way_in) *way_in = in;
  switch (ways_rad.size()) {
    case 0: return TrackFeatureKind::kNone;
    case 1: return TrackFeatureKind::kEnd;
    case 2: {
      const double between = std::abs(wrap_rad_pi(ways_rad[0] - ways_rad[1]));
      if (between >= kPi - deg_to_rad(config.straight_deg)) return TrackFeatureKind::kNone;
      const double other = ways_rad[in == 0 ? 1 : 0];
      return wrap_rad_pi(other - arrival_heading_rad) > 0.0 ? TrackFeatureKind::kCornerLeft
                                                            : TrackFeatureKind::kCornerRight;
    }
    case 3: return TrackFeatureKind::kTee;
    default: return TrackFeatureKind::kCross;
  }
}

Vec2 meet_of_lines(std::span<const Vec2> points_m, std::span<const double> directions_rad, Vec2 fallback) {
  // Minimise the sum of squared distances to the lines: sum (I - d d^T) (x - p) = 0.
  double a = 0, b = 0, c = 0, rx = 0, ry = 0;
  const std::size_t n = std::min(points_m.size(), directions_rad.size());
  if (n < 2) return fallback;
  for (std::size_t k = 0; k < n; ++k) {
    const double dx = std::cos(directions_rad[k]), dy = std::sin(directions_rad[k]);
    const double m00 = 1 - dx * dx, m01 = -dx * dy, m11 = 1 - dy * dy;
    a += m00;
    b += m01;
    c += m11;
    rx += m00 * points_m[k].x + m01 * points_m[k].y;
    ry += m01 * points_m[k].x + m11 * points_m[k].y;
  }
  const double det = a * c - b * b;
  // Nearly parallel lines (a straight tape) meet nowhere useful.
  if (det < 0.05 * (a + c) * (a + c) / 4) return fallback;
  return {(c * rx - b * ry) / det, (a * ry - b * rx) / det};
}

BranchScan::BranchScan(TrackArray array, TrackReadingConfig reading, BranchScanConfig config)
    : array_(std::move(array)), reading_(reading), config_(config) {
  for (const Vec2& p : array_.points_m) farthest_m_ = std::max(farthest_m_, p.norm());
  for (int i = 0; i < static_cast<int>(array_.points_m.size()); ++i) {
    const double r = array_.points_m[static_cast<std::size_t>(i)].norm();
    // Elements on the axis of the turn see one spot, not a circle.
    if (r < 0.008) continue;
    used_.push_back(i);
    primary_.push_back(r >= config_.min_radius_share * farthest_m_);
  }
  samples_.resize(used_.size());
}

void BranchScan::start(Pose2 pose, double arrival_heading_rad) {
  for (auto& s : samples_) s.clear();
  start_ = pose;
  last_heading_rad_ = pose.heading_rad;
  turned_rad_ = 0.0;
  arrival_heading_rad_ = arrival_heading_rad;
}

void BranchScan::add(Pose2 pose, std::span<const int> track) {
  turned_rad_ += std::abs(wrap_rad_pi(pose.heading_rad - last_heading_rad_));
  last_heading_rad_ = pose.heading_rad;
  // Only the first full turn: later samples would count crossings twice.
  if (turned_rad_ > 2 * kPi + 1e-9) return;
  const double on = reading_.on_fraction * reading_.max_value;
  for (std::size_t u = 0; u < used_.size(); ++u) {
    const std::size_t i = static_cast<std::size_t>(used_[u]);
    if (i >= track.size()) continue;
    const Vec2 p = array_.points_m[i];
    samples_[u].push_back({pose.heading_rad + std::atan2(p.y, p.x), pose.position_m, track[i] >= on});
  }
}

bool BranchScan::complete() const { return turned_rad_ >= 2 * kPi; }

namespace {

struct Crossing {
  double angle_rad;  // direction from the robot's centre, [0, 2 pi)
  double span_rad;   // of the arc the element saw tape over
  Vec2 point_m;      // on the tape's centre line
  double radius_m;   // the element's distance from the robot's centre
};

double unit_angle(double a) {
  a = std::fmod(a, 2 * kPi);
  return a < 0 ? a + 2 * kPi : a;
}

double angle_gap(double a, double b) { return std::abs(wrap_rad_pi(a - b)); }

}  // namespace

std::vector<BranchScan::Way> BranchScan::crossings_to_ways() const {
  std::vector<Crossing> primary, secondary;
  for (std::size_t u = 0; u < used_.size(); ++u) {
    auto samples = samples_[u];
    if (samples.size() < 3) continue;
    for (auto& s : samples) s.angle_rad = unit_angle(s.angle_rad);
    std::sort(samples.begin(), samples.end(), [](const auto& a, const auto& b) { return a.angle_rad < b.angle_rad; });
    const std::size_t n = samples.size();
    if (std::all_of(samples.begin(), samples.end(), [](const auto& s) { return s.on; })) continue;
    // Start the circular walk at an off sample, so no run straddles the start.
    std::size_t first = 0;
    while (samples[first].on) ++first;
    const double radius = array_.points_m[static_cast<std::size_t>(used_[u])].norm();
    for (std::size_t k = 1; k <= n; ++k) {
      const std::size_t i = (first + k) % n;
      if (!samples[i].on) continue;
      std::size_t last = i, length = 1;
      while (samples[(last + 1) % n].on) {
        last = (last + 1) % n;
        ++length;
      }
      // The arc's ends lie between the last sample off and the first on (and back).
      const std::size_t before = (i + n - 1) % n, after = (last + 1) % n;
      auto gap = [](double from, double to) { return to >= from ? to - from : to + 2 * kPi - from; };
      const double begin = samples[i].angle_rad - 0.5 * gap(samples[before].angle_rad, samples[i].angle_rad);
      const double span = gap(samples[i].angle_rad, samples[last].angle_rad) +
                          0.5 * gap(samples[before].angle_rad, samples[i].angle_rad) +
                          0.5 * gap(samples[last].angle_rad, samples[after].angle_rad);
      const double middle = begin + 0.5 * span;
      const Vec2 centre = samples[(i + length / 2) % n].centre_m;
      auto crossing = [&](double angle) {
        return Crossing{unit_angle(angle), span, centre + Vec2{std::cos(angle), std::sin(angle)} * radius, radius};
      };
      // Two tapes leaving at a sharp angle can run together on the circle: an arc much
      // wider than one tape makes is two ways, one at each of its ends.
      const double single =
          2 * std::asin(std::min(1.0, (0.5 * reading_.tape_width_m + 0.5 * array_.footprint_radius_m) / radius));
      if (primary_[u] && span > 1.6 * single && span < kPi) {
        primary.push_back(crossing(begin + 0.5 * single));
        primary.push_back(crossing(begin + span - 0.5 * single));
      } else {
        (primary_[u] ? primary : secondary).push_back(crossing(middle));
      }
      k += length;  // past the run (and its closing off sample)
    }
  }
  std::sort(primary.begin(), primary.end(), [](const auto& a, const auto& b) { return a.angle_rad < b.angle_rad; });
  // Crossings of the outer elements that point the same way are one way.
  std::vector<std::vector<Crossing>> groups;
  const double merge = deg_to_rad(config_.merge_deg);
  for (const Crossing& c : primary) {
    if (!groups.empty() && c.angle_rad - groups.back().back().angle_rad < merge)
      groups.back().push_back(c);
    else
      groups.push_back({c});
  }
  if (groups.size() > 1 && groups.front().front().angle_rad + 2 * kPi - groups.back().back().angle_rad < merge) {
    groups.front().insert(groups.front().end(), groups.back().begin(), groups.back().end());
    groups.pop_back();
  }
  std::vector<Way> ways;
  for (const auto& g : groups) {
    Way w;
    for (const Crossing& c : g) w.outer_m = w.outer_m + c.point_m;
    w.outer_m = w.outer_m / static_cast<double>(g.size());
    w.outer_radius_m = g.front().radius_m;
    ways.push_back(w);
  }
  // Nearer elements' crossings of the same way give a second point on its centre line,
  // hence its direction without assuming the robot turned on the node. A crossing wider
  // than one tape at that radius is two ways seen as one, and not used.
  for (const Crossing& c : secondary) {
    const double reach = 0.5 * reading_.tape_width_m + array_.footprint_radius_m + 0.003;
    const double widest = 2 * std::asin(std::min(1.0, reach / c.radius_m)) + deg_to_rad(10.0);
    if (c.span_rad > widest) continue;
    Way* best = nullptr;
    for (Way& w : ways) {
      const Vec2 d = w.outer_m - start_.position_m;
      if (angle_gap(std::atan2(d.y, d.x), c.angle_rad) < 0.5 * merge &&
          (!best || (c.point_m - w.outer_m).norm() < (c.point_m - best->outer_m).norm()))
        best = &w;
    }
    if (!best) continue;
    best->inner_m = best->inner_m + c.point_m;
    best->inner_radius_m += c.radius_m;
    ++best->inner_count;
  }
  for (Way& w : ways) {
    if (w.inner_count == 0) continue;
    w.inner_m = w.inner_m / static_cast<double>(w.inner_count);
    w.inner_radius_m /= w.inner_count;
  }
  return ways;
}

ScanResult BranchScan::result() const {
  const std::vector<Way> ways = crossings_to_ways();
  std::vector<Vec2> points;
  std::vector<double> directions;
  // Ways whose direction two radii tell; the node is where their lines meet.
  for (const Way& w : ways) {
    if (w.inner_count == 0 || w.outer_radius_m - w.inner_radius_m < 0.006) continue;
    const Vec2 d = w.outer_m - w.inner_m;
    points.push_back(w.outer_m);
    directions.push_back(std::atan2(d.y, d.x));
  }
  Vec2 node = meet_of_lines(points, directions, start_.position_m);
  // The node is where the ways' lines through both their points pass nearest: the
  // meeting point when it fits them better than where the robot turned (a way's inner
  // point from the wrong tape, near a sharp fork, pulls the meeting point off), and
  // never far from where the robot turned.
  auto misfit = [&](Vec2 at) {
    double sum = 0.0;
    for (const Way& w : ways) {
      if (w.inner_count == 0) continue;
      const Vec2 d = w.outer_m - at;
      const double n = d.norm();
      if (n > 0) sum += std::abs(d.cross(w.inner_m - at)) / n;
    }
    return sum;
  };
  if ((node - start_.position_m).norm() > 0.4 * farthest_m_ + 0.01 || misfit(node) >= misfit(start_.position_m))
    node = start_.position_m;
  ScanResult result;
  for (const Way& w : ways) {
    const Vec2 d = w.outer_m - node;
    result.ways_rad.push_back(std::atan2(d.y, d.x));
    result.way_points_m.push_back(w.outer_m);
  }
  result.node_m = node;
  result.kind = classify_ways(result.ways_rad, arrival_heading_rad_, config_, &result.way_in);
  if (result.kind == TrackFeatureKind::kNone || result.kind == TrackFeatureKind::kEnd)
    result.node_m = start_.position_m;
  return result;
}

}  // namespace rilbed::agents
