// The expert door. `--help` lists what a user needs; tuning knobs (and the viewer's scripting and
// test hooks) are registered in one group, kExpertGroup, which `--help` hides and `--help-all`
// lists, and are set with `--set NAME=VALUE` (NAME as --help-all spells it, without the dashes;
// a flag: `--set NAME`). docs/cli.md is the --help-all of every command (tools/gen_cli_docs.sh;
// a test fails when it is stale).
#pragma once

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

namespace ffcube::cli {

inline constexpr const char* kExpertGroup = "Tuning knobs (--set NAME=VALUE)";

// Puts an option behind the door; returns it for chaining.
CLI::Option* expert(CLI::Option* o);

// Adds --set and --help-all to a subcommand's listing (they are consumed by open_door before
// CLI11 parses).
void add_door_options(CLI::App& sub);

// The command line with the door opened: every `--set NAME=VALUE` (or `--set=NAME=VALUE`)
// becomes `--NAME=VALUE`, after checking that NAME is a tuning knob of the chosen subcommand
// (CLI::ValidationError naming it otherwise); `--help-all` becomes `--help`. Unless --help-all
// was asked for, the tuning knobs of every subcommand are left out of the help.
std::vector<std::string> open_door(CLI::App& app, int argc, char** argv);

}  // namespace ffcube::cli
