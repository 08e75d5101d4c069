// `vkas render [FILE...]`: builds the built-in scene, or the meshes of the files (one bottom level per mesh, a top
// level over the files' node transforms), through the Vulkan commands, traces primary, ambient-occlusion and shadow
// rays, writes a PNG and reports build statistics and timings. --heatmap draws the traversal cost instead.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "file_scene.hpp"

namespace vkas_tool {

struct RenderCommandOptions {
    std::string output = "vkas-render.png";
    uint32_t width = 800;
    uint32_t height = 600;
    uint32_t aoSamples = 8;
    uint32_t threads = 0;  // 0: all cores
    uint32_t instances = 2000;
    uint64_t seed = 1;
    bool validation = true;
    std::vector<std::string> files;      // empty: the built-in scene
    ViewOptions view;
    std::string preference = "fast-trace";
    bool heatmap = false;
    std::string metric = "nodes";
};

int runRender(const RenderCommandOptions& options);

}  // namespace vkas_tool
