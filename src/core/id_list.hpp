// Parsing of ID lists such as "1-8" or "1,3,5-7" given on command lines and in files.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace rilbed {

/// Result of parsing an ID list: the sorted, de-duplicated IDs, or an error message
/// that quotes the offending part of the text.
struct IdListResult {
  std::vector<int> ids;
  std::string error;  ///< empty on success
  bool ok() const { return error.empty(); }
};

/// Parses a comma-separated list of IDs and inclusive ranges ("1-8", "2,4,9-12").
/// Every ID must lie in [min_id, max_id]. Whitespace around items is ignored. `what`
/// names the list in errors ("ID list"; a list of counts says "list").
IdListResult parse_id_list(std::string_view text, int min_id, int max_id, std::string_view what = "ID list");

/// IDs as people read them: "4, 5, 7" (in the order given; empty for none).
std::string id_list_text(const std::vector<int>& ids);

/// IDs as parse_id_list reads them, runs of consecutive IDs as ranges: "1-4,7,9-12" (in
/// the order given; empty for none). A thousand robots make a short argument.
std::string id_ranges_text(const std::vector<int>& ids);

}  // namespace rilbed
