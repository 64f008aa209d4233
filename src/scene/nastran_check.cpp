// The pre-check of Nastran bulk data read through Gmsh (gmsh_loader.hpp): Gmsh's reader skips
// every card it does not know without a word, so a deck whose geometry depends on such a card
// (a coordinate system, an INCLUDE, an element type it lacks) would come back quietly wrong.
// ffcube refuses those cards up front, naming the file, line and card.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <string>
#include <string_view>

#include "ffcube/core/error.hpp"
#include "ffcube/scene/gmsh_loader.hpp"

namespace ffcube {
namespace {

// Cards Gmsh 4.8 reads (GModelIO_BDF.cpp): nodes and the elements it turns into mesh elements.
constexpr std::array<std::string_view, 14> kRead = {"GRID",  "CTRIA3", "CTRIA6", "CQUAD4", "CQUAD8", "CQUAD",  "CTETRA",
                                                   "CHEXA", "CPENTA", "CPYRAM", "CBAR",   "CROD",   "CBEAM",  "CONM2"};
// Cards that carry no geometry ffcube uses (properties, materials, loads, constraints, case
// control words that may appear in a bulk-only deck): read past.
constexpr std::array<std::string_view, 24> kPast = {"PSHELL", "PSOLID", "PCOMP",  "PBAR",  "PBARL", "PBEAM", "PBEAML", "PROD",
                                                    "MAT1",   "MAT2",   "MAT4",   "MAT5",  "MAT8",  "MAT9",  "SPC",    "SPC1",
                                                    "FORCE",  "MOMENT", "PLOAD4", "LOAD",  "TEMP",  "TEMPD", "PARAM",  "ENDDATA"};

std::string card_name(std::string_view line) {
    std::size_t end = 0;
    while (end < line.size() && end < 8 && line[end] != ',' && line[end] != ' ' && line[end] != '\t') ++end;
    std::string name(line.substr(0, end));
    if (!name.empty() && name.back() == '*') name.pop_back();  // large-field form
    std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
    return name;
}

}  // namespace

void check_nastran_cards(std::string_view text, const std::string& source) {
    // Executive and case control (before BEGIN BULK, when the deck has one) are not bulk data.
    bool bulk = text.find("BEGIN BULK") == std::string_view::npos && text.find("begin bulk") == std::string_view::npos;
    std::size_t line_no = 0, cards = 0;
    for (std::size_t at = 0; at < text.size();) {
        std::size_t end = text.find('\n', at);
        if (end == std::string_view::npos) end = text.size();
        std::string_view line = text.substr(at, end - at);
        at = end + 1;
        ++line_no;
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        for (const char c : line)
            if (c == '\0' || (static_cast<unsigned char>(c) < 32 && c != '\t'))
                throw InputError(fmt::format("{}: line {}: a control byte (0x{:02x}): a Nastran deck is text", source, line_no,
                                             static_cast<unsigned>(static_cast<unsigned char>(c))));
        if (line.empty() || line.front() == '$') continue;
        if (!bulk) {
            std::string upper(line);
            std::transform(upper.begin(), upper.end(), upper.begin(), [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
            if (upper.rfind("BEGIN BULK", 0) == 0) bulk = true;
            continue;
        }
        // Continuations: '+', '*' or a blank first field.
        if (line.front() == '+' || line.front() == '*' || line.front() == ' ' || line.front() == '\t' || line.front() == ',') continue;
        const std::string name = card_name(line);
        if (name == "ENDDATA") break;
        if (std::find(kRead.begin(), kRead.end(), name) != kRead.end()) {
            ++cards;
            continue;
        }
        if (std::find(kPast.begin(), kPast.end(), name) != kPast.end()) continue;
        throw InputError(fmt::format("{}: line {}: card '{}' is not read (ffcube reads Nastran's GRID, CTRIA3, CTRIA6, CQUAD4, "
                                     "CQUAD8, CTETRA, CHEXA, CPENTA, CPYRAM through Gmsh, and passes over properties, materials "
                                     "and loads; coordinate systems and INCLUDE are not followed)",
                                     source, line_no, name));
    }
    if (cards == 0) throw InputError(fmt::format("{}: no GRID or element cards: not a Nastran bulk-data deck", source));
}

}  // namespace ffcube
