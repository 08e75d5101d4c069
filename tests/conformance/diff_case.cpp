#include "diff_case.hpp"

#include <cstring>
#include <stdexcept>

namespace diff {

VkAccelerationStructureGeometryKHR vulkanGeometry(const Geometry& g, uint64_t blob) {
    VkAccelerationStructureGeometryKHR geom{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
    geom.geometryType = g.type;
    geom.flags = g.flags;
    if (g.type == VK_GEOMETRY_TYPE_TRIANGLES_KHR) {
        auto& t = geom.geometry.triangles;
        t.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR;
        t.vertexFormat = g.triangles.vertexFormat;
        t.vertexData.deviceAddress = blob + g.triangles.vertexOffset;
        t.vertexStride = g.triangles.vertexStride;
        t.maxVertex = g.triangles.maxVertex;
        t.indexType = g.triangles.indexType;
        if (g.triangles.indexType != VK_INDEX_TYPE_NONE_KHR) t.indexData.deviceAddress = blob + g.triangles.indexOffset;
        if (g.triangles.hasTransform) t.transformData.deviceAddress = blob + g.triangles.transformOffset;
    } else if (g.type == VK_GEOMETRY_TYPE_AABBS_KHR) {
        auto& a = geom.geometry.aabbs;
        a.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_AABBS_DATA_KHR;
        a.data.deviceAddress = blob + g.aabbs.dataOffset;
        a.stride = g.aabbs.stride;
    } else {
        throw std::invalid_argument("a BLAS geometry is neither triangles nor AABBs");
    }
    return geom;
}

void packInstance(const Instance& in, uint64_t reference, uint8_t out[64]) {
    const uint32_t customIndexAndMask = (in.customIndex & 0xFF'FFFFu) | ((in.mask & 0xFFu) << 24);
    const uint32_t sbtOffsetAndFlags = (in.sbtOffset & 0xFF'FFFFu) | ((in.flags & 0xFFu) << 24);
    std::memcpy(out, &in.transform, 48);
    std::memcpy(out + 48, &customIndexAndMask, 4);
    std::memcpy(out + 52, &sbtOffsetAndFlags, 4);
    std::memcpy(out + 56, &reference, 8);
}

ProceduralTables makeProceduralTables(const Scene& scene) {
    ProceduralTables t;
    for (const Instance& inst : scene.instances)
        t.instanceBlas.push_back(inst.blas < 0 ? 0xFFFF'FFFFu : uint32_t(inst.blas));
    for (const Blas& blas : scene.blases) {
        t.blasFirstGeometry.push_back(uint32_t(t.geometryFirstBox.size()));
        t.blasFlags.push_back((blas.buildFlags & 0x800u) ? 1u : 0u);  // ALLOW_DATA_ACCESS
        for (const Geometry& g : blas.geometries) {
            if (g.type != VK_GEOMETRY_TYPE_AABBS_KHR) {
                t.geometryFirstBox.push_back(0);
                continue;
            }
            t.geometryFirstBox.push_back(uint32_t(t.boxes.size() / 8));
            for (uint32_t p = 0; p < g.range.primitiveCount; ++p) {
                float box[6];
                std::memcpy(box, scene.blob.data() + g.aabbs.dataOffset + g.range.primitiveOffset + p * g.aabbs.stride,
                            sizeof box);
                const float row[8] = {box[0], box[1], box[2], 0.0f, box[3], box[4], box[5], 0.0f};
                t.boxes.insert(t.boxes.end(), row, row + 8);
            }
        }
    }
    // Storage buffers may not be empty: keep one element in each table.
    if (t.instanceBlas.empty()) t.instanceBlas.push_back(0xFFFF'FFFFu);
    if (t.blasFirstGeometry.empty()) t.blasFirstGeometry.push_back(0), t.blasFlags.push_back(0);
    if (t.geometryFirstBox.empty()) t.geometryFirstBox.push_back(0);
    if (t.boxes.empty()) t.boxes.resize(8, 0.0f);
    return t;
}

}  // namespace diff
