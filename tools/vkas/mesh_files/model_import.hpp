// assimp's side of loading a mesh file: the file read with no post-processing, checked (imported_scene_check.hpp),
// post-processed (triangulated, identical vertices joined, points and lines dropped) and copied out as plain arrays.
// model_loader.cpp runs it in a child process only: assimp never runs in the tool's own process.
#pragma once

#include <string>

#include "imported_model.hpp"

namespace vkas_tool {

// The file's triangles, materials and the instances its node tree places (world transforms, depth first). Throws
// InputError naming `path` for what assimp refuses or logs as an error and what the scene check refuses.
ImportedModel importModel(const std::string& path);

}  // namespace vkas_tool
