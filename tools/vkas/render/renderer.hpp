// Ray-traced ambient-occlusion renderer: primary rays (closest hit) and occlusion rays (any hit: ambient
// occlusion within a radius, plus one sun shadow ray) traced in batches with vkasTraceRaysProcedural, whose
// intersection callback makes the procedural boxes solid crates. Surface normals come from the application's own
// mesh and primitive data, found through the hit's instance, geometry and primitive indices.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "scene.hpp"
#include "vk_context.hpp"

namespace vkas_tool {

struct RenderOptions {
    uint32_t width = 800;
    uint32_t height = 600;
    uint32_t aoSamples = 8;  // ambient-occlusion rays per pixel
    std::function<void(uint64_t done, uint64_t total)> progress;  // pixels shaded so far (may be empty)
};

struct RenderStats {
    uint64_t primaryRays = 0, primaryHits = 0;
    double primaryMs = 0;            // vkasTraceRays time of the primary rays
    uint64_t occlusionRays = 0, occlusionHits = 0;
    double occlusionMs = 0;          // vkasTraceRays time of the AO and shadow rays
    double totalMs = 0;              // everything, ray generation and shading included
};

struct Image {
    uint32_t width = 0, height = 0;
    std::vector<uint8_t> rgb;  // 8-bit sRGB, rows top to bottom
};

Image render(VkContext& ctx, const Scene& scene, VkAccelerationStructureKHR topLevel, const RenderOptions& options,
             RenderStats& stats);

}  // namespace vkas_tool
