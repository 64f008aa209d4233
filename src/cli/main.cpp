// ffcube: radiosity form factors by hemicubes. Only main() catches; errors map to exit codes:
//   1 generic failure, 2 bad input (file, option), 3 I/O failure, 4 no usable OpenGL context,
//   5 a solve that did not reach its tolerance (docs/solvers.md), 70 internal error (a bug in ffcube).
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>
#include <functional>

#include "cli/commands.hpp"
#include "cli/expert.hpp"
#include "cli/mpi_glue.hpp"
#include "ffcube/core/error.hpp"

namespace {

int run(int argc, char** argv) {
    CLI::App app{"ffcube: radiosity form factors (view factors) by hemicubes, and radiosity solvers"};
    app.name("ffcube");  // not argv[0]: the help (and docs/cli.md) reads the same wherever it runs
    app.require_subcommand(1);
    app.set_version_flag("--version", "ffcube 0.1.0");
    std::function<int()> action;
    ffcube::cli::add_formfactors_command(app, action);
    ffcube::cli::add_view_command(app, action);
    ffcube::cli::add_solve_command(app, action);
    ffcube::cli::add_bench_command(app, action);
    ffcube::cli::add_calibrate_command(app, action);
    ffcube::cli::add_view3d_command(app, action);
    ffcube::cli::add_radiate_command(app, action);
    ffcube::cli::add_sun_command(app, action);
    for (CLI::App* sub : app.get_subcommands({})) ffcube::cli::add_door_options(*sub);
    try {
        // The expert door (cli/expert.hpp): --set NAME=VALUE and --help-all, rewritten for CLI11.
        std::vector<std::string> args = ffcube::cli::open_door(app, argc, argv);
        std::reverse(args.begin(), args.end());  // CLI11 takes a vector last argument first
        app.parse(args);
    } catch (const CLI::ParseError& e) {
        return app.exit(e) == 0 ? 0 : 2;
    }
    try {
        // Under mpirun only (docs/scaling.md).
        ffcube::cli::mpi_start(argc, argv, app.get_subcommands().empty() ? "" : app.get_subcommands().front()->get_name());
        return action ? action() : 0;
    } catch (const ffcube::InputError& e) {
        std::fprintf(stderr, "ffcube: error: %s\n", e.what());
        return 2;
    } catch (const ffcube::IoError& e) {
        std::fprintf(stderr, "ffcube: error: %s\n", e.what());
        return 3;
    } catch (const ffcube::GlError& e) {
        std::fprintf(stderr, "ffcube: error: %s\n", e.what());
        return 4;
    } catch (const ffcube::NotConvergedError& e) {
        std::fprintf(stderr, "ffcube: error: %s\n", e.what());
        return 5;
    } catch (const ffcube::InternalError& e) {
        std::fprintf(stderr, "ffcube: %s\n", e.what());
        return 70;
    } catch (const std::bad_alloc&) {
        std::fprintf(stderr, "ffcube: error: out of memory\n");
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "ffcube: error: %s\n", e.what());
        return 1;
    }
}

}  // namespace

// Under mpirun a failing rank's code aborts every rank (cli/mpi_glue.hpp); otherwise the code as is.
int main(int argc, char** argv) { return ffcube::cli::mpi_finish(run(argc, argv)); }
