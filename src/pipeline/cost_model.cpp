#include "ffcube/pipeline/cost_model.hpp"

#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "ffcube/core/error.hpp"
#include "ffcube/core/input_file.hpp"
#include "ffcube/io/atomic_file.hpp"

namespace ffcube {

void check_cost_model(const CostModel& m, const std::string& where) {
    if (!std::isfinite(m.pixel_ns) || m.pixel_ns < 1e-4 || m.pixel_ns > 1e4)
        throw InputError(fmt::format("{}: pixel_ns {} is outside 1e-4..1e4 (ns per hemicube pixel)", where, m.pixel_ns));
    if (!std::isfinite(m.cpu_scale) || m.cpu_scale < 1e-3 || m.cpu_scale > 1e3)
        throw InputError(fmt::format("{}: cpu_scale {} is outside 1e-3..1e3 (the CPU's time against the "
                                     "development machine's)",
                                     where, m.cpu_scale));
    if (!std::isfinite(m.piece_ns) || m.piece_ns < 1e-3 || m.piece_ns > 1e7)
        throw InputError(fmt::format("{}: piece_ns {} is outside 1e-3..1e7 (ns per piece per hemicube)", where, m.piece_ns));
    if (!std::isfinite(m.ray_ns) || m.ray_ns < 1e-2 || m.ray_ns > 1e6)
        throw InputError(fmt::format("{}: ray_ns {} is outside 1e-2..1e6 (CPU ns per ray)", where, m.ray_ns));
}

CostModel read_cost_model(const std::string& path) {
    // Regular files only (a FIFO would block the read for ever): docs/robustness.md, "Input paths".
    try {
        require_regular_file(path, "a cost model file", "the cost model");
    } catch (const InputError& e) {
        throw InputError(fmt::format("--cost-model {}", e.what()));
    }
    std::ifstream in(path);
    if (!in) throw InputError(fmt::format("--cost-model {}: cannot open the file", path));
    nlohmann::json j;
    try {
        j = nlohmann::json::parse(in);
    } catch (const nlohmann::json::parse_error& e) {
        throw InputError(fmt::format("--cost-model {}: not JSON (byte {}): {}", path, e.byte, e.what()));
    }
    if (!j.is_object()) throw InputError(fmt::format("--cost-model {}: not a JSON object", path));
    CostModel m;
    for (auto [key, value] : {std::pair<const char*, double*>{"pixel_ns", &m.pixel_ns}, {"cpu_scale", &m.cpu_scale}}) {
        const auto it = j.find(key);
        if (it == j.end()) throw InputError(fmt::format("--cost-model {}: the key \"{}\" is missing", path, key));
        if (!it->is_number()) throw InputError(fmt::format("--cost-model {}: \"{}\" is not a number", path, key));
        *value = it->get<double>();
    }
    // Keys a file from before `--method auto` followed the costs lacks: the built-in values.
    for (auto [key, value] : {std::pair<const char*, double*>{"piece_ns", &m.piece_ns}, {"ray_ns", &m.ray_ns}}) {
        const auto it = j.find(key);
        if (it == j.end()) continue;
        if (!it->is_number()) throw InputError(fmt::format("--cost-model {}: \"{}\" is not a number", path, key));
        *value = it->get<double>();
    }
    m.source = path;
    check_cost_model(m, fmt::format("--cost-model {}", path));
    return m;
}

void write_cost_model(const std::string& path, const CostModel& m, const std::string& measured_on, int resolution,
                      double cpu_seconds, double reference_cpu_seconds) {
    nlohmann::json j;
    j["pixel_ns"] = m.pixel_ns;
    j["cpu_scale"] = m.cpu_scale;
    j["piece_ns"] = m.piece_ns;
    j["ray_ns"] = m.ray_ns;
    j["measured_on"] = measured_on;
    j["resolution"] = resolution;
    j["cpu_workload_seconds"] = cpu_seconds;
    j["cpu_workload_reference_seconds"] = reference_cpu_seconds;
    const CostModel b;
    j["built_in"] = {{"pixel_ns", b.pixel_ns}, {"cpu_scale", b.cpu_scale}, {"piece_ns", b.piece_ns}, {"ray_ns", b.ray_ns}};
    write_file_atomically(path, [&](std::ostream& out) { out << j.dump(2) << '\n'; });
}

}  // namespace ffcube
