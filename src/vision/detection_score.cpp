#include "vision/detection_score.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

#include "core/geometry.hpp"

namespace rilbed::vision {

namespace {

std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream s(line);
  std::string cell;
  while (std::getline(s, cell, ',')) {
    while (!cell.empty() && (cell.back() == '\r' || cell.back() == ' ')) cell.pop_back();
    while (!cell.empty() && cell.front() == ' ') cell.erase(cell.begin());
    out.push_back(cell);
  }
  return out;
}

bool parse_double(const std::string& s, double& out) {
  if (s.empty()) return false;
  char* end = nullptr;
  out = std::strtod(s.c_str(), &end);
  return end == s.c_str() + s.size() && std::isfinite(out);
}

}  // namespace

MarkerRowsResult read_marker_csv(const std::string& path) {
  MarkerRowsResult result;
  std::ifstream in(path);
  if (!in) {
    result.error = path + ": cannot open";
    return result;
  }
  std::string line;
  if (!std::getline(in, line)) {
    result.error = path + ": empty file (expected a header line)";
    return result;
  }
  const auto header = split_csv_line(line);
  std::map<std::string, int> col;
  for (std::size_t i = 0; i < header.size(); ++i) col[header[i]] = static_cast<int>(i);
  for (const char* required : {"frame", "id", "u", "v", "heading_deg"}) {
    if (!col.count(required)) {
      result.error = path + ":1: missing column '" + required + "'";
      return result;
    }
  }
  const bool has_field = col.count("x_m") && col.count("y_m") && col.count("theta_deg");
  int line_no = 1;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty() || line == "\r") continue;
    const auto cells = split_csv_line(line);
    auto get = [&](const char* name, double& out) {
      const int c = col[name];
      return c < static_cast<int>(cells.size()) && parse_double(cells[c], out);
    };
    double frame, id;
    MarkerRow row;
    if (!get("frame", frame) || !get("id", id) || !get("u", row.u) || !get("v", row.v) ||
        !get("heading_deg", row.heading_deg)) {
      result.error = path + ":" + std::to_string(line_no) + ": bad row '" + line + "'";
      return result;
    }
    row.frame = static_cast<int>(frame);
    row.id = static_cast<int>(id);
    double x, y, t;
    if (has_field && get("x_m", x) && get("y_m", y) && get("theta_deg", t)) {
      row.x_m = x;
      row.y_m = y;
      row.theta_deg = t;
    }
    result.rows.push_back(row);
  }
  return result;
}

DetectionScore score_detections(const std::vector<MarkerRow>& truth, const std::vector<MarkerRow>& detections,
                                double match_radius_px) {
  DetectionScore s;
  std::map<std::pair<int, int>, const MarkerRow*> by_key;
  for (const auto& t : truth) by_key[{t.frame, t.id}] = &t;
  s.truth_markers = static_cast<int>(by_key.size());
  std::map<std::pair<int, int>, int> seen;
  double c2 = 0, h2 = 0, f2 = 0, th2 = 0;
  for (const auto& d : detections) {
    if (seen[{d.frame, d.id}]++ > 0) {
      ++s.duplicates;
      continue;
    }
    auto it = by_key.find({d.frame, d.id});
    const double dc = it == by_key.end() ? 1e9 : std::hypot(d.u - it->second->u, d.v - it->second->v);
    if (dc > match_radius_px) {
      ++s.wrong_id;
      continue;
    }
    ++s.found;
    const double dh = std::abs(wrap_deg_180(d.heading_deg - it->second->heading_deg));
    c2 += dc * dc;
    h2 += dh * dh;
    s.centre_max_px = std::max(s.centre_max_px, dc);
    s.heading_max_deg = std::max(s.heading_max_deg, dh);
    const MarkerRow& t = *it->second;
    if (d.x_m && t.x_m) {
      const double df = 1000.0 * std::hypot(*d.x_m - *t.x_m, *d.y_m - *t.y_m);
      const double dt = wrap_deg_180(*d.theta_deg - *t.theta_deg);
      ++s.field_pairs;
      f2 += df * df;
      th2 += dt * dt;
      s.field_max_mm = std::max(s.field_max_mm, df);
    }
  }
  if (s.found) {
    s.centre_rms_px = std::sqrt(c2 / s.found);
    s.heading_rms_deg = std::sqrt(h2 / s.found);
  }
  if (s.field_pairs) {
    s.field_rms_mm = std::sqrt(f2 / s.field_pairs);
    s.theta_rms_deg = std::sqrt(th2 / s.field_pairs);
  }
  return s;
}

std::string format_score(const DetectionScore& s) {
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "recall %.4f (%d of %d), wrong IDs %d, duplicates %d\n"
                "centre error %.3f px RMS (max %.3f), heading error %.3f deg RMS (max %.3f)\n",
                s.recall(), s.found, s.truth_markers, s.wrong_id, s.duplicates, s.centre_rms_px, s.centre_max_px,
                s.heading_rms_deg, s.heading_max_deg);
  std::string out = buf;
  if (s.field_pairs) {
    std::snprintf(buf, sizeof buf, "field error %.2f mm RMS (max %.2f), field heading error %.3f deg RMS\n",
                  s.field_rms_mm, s.field_max_mm, s.theta_rms_deg);
    out += buf;
  }
  return out;
}

}  // namespace rilbed::vision
