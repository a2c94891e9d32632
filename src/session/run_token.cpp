#include "session/run_token.hpp"

#include "bus/lcm_console.hpp"

namespace rilbed::session {

RunToken::RunToken(const std::string& channel_prefix)
    : token_(bus::make_run_token()), file_(bus::token_path(channel_prefix)) {
  problem_ = bus::write_token(file_, token_);
}

RunToken::~RunToken() {
  std::error_code ignored;
  if (!file_.empty() && bus::read_token(file_) == token_) std::filesystem::remove(file_, ignored);
}

}  // namespace rilbed::session
