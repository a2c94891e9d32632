#include "agents/track_explore.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <queue>

namespace rilbed::agents {

namespace {

std::string fixed(double v, int digits = 4) {
  char buffer[48];
  std::snprintf(buffer, sizeof buffer, "%.*f", digits, v);
  return buffer;
}

Vec2 unit(double angle_rad) { return {std::cos(angle_rad), std::sin(angle_rad)}; }

double angle_between_deg(Vec2 a, Vec2 b) { return rad_to_deg(std::abs(std::atan2(a.cross(b), a.dot(b)))); }

double distance_to_line(Vec2 p, Vec2 a, Vec2 b) {
  const Vec2 d = b - a;
  const double n = d.norm();
  return n > 0 ? std::abs(d.cross(p - a)) / n : (p - a).norm();
}

}  // namespace

std::string_view track_node_kind_of(TrackFeatureKind kind) {
  switch (kind) {
    case TrackFeatureKind::kEnd: return "end";
    case TrackFeatureKind::kCornerLeft:
    case TrackFeatureKind::kCornerRight: return "corner";
    case TrackFeatureKind::kTee: return "tee";
    case TrackFeatureKind::kCross: return "cross";
    case TrackFeatureKind::kNone: break;
  }
  return "none";
}

int ExploredTrackMap::nearest_node(Vec2 at, double radius_m) const {
  int best = -1;
  double best_d = radius_m;
  for (const Node& n : nodes) {
    const double d = (n.position_m - at).norm();
    if (d <= best_d) {
      best_d = d;
      best = n.id;
    }
  }
  return best;
}

int ExploredTrackMap::nearest_way(int node, double direction_rad) const {
  int best = -1;
  double best_off = std::numeric_limits<double>::infinity();
  const auto& ways = nodes[static_cast<std::size_t>(node)].ways;
  // Ways with tape first; a node whose ways were all struck off still answers one.
  for (const bool struck : {false, true}) {
    for (int w = 0; w < static_cast<int>(ways.size()); ++w) {
      if ((ways[static_cast<std::size_t>(w)].edge == kNoTape) != struck) continue;
      const double off = std::abs(wrap_rad_pi(ways[static_cast<std::size_t>(w)].direction_rad - direction_rad));
      if (off < best_off) {
        best_off = off;
        best = w;
      }
    }
    if (best >= 0) return best;
  }
  return best;
}

bool ExploredTrackMap::has_untaken_way() const {
  for (const Node& n : nodes)
    for (const Way& w : n.ways)
      if (w.edge == kUntaken) return true;
  return false;
}

std::vector<std::pair<int, int>> ExploredTrackMap::route_to_untaken(int from) const {
  const std::size_t n = nodes.size();
  std::vector<double> dist(n, std::numeric_limits<double>::infinity());
  std::vector<std::pair<int, int>> came(n, {-1, -1});  // (previous node, the way left by)
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> open;
  dist[static_cast<std::size_t>(from)] = 0;
  open.push({0.0, from});
  int goal = -1;
  while (!open.empty()) {
    const auto [d, v] = open.top();
    open.pop();
    if (d > dist[static_cast<std::size_t>(v)]) continue;
    const Node& node = nodes[static_cast<std::size_t>(v)];
    if (std::any_of(node.ways.begin(), node.ways.end(), [](const Way& w) { return w.edge == kUntaken; })) {
      goal = v;
      break;
    }
    for (int w = 0; w < static_cast<int>(node.ways.size()); ++w) {
      const int e = node.ways[static_cast<std::size_t>(w)].edge;
      if (e < 0) continue;
      const Edge& edge = edges[static_cast<std::size_t>(e)];
      const int to = edge.from == v && edge.from_way == w ? edge.to : edge.from;
      const double nd = d + std::max(edge.length_m, 1e-3);
      if (nd < dist[static_cast<std::size_t>(to)]) {
        dist[static_cast<std::size_t>(to)] = nd;
        came[static_cast<std::size_t>(to)] = {v, w};
        open.push({nd, to});
      }
    }
  }
  std::vector<std::pair<int, int>> route;
  if (goal < 0 || goal == from) return route;
  for (int v = goal; v != from; v = came[static_cast<std::size_t>(v)].first)
    route.push_back(came[static_cast<std::size_t>(v)]);
  std::reverse(route.begin(), route.end());
  return route;
}

std::string ExploredTrackMap::to_json() const {
  std::string out = "{\"nodes\": [";
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const Node& n = nodes[i];
    out += (i ? ", " : "") + std::string("{\"id\": ") + std::to_string(n.id) + ", \"kind\": \"" +
           std::string(track_node_kind_of(n.kind)) + "\", \"x_m\": " + fixed(n.position_m.x) +
           ", \"y_m\": " + fixed(n.position_m.y) + "}";
  }
  out += "], \"edges\": [";
  for (std::size_t i = 0; i < edges.size(); ++i) {
    const Edge& e = edges[i];
    out += (i ? ", " : "") + std::string("{\"from\": ") + std::to_string(e.from) + ", \"to\": " + std::to_string(e.to) +
           ", \"length_m\": " + fixed(e.length_m) + "}";
  }
  return out + "]}\n";
}

TrackExploreController::TrackExploreController(TrackArray array, TrackExploreConfig config)
    : array_(std::move(array)),
      config_(config),
      sides_(arm_sides(array_, config_.reading)),
      centre_element_(array_.centre_element()),
      odometry_(config_.wheel_base_m),
      scanner_(array_, config_.reading, config_.scan) {
  if (std::none_of(array_.points_m.begin(), array_.points_m.end(), [](Vec2 p) { return p.norm() >= 0.008; }))
    throw std::invalid_argument("track_explore needs track sensors 8 mm or more from the robot's centre");
  double ahead = 0.0;
  for (const Vec2& p : array_.points_m) ahead += p.x;
  sensor_ahead_m_ = ahead / static_cast<double>(array_.points_m.size());
}

void TrackExploreController::take_events(std::vector<ControllerEvent>& out) {
  for (auto& e : events_) out.push_back(std::move(e));
  events_.clear();
}

ControlOutput TrackExploreController::drive(double speed_mps, double turn_radps, std::string_view behaviour) const {
  return {wheels_from_twist(speed_mps, turn_radps), behaviour};
}

ControlOutput TrackExploreController::step(const ControlInput& input) {
  if (!input.sensors.odometry) throw ControllerError("track_explore needs the wheel counters (sensors: odometer)");
  odometry_.update(*input.sensors.odometry);
  if (!anchored_) {
    // The one pose it is told: where the lab put it. Everything after is odometry.
    if (input.pose) odometry_.set_pose(*input.pose);
    anchored_ = true;
  }
  if (config_.time_limit_s > 0 && static_cast<double>(input.t_us) * 1e-6 >= config_.time_limit_s) mode_ = Mode::kDone;
  const TrackArrayReading reading =
      read_track_array(array_, input.sensors.track, config_.reading, sides_, followed_tape_offset());
  switch (mode_) {
    case Mode::kSearch: return search(input, reading);
    case Mode::kAcquire: return acquire();
    case Mode::kApproach: return approach();
    case Mode::kScan: return scan(input);
    case Mode::kCentre: return centre();
    case Mode::kTurn: return turn(reading);
    case Mode::kFind: return find(reading);
    case Mode::kFollow: return follow(reading);
    case Mode::kDone: break;
  }
  return drive(0, 0, "done");
}

double TrackExploreController::followed_tape_offset() const {
  if (mode_ != Mode::kFollow) return 0.0;
  const double since_leaving = odometry_.travelled_m() - leg_.start_travel_m;
  if (leg_.from_node < 0 || since_leaving > config_.leave_zone_m) return last_offset_m_;
  // Leaving a node, the other ways still pass under the array: the tape to follow is the
  // one where the way it left by crosses the array's row.
  const auto& node = map_.nodes[static_cast<std::size_t>(leg_.from_node)];
  const Vec2 d = unit(node.ways[static_cast<std::size_t>(leg_.from_way)].direction_rad);
  const Pose2 pose = odometry_.pose();
  const Vec2 row = pose.position_m + unit(pose.heading_rad) * sensor_ahead_m_;
  const Vec2 across = unit(pose.heading_rad + kPi / 2);
  const double denominator = d.cross(across);
  if (std::abs(denominator) < 0.2) return last_offset_m_;
  return std::clamp(-d.cross(row - node.position_m) / denominator, -0.03, 0.03);
}

ControlOutput TrackExploreController::search(const ControlInput& input, const TrackArrayReading& reading) {
  const Pose2 pose = odometry_.pose();
  if (reading.on_track) {
    // Put the robot's centre where the array saw the tape, then look round: from there
    // every element's circle crosses the tape.
    Vec2 seen{};
    int count = 0;
    const double on = config_.reading.on_fraction * config_.reading.max_value;
    for (std::size_t i = 0; i < array_.points_m.size() && i < input.sensors.track.size(); ++i) {
      if (input.sensors.track[i] < on) continue;
      seen = seen + array_.points_m[i];
      ++count;
    }
    seen = seen / std::max(1, count);
    acquire_at_m_ = pose.position_m + unit(pose.heading_rad) * seen.x + unit(pose.heading_rad + kPi / 2) * seen.y;
    mode_ = Mode::kAcquire;
    on_leg_ = false;
    approach_heading_rad_ = pose.heading_rad;
    return acquire();
  }
  if (search_turning_) {
    // Turning away from a wall by a different angle each time: bouncing back and forth by
    // the same angle can circle the tapes for ever.
    const double error = wrap_rad_pi(search_heading_rad_ - pose.heading_rad);
    if (std::abs(error) > deg_to_rad(5.0))
      return drive(0, error > 0 ? config_.turn_radps : -config_.turn_radps, "avoid");
    search_turning_ = false;
  }
  const auto& prox = input.sensors.proximity;
  if (prox && obstacle_level(*prox, 0.2, 0.6) > 0.0) {
    const double left = (*prox)[0] + (*prox)[1] + (*prox)[2], right = (*prox)[3] + (*prox)[4] + (*prox)[5];
    const double away = deg_to_rad(100.0 + std::fmod(137.5 * ++search_bounces_, 70.0));
    search_heading_rad_ = wrap_rad_pi(pose.heading_rad + (left > right ? -away : away));
    search_turning_ = true;
    return drive(0, 0, "avoid");
  }
  return drive(config_.search_speed_mps, 0, "search");
}

ControlOutput TrackExploreController::acquire() {
  const Pose2 pose = odometry_.pose();
  const Vec2 to = acquire_at_m_ - pose.position_m;
  const double distance = to.norm();
  if (distance < 0.003) {
    start_scan();
    return drive(0, config_.scan_turn_radps, "scan");
  }
  const double error = wrap_rad_pi(std::atan2(to.y, to.x) - pose.heading_rad);
  if (std::abs(error) > deg_to_rad(90.0) && distance < 0.01) {
    // Just past it (a step's travel): close enough.
    start_scan();
    return drive(0, config_.scan_turn_radps, "scan");
  }
  if (std::abs(error) > deg_to_rad(15.0))
    return drive(0, error > 0 ? config_.turn_radps : -config_.turn_radps, "acquire");
  return drive(std::min(config_.speed_mps, std::max(0.02, 3.0 * distance)), 3.0 * error, "acquire");
}

ControlOutput TrackExploreController::approach() {
  const Pose2 pose = odometry_.pose();
  if (!approach_started_) {
    approach_started_ = true;
    approach_left_m_ = approach_until_m_ - odometry_.travelled_m();
    approach_from_m_ = odometry_.signed_travel_m();
  }
  const double left = approach_left_m_ - (odometry_.signed_travel_m() - approach_from_m_);
  if (left < -0.002) {
    // Past the node: back up to it.
    const double hold = 3.0 * wrap_rad_pi(approach_heading_rad_ - pose.heading_rad);
    return drive(-std::min(config_.speed_mps, std::max(0.02, -4.0 * left)), hold, "approach");
  }
  if (left <= 0.001) {
    start_scan();
    return drive(0, config_.scan_turn_radps, "scan");
  }
  const double hold = 3.0 * wrap_rad_pi(approach_heading_rad_ - pose.heading_rad);
  const double speed = std::min(config_.speed_mps, std::max(0.02, 4.0 * left));
  return drive(speed, hold, "approach");
}

void TrackExploreController::start_scan() {
  approach_started_ = false;
  scanner_start_m_ = odometry_.pose().position_m;
  scanner_.start(odometry_.pose(), approach_heading_rad_);
  mode_ = Mode::kScan;
}

ControlOutput TrackExploreController::scan(const ControlInput& input) {
  scanner_.add(odometry_.pose(), input.sensors.track);
  if (scanner_.complete()) {
    after_scan(scanner_.result());
    return drive(0, 0, "scan");
  }
  return drive(0, config_.scan_turn_radps, "scan");
}

void TrackExploreController::after_scan(const ScanResult& result) {
  if (verifying_node_ >= 0) {
    // The look from the node's centre: the ways it adds are the node's.
    const int node = verifying_node_;
    verifying_node_ = -1;
    auto& n = map_.nodes[static_cast<std::size_t>(node)];
    n.looked_from_centre = true;
    const Arrival look{result.kind,  n.position_m, result.ways_rad, result.way_points_m,
                       n.position_m, 0.0,          std::nullopt};
    merge_ways(node, look, n.position_m, 0.0);
    on_leg_ = false;
    route_.clear();
    leave(node);
    return;
  }
  if (result.ways_rad.empty()) {
    rescans_ = 0;
    on_leg_ = false;
    mode_ = Mode::kSearch;
    return;
  }
  // Where a known node is, the scan is of that node, whatever it made of it: a scan off
  // the node's centre can take a corner for plain tape.
  const bool plain = result.kind == TrackFeatureKind::kNone;
  const int known = on_leg_ && plain ? map_.nearest_node(result.node_m, 0.4 * config_.match_radius_m) : -1;
  // Found from the open field: only a node that cannot be plain tape seen off its centre
  // (an end, a junction) is one; the rest is a tape to follow.
  const bool acquired = !on_leg_ && (plain || result.ways_rad.size() == 2);
  if ((plain && known < 0) || acquired) {
    // Plain tape (drift, or found mid-edge): go on the way nearest the heading it had.
    int best = 0;
    for (int k = 1; k < static_cast<int>(result.ways_rad.size()); ++k)
      if (std::abs(wrap_rad_pi(result.ways_rad[static_cast<std::size_t>(k)] - approach_heading_rad_)) <
          std::abs(wrap_rad_pi(result.ways_rad[static_cast<std::size_t>(best)] - approach_heading_rad_)))
        best = k;
    target_heading_rad_ = result.ways_rad[static_cast<std::size_t>(best)];
    rescans_ = 0;
    if (!on_leg_) leg_ = {-1, -1, odometry_.travelled_m()};
    on_leg_ = true;
    mode_ = Mode::kTurn;
    return;
  }
  if (rescans_ == 0) arrival_length_m_ = odometry_.travelled_m() - leg_.start_travel_m;
  double length = arrival_length_m_;
  // A new node seen from off its centre: turn again where its ways seem to meet, so that
  // its place and ways are read from (nearly) its centre.
  if (result.kind != TrackFeatureKind::kEnd && rescans_ < config_.max_rescans &&
      map_.nearest_node(result.node_m, config_.match_radius_m) < 0) {
    const Vec2 better = node_from_in_line(result);
    if ((better - result.node_m).norm() > 0.006) {
      ++rescans_;
      centre_at_m_ = better;
      scan_after_centre_ = true;
      mode_ = Mode::kCentre;
      return;
    }
  }
  const Arrival arrival{result.kind,
                        result.node_m,
                        result.ways_rad,
                        result.way_points_m,
                        scanner_start_m_,
                        approach_heading_rad_,
                        on_leg_ ? arrival_line() : std::nullopt};
  rescans_ = 0;
  const int node = arrive(arrival, length);
  leave(node);
}

Vec2 TrackExploreController::node_from_in_line(const ScanResult& result) const {
  // The node lies on the tape it came in along; each other way's crossing, dropped onto
  // that line, is near the node (exactly, for a way square to it). Done again from there,
  // the error shrinks by the cosine of the way's angle to that line.
  const auto in = on_leg_ ? arrival_line() : std::nullopt;
  const Vec2 base = in ? in->point_m : result.node_m;
  const Vec2 along = unit(in ? in->heading_rad : approach_heading_rad_);
  Vec2 sum{};
  int count = 0;
  for (const Vec2& q : result.way_points_m) {
    const Vec2 d = q - result.node_m;
    const double off = std::abs(std::atan2(along.cross(d), along.dot(d)));
    // Only ways nearly square to it: an oblique way's crossing drops beyond the node.
    if (off < deg_to_rad(60.0) || off > deg_to_rad(120.0)) continue;
    sum = sum + base + along * along.dot(q - base);
    ++count;
  }
  if (count == 0) return result.node_m;
  const Vec2 at = sum / count;
  return (at - result.node_m).norm() < 0.06 ? at : result.node_m;
}

namespace {

double angle_off(double a, double b) { return std::abs(wrap_rad_pi(a - b)); }

// Whether two of the followed ways cross at a useful angle (their lines place the node).
bool followed_lines_cross(const ExploredTrackMap::Node& node) {
  for (std::size_t i = 0; i < node.ways.size(); ++i)
    for (std::size_t j = i + 1; j < node.ways.size(); ++j) {
      if (!node.ways[i].followed || !node.ways[j].followed) continue;
      const double off = angle_off(node.ways[i].direction_rad, node.ways[j].direction_rad);
      if (off > deg_to_rad(25.0) && off < deg_to_rad(155.0)) return true;
    }
  return false;
}

}  // namespace

Vec2 TrackExploreController::locate_known(const ExploredTrackMap::Node& known, const Arrival& arrival,
                                          double turn_rad) const {
  // The known ways' directions, turned into the odometry's frame, through the points
  // where this turn crossed them (and the tape followed in), meet at the node.
  if (!followed_lines_cross(known)) return arrival.node_m;
  std::vector<Vec2> points;
  std::vector<double> directions;
  for (const Vec2& q : arrival.way_points_m) {
    const Vec2 d = q - arrival.node_m;
    const double seen = std::atan2(d.y, d.x) + turn_rad;
    const int k = map_.nearest_way(known.id, seen);
    const ExploredTrackMap::Way& way = known.ways[static_cast<std::size_t>(k)];
    if (!way.followed || angle_off(way.direction_rad, seen) > deg_to_rad(25.0)) continue;
    points.push_back(q);
    directions.push_back(way.direction_rad - turn_rad);
  }
  if (arrival.followed_in) {
    points.push_back(arrival.followed_in->point_m);
    directions.push_back(arrival.followed_in->heading_rad);
  }
  const Vec2 at = meet_of_lines(points, directions, arrival.node_m);
  return (at - arrival.node_m).norm() < 0.04 ? at : arrival.node_m;
}

void TrackExploreController::hold_to_known_tapes(double travel_m) {
  // On a tape the map knows as a line (a way followed before, near its node), the line
  // the array draws now must lie on it: the odometry's heading and its place across the
  // tape are corrected, so that drift does not build up along known edges.
  const double since_leaving = travel_m - leg_.start_travel_m;
  const ExploredTrackMap::Way* way = nullptr;
  if (leg_.from_node >= 0 && since_leaving > config_.leave_zone_m + 0.08 && since_leaving < 0.35) {
    const auto& w = map_.nodes[static_cast<std::size_t>(leg_.from_node)].ways[static_cast<std::size_t>(leg_.from_way)];
    if (w.followed && leg_way_known_) way = &w;
  }
  if (!way) return;
  const auto now = fitted_line(travel_m - 0.08, travel_m);
  if (!now) return;
  // A share of the difference: each 8 cm line wavers by a degree with the follower.
  const double gain = 0.3;
  const Vec2 d = unit(way->direction_rad);
  const double across_full = d.cross(now->point_m - way->point_m);  // left of the known line
  const double turn_full = wrap_rad_pi(way->direction_rad - now->heading_rad);
  if (std::abs(turn_full) > deg_to_rad(10.0) || std::abs(across_full) > 0.04) return;
  const double turn = gain * turn_full, across = gain * across_full;
  // Rotate about the fitted point, then move across onto the known line.
  const double c = std::cos(turn), s = std::sin(turn);
  const Vec2 shift = unit(way->direction_rad + kPi / 2) * -across;
  auto move = [&](Vec2 p) {
    const Vec2 r = p - now->point_m;
    return now->point_m + Vec2{c * r.x - s * r.y, s * r.x + c * r.y} + shift;
  };
  Pose2 pose = odometry_.pose();
  pose.position_m = move(pose.position_m);
  pose.heading_rad = wrap_rad_pi(pose.heading_rad + turn);
  odometry_.set_pose(pose);
  for (PathPoint& p : path_) p.sensor_m = move(p.sensor_m);
}

void TrackExploreController::spread_closure(Vec2 error_m) {
  // The odometry drifted by -error_m since it last stood on a known node; the nodes found
  // on the way drifted by a share of it growing with the distance driven (the surveyor's
  // rule for a traverse closed on a known point).
  if (chain_.empty() || error_m.norm() < 1e-4) return;
  const double span = odometry_.travelled_m() - chain_start_m_;
  if (span <= 0.0) return;
  for (const ChainNode& c : chain_) {
    auto& n = map_.nodes[static_cast<std::size_t>(c.node)];
    n.position_m = n.position_m + error_m * std::clamp((c.travel_m - chain_start_m_) / span, 0.0, 1.0);
    for (auto& w : n.ways)
      if (w.followed) w.point_m = w.point_m + error_m * std::clamp((c.travel_m - chain_start_m_) / span, 0.0, 1.0);
    emit_node(n);
  }
}

void TrackExploreController::set_followed(int node, int way, const TapeLine& line) {
  auto& n = map_.nodes[static_cast<std::size_t>(node)];
  auto& w = n.ways[static_cast<std::size_t>(way)];
  // The followed line is the better measure; it is this way's when no other way of the
  // node is nearer (a turn off the node's centre can be 30 degrees off).
  if (w.followed || angle_off(line.heading_rad, w.direction_rad) > deg_to_rad(45.0) ||
      map_.nearest_way(node, line.heading_rad) != way)
    return;
  w.direction_rad = line.heading_rad;
  w.point_m = line.point_m;
  w.followed = true;
  if (!followed_lines_cross(n) || n.kind == TrackFeatureKind::kEnd) return;
  // The node is where the tapes it has followed meet: better than where it turned.
  std::vector<Vec2> points;
  std::vector<double> directions;
  for (const auto& x : n.ways)
    if (x.followed) {
      points.push_back(x.point_m);
      directions.push_back(x.direction_rad);
    }
  const Vec2 at = meet_of_lines(points, directions, n.position_m);
  if ((at - n.position_m).norm() < 0.05 && (at - n.position_m).norm() > 1e-4) {
    n.position_m = at;
    emit_node(n);
  }
}

void TrackExploreController::merge_ways(int node, const Arrival& arrival, Vec2 at, double turn_rad) {
  // A way this turn saw that the node lacks (a turn off its centre missed it, or took two
  // ways for one) is added, untaken; the kind follows the number of ways. Ways it has
  // take this turn's directions unless followed.
  auto& n = map_.nodes[static_cast<std::size_t>(node)];
  // Only a turn on the node's centre: off it, one tape's crossings point elsewhere.
  if (!arrival.scanned_from_m || (*arrival.scanned_from_m - at).norm() > 0.01) return;
  bool changed = false;
  for (const Vec2& q : arrival.way_points_m) {
    const Vec2 d = q - at;
    const double direction = wrap_rad_pi(std::atan2(d.y, d.x) + turn_rad);
    const int k = map_.nearest_way(node, direction);
    if (k >= 0 && angle_off(n.ways[static_cast<std::size_t>(k)].direction_rad, direction) <
                      deg_to_rad(config_.scan.merge_deg + 5.0)) {
      // A way it knows. Unless its tape was followed (a line, the better measure), it takes
      // this turn's direction: the robot leaves from where it turned, along what it saw.
      auto& w = n.ways[static_cast<std::size_t>(k)];
      if (!w.followed) w.direction_rad = direction;
      continue;
    }
    n.ways.push_back({direction, ExploredTrackMap::kUntaken, false, {}});
    changed = true;
  }
  if (!changed) return;
  const auto live =
      std::count_if(n.ways.begin(), n.ways.end(), [](const auto& w) { return w.edge != ExploredTrackMap::kNoTape; });
  if (live >= 4)
    n.kind = TrackFeatureKind::kCross;
  else if (live == 3)
    n.kind = TrackFeatureKind::kTee;
  emit_node(n);
}

int TrackExploreController::arrive(const Arrival& arrival, double length_m) {
  int node = map_.nearest_node(arrival.node_m, config_.match_radius_m);
  double arrival_heading_rad = arrival.heading_rad;
  if (node >= 0) {
    const ExploredTrackMap::Node& known = map_.nodes[static_cast<std::size_t>(node)];
    // The known node's place and ways are the map's: the odometry is corrected to them,
    // its heading by the tape it came in along, when both that and the map's way were
    // followed (a turn on the spot resolves directions to a few degrees only).
    double turn = 0.0;
    if (arrival.followed_in) {
      const int in = map_.nearest_way(node, arrival.followed_in->heading_rad + kPi);
      const ExploredTrackMap::Way& way = known.ways[static_cast<std::size_t>(in)];
      const double off = wrap_rad_pi(way.direction_rad - (arrival.followed_in->heading_rad + kPi));
      if (way.followed && std::abs(off) < deg_to_rad(20.0)) turn = off;
    }
    const Vec2 at = known.ways.size() == arrival.ways_rad.size() || !arrival.way_points_m.empty()
                        ? locate_known(known, arrival, turn)
                        : arrival.node_m;
    merge_ways(node, arrival, at, turn);
    Pose2 pose = odometry_.pose();
    const Vec2 rel = pose.position_m - at;
    const double c = std::cos(turn), s = std::sin(turn);
    pose.position_m = known.position_m + Vec2{c * rel.x - s * rel.y, s * rel.x + c * rel.y};
    pose.heading_rad = wrap_rad_pi(pose.heading_rad + turn);
    if (config_.correct_odometry) {
      spread_closure(known.position_m - at);
      odometry_.set_pose(pose);
      arrival_heading_rad = wrap_rad_pi(arrival_heading_rad + turn);
    }
    chain_.clear();
    if (arrival.followed_in) {
      // The tape it came in along, in the map's frame, is the way in's line if it had none.
      const TapeLine& in = *arrival.followed_in;
      const Vec2 rel_in = in.point_m - at;
      const TapeLine back{known.position_m + Vec2{c * rel_in.x - s * rel_in.y, s * rel_in.x + c * rel_in.y},
                          wrap_rad_pi(in.heading_rad + turn + kPi)};
      set_followed(node, map_.nearest_way(node, back.heading_rad), back);
    }
  } else {
    ExploredTrackMap::Node added;
    added.id = static_cast<int>(map_.nodes.size());
    added.kind = arrival.kind;
    added.position_m = arrival.node_m;
    for (double w : arrival.ways_rad) added.ways.push_back({w, -1, false, {}});
    added.looked_from_centre = arrival.scanned_from_m && (*arrival.scanned_from_m - arrival.node_m).norm() < 0.008;
    map_.nodes.push_back(added);
    node = added.id;
    emit_node(added);
    chain_.push_back({node, odometry_.travelled_m()});
    if (arrival.followed_in) {
      // The way in is known better from the tape followed than from the turn.
      const TapeLine back{arrival.followed_in->point_m, wrap_rad_pi(arrival.followed_in->heading_rad + kPi)};
      set_followed(node, map_.nearest_way(node, back.heading_rad), back);
    }
  }
  if (on_leg_ && leg_.from_node >= 0) {
    const int in = map_.nearest_way(node, arrival_heading_rad + kPi);
    auto& a = map_.nodes[static_cast<std::size_t>(leg_.from_node)].ways[static_cast<std::size_t>(leg_.from_way)];
    auto& b = map_.nodes[static_cast<std::size_t>(node)].ways[static_cast<std::size_t>(in)];
    if (a.edge < 0 && b.edge < 0 && !(leg_.from_node == node && leg_.from_way == in)) {
      map_.edges.push_back({leg_.from_node, leg_.from_way, node, in, std::max(0.0, length_m)});
      a.edge = b.edge = static_cast<int>(map_.edges.size()) - 1;
      emit_edge(a.edge);
    } else if (a.edge < 0) {
      a.edge = b.edge;  // came in by a way already linked: the edge is known
    } else if (b.edge < 0) {
      b.edge = a.edge;
    }
  }
  on_leg_ = false;
  if (chain_.empty()) chain_start_m_ = odometry_.travelled_m();
  return node;
}

void TrackExploreController::leave(int node) {
  if (!route_.empty() && route_.front().first == node) {
    const int way = route_.front().second;
    route_.erase(route_.begin());
    leave_by(node, way);
    return;
  }
  route_.clear();
  const auto& ways = map_.nodes[static_cast<std::size_t>(node)].ways;
  const double heading = odometry_.pose().heading_rad;
  int best = -1;
  for (int w = 0; w < static_cast<int>(ways.size()); ++w) {
    if (ways[static_cast<std::size_t>(w)].edge != ExploredTrackMap::kUntaken) continue;
    if (best < 0 || std::abs(wrap_rad_pi(ways[static_cast<std::size_t>(w)].direction_rad - heading)) <
                        std::abs(wrap_rad_pi(ways[static_cast<std::size_t>(best)].direction_rad - heading)))
      best = w;
  }
  if (best >= 0) {
    leave_by(node, best);
    return;
  }
  route_ = map_.route_to_untaken(node);
  if (route_.empty()) {
    mode_ = Mode::kDone;
    return;
  }
  const int way = route_.front().second;
  route_.erase(route_.begin());
  leave_by(node, way);
}

void TrackExploreController::leave_by(int node, int way) {
  scan_after_centre_ = false;
  target_heading_rad_ = map_.nodes[static_cast<std::size_t>(node)].ways[static_cast<std::size_t>(way)].direction_rad;
  leg_ = {node, way, odometry_.travelled_m()};
  leg_way_fitted_ = false;
  leg_way_known_ = map_.nodes[static_cast<std::size_t>(node)].ways[static_cast<std::size_t>(way)].followed;
  on_leg_ = true;
  // Leave from the node's centre: off it, the way's tape is not where its direction says.
  centre_at_m_ = map_.nodes[static_cast<std::size_t>(node)].position_m;
  mode_ = (centre_at_m_ - odometry_.pose().position_m).norm() > 0.006 ? Mode::kCentre : Mode::kTurn;
  if (!map_.nodes[static_cast<std::size_t>(node)].looked_from_centre) {
    // Its ways were read off its centre (or from a bend): look again from there first.
    verifying_node_ = node;
    scan_after_centre_ = true;
    approach_heading_rad_ = odometry_.pose().heading_rad;
    if (mode_ == Mode::kTurn) start_scan();
  }
}

ControlOutput TrackExploreController::centre() {
  const Pose2 pose = odometry_.pose();
  const Vec2 to = centre_at_m_ - pose.position_m;
  const double distance = to.norm();
  const double error = wrap_rad_pi(std::atan2(to.y, to.x) - pose.heading_rad);
  if (distance < 0.003 || (std::abs(error) > deg_to_rad(90.0) && distance < 0.008)) {
    if (scan_after_centre_) {
      scan_after_centre_ = false;
      start_scan();
      return drive(0, 0, "scan");
    }
    leg_.start_travel_m = odometry_.travelled_m();
    mode_ = Mode::kTurn;
    return drive(0, 0, "turn");
  }
  if (distance > 0.003 && std::abs(error) > deg_to_rad(100.0) && distance < 0.03) {
    // Just behind: back up rather than turn round on the node.
    return drive(-std::max(0.02, 3.0 * distance), 0, "centre");
  }
  if (std::abs(error) > deg_to_rad(15.0))
    return drive(0, error > 0 ? config_.turn_radps : -config_.turn_radps, "centre");
  return drive(std::min(config_.speed_mps, std::max(0.02, 3.0 * distance)), 3.0 * error, "centre");
}

ControlOutput TrackExploreController::turn(const TrackArrayReading& reading) {
  const double error = wrap_rad_pi(target_heading_rad_ - odometry_.pose().heading_rad);
  if (std::abs(error) < deg_to_rad(4.0)) {
    mode_ = Mode::kFind;
    find_round_ = 0;
    find_sweep_rad_ = 0.0;
    return find(reading);
  }
  const double rate = std::min(config_.turn_radps, 4.0 * std::abs(error) + 0.3);
  return drive(0, error > 0 ? rate : -rate, "turn");
}

ControlOutput TrackExploreController::find(const TrackArrayReading& reading) {
  if (reading.on_track) {
    mode_ = Mode::kFollow;
    last_offset_m_ = 0.0;
    seen_on_leg_ = false;
    arm_pending_ = false;
    off_since_m_ = -1.0;
    path_.clear();
    last_bend_deg_ = 0.0;
    return drive(0, 0, "follow");
  }
  // Sweep either side of the expected way, wider each round, before giving up.
  const double aim = target_heading_rad_ + find_sweep_rad_;
  const double error = wrap_rad_pi(aim - odometry_.pose().heading_rad);
  if (std::abs(error) < deg_to_rad(3.0)) {
    ++find_round_;
    if (find_round_ > 6) {
      if (leg_.from_node < 0) {
        on_leg_ = false;
        mode_ = Mode::kSearch;
        return drive(0, 0, "search");
      }
      // No tape that way from the node (a way a turn off the node's centre made up): the
      // way is struck off and the robot goes on from the node.
      auto& way = map_.nodes[static_cast<std::size_t>(leg_.from_node)].ways[static_cast<std::size_t>(leg_.from_way)];
      if (way.edge == ExploredTrackMap::kUntaken) way.edge = ExploredTrackMap::kNoTape;
      route_.clear();
      leave(leg_.from_node);
      return drive(0, 0, "find");
    }
    find_sweep_rad_ = deg_to_rad(15.0) * ((find_round_ + 1) / 2) * (find_round_ % 2 ? 1.0 : -1.0);
  }
  return drive(0, error > 0 ? 1.0 : -1.0, "find");
}

ControlOutput TrackExploreController::follow(const TrackArrayReading& reading) {
  const Pose2 pose = odometry_.pose();
  const double travel = odometry_.travelled_m();
  if (!reading.on_track) {
    if (off_since_m_ < 0) off_since_m_ = travel;
    if (seen_on_leg_ && travel - off_since_m_ >= config_.lost_after_m) {
      // Lost: the tape ends or turns away. The node is where the array lost it.
      arm_pending_ = false;
      mode_ = Mode::kApproach;
      cue_travel_m_ = off_since_m_;
      // The array loses the tape half its width past the centre line's end (the far edge
      // of a tape leaving square, or a tape's round end): the robot's centre goes there.
      approach_until_m_ = off_since_m_ + sensor_ahead_m_ - 0.5 * config_.reading.tape_width_m;
      approach_heading_rad_ = pose.heading_rad;
      return approach();
    }
    return drive(config_.speed_mps * 0.5, 0, "follow");
  }
  off_since_m_ = -1.0;
  seen_on_leg_ = true;
  const double since_leaving = travel - leg_.start_travel_m;
  const Vec2 ahead = unit(pose.heading_rad), left = unit(pose.heading_rad + kPi / 2);
  path_.push_back({travel, pose.position_m + ahead * sensor_ahead_m_ + left * reading.run_offset_m});
  while (!path_.empty() && travel - path_.front().travel_m > 0.25) path_.pop_front();
  if (!leg_way_fitted_ && leg_.from_node >= 0 && since_leaving > config_.leave_zone_m + 0.08 && path_.size() % 4 == 0) {
    // The way it left by, as a line, once a straight stretch of it has been followed.
    if (const auto fitted = fitted_line(leg_.start_travel_m + config_.leave_zone_m, travel)) {
      leg_way_fitted_ = true;
      set_followed(leg_.from_node, leg_.from_way, *fitted);
    }
  }
  if (config_.correct_odometry && path_.size() % 4 == 0) hold_to_known_tapes(travel);
  if (since_leaving > config_.leave_zone_m) {
    if ((reading.arm_left || reading.arm_right) && !arm_pending_) {
      // A side arm: a junction, or the tape of a corner turning away. Which, the next few
      // centimetres tell: the tape goes on straight past a junction.
      arm_pending_ = true;
      cue_travel_m_ = travel;
      arm_heading_rad_ = pose.heading_rad;
      arm_node_m_ = pose.position_m + unit(pose.heading_rad) * (sensor_ahead_m_ + 0.5 * config_.reading.tape_width_m);
    }
    const double arm_at = cue_travel_m_ + sensor_ahead_m_ + 0.5 * config_.reading.tape_width_m;
    const bool turned = std::abs(wrap_rad_pi(pose.heading_rad - arm_heading_rad_)) >= deg_to_rad(15.0);
    // Straight on past the arm (a junction), or turned without a corner showing in the
    // path by now: back to where the arm crossed, and look round there.
    if (arm_pending_ && travel > arm_at + (turned ? 0.08 : 0.03)) {
      arm_pending_ = false;
      centre_at_m_ = arm_node_m_;
      if (turned) {
        // Where the tape it came in along meets the tape it turned onto: an oblique arm's
        // node is short of where a square one's would be.
        const auto in = fitted_line(cue_travel_m_ - 0.15, cue_travel_m_ - 0.01);
        const auto out = fitted_line(travel - 0.05, travel);
        if (in && out) {
          const Vec2 at = meet_of_lines(std::vector<Vec2>{in->point_m, out->point_m},
                                        std::vector<double>{in->heading_rad, out->heading_rad}, arm_node_m_);
          if ((at - arm_node_m_).norm() < 0.08) centre_at_m_ = at;
        }
      }
      scan_after_centre_ = true;
      approach_heading_rad_ = arm_heading_rad_;
      cue_travel_m_ = arm_at - sensor_ahead_m_;
      mode_ = Mode::kCentre;
      return drive(0, 0, "approach");
    }
    if (const auto corner = bend_corner()) {
      // A corner the follower takes without losing the tape: a node on the way, left by
      // the way it already goes.
      const PathPoint vertex = *corner;
      const Vec2 in_dir = vertex.sensor_m - path_.front().sensor_m;
      const Vec2 out_dir = path_.back().sensor_m - vertex.sensor_m;
      const double in_heading = std::atan2(in_dir.y, in_dir.x), out_heading = std::atan2(out_dir.y, out_dir.x);
      if (arm_pending_) {
        // A bend where the array also saw another tape: a junction whose way on bends. Look
        // round at the bend.
        arm_pending_ = false;
        centre_at_m_ = vertex.sensor_m;
        scan_after_centre_ = true;
        approach_heading_rad_ = in_heading;
        cue_travel_m_ = vertex.travel_m;
        mode_ = Mode::kCentre;
        return drive(0, 0, "approach");
      }
      const TrackFeatureKind kind =
          in_dir.cross(out_dir) > 0 ? TrackFeatureKind::kCornerLeft : TrackFeatureKind::kCornerRight;
      const double past = travel - vertex.travel_m;
      const Arrival arrival{kind,         vertex.sensor_m, {wrap_rad_pi(in_heading + kPi), out_heading}, {},
                            std::nullopt, in_heading,      TapeLine{vertex.sensor_m, in_heading}};
      const int node = arrive(arrival, vertex.travel_m - leg_.start_travel_m);
      const int out = map_.nearest_way(node, out_heading);
      set_followed(node, out, {vertex.sensor_m, out_heading});
      leg_way_fitted_ = true;
      route_.clear();
      leg_ = {node, out, travel - past};
      on_leg_ = true;
      arm_pending_ = false;
      path_.clear();
      last_bend_deg_ = 0.0;
    }
  }
  // Steer by the tape it follows, not by others passing under the array near a node.
  const double offset = reading.run_offset_m;
  last_offset_m_ = offset;
  const double turn = std::clamp(config_.follow_gain * offset, -3.0, 3.0);
  const double speed = config_.speed_mps * (1.0 - std::min(0.6, std::abs(offset) / 0.025));
  return drive(speed, turn, "follow");
}

std::optional<TrackExploreController::PathPoint> TrackExploreController::bend_corner() {
  if (path_.size() < 8) return std::nullopt;
  const double d = path_.back().travel_m;
  // The stretch before the bend: 6 cm, or what there is of it down to 4 cm on a short edge.
  const double before = std::max(path_.front().travel_m, d - 0.13);
  if (d - 0.07 - before < 0.04) return std::nullopt;
  auto at = [&](double travel) {
    const auto it = std::lower_bound(path_.begin(), path_.end(), travel,
                                     [](const PathPoint& p, double t) { return p.travel_m < t; });
    return it == path_.end() ? path_.back().sensor_m : it->sensor_m;
  };
  const Vec2 a0 = at(before), a1 = at(d - 0.07), c0 = at(d - 0.04), c1 = path_.back().sensor_m;
  const double angle = angle_between_deg(a1 - a0, c1 - c0);
  const double previous = last_bend_deg_;
  last_bend_deg_ = angle;
  if (angle < config_.bend_min_deg || angle > previous) return std::nullopt;
  // Both stretches straight, so that the follower's own wiggle is no corner.
  if (distance_to_line(at(0.5 * (before + d - 0.07)), a0, a1) > 0.003 || distance_to_line(at(d - 0.02), c0, c1) > 0.003)
    return std::nullopt;
  const Vec2 u = a1 - a0, v = c1 - c0;
  const double denom = u.cross(v);
  if (std::abs(denom) < 1e-12) return std::nullopt;
  const double s = (c0 - a0).cross(v) / denom;
  const Vec2 vertex = a0 + u * s;
  // The travel at the vertex: where the path comes nearest it.
  double best = 1e9, travel = d;
  for (const PathPoint& p : path_) {
    const double dist = (p.sensor_m - vertex).norm();
    if (dist < best) {
      best = dist;
      travel = p.travel_m;
    }
  }
  return PathPoint{travel, vertex};
}

std::optional<TrackExploreController::TapeLine> TrackExploreController::fitted_line(double from_travel_m,
                                                                                    double to_travel_m) const {
  std::vector<Vec2> points;
  for (const PathPoint& p : path_)
    if (p.travel_m >= from_travel_m && p.travel_m <= to_travel_m) points.push_back(p.sensor_m);
  // A straight stretch only: while the points lie more than 2 mm (RMS) off the line, the
  // end farther off (a node's turn, or the follower settling onto the tape) is dropped.
  while (points.size() >= 6 && (points.back() - points.front()).norm() >= 0.04) {
    Vec2 mean{};
    for (const Vec2& p : points) mean = mean + p;
    mean = mean / static_cast<double>(points.size());
    double sxx = 0, sxy = 0, syy = 0;
    for (const Vec2& p : points) {
      const Vec2 d = p - mean;
      sxx += d.x * d.x;
      sxy += d.x * d.y;
      syy += d.y * d.y;
    }
    // The principal axis, pointed the way the robot went.
    Vec2 direction = unit(0.5 * std::atan2(2 * sxy, sxx - syy));
    if (direction.dot(points.back() - points.front()) < 0) direction = direction * -1.0;
    // By the RMS: the array reads the tape's place in steps of half its spacing.
    double square_sum = 0.0;
    for (const Vec2& p : points) square_sum += std::pow(direction.cross(p - mean), 2);
    if (std::sqrt(square_sum / static_cast<double>(points.size())) <= 0.002)
      return TapeLine{mean, std::atan2(direction.y, direction.x)};
    const double head = std::abs(direction.cross(points.front() - mean)) + std::abs(direction.cross(points[1] - mean));
    const double tail =
        std::abs(direction.cross(points.back() - mean)) + std::abs(direction.cross(points[points.size() - 2] - mean));
    if (head > tail)
      points.erase(points.begin(), points.begin() + 2);
    else
      points.resize(points.size() - 2);
  }
  return std::nullopt;
}

std::optional<TrackExploreController::TapeLine> TrackExploreController::arrival_line() const {
  const double from = std::max(leg_.start_travel_m + config_.leave_zone_m, cue_travel_m_ - 0.15);
  return fitted_line(from, cue_travel_m_ - 0.01);
}

void TrackExploreController::emit_node(const ExploredTrackMap::Node& node) {
  std::string ways;
  for (const auto& w : node.ways) ways += (ways.empty() ? "" : ", ") + fixed(rad_to_deg(w.direction_rad), 1);
  events_.push_back({"track_node", node.id,
                     "{\"kind\": \"" + std::string(track_node_kind_of(node.kind)) + "\", \"feature\": \"" +
                         std::string(track_feature_name(node.kind)) + "\", \"x_m\": " + fixed(node.position_m.x) +
                         ", \"y_m\": " + fixed(node.position_m.y) + ", \"ways_deg\": [" + ways + "]}"});
}

void TrackExploreController::emit_edge(int edge) {
  const auto& e = map_.edges[static_cast<std::size_t>(edge)];
  events_.push_back({"track_edge", edge,
                     "{\"from\": " + std::to_string(e.from) + ", \"to\": " + std::to_string(e.to) +
                         ", \"length_m\": " + fixed(e.length_m) + "}"});
}

}  // namespace rilbed::agents
