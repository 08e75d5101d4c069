// The rules that decide whether a primitive the ray meets becomes a hit, shared by the ray query's state machine
// (traversal.cpp) and the batch kernel (trace_kernel.cpp): ray and instance flag bits, opacity in the spec's
// order, and the world-to-object ray transform.
#pragma once

#include <cstdint>

namespace vkas {

constexpr uint32_t kRayOpaque = 0x1, kRayNoOpaque = 0x2, kRayTerminateOnFirstHit = 0x4;
constexpr uint32_t kRayCullBack = 0x10, kRayCullFront = 0x20, kRayCullOpaque = 0x40, kRayCullNoOpaque = 0x80;
constexpr uint32_t kRaySkipTriangles = 0x100, kRaySkipAabbs = 0x200;
constexpr uint32_t kInstanceCullDisable = 0x1, kInstanceFlipFacing = 0x2, kInstanceForceOpaque = 0x4,
                   kInstanceForceNoOpaque = 0x8;

// Opacity in the spec's order: the geometry's OPAQUE flag, overridden by the instance's FORCE_* flags,
// overridden by the ray's Opaque / NoOpaque flags.
inline bool resolveOpacity(bool geometryOpaque, uint32_t instanceFlags, uint32_t rayFlags) {
    bool opaque = geometryOpaque;
    if (instanceFlags & kInstanceForceOpaque)
        opaque = true;
    else if (instanceFlags & kInstanceForceNoOpaque)
        opaque = false;
    if (rayFlags & kRayOpaque)
        opaque = true;
    else if (rayFlags & kRayNoOpaque)
        opaque = false;
    return opaque;
}

inline bool culledByOpacity(bool opaque, uint32_t rayFlags) {
    return opaque ? (rayFlags & kRayCullOpaque) != 0 : (rayFlags & kRayCullNoOpaque) != 0;
}

// The ray in an instance's object space: the 3x4 row-major world-to-object matrix applied in double, each result
// rounded once.
inline void transformRay(const float (*m)[4], const float o[3], const float d[3], float oo[3], float od[3]) {
    for (int r = 0; r < 3; ++r) {
        oo[r] = float(double(m[r][0]) * o[0] + double(m[r][1]) * o[1] + double(m[r][2]) * o[2] + double(m[r][3]));
        od[r] = float(double(m[r][0]) * d[0] + double(m[r][1]) * d[1] + double(m[r][2]) * d[2]);
    }
}

}  // namespace vkas
