#include "engine/assemble/kinds/kind.hpp"

namespace vkas {

const PrimitiveKind& primitiveKind(bool topLevel, uint32_t primitiveType, bool motion) {
    if (topLevel) return motion ? kMotionInstanceKind : kInstanceKind;
    switch (primitiveType) {
        case VK_GEOMETRY_TYPE_AABBS_KHR: return kAabbKind;
        case VK_GEOMETRY_TYPE_SPHERES_NV: return kSphereKind;
        case VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV: return kLssKind;
        default: return motion ? kMotionTriangleKind : kTriangleKind;
    }
}

}  // namespace vkas
