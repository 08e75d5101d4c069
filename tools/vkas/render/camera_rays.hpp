// The primary rays of a pinhole camera, one per pixel through its centre, rows top to bottom: the same rays for the
// rendered image and the heatmap, so that both show the same view.
#pragma once

#include <cstdint>
#include <vector>

#include <vkas/vkas.h>

#include "scene.hpp"

namespace vkas_tool {

std::vector<VkasRay> primaryRays(const Camera& camera, uint32_t width, uint32_t height, float tMax);

}  // namespace vkas_tool
