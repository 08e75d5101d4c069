// [NV-LSS] Build inputs of sphere and linear-swept-sphere geometries (VK_NV_ray_tracing_linear_swept_spheres):
// which bytes hold primitive i's positions and radii under VkAccelerationStructureBuildRangeInfoKHR.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstddef>
#include <cstdint>

#include "engine/format/layout.hpp"
#include "vkas/vkas_compat.h"

namespace vkas {

// Either data structure, read through one view. `lss` tells which one the geometry has.
struct SweptSpheresData {
    bool lss = false;
    VkFormat vertexFormat = VK_FORMAT_UNDEFINED;
    const std::byte* vertexData = nullptr;
    uint64_t vertexStride = 0;
    VkFormat radiusFormat = VK_FORMAT_UNDEFINED;
    const std::byte* radiusData = nullptr;
    uint64_t radiusStride = 0;
    VkIndexType indexType = VK_INDEX_TYPE_NONE_KHR;
    const std::byte* indexData = nullptr;
    uint64_t indexStride = 0;
    uint32_t indexingMode = VK_RAY_TRACING_LSS_INDEXING_MODE_LIST_NV;
    uint32_t endCapsMode = VK_RAY_TRACING_LSS_PRIMITIVE_END_CAPS_MODE_NONE_NV;
};

// Finds the geometry's VkAccelerationStructureGeometrySpheresDataNV or ...LinearSweptSpheresDataNV (by its
// geometryType) in its pNext chain. False when the type is neither or the structure is missing.
bool sweptSpheresData(const VkAccelerationStructureGeometryKHR& geometry, SweptSpheresData& out);

// Radius formats with VK_FORMAT_FEATURE_2_ACCELERATION_STRUCTURE_RADIUS_BUFFER_BIT_NV: R32_SFLOAT, R16_SFLOAT.
bool isRadiusFormat(VkFormat format);

// Fetch rules (spec digest section 4, "Spheres" and "LSS" rows):
//  - indexed (indexType UINT16/UINT32): index n is read at indexData + primitiveOffset + n * indexStride; the
//    vertex it names is index + firstVertex, for the position and the radius alike;
//  - not indexed: vertex n is at vertexData + primitiveOffset + vertexStride * (firstVertex + n), its radius at
//    radiusData + primitiveOffset + radiusStride * (firstVertex + n): primitiveOffset moves both buffers.
// Sphere i uses vertex (index) i. LSS i uses vertices (indices) 2i and 2i+1 in LIST mode; in SUCCESSIVE mode it
// uses index i = k and the vertices k + firstVertex and k + 1 + firstVertex (without indices: vertices i, i+1).
class SweptSpheresSource {
public:
    SweptSpheresSource(const SweptSpheresData& data, const VkAccelerationStructureBuildRangeInfoKHR& range);
    uint32_t primitiveCount() const { return count_; }
    // The vertex number (firstVertex not yet added) of endpoint j (0 or 1; spheres: 0) of primitive i.
    uint64_t vertexNumber(uint32_t i, uint32_t j) const;
    // Decoded position (rounded to float) and radius of a vertex number. Returns false when a component of
    // either is NaN (the primitive is then inactive).
    bool fetchVertex(uint64_t vertex, float position[3], float& radius) const;
    // The end caps (kLssCap0 | kLssCap1 record flags) of LSS i under the geometry's end-caps mode.
    uint32_t endCaps(uint32_t i) const;

private:
    uint64_t indexValue(uint64_t n) const;
    SweptSpheresData data_;
    const std::byte* vertices_;  // first addressable vertex (non-indexed: primitiveOffset applied)
    const std::byte* radii_;
    const std::byte* indices_;   // indexData + primitiveOffset, null when not indexed
    uint64_t firstVertex_;
    uint32_t count_;
};

}  // namespace vkas
