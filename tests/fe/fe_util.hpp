// Helpers of the FE-mesh tests (tests/fe): the models Gmsh writes (tools/gmsh_models.cpp) and a
// CSV reader.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "cli/cli_util.hpp"

namespace ffcube::test {

// The models, written once per process into a temporary directory.
inline const TempDir& models() {
    static TempDir dir;
    static const int status = std::system((std::string(FFCUBE_GMSH_MODELS) + " " + dir.path().string() + " > /dev/null").c_str());
    EXPECT_EQ(status, 0);
    return dir;
}

// The rows of a CSV text without its header line, split at commas (no quoting).
inline std::vector<std::vector<std::string>> csv(const std::string& text) {
    std::vector<std::vector<std::string>> rows;
    std::istringstream in(text);
    std::string line;
    std::getline(in, line);  // header
    while (std::getline(in, line)) {
        std::vector<std::string> cells;
        std::stringstream ls(line);
        std::string cell;
        while (std::getline(ls, cell, ',')) cells.push_back(cell);
        rows.push_back(cells);
    }
    return rows;
}

}  // namespace ffcube::test
