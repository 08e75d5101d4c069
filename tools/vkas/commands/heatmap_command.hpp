// `vkas heatmap FILE... -o out.png` (also `vkas render --heatmap`): the traversal cost of each pixel's camera ray
// (internal nodes visited, or triangles tested) as a viridis image with a legend, and its minimum, mean and maximum.
// The counts come from the tool's counting traversal (cost_tracer.hpp); its hit for every pixel is checked against
// vkasTraceRays' closest hit and the agreement printed.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "file_scene.hpp"

namespace vkas_tool {

struct HeatmapOptions {
    std::vector<std::string> files;
    std::string output = "vkas-heatmap.png";
    std::string metric = "nodes";  // nodes | primitives
    uint32_t width = 640, height = 480;
    ViewOptions view;
    std::string preference = "fast-trace";
    uint32_t threads = 0;  // 0: all cores
    bool json = false;
    std::string countsFile;  // per-pixel counts as text ("nodes primitives instances" a line), if set
    bool validation = true;
};

int runHeatmap(HeatmapOptions options);

}  // namespace vkas_tool
