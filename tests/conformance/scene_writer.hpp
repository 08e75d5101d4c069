// Writes the application data of a differential scene into its blob: vertices in any vertex format, indices,
// geometry transforms and AABBs, with the offsets, strides and paddings a demanding application would use.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "diff_case.hpp"

namespace diff {

using Point = std::array<double, 3>;

// Encodes p in `format`, rounding each component to the nearest representable value (SNORM/UNORM: clamped to the
// format's range; 2-component formats drop z; 4-component formats write 1 in w).
void encodeVertex(VkFormat format, const Point& p, uint8_t* out);
uint32_t vertexSize(VkFormat format);
uint32_t componentSize(VkFormat format);

struct TriangleOptions {
    VkFormat format = VK_FORMAT_R32G32B32_SFLOAT;
    VkIndexType indexType = VK_INDEX_TYPE_NONE_KHR;
    VkGeometryFlagsKHR flags = 0;
    const VkTransformMatrixKHR* transform = nullptr;  // optional geometry transform
    uint32_t extraStride = 0;    // components of padding after each vertex
    uint32_t primitiveSkip = 0;  // primitives of garbage in front of the first one (primitiveOffset)
    uint32_t firstVertex = 0;
    uint32_t transformSkip = 0;  // matrices of garbage in front of the transform (transformOffset)
};

struct AabbOptions {
    VkGeometryFlagsKHR flags = 0;
    uint32_t extraStride = 0;    // 8-byte units of padding after each AABB
    uint32_t primitiveSkip = 0;  // AABBs of garbage in front of the first one (primitiveOffset)
};

class SceneWriter {
  public:
    explicit SceneWriter(Scene& scene) : scene_(scene) {}

    // Appends `size` bytes (filled with 0xAA) at an offset aligned to `alignment`; returns the offset.
    uint64_t reserve(size_t size, size_t alignment = 16);
    uint64_t append(const void* data, size_t size, size_t alignment = 16);

    // Triangles given as positions and 3 indices per triangle. Non-indexed geometry gets its vertices unrolled.
    // A NaN x coordinate makes the triangles that use the vertex inactive (float formats only).
    Geometry triangles(const std::vector<Point>& positions, const std::vector<uint32_t>& indices,
                       const TriangleOptions& options);
    // Boxes as min xyz, max xyz; a NaN minX makes the AABB inactive.
    Geometry aabbs(const std::vector<std::array<float, 6>>& boxes, const AabbOptions& options);

  private:
    Scene& scene_;
};

}  // namespace diff
