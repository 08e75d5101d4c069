// Writes 8-bit RGB images as PNG with libpng.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace vkas_tool {

// Throws std::runtime_error with the reason when the file cannot be written.
void writePng(const std::string& path, uint32_t width, uint32_t height, const std::vector<uint8_t>& rgb);

}  // namespace vkas_tool
