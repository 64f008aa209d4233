// FE and CAD meshes through Gmsh's library (gmsh_loader.hpp). Gmsh is not written for hostile
// input (a truncated .msh makes it throw from deep inside, a garbage one may loop, OpenCASCADE's
// STEP reader allocates what the file asks), so it never runs in ffcube's process: the file is
// checked as a regular file (core/input_file.hpp), Nastran decks get ffcube's card pre-check,
// and Gmsh then runs in a forked child with a time limit and an address-space cap
// (core/guarded_child.hpp), which collects the faces and sends the model back as bytes
// (model_wire.hpp), as the assimp reader does (docs/robustness.md, "Third-party parsers").
#include "ffcube/scene/gmsh_loader.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <gmsh.h>
#include <string.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>

#include "ffcube/core/error.hpp"
#include "ffcube/core/error_transport.hpp"
#include "ffcube/core/guarded_child.hpp"
#include "ffcube/core/input_file.hpp"
#include "ffcube/scene/assimp_loader.hpp"
#include "ffcube/scene/fe_cells.hpp"
#include "ffcube/scene/vtk_legacy.hpp"
#include "scene/gmsh_collector.hpp"
#include "scene/model_wire.hpp"

namespace ffcube {
namespace {

std::string lower_extension(std::string_view extension) {
    std::string ext(extension);
    if (!ext.empty() && ext.front() != '.') ext = "." + ext;
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return ext;
}

// When Gmsh refuses an ASCII .msh file and says only "Error loading", the reason may be an
// element type it does not know: this scan (in the child, after the refusal) finds it and names
// the line. $Elements of version 2.2 has "id type ntags ..." lines; of version 4, blocks with a
// header "dim tag type count".
std::string unknown_element_type(const std::filesystem::path& path) {
    std::string text;
    try {
        text = read_input_file(path, "a Gmsh mesh", "the scene");
    } catch (const Error&) {
        return {};
    }
    const std::size_t format = text.find("$MeshFormat\n");
    const std::size_t elements = text.find("$Elements\n");
    if (format == std::string::npos || elements == std::string::npos) return {};
    double version = 0.0;
    int binary = 1;
    if (std::sscanf(text.c_str() + format + 12, "%lf %d", &version, &binary) != 2 || binary != 0) return {};
    std::map<int, bool> known;
    const auto is_known = [&](int type) {
        const auto [it, inserted] = known.emplace(type, true);
        if (inserted) {
            try {
                std::string name;
                int dim = 0, order = 0, nodes = 0, primary = 0;
                std::vector<double> local;
                gmsh::model::mesh::getElementProperties(type, name, dim, order, nodes, local, primary);
            } catch (...) {
                it->second = false;
            }
        }
        return it->second;
    };
    std::size_t line_no = std::size_t(std::count(text.begin(), text.begin() + std::ptrdiff_t(elements), '\n')) + 1;
    std::size_t at = text.find('\n', elements) + 1;
    const auto next_line = [&]() -> std::string_view {
        if (at >= text.size()) return {};
        std::size_t end = text.find('\n', at);
        if (end == std::string::npos) end = text.size();
        const std::string_view line(text.data() + at, end - at);
        at = end + 1;
        ++line_no;
        return line;
    };
    const auto numbers = [](std::string_view line) {
        std::vector<long long> v;
        std::string s(line);
        char* p = s.data();
        for (char* e = nullptr;; p = e) {
            const long long x = std::strtoll(p, &e, 10);
            if (e == p) break;
            v.push_back(x);
        }
        return v;
    };
    const std::vector<long long> head = numbers(next_line());
    if (head.empty()) return {};
    if (version < 3) {
        for (long long k = 0; k < head[0] && at < text.size(); ++k) {
            const std::vector<long long> e = numbers(next_line());
            if (e.size() >= 2 && !is_known(int(e[1])))
                return fmt::format("line {}: element {} is of type {}, which Gmsh does not know", line_no, e[0], e[1]);
        }
        return {};
    }
    for (long long b = 0; b < head[0] && at < text.size(); ++b) {
        const std::vector<long long> block = numbers(next_line());
        if (block.size() < 4) return {};
        if (!is_known(int(block[2])))
            return fmt::format("line {}: an element block of type {}, which Gmsh does not know", line_no, block[2]);
        for (long long k = 0; k < block[3] && at < text.size(); ++k) next_line();
    }
    return {};
}

// Gmsh's errors, as its log has them (the first says why; what it throws may only say
// "Error loading"), else what it threw.
[[noreturn]] void rethrow_gmsh(const std::string& source, const std::string& what) {
    std::vector<std::string> errors;
    try {
        std::vector<std::string> log;
        gmsh::logger::get(log);
        for (const std::string& line : log)
            if (line.starts_with("Error: ")) errors.push_back(line.substr(7));
    } catch (...) {
    }
    if (errors.empty() && !what.empty()) errors.push_back(what);
    std::string message;
    for (std::size_t i = 0; i < errors.size() && i < 3; ++i) message += (i ? "; " : "") + errors[i];
    throw InputError(fmt::format("{}: Gmsh cannot read it: {}", source, message.empty() ? "(no message)" : message));
}

// Gmsh, in the guarded child: open (and mesh a CAD model), collect, encode.
std::string read_in_child(const std::filesystem::path& path, const FeLoadOptions& options) {
    // OpenCASCADE writes its statistics to stdout, which may be ffcube's output: silence it here.
    const int devnull = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
    if (devnull >= 0) ::dup2(devnull, 1);
    const std::string source = path.string();
    const std::string ext = lower_extension(path.extension().string());
    const bool cad = gmsh_is_cad_extension(ext);
    std::string what;
    try {
        gmsh::initialize(0, nullptr, false);
        gmsh::option::setNumber("General.Terminal", 0);
        gmsh::option::setNumber("General.NumThreads", 1);  // one answer whatever the machine
        gmsh::logger::start();
        gmsh::open(source);
        if (cad) {
            double size = options.cad_mesh_size;
            if (size <= 0.0 && options.cad_patches > 0) {
                double area = 0.0;
                gmsh::vectorpair surfaces;
                gmsh::model::getEntities(surfaces, 2);
                for (const auto& [dim, tag] : surfaces) {
                    double a = 0.0;
                    gmsh::model::occ::getMass(dim, tag, a);
                    area += a;
                }
                size = std::sqrt(area / double(options.cad_patches));
            }
            if (size > 0.0) {
                // Else the sizes OpenCASCADE gives the model's points win over the maximum.
                gmsh::option::setNumber("Mesh.MeshSizeFromPoints", 0);
                gmsh::option::setNumber("Mesh.MeshSizeMax", size);
            }
            gmsh::model::mesh::generate(2);
        }
        std::string last;
        gmsh::logger::getLastError(last);
        if (!last.empty()) rethrow_gmsh(source, last);
        return detail::encode_imported(collect_gmsh_model(source, options, ext == ".bdf" || ext == ".nas", cad), ImportedMaterials{});
    } catch (const Error&) {
        throw;
    } catch (const std::string& s) {
        what = s;
        if (ext == ".msh")
            if (const std::string why = unknown_element_type(path); !why.empty())
                throw InputError(fmt::format("{}: {}", source, why));
    } catch (const std::exception& e) {
        what = e.what();
    } catch (...) {
    }
    rethrow_gmsh(source, what);
}

// The child's limits (docs/robustness.md, "Third-party parsers"): time 20 s + 2 s per MiB of
// input (Gmsh reads meshes at tens of MiB a second; meshing a CAD model takes longer, and
// OpenCASCADE's start alone takes about a second), address space 2 GiB + 256 bytes per byte
// (OpenCASCADE's shapes and Gmsh's mesh structures take far more per byte than the file).
ChildLimits gmsh_limits(std::uint64_t input_bytes) {
    ChildLimits limits;
    const std::uint64_t mib = (input_bytes + (1u << 20) - 1) >> 20;
    limits.wall = std::chrono::milliseconds(20000 + 2000 * std::min<std::uint64_t>(mib, 1u << 20));
    limits.extra_address_space = (std::uint64_t(2) << 30) + 256 * input_bytes;
    return limits;
}

}  // namespace

// Gmsh keeps the first of two physical groups of one name and leaves the other unnamed without a
// word, so ffcube reads a .msh file's $PhysicalNames section (text in every .msh version, binary
// files included) itself: one name per dimension.
void check_msh_physical_names(std::string_view bytes, const std::string& source) {
    const std::size_t at = bytes.find("$PhysicalNames");
    if (at == std::string_view::npos) return;
    const std::size_t end = bytes.find("$EndPhysicalNames", at);
    if (end == std::string_view::npos)
        throw InputError(fmt::format("{}: $PhysicalNames has no $EndPhysicalNames (the file is cut short)", source));
    const std::size_t line0 = std::size_t(std::count(bytes.begin(), bytes.begin() + std::ptrdiff_t(at), '\n')) + 1;
    std::map<std::pair<int, std::string>, std::size_t> seen;
    std::size_t line_no = line0, pos = bytes.find('\n', at);
    while (pos != std::string_view::npos && pos < end) {
        const std::size_t next = bytes.find('\n', pos + 1);
        const std::string_view line = bytes.substr(pos + 1, (next == std::string_view::npos ? bytes.size() : next) - pos - 1);
        ++line_no;
        pos = next;
        const std::size_t q1 = line.find('"'), q2 = line.rfind('"');
        if (q1 == std::string_view::npos || q2 <= q1) continue;  // the count line
        const int dim = std::atoi(std::string(line.substr(0, q1)).c_str());
        const auto [it, inserted] = seen.emplace(std::pair{dim, std::string(line.substr(q1 + 1, q2 - q1 - 1))}, line_no);
        if (!inserted)
            throw InputError(fmt::format("{}: line {}: the physical group name \"{}\" is used twice (also line {}); each group "
                                         "needs its own name",
                                         source, line_no, it->first.second, it->second));
    }
}

// Gmsh's last error, or what it threw (it throws the message as a std::string, or an int).
bool gmsh_reads_extension(std::string_view extension) {
    const std::string ext = lower_extension(extension);
    return ext == ".msh" || ext == ".unv" || ext == ".bdf" || ext == ".nas" || ext == ".vtk" || gmsh_is_cad_extension(ext);
}

bool gmsh_is_cad_extension(std::string_view extension) {
    const std::string ext = lower_extension(extension);
    return ext == ".step" || ext == ".stp" || ext == ".iges" || ext == ".igs";
}

ObjModel run_gmsh_child(const std::string& source, std::uint64_t bytes, const std::function<std::string()>& work) {
    const ChildLimits limits = gmsh_limits(bytes);
    const ChildResult r = run_guarded(work, limits);
    const double mib = double(bytes) / double(1 << 20);
    switch (r.end) {
    case ChildResult::End::returned: break;
    case ChildResult::End::threw: throw_error(r.error_kind, r.error_message);
    case ChildResult::End::signalled:
        throw InputError(fmt::format("{}: Gmsh crashed reading it (signal {}: {}); the file is malformed", source, r.signal,
                                     strsignal(r.signal)));
    case ChildResult::End::timed_out:
        throw InputError(fmt::format("{}: Gmsh took longer than {} s to read it (the limit for {:.1f} MiB of input: 20 s + 2 s "
                                     "per MiB), and was stopped",
                                     source, limits.wall.count() / 1000, mib));
    case ChildResult::End::out_of_memory:
        throw InputError(fmt::format("{}: Gmsh needed more than {} MiB to read it (the limit for {:.1f} MiB of input: 2 GiB + "
                                     "256 bytes per byte), and was stopped",
                                     source, limits.extra_address_space >> 20, mib));
    case ChildResult::End::exited:
        throw InputError(fmt::format("{}: the Gmsh reading process ended (status {}) without a result", source, r.status));
    }
    ImportedMaterials unused;
    return detail::decode_imported(r.payload, unused);
}

ObjModel load_with_gmsh(const std::filesystem::path& path, const FeLoadOptions& options) {
    const std::string source = path.string();
    std::uint64_t bytes = 0;
    {
        const MappedInput file(path, "a mesh or CAD file", "the scene");
        bytes = file.bytes().size();
        const std::string ext = lower_extension(path.extension().string());
        if (bytes == 0) throw InputError(fmt::format("{}: the file is empty", source));
        if (ext == ".bdf" || ext == ".nas") check_nastran_cards(file.bytes(), source);
        if (ext == ".msh") check_msh_physical_names(file.bytes(), source);
        // A cell array as the objects, or a version Gmsh 4.8 misreads (5.x): ffcube's own VTK
        // reader, and the cells through Gmsh's model API as for Python's meshio (vtk_legacy.hpp).
        if (ext == ".vtk" && (!options.field.empty() || vtk_legacy_version(file.bytes()) >= 5))
            return load_fe_cells(read_vtk_legacy(file.bytes(), source, options.field), options);
        if (gmsh_is_cad_extension(ext)) {
            const std::string_view head = file.bytes().substr(0, 80);
            const bool step = ext == ".step" || ext == ".stp";
            if (step && !head.starts_with("ISO-10303-21;"))
                throw InputError(fmt::format("{}: not a STEP file (a STEP file begins with 'ISO-10303-21;')", source));
        }
    }
    return run_gmsh_child(source, bytes, [&] { return read_in_child(path, options); });
}

}  // namespace ffcube
