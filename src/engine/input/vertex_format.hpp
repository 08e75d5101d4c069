// Vertex formats usable for acceleration-structure triangles, and their exact decoding.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstddef>
#include <cstdint>

namespace vkas {

struct VertexFormatInfo {
    uint32_t size;           // bytes of one vertex (all components)
    uint32_t componentSize;  // bytes of the smallest component (for stride/offset rules); 4 for packed formats
    bool packed;             // a single packed word (A2B10G10R10)
};

// Null when the format cannot be used for acceleration-structure vertex data.
const VertexFormatInfo* vertexFormatInfo(VkFormat format);

// The formats vkas supports, in the order `vkas info` lists them.
extern const VkFormat kSupportedVertexFormats[];
extern const uint32_t kSupportedVertexFormatCount;

// Decodes one vertex: 2-component formats give z = 0, a 4th component is ignored. SNORM and UNORM follow the
// Vulkan conversion rules; half floats are converted exactly. Results are doubles so that 64-bit formats keep
// their precision until the geometry transform has been applied.
void decodeVertex(VkFormat format, const std::byte* p, double out[3]);

float halfToFloat(uint16_t h);

}  // namespace vkas
