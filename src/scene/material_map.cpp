// --materials FILE: Kd and Ke per object name, from a small CSV file (material_map.hpp).
#include "ffcube/scene/material_map.hpp"

#include <fmt/format.h>

#include <unordered_map>
#include <vector>

#include "ffcube/core/error.hpp"
#include "ffcube/scene/load_model.hpp"
#include "text_number.hpp"

namespace ffcube {

void apply_material_map(ObjModel& model, std::string_view csv, const std::string& source) {
    std::unordered_map<std::string, std::uint32_t> object_of_name;
    for (std::size_t i = 0; i < model.objects.size(); ++i) object_of_name.emplace(model.objects[i], static_cast<std::uint32_t>(i));
    std::vector<std::uint32_t> material_of_object(model.objects.size(), std::uint32_t(-1));
    std::unordered_map<std::string, std::uint32_t> line_of_name;
    std::uint32_t number = 0;
    std::size_t unknown = 0;
    for (bool done = false; !done;) {
        const std::size_t eol = csv.find('\n');
        std::string_view line = csv.substr(0, eol);
        if (eol == std::string_view::npos)
            done = true;
        else
            csv.remove_prefix(eol + 1);
        ++number;
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        if (number == 1 && line.substr(0, 3) == "\xEF\xBB\xBF") line.remove_prefix(3);
        if (line.find('\0') != std::string_view::npos) detail::fail_at(source, number, "not a CSV file (a NUL byte)");
        if (line.empty() || line.front() == '#') continue;
        if (number == 1 && line.substr(0, 7) == "object,") continue;  // header
        std::vector<std::string_view> field;
        for (std::size_t start = 0;;) {
            const std::size_t comma = line.find(',', start);
            field.push_back(line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start));
            if (comma == std::string_view::npos) break;
            start = comma + 1;
        }
        if (field.size() != 7)
            detail::fail_at(source, number, fmt::format("expected 7 fields (object,kd_r,kd_g,kd_b,ke_r,ke_g,ke_b), found {}", field.size()));
        const std::string name(field[0]);
        if (name.empty()) detail::fail_at(source, number, "the object name is empty");
        Material m{name, Vec3(0.0), Vec3(0.0)};
        for (int c = 0; c < 3; ++c) {
            m.kd[c] = detail::parse_number(field[1 + c], source, number, "Kd: diffuse reflectance within [0,1]");
            if (!(m.kd[c] >= 0.0 && m.kd[c] <= 1.0))
                detail::fail_at(source, number, fmt::format("Kd {} must be within [0,1] (diffuse reflectance per channel)", m.kd[c]));
            m.ke[c] = detail::parse_number(field[4 + c], source, number, "Ke: emitted radiosity >= 0");
            if (!(m.ke[c] >= 0.0)) detail::fail_at(source, number, fmt::format("Ke {} must be >= 0 (emitted radiosity per channel)", m.ke[c]));
        }
        if (const auto [it, inserted] = line_of_name.try_emplace(name, number); !inserted)
            detail::fail_at(source, number, fmt::format("object '{}' is given twice (first on line {})", name, it->second));
        const auto obj = object_of_name.find(name);
        if (obj == object_of_name.end()) {
            if (unknown++ < 10)
                model.warnings.push_back(fmt::format("{}:{}: the scene has no object '{}'; the line is ignored", source, number, name));
            continue;
        }
        material_of_object[obj->second] = static_cast<std::uint32_t>(model.materials.size());
        model.materials.push_back(std::move(m));
    }
    if (unknown > 10) model.warnings.push_back(fmt::format("{}: {} more unknown objects ignored", source, unknown - 10));
    for (ObjFace& f : model.faces)
        if (material_of_object[f.object] != std::uint32_t(-1)) f.material = material_of_object[f.object];
}

void apply_material_map_file(ObjModel& model, const std::filesystem::path& path) {
    apply_material_map(model, read_scene_file(path, "a materials CSV file"), path.string());
}

}  // namespace ffcube
