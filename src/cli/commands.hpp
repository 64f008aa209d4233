// Each subcommand registers its options on the app and, when chosen, sets 'action'.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>

namespace ffcube::cli {

void add_formfactors_command(CLI::App& app, std::function<int()>& action);
void add_view_command(CLI::App& app, std::function<int()>& action);
void add_solve_command(CLI::App& app, std::function<int()>& action);
void add_bench_command(CLI::App& app, std::function<int()>& action);
void add_calibrate_command(CLI::App& app, std::function<int()>& action);
// `ffcube view3d IN OUT` (cmd_view3d.cpp; `ffcube-view3d IN OUT` runs it: src/cli/ffcube_view3d/).
void add_view3d_command(CLI::App& app, std::function<int()>& action);
// `ffcube radiate`: gray-body heat flux, temperatures and conductances (cmd_radiate.cpp; docs/radiate.md).
void add_radiate_command(CLI::App& app, std::function<int()>& action);
// `ffcube sun`: sunlit fractions for one sun direction (cmd_sun.cpp; docs/urban.md, "Sun and shade").
void add_sun_command(CLI::App& app, std::function<int()>& action);

}  // namespace ffcube::cli
