#include "diff_case.h"

#include <cstring>

namespace diff {

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
