// The scene of `vkas render FILE...` and `vkas heatmap FILE`: the files' meshes (model_loader), a camera framed on
// their bounds or given with --camera, a sun, and optionally a ground quad under them that catches their shadows.
#pragma once

#include <string>
#include <vector>

#include "model_loader.hpp"
#include "scene.hpp"

namespace vkas_tool {

struct ViewOptions {
    std::string camera;        // "ex,ey,ez,tx,ty,tz,ux,uy,uz" (eye, target, up) or empty: framed on the bounds
    float fovDegrees = 40.0f;  // vertical field of view
    char up = 'y';             // the files' up axis: 'y' (OBJ, glTF, PLY) or 'z' (many 3DS and STL files)
    bool ground = true;        // add a ground quad below the meshes
};

struct FileScene {
    Scene scene;
    std::vector<ModelInfo> models;
    Box bounds;  // of the files' meshes (the ground excluded)
};

// Throws InputError for a bad file and std::invalid_argument for a malformed --camera.
FileScene loadFileScene(const std::vector<std::string>& files, const ViewOptions& view, float aspect);

// Parses "ex,ey,ez,tx,ty,tz,ux,uy,uz" into camera (throws std::invalid_argument).
void parseCamera(const std::string& spec, Camera& camera);

}  // namespace vkas_tool
