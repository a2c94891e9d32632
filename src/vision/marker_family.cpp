#include "vision/marker_family.hpp"

#include <cmath>
#include <stdexcept>

#include "core/geometry.hpp"

namespace rilbed::vision {

MarkerFamily::MarkerFamily(std::string name, std::vector<double> slice_deg)
    : name_(std::move(name)), slice_deg_(std::move(slice_deg)) {}

MarkerFamily MarkerFamily::six_ucp() { return MarkerFamily("6ucp", {85, 55, 55, 55, 55, 55}); }

MarkerFamily MarkerFamily::k_ucp(int slice_count) {
  if (slice_count == 6) return six_ucp();
  if (slice_count < 6 || slice_count > 14) {
    throw std::invalid_argument("kUCP families exist for k in 6..14, not " + std::to_string(slice_count));
  }
  const double unit_deg = 360.0 / (slice_count - 1 + 1.5);
  std::vector<double> widths(slice_count, unit_deg);
  widths[0] = 1.5 * unit_deg;
  return MarkerFamily(std::to_string(slice_count) + "ucp", std::move(widths));
}

MarkerFamily MarkerFamily::by_name(std::string_view name) {
  std::string lower;
  for (char c : name) lower.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(c))));
  if (lower.size() >= 4 && lower.substr(lower.size() - 3) == "ucp") {
    const std::string digits = lower.substr(0, lower.size() - 3);
    if (!digits.empty() && digits.size() <= 2 && digits.find_first_not_of("0123456789") == std::string::npos) {
      const int k = std::stoi(digits);
      if (k >= 6 && k <= 14) return k_ucp(k);
    }
  }
  throw std::invalid_argument("unknown marker family '" + std::string(name) +
                              "' (expected 6ucp, or kucp for k in 7..14)");
}

std::vector<MarkerSlice> MarkerFamily::slices(int id) const {
  if (!valid_id(id)) {
    throw std::out_of_range("ID " + std::to_string(id) + " is not in family " + name_ + " (1.." +
                            std::to_string(max_id()) + ")");
  }
  const int code = id - 1;
  std::vector<MarkerSlice> out;
  double start = -slice_deg_[0] / 2.0;
  for (int i = 0; i < slice_count(); ++i) {
    MarkerSlice s{start, start + slice_deg_[i], false};
    if (i == 0) {
      s.white = true;  // key slice
    } else if (i >= 2 && i <= slice_count() - 2) {
      s.white = ((code >> (i - 2)) & 1) != 0;  // code bit x_(i-1), least significant first
    }
    out.push_back(s);
    start = s.end_deg;
  }
  return out;
}

double MarkerFamily::colour_at(int id, double r, double angle_deg) const {
  if (r > 1.0) return -1.0;
  if (r > black_ring_outer_radius) return 1.0;
  if (r > code_outer_radius || r <= hole_radius) return 0.0;
  // Angle measured from the start of the key slice, in [0, 360).
  double a = wrap_deg_360(angle_deg + slice_deg_[0] / 2.0);
  const int code = id - 1;
  for (int i = 0; i < slice_count(); ++i) {
    if (a < slice_deg_[i] || i == slice_count() - 1) {
      if (i == 0) return 1.0;
      if (i >= 2 && i <= slice_count() - 2) return ((code >> (i - 2)) & 1) ? 1.0 : 0.0;
      return 0.0;
    }
    a -= slice_deg_[i];
  }
  return 0.0;
}

}  // namespace rilbed::vision
