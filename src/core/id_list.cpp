#include "core/id_list.hpp"

#include <algorithm>
#include <charconv>

namespace rilbed {
namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

std::optional<int> parse_int(std::string_view s) {
  s = trim(s);
  int value = 0;
  const auto* end = s.data() + s.size();
  auto [ptr, ec] = std::from_chars(s.data(), end, value);
  if (s.empty() || ec != std::errc{} || ptr != end) return std::nullopt;
  return value;
}

}  // namespace

IdListResult parse_id_list(std::string_view text, int min_id, int max_id, std::string_view what) {
  IdListResult result;
  if (trim(text).empty()) {
    result.error = "empty " + std::string(what);
    return result;
  }
  std::size_t start = 0;
  while (start <= text.size()) {
    std::size_t comma = text.find(',', start);
    if (comma == std::string_view::npos) comma = text.size();
    std::string_view item = trim(text.substr(start, comma - start));
    std::size_t dash = item.find('-', 1);  // from 1: a leading '-' is a sign, not a range
    std::optional<int> lo = parse_int(dash == std::string_view::npos ? item : item.substr(0, dash));
    std::optional<int> hi = dash == std::string_view::npos ? lo : parse_int(item.substr(dash + 1));
    if (!lo || !hi || *lo > *hi) {
      result.error = "bad " + std::string(what) + " item '" + std::string(item) + "' (expected N or A-B with A<=B)";
      return result;
    }
    if (*lo < min_id || *hi > max_id) {
      result.error = std::string(what) + " item '" + std::string(item) + "' is outside " + std::to_string(min_id) +
                     ".." + std::to_string(max_id);
      return result;
    }
    for (int id = *lo; id <= *hi; ++id) result.ids.push_back(id);
    start = comma + 1;
  }
  std::sort(result.ids.begin(), result.ids.end());
  result.ids.erase(std::unique(result.ids.begin(), result.ids.end()), result.ids.end());
  return result;
}

std::string id_list_text(const std::vector<int>& ids) {
  std::string text;
  for (const int id : ids) {
    if (!text.empty()) text += ", ";
    text += std::to_string(id);
  }
  return text;
}

std::string id_ranges_text(const std::vector<int>& ids) {
  std::string text;
  for (std::size_t i = 0; i < ids.size();) {
    std::size_t last = i;
    while (last + 1 < ids.size() && ids[last] < ids[last + 1] && ids[last + 1] - ids[last] == 1) ++last;
    if (!text.empty()) text.push_back(',');
    text.append(std::to_string(ids[i]));
    if (last > i) text.append("-").append(std::to_string(ids[last]));
    i = last + 1;
  }
  return text;
}

}  // namespace rilbed
