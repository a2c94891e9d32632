// A run's console token, and the file that hands it to `rilbed console` and `rilbed gui`
// of the same user: written readable by that user only, removed when the run goes.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

namespace rilbed::session {

/// A fresh token, written to bus::token_path(channel_prefix). A finished run's token opens
/// nothing, so the file goes with this object, unless a newer run with the same prefix has
/// written its own since.
class RunToken {
 public:
  explicit RunToken(const std::string& channel_prefix);
  ~RunToken();
  RunToken(const RunToken&) = delete;
  RunToken& operator=(const RunToken&) = delete;

  const std::string& token() const { return token_; }
  const std::filesystem::path& file() const { return file_; }
  /// Why the file could not be written (the token still works, given with --token).
  const std::optional<std::string>& file_problem() const { return problem_; }

 private:
  std::string token_;
  std::filesystem::path file_;
  std::optional<std::string> problem_;
};

}  // namespace rilbed::session
