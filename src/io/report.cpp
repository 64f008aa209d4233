#include "ffcube/io/report.hpp"

#include <cmath>
#include <nlohmann/json.hpp>

#include "ffcube/core/error.hpp"
#include "ffcube/io/atomic_file.hpp"

namespace ffcube {

struct Report::Impl {
    nlohmann::ordered_json root = nlohmann::ordered_json::object();

    // The slot for key, creating the objects on its path. The key is checked before anything is
    // created, so a bad key leaves the report unchanged.
    nlohmann::ordered_json& slot(std::string_view key) {
        FFCUBE_CHECK_MSG(
            !key.empty() && key.front() != '.' && key.back() != '.' && key.find("..") == std::string_view::npos,
            "report key '" + std::string(key) + "' has an empty segment");
        nlohmann::ordered_json* node = &root;
        std::size_t start = 0;
        while (true) {
            const std::size_t dot = key.find('.', start);
            const std::string_view part = key.substr(start, dot == std::string_view::npos ? dot : dot - start);
            FFCUBE_CHECK_MSG(node->is_object(),
                             "report key '" + std::string(key) + "' goes through a value that is not an object");
            node = &(*node)[std::string(part)];
            if (dot == std::string_view::npos) return *node;
            if (node->is_null()) *node = nlohmann::ordered_json::object();
            start = dot + 1;
        }
    }

    // Looks key up without creating anything.
    const nlohmann::ordered_json* find(std::string_view key) const {
        const nlohmann::ordered_json* node = &root;
        std::size_t start = 0;
        while (true) {
            const std::size_t dot = key.find('.', start);
            const std::string part(key.substr(start, dot == std::string_view::npos ? dot : dot - start));
            if (!node->is_object()) return nullptr;
            const auto it = node->find(part);
            if (it == node->end()) return nullptr;
            node = &*it;
            if (dot == std::string_view::npos) return node;
            start = dot + 1;
        }
    }
};

namespace {

// JSON has no NaN or infinity; null says "no meaningful value" in every JSON reader.
nlohmann::ordered_json number(double v) {
    if (!std::isfinite(v)) return nullptr;
    return v;
}

}  // namespace

Report::Report() : impl_(std::make_unique<Impl>()) {}
Report::~Report() = default;
Report::Report(Report&&) noexcept = default;
Report& Report::operator=(Report&&) noexcept = default;

void Report::set(std::string_view key, double value) { impl_->slot(key) = number(value); }
void Report::set(std::string_view key, bool value) { impl_->slot(key) = value; }
void Report::set(std::string_view key, std::string_view value) { impl_->slot(key) = std::string(value); }
void Report::set_int(std::string_view key, std::int64_t value) { impl_->slot(key) = value; }
void Report::set_uint(std::string_view key, std::uint64_t value) { impl_->slot(key) = value; }

void Report::set_array(std::string_view key, std::span<const double> values) {
    nlohmann::ordered_json a = nlohmann::ordered_json::array();
    for (double v : values) a.push_back(number(v));
    impl_->slot(key) = std::move(a);
}
void Report::set_array(std::string_view key, std::span<const std::int64_t> values) {
    impl_->slot(key) = nlohmann::ordered_json(std::vector<std::int64_t>(values.begin(), values.end()));
}
void Report::set_array(std::string_view key, std::span<const std::uint64_t> values) {
    impl_->slot(key) = nlohmann::ordered_json(std::vector<std::uint64_t>(values.begin(), values.end()));
}
void Report::set_array(std::string_view key, const std::vector<std::string>& values) {
    impl_->slot(key) = nlohmann::ordered_json(values);
}

bool Report::contains(std::string_view key) const { return impl_->find(key) != nullptr; }

std::string Report::dump() const {
    // Invalid UTF-8 (an object name from a Latin-1 OBJ) is replaced rather than throwing.
    return impl_->root.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) + "\n";
}

void Report::write(const std::filesystem::path& path) const {
    const std::string text = dump();
    write_file_atomically(
        path, [&](std::ostream& out) { out.write(text.data(), static_cast<std::streamsize>(text.size())); });
}

}  // namespace ffcube
