#include "engine/input/build_inputs.hpp"

#include "engine/format/motion.hpp"
#include "vkas/vkas_compat.h"

namespace vkas {

bool usesMotionRecords(const VkAccelerationStructureBuildGeometryInfoKHR& info) {
    if (!motion::isMotionBuild(info.flags)) return false;
    if (info.type == VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR) return true;
    if (info.geometryCount == 0 || (!info.pGeometries && !info.ppGeometries)) return false;
    return buildGeometry(info, 0).geometryType == VK_GEOMETRY_TYPE_TRIANGLES_KHR;
}

VkGeometryTypeKHR recordPrimitiveType(const VkAccelerationStructureBuildGeometryInfoKHR& info) {
    if (info.type == VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR) return VK_GEOMETRY_TYPE_INSTANCES_KHR;
    // Read only through pointers that name a geometry (the sizes query and validation may see invalid ones).
    if (const auto* g0 = info.geometryCount != 0 ? geometryAt(info, 0) : nullptr) {
        const VkGeometryTypeKHR first = g0->geometryType;
        if (first == VK_GEOMETRY_TYPE_AABBS_KHR || first == VK_GEOMETRY_TYPE_SPHERES_NV ||
            first == VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV)
            return first;
    }
    return VK_GEOMETRY_TYPE_TRIANGLES_KHR;
}

}  // namespace vkas
