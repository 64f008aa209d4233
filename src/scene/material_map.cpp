// --materials FILE: Kd and Ke per object name, from a small CSV file (material_map.hpp).
#include "ffcube/scene/material_map.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <optional>
#include <unordered_map>
#include <utility>
#include <vector>

#include "ffcube/core/csv_input.hpp"
#include "ffcube/core/error.hpp"
#include "ffcube/scene/load_model.hpp"
#include "text_number.hpp"

namespace ffcube {

namespace {

constexpr std::uint32_t kNone = std::uint32_t(-1);

// One line's Kd (fields 1..3) or Ke (fields 4..6): three numbers, or three empty fields (nullopt:
// keep the file's).
std::optional<Vec3> read_triple(const CsvRow& row, bool kd) {
    const char* what = kd ? "Kd" : "Ke";
    const std::size_t first = kd ? 1 : 4;
    const auto empty = std::count_if(row.fields.begin() + first, row.fields.begin() + first + 3,
                                     [](const std::string& f) { return f.empty(); });
    if (empty == 3) return std::nullopt;
    if (empty > 0)
        row.fail(fmt::format("{} has {} of its 3 fields empty: give all three, or leave all three empty to keep the scene "
                             "file's {}",
                             what, empty, what));
    Vec3 v(0.0);
    for (int c = 0; c < 3; ++c) {
        v[c] = *row.number(first + c, kd ? "Kd: diffuse reflectance within [0,1]" : "Ke: emitted radiosity >= 0");
        // Below 1, not at most 1: a surface that reflects all it receives has no steady state, and
        // every solve refuses it (solver.cpp) — here the message can name this line.
        if (kd && !(v[c] >= 0.0 && v[c] < 1.0))
            row.fail(fmt::format("Kd {} must be within [0,1) (diffuse reflectance per channel; a surface that reflects "
                                 "everything it receives has no steady state)",
                                 v[c]));
        if (!kd && !(v[c] >= 0.0)) row.fail(fmt::format("Ke {} must be >= 0 (emitted radiosity per channel)", v[c]));
        // The scene formats' bound on every number (text_number.hpp), which keeps emitted powers far from overflow.
        if (!kd && v[c] > detail::kMaxCoordinate)
            row.fail(fmt::format("Ke {} is too large (numbers must have magnitude at most 1e15)", v[c]));
    }
    return v;
}

// What one line asks of its object: Kd, Ke, or both (what is not given stays the file's).
struct Override {
    std::string name;
    std::optional<Vec3> kd, ke;
    std::uint32_t whole = kNone;  // both given: the object's one material
};

// The lines of the CSV (core/csv_input.hpp's rules; the header is optional).
std::vector<Override> read_overrides(std::string_view csv, const std::string& source, std::vector<std::uint32_t>& lines) {
    static const CsvHeader kHeader = {"object", "kd_r", "kd_g", "kd_b", "ke_r", "ke_g", "ke_b"};
    std::vector<Override> out;
    for (const CsvRow& row : parse_csv(csv, source, std::span(&kHeader, 1), /*header_optional=*/true).rows) {
        if (row.fields[0].empty()) row.fail("the object name is empty");
        std::optional<Vec3> kd = read_triple(row, true);
        out.push_back(Override{row.fields[0], kd, read_triple(row, false)});
        lines.push_back(static_cast<std::uint32_t>(row.line));
    }
    return out;
}

// The material of a face of `o`'s object that had `old`: o's own when it gives both, else one per
// (object, old material) with what o does not give kept from `old`.
std::uint32_t overridden(ObjModel& model, const Override& o, std::uint32_t object, std::uint32_t old,
                         std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t>& made) {
    if (o.whole != kNone) return o.whole;
    const auto [it, inserted] = made.try_emplace({object, old}, static_cast<std::uint32_t>(model.materials.size()));
    if (inserted) {
        const Material& was = model.materials[old];
        Material m{o.name, o.kd.value_or(was.kd), o.ke.value_or(was.ke)};
        model.materials.push_back(std::move(m));
    }
    return it->second;
}

}  // namespace

void apply_material_map(ObjModel& model, std::string_view csv, const std::string& source) {
    std::unordered_map<std::string, std::uint32_t> object_of_name;
    for (std::size_t i = 0; i < model.objects.size(); ++i) object_of_name.emplace(model.objects[i], static_cast<std::uint32_t>(i));
    std::vector<std::uint32_t> lines;
    std::vector<Override> overrides = read_overrides(csv, source, lines);
    std::vector<const Override*> override_of_object(model.objects.size(), nullptr);
    std::unordered_map<std::string, std::uint32_t> line_of_name;
    std::size_t unknown = 0;
    for (std::size_t k = 0; k < overrides.size(); ++k) {
        Override& o = overrides[k];
        if (const auto [it, inserted] = line_of_name.try_emplace(o.name, lines[k]); !inserted)
            detail::fail_at(source, lines[k], fmt::format("object '{}' is given twice (first on line {})", o.name, it->second));
        const auto obj = object_of_name.find(o.name);
        if (obj == object_of_name.end()) {
            if (unknown++ < 10)
                model.warnings.push_back(fmt::format("{}:{}: the scene has no object '{}'; the line is ignored", source, lines[k], o.name));
            continue;
        }
        if (!o.kd && !o.ke) continue;  // both kept: nothing to do
        if (o.kd && o.ke) {
            o.whole = static_cast<std::uint32_t>(model.materials.size());
            model.materials.push_back(Material{o.name, *o.kd, *o.ke});
        }
        override_of_object[obj->second] = &o;
    }
    if (unknown > 10) model.warnings.push_back(fmt::format("{}: {} more unknown objects ignored", source, unknown - 10));
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> made;
    for (ObjFace& f : model.faces)
        if (const Override* o = override_of_object[f.object]) f.material = overridden(model, *o, f.object, f.material, made);
}

void apply_material_map_file(ObjModel& model, const std::filesystem::path& path) {
    apply_material_map(model, read_scene_file(path, "a materials CSV file", "the materials"), path.string());
}

}  // namespace ffcube
