// The manual (docs/*.md) against the binary: every command and nested command `rilbed
// --help` lists has one section `## rilbed <command>`, whose options table lists exactly
// the options and positionals its --help prints (less -h/--help and --version). The
// docs and the flags cannot drift apart.
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "run_command.hpp"

namespace rilbed::e2e {
namespace {

namespace fs = std::filesystem;

// What one `--help` lists.
struct Help {
  std::set<std::string> options;         // every name: "--seed", "-o", "scenario"
  std::vector<std::string> subcommands;  // nested commands
};

// CLI11's help: sections "Positionals:", "Options:", "Subcommands:"; an entry is a line
// with two spaces and its names ("-o,--out TEXT ..."), continuation lines are indented more.
Help parse_help(const std::string& text) {
  Help h;
  std::istringstream in(text);
  std::string line, section;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == ':' && line.find(' ') == std::string::npos) {
      section = line;
      continue;
    }
    if (line.size() < 3 || line.compare(0, 2, "  ") != 0 || line[2] == ' ') continue;
    const std::string first = line.substr(2, line.find(' ', 2) - 2);
    if (section == "Subcommands:") {
      h.subcommands.push_back(first);
      continue;
    }
    if (section != "Options:" && section != "Positionals:") continue;
    std::istringstream names(first);
    for (std::string name; std::getline(names, name, ',');) {
      if (name != "-h" && name != "--help" && name != "--version") h.options.insert(name);
    }
  }
  return h;
}

// Every section of docs/*.md, by heading ("rilbed run"), with the option names its
// tables' first cells hold in backticks; and the files a heading appears in.
struct Manual {
  std::map<std::string, std::set<std::string>> options;
  std::map<std::string, std::vector<std::string>> files;
};

Manual read_manual() {
  Manual m;
  const std::regex backticked("`([^`]+)`");
  for (const auto& entry : fs::directory_iterator(fs::path(RILBED_SOURCE_DIR) / "docs")) {
    if (entry.path().extension() != ".md") continue;
    std::istringstream in(read_file(entry.path()));
    std::string line, heading;
    while (std::getline(in, line)) {
      if (line.rfind("## ", 0) == 0) {
        heading = line.rfind("## rilbed ", 0) == 0 ? line.substr(3) : "";
        if (!heading.empty()) {
          m.options[heading];
          m.files[heading].push_back(entry.path().filename().string());
        }
        continue;
      }
      if (heading.empty() || line.rfind("| ", 0) != 0) continue;
      const std::string cell = line.substr(2, line.find('|', 2) - 2);
      for (auto it = std::sregex_iterator(cell.begin(), cell.end(), backticked); it != std::sregex_iterator(); ++it) {
        const std::string name = (*it)[1];
        if (name.find(' ') == std::string::npos) m.options[heading].insert(name);
      }
    }
  }
  return m;
}

// "rilbed run" and its nested commands' names, from their --help.
void each_command(const std::string& words, std::map<std::string, Help>& out) {
  const CommandResult r = run_rilbed(words.substr(std::string("rilbed").size()) + " --help");
  ASSERT_EQ(r.exit_code, 0) << words << ": " << r.err;
  const Help help = parse_help(r.out);
  if (words != "rilbed") out[words] = help;
  for (const std::string& sub : help.subcommands) each_command(words + " " + sub, out);
}

TEST(DocsCli, EveryCommandsOptionsAreTheManualsAndNoOthers) {
  std::map<std::string, Help> commands;
  each_command("rilbed", commands);
  ASSERT_GT(commands.size(), 15u);  // run, detect, calibrate intrinsics, ...
  const Manual manual = read_manual();
  for (const auto& [command, help] : commands) {
    SCOPED_TRACE(command);
    const auto section = manual.options.find(command);
    if (section == manual.options.end()) {
      ADD_FAILURE() << "docs/ has no section '## " << command << "'";
      continue;
    }
    EXPECT_EQ(manual.files.at(command).size(), 1u) << "'## " << command << "' is in more than one page";
    for (const std::string& o : help.options) {
      EXPECT_TRUE(section->second.contains(o)) << command << " --help lists " << o << ", its section does not";
    }
    for (const std::string& o : section->second) {
      EXPECT_TRUE(help.options.contains(o)) << "its section lists " << o << ", which " << command << " --help does not";
    }
  }
  for (const auto& [heading, options] : manual.options) {
    EXPECT_TRUE(commands.contains(heading)) << "docs/ has '## " << heading << "', which is no command";
  }
}

}  // namespace
}  // namespace rilbed::e2e
