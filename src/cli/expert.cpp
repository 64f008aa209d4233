#include "cli/expert.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <memory>
#include <utility>

namespace ffcube::cli {

CLI::Option* expert(CLI::Option* o) { return o->group(kExpertGroup); }

void add_door_options(CLI::App& sub) {
    // Never parsed by CLI11 (open_door rewrites them); registered so that --help lists them.
    sub.add_flag("--help-all")->description("list every option, the tuning knobs included (docs/cli.md)");
    static std::vector<std::string> unused;
    sub.add_option("--set", unused, "set a tuning knob: --set NAME=VALUE (a flag: --set NAME); --help-all lists them")
        ->type_name("NAME=VALUE")
        ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
}

namespace {

// CLI11's help, without the tuning knobs' group unless --help-all asked for it.
class DoorFormatter final : public CLI::Formatter {
public:
    explicit DoorFormatter(bool hide_knobs) : hide_knobs_(hide_knobs) {}
    std::string make_group(std::string group, bool is_positional, std::vector<const CLI::Option*> opts) const override {
        if (hide_knobs_ && group == kExpertGroup) return {};
        return CLI::Formatter::make_group(std::move(group), is_positional, std::move(opts));
    }

private:
    bool hide_knobs_;
};

CLI::App* chosen_subcommand(CLI::App& app, const std::vector<std::string>& args) {
    for (const std::string& a : args) {
        if (a.starts_with("-")) continue;
        for (CLI::App* sub : app.get_subcommands({}))
            if (sub->get_name() == a) return sub;
        return nullptr;  // the first word is not a command: CLI11 says so
    }
    return nullptr;
}

std::string knob_list(CLI::App& sub) {
    std::vector<std::string> names;
    for (const CLI::Option* o : sub.get_options())
        if (o->get_group() == kExpertGroup) names.push_back(o->get_name(false, true).substr(2));
    std::sort(names.begin(), names.end());
    std::string out;
    for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
    return out;
}

}  // namespace

std::vector<std::string> open_door(CLI::App& app, int argc, char** argv) {
    std::vector<std::string> in(argv + 1, argv + argc), out;
    CLI::App* sub = chosen_subcommand(app, in);
    bool help_all = false;
    for (std::size_t k = 0; k < in.size(); ++k) {
        const std::string& a = in[k];
        if (a == "--help-all") {
            help_all = true;
            out.push_back("--help");
            continue;
        }
        std::string setting;
        if (a == "--set") {
            if (k + 1 == in.size()) throw CLI::ValidationError("--set: give NAME=VALUE (--help-all lists the names)");
            setting = in[++k];
        } else if (a.starts_with("--set=")) {
            setting = a.substr(6);
        } else {
            out.push_back(a);
            continue;
        }
        const std::size_t eq = setting.find('=');
        const std::string name = setting.substr(0, eq);
        if (sub == nullptr) throw CLI::ValidationError(fmt::format("--set {}: comes after a command's name", setting));
        const CLI::Option* o = name.empty() ? nullptr : sub->get_option_no_throw("--" + name);
        if (o == nullptr || o->get_group() != kExpertGroup)
            throw CLI::ValidationError(fmt::format("--set {}: {} is not a tuning knob of `ffcube {}` (they are: {})",
                                                   setting, name.empty() ? "''" : name, sub->get_name(), knob_list(*sub)));
        out.push_back(eq == std::string::npos ? "--" + name : "--" + setting);
    }
    // The knobs' group is left out of the help text by the formatter, not by CLI11's empty group:
    // a hidden option would lose its name in CLI11's error messages ("--near-k: ..." -> ": ...").
    const auto formatter = std::make_shared<DoorFormatter>(!help_all);
    for (CLI::App* s : app.get_subcommands({})) s->formatter(formatter);
    return out;
}

}  // namespace ffcube::cli
