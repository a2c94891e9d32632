#include "run/run_recorder.hpp"

#include <cmath>
#include <cstdio>
#include <ostream>
#include <stdexcept>
#include <string>

namespace rilbed::run {

namespace {

std::string format(const char* fmt, double a) {
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, a);
  return buf;
}

// Distinct colours for up to ten robots, then repeating.
const char* colour(int index) {
  static const char* kColours[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd",
                                   "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"};
  return kColours[static_cast<std::size_t>(index) % 10];
}

// The legend under the field: what a virtual and a real robot look like, and the start.
void write_legend(std::ostream& svg, double x, double top) {
  const double mid = top + 11.0;
  auto num = [](double v) { return format("%.1f", v); };
  svg << "<g class=\"legend\">\n";
  svg << "<circle r=\"8\" fill=\"#888\" fill-opacity=\"0.35\" stroke=\"#888\" cx=\"" << num(x + 8) << "\" cy=\""
      << num(mid) << "\"/>\n";
  svg << "<line stroke=\"#888\" stroke-width=\"1.5\" x1=\"" << num(x + 20) << "\" y1=\"" << num(mid) << "\" x2=\""
      << num(x + 44) << "\" y2=\"" << num(mid) << "\"/>\n";
  svg << "<text x=\"" << num(x + 50) << "\" y=\"" << num(mid + 4) << "\">virtual robot</text>\n";
  const double rx = x + 150;
  svg << "<rect width=\"16\" height=\"16\" x=\"" << num(rx) << "\" y=\"" << num(mid - 8)
      << "\" fill=\"#888\" fill-opacity=\"0.35\" stroke=\"#000\" stroke-width=\"2\"/>\n";
  svg << "<line stroke=\"#888\" stroke-width=\"1.5\" stroke-dasharray=\"6,3\" x1=\"" << num(rx + 20) << "\" y1=\""
      << num(mid) << "\" x2=\"" << num(rx + 44) << "\" y2=\"" << num(mid) << "\"/>\n";
  svg << "<text x=\"" << num(rx + 50) << "\" y=\"" << num(mid + 4) << "\">real robot (as the camera saw it)</text>\n";
  const double sx = rx + 260;
  svg << "<circle r=\"3\" fill=\"none\" stroke=\"#888\" cx=\"" << num(sx + 8) << "\" cy=\"" << num(mid) << "\"/>\n";
  svg << "<text x=\"" << num(sx + 16) << "\" y=\"" << num(mid + 4)
      << "\">start (the last pose shows the heading)</text>\n";
  svg << "</g>\n";
}

}  // namespace

std::string csv_field(std::string_view text) {
  if (text.find_first_of(",\"\n\r") == std::string_view::npos) return std::string(text);
  std::string out = "\"";
  for (char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

RunRecorder::RunRecorder(const std::filesystem::path& dir, FieldDrawing field) : dir_(dir), field_(std::move(field)) {
  std::error_code ec;
  std::filesystem::create_directories(dir_, ec);
  if (ec) throw std::runtime_error("cannot create run folder " + dir_.string() + ": " + ec.message());
  trajectories_.open(dir_ / "trajectories.csv");
  events_.open(dir_ / "events.csv");
  if (!trajectories_ || !events_) throw std::runtime_error("cannot write in run folder " + dir_.string());
  trajectories_ << "t_s,id,x_m,y_m,theta_deg,behaviour\n";
  events_ << "t_s,kind,id,other,detail\n";
  trajectories_.flush();
  events_.flush();
}

void RunRecorder::add_samples(const std::vector<TrajectorySample>& samples) {
  char line[160];
  for (const TrajectorySample& s : samples) {
    std::snprintf(line, sizeof line, "%.3f,%d,%.5f,%.5f,%.2f,", us_to_seconds(s.t_us), s.id, s.pose.position_m.x,
                  s.pose.position_m.y, wrap_deg_360(rad_to_deg(s.pose.heading_rad)));
    trajectories_ << line << csv_field(s.behaviour) << '\n';
    if (sample_count_[s.id]++ % 5 == 0) paths_[s.id].push_back(s.pose.position_m);
    last_pose_[s.id] = s.pose;
  }
  // Flushed about once a simulated second of a small team, so that a crash or Ctrl-C
  // loses at most that much; a large run flushes by volume.
  rows_since_flush_ += static_cast<int>(samples.size());
  if (rows_since_flush_ >= 100) {
    trajectories_.flush();
    rows_since_flush_ = 0;
  }
}

void RunRecorder::add_event(const RunEvent& e) {
  events_ << format("%.3f", us_to_seconds(e.t_us)) << ',' << csv_field(e.kind) << ',' << e.id << ',' << e.other << ','
          << csv_field(e.detail) << '\n';
  events_.flush();
  if (e.kind == "track_node" || e.kind == "track_edge") keep_track_event(e);
}

std::optional<ReportedTrackNode> reported_track_node(const RunEvent& e) {
  if (e.kind != "track_node") return std::nullopt;
  const nlohmann::json d = nlohmann::json::parse(e.detail, nullptr, false);
  if (!d.is_object()) return std::nullopt;
  const auto kind = d.find("kind");
  const auto x = d.find("x_m");
  const auto y = d.find("y_m");
  if (kind == d.end() || !kind->is_string() || x == d.end() || !x->is_number() || y == d.end() || !y->is_number())
    return std::nullopt;
  return ReportedTrackNode{e.other, kind->get<std::string>(), {x->get<double>(), y->get<double>()}, e.t_us};
}

void RunRecorder::keep_track_event(const RunEvent& e) {
  // Each robot's map, from its own events; the detail is JSON (an explorer's, or any
  // program's on the bus: what does not parse is left out of the map, not thrown).
  const nlohmann::json detail = nlohmann::json::parse(e.detail, nullptr, false);
  if (!detail.is_object()) return;
  TrackMap& map = track_maps_[e.id];
  if (e.kind == "track_node") {
    if (const auto node = reported_track_node(e))
      map.nodes[e.other] = {
          {"id", e.other}, {"kind", node->kind}, {"x_m", node->position_m.x}, {"y_m", node->position_m.y}};
  } else {
    const auto from = detail.find("from");
    const auto to = detail.find("to");
    const auto length = detail.find("length_m");
    if (from == detail.end() || !from->is_number_integer() || to == detail.end() || !to->is_number_integer() ||
        length == detail.end() || !length->is_number())
      return;
    map.edges[e.other] = {{"from", *from}, {"to", *to}, {"length_m", *length}};
  }
}

void RunRecorder::write_track_map() const {
  if (track_maps_.empty()) return;
  // One robot's map: the one that learned the most edges (then nodes; then the lowest ID).
  const TrackMap* best = nullptr;
  int best_id = 0;
  for (const auto& [id, map] : track_maps_) {
    if (!best || map.edges.size() > best->edges.size() ||
        (map.edges.size() == best->edges.size() && map.nodes.size() > best->nodes.size())) {
      best = &map;
      best_id = id;
    }
  }
  nlohmann::json out = {{"robot", best_id}, {"nodes", nlohmann::json::array()}, {"edges", nlohmann::json::array()}};
  for (const auto& [id, node] : best->nodes) out["nodes"].push_back(node);
  for (const auto& [id, edge] : best->edges) out["edges"].push_back(edge);
  std::ofstream file(dir_ / "track_map.json");
  file << out.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) << '\n';
  if (!file) throw std::runtime_error("cannot write " + (dir_ / "track_map.json").string());
}

void RunRecorder::finish(const nlohmann::json& summary) {
  if (finished_) return;
  finished_ = true;
  for (const auto& [id, pose] : last_pose_) paths_[id].push_back(pose.position_m);
  trajectories_.flush();
  events_.flush();
  trajectories_.close();
  events_.close();
  std::ofstream json(dir_ / "summary.json");
  // Names from a scenario file may not be UTF-8: replaced, not thrown at the run's end.
  json << summary.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) << '\n';
  if (!json) throw std::runtime_error("cannot write " + (dir_ / "summary.json").string());
  write_track_map();
  write_svg();
}

void RunRecorder::write_svg() const {
  // 500 pixels per metre; y flipped so that the field's +y is up on screen.
  const double scale = 500.0, margin = 20.0;
  const double legend_h = 28.0;
  const double w = field_.width_m * scale + 2 * margin, h = field_.height_m * scale + 2 * margin + legend_h;
  // Screen coordinates of a field point, as text.
  struct Screen {
    std::string x, y;
  };
  auto screen = [&](Vec2 p) -> Screen {
    return {format("%.1f", margin + p.x * scale), format("%.1f", margin + (field_.height_m - p.y) * scale)};
  };
  auto px = [&](Vec2 p) {
    const Screen s = screen(p);
    return s.x + "," + s.y;
  };
  std::ofstream svg(dir_ / "trajectories.svg");
  svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << format("%.0f", w) << "\" height=\""
      << format("%.0f", h) << "\" font-family=\"sans-serif\" font-size=\"11\">\n";
  svg << "<rect x=\"" << margin << "\" y=\"" << margin << "\" width=\"" << field_.width_m * scale << "\" height=\""
      << field_.height_m * scale << "\" fill=\"#fafafa\" stroke=\"#2a2\" stroke-width=\"2\"/>\n";
  for (const auto& [points, width_m] : field_.tracks) {
    svg << "<polyline fill=\"none\" stroke=\"#bbb\" stroke-linecap=\"round\" stroke-linejoin=\"round\" stroke-width=\""
        << format("%.1f", width_m * scale) << "\" points=\"";
    for (const Vec2& p : points) svg << px(p) << ' ';
    svg << "\"/>\n";
  }
  for (const auto& poly : field_.obstacles) {
    svg << "<polygon fill=\"#555\" points=\"";
    for (const Vec2& p : poly) svg << px(p) << ' ';
    svg << "\"/>\n";
  }
  for (const Vec2& b : field_.beacons) {
    const Screen s = screen(b);
    svg << "<circle r=\"6\" fill=\"#fc0\" stroke=\"#a80\" cx=\"" << s.x << "\" cy=\"" << s.y << "\"/>\n";
  }
  int index = 0;
  for (const auto& [id, path] : paths_) {
    const char* c = colour(index++);
    const bool real = field_.real_robot_ids.contains(id);
    svg << "<polyline fill=\"none\" stroke=\"" << c << "\" stroke-width=\"1.5\""
        << (real ? " stroke-dasharray=\"6,3\"" : "") << " points=\"";
    for (const Vec2& p : path) svg << px(p) << ' ';
    svg << "\"/>\n";
    if (!path.empty()) {
      const Screen start = screen(path.front());
      svg << "<circle r=\"3\" fill=\"none\" stroke=\"" << c << "\" cx=\"" << start.x << "\" cy=\"" << start.y
          << "\"/>\n";
    }
    const auto it = last_pose_.find(id);
    if (it != last_pose_.end()) {
      const Pose2& p = it->second;
      const auto radius = field_.body_radius_m.find(id);
      const double radius_m = radius != field_.body_radius_m.end() ? radius->second : 0.0275;  // a Khepera's
      const double body_r = radius_m * scale;
      const Screen centre = screen(p.position_m);
      const Screen nose = screen(p.position_m + Vec2{std::cos(p.heading_rad), std::sin(p.heading_rad)} * radius_m);
      const std::string& cx = centre.x;
      const std::string& cy = centre.y;
      if (const auto outline = field_.body_outline_m.find(id); outline != field_.body_outline_m.end()) {
        // Its outline, turned with it; dashed when real.
        const double ch = std::cos(p.heading_rad), sh = std::sin(p.heading_rad);
        svg << "<polygon class=\"" << (real ? "real" : "virtual") << "\" fill=\"" << c
            << "\" fill-opacity=\"0.35\" stroke=\"" << (real ? "#000" : c) << "\""
            << (real ? " stroke-width=\"2\"" : "") << " points=\"";
        for (const Vec2& v : outline->second)
          svg << px(p.position_m + Vec2{ch * v.x - sh * v.y, sh * v.x + ch * v.y}) << ' ';
        svg << "\"/>\n";
      } else if (real) {
        svg << "<rect class=\"real\" width=\"" << format("%.1f", 2 * body_r) << "\" height=\""
            << format("%.1f", 2 * body_r) << "\" x=\"" << format("%.1f", std::stod(cx) - body_r) << "\" y=\""
            << format("%.1f", std::stod(cy) - body_r) << "\" fill=\"" << c
            << "\" fill-opacity=\"0.35\" stroke=\"#000\" stroke-width=\"2\"/>\n";
      } else {
        svg << "<circle class=\"virtual\" r=\"" << format("%.1f", body_r) << "\" fill=\"" << c
            << "\" fill-opacity=\"0.35\" stroke=\"" << c << "\" cx=\"" << cx << "\" cy=\"" << cy << "\"/>\n";
      }
      svg << "<line stroke=\"#000\" x1=\"" << cx << "\" y1=\"" << cy << "\" x2=\"" << nose.x << "\" y2=\"" << nose.y
          << "\"/>\n";
      svg << "<text x=\"" << cx << "\" y=\"" << cy << "\" dy=\"4\" text-anchor=\"middle\">" << id << "</text>\n";
    }
  }
  write_legend(svg, margin, h - legend_h + 4.0);
  svg << "</svg>\n";
}

}  // namespace rilbed::run
