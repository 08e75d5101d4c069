// The benchmark's scenes: meshes loaded with assimp from the Debian packages scripts/setup-bench.sh installs, their
// midpoint subdivisions, and a many-instance scene for top-level builds.
#pragma once

#include "common.hpp"

#include <string>
#include <vector>

namespace vb {

// Loads every triangle of a file assimp reads (.obj, .3ds, .off, .ac/.acc, .ply, ...) into one mesh, node
// transforms applied. Throws std::runtime_error on failure.
Mesh loadMesh(const std::string& path);

// Midpoint subdivision: every triangle becomes four (shared edge midpoints are shared vertices).
Mesh subdivide(const Mesh& m);

// The named scenes (`--scene`): bunny, bunny-1m, bunny-4m, bunny-16m (not in the default list: scaling runs),
// cgal-elephant, cgal-armadillo, torcs-forza, instances.
struct SceneInfo {
    const char* name;
    const char* what;
};
const std::vector<SceneInfo>& sceneCatalogue();

// Builds the named scene, or a mesh file given by path (`--mesh`). `dataDir` holds the extracted CGAL meshes;
// `instanceCount` sizes the many-instance scene.
Scene makeScene(const std::string& nameOrPath, bool isPath, const std::string& dataDir, unsigned instanceCount);

}  // namespace vb
