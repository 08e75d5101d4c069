// `vkas render`: builds the built-in scene through the Vulkan commands, traces it, writes a PNG and reports
// build statistics and timings.
#pragma once

#include <cstdint>
#include <string>

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
};

int runRender(const RenderCommandOptions& options);

}  // namespace vkas_tool
