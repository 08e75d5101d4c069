// The heatmap's picture: per-pixel values in viridis (a perceptually uniform map that stays readable in grey and
// to colour-blind eyes), with a legend bar along the bottom labelled with the minimum and maximum.
#pragma once

#include <cstdint>
#include <vector>

#include "renderer.hpp"

namespace vkas_tool {

// Viridis at t in [0, 1], 8-bit sRGB.
void viridis(float t, uint8_t rgb[3]);

// values: width x height, rows top to bottom; colours map [lo, hi] linearly.
Image heatmapImage(const std::vector<uint32_t>& values, uint32_t width, uint32_t height, uint32_t lo, uint32_t hi);

}  // namespace vkas_tool
