// Internal to the Gmsh readers (gmsh_loader.cpp, fe_cells.cpp): the collector of the faces of
// the model Gmsh holds, and the guarded child that Gmsh runs in.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "ffcube/scene/gmsh_loader.hpp"

namespace ffcube {

// The faces of the model now in Gmsh (gmsh_loader.hpp says what becomes a face and what names
// it); `nastran`: ungrouped entities are property ids (pid_<n>); `cad`: no warning for entities
// without a group. Call in the child, after Gmsh has the model.
ObjModel collect_gmsh_model(const std::string& source, const FeLoadOptions& options, bool nastran, bool cad);

// Runs `work` (which initialises Gmsh, builds or reads the model and returns
// detail::encode_imported of the collected faces) in a guarded child with the limits for
// `input_bytes` of input (20 s + 2 s per MiB, 2 GiB + 256 bytes per byte), and decodes its
// answer; a crash, a timeout or the memory cap becomes an InputError naming `source`.
ObjModel run_gmsh_child(const std::string& source, std::uint64_t input_bytes, const std::function<std::string()>& work);

}  // namespace ffcube
