// Mesh files as a scene source: assimp reads the file (OBJ, PLY, STL, OFF, glTF/GLB, 3DS, AC3D, ...), each mesh with
// triangles becomes one bottom-level structure and each (node, mesh) pair one instance with the node's world
// transform. Every problem of the file (missing, unreadable, empty, malformed, no triangles, non-finite vertices,
// out-of-range indices) is an InputError naming the file.
#pragma once

#include <cstdint>
#include <string>

#include "scene.hpp"

namespace vkas_tool {

struct ModelInfo {
    std::string path;
    uint32_t meshes = 0;       // meshes with triangles (bottom-level structures added)
    uint32_t instances = 0;    // instances added
    uint64_t triangles = 0;    // triangles of those meshes (each counted once)
    uint64_t vertices = 0;
};

// Appends the file's meshes, bottom levels, materials and instances to `scene`.
ModelInfo loadModel(const std::string& path, Scene& scene);

// A program that hosts the loader in a runtime which ends a process on one too large allocation (libFuzzer ends it
// with status 71 when one allocation passes its -malloc_limit_mb) names that status here: an importer child ending
// with it ran out of memory, and the file is refused as out of memory, as when the child's allocation fails. 0: none.
void setImporterOutOfMemoryExitStatus(int status);

// The world-space bounds of every instanced triangle vertex (lo > hi when the scene is empty).
Box instancedBounds(const Scene& scene);

}  // namespace vkas_tool
