#include "engine/input/build_inputs.hpp"

#include "engine/format/motion.hpp"

namespace vkas {

const VkAccelerationStructureGeometryKHR& buildGeometry(const VkAccelerationStructureBuildGeometryInfoKHR& info,
                                                        uint32_t i) {
    return info.pGeometries ? info.pGeometries[i] : *info.ppGeometries[i];
}

bool usesMotionRecords(const VkAccelerationStructureBuildGeometryInfoKHR& info) {
    if (!motion::isMotionBuild(info.flags)) return false;
    if (info.type == VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR) return true;
    if (info.geometryCount == 0 || (!info.pGeometries && !info.ppGeometries)) return false;
    return buildGeometry(info, 0).geometryType == VK_GEOMETRY_TYPE_TRIANGLES_KHR;
}

}  // namespace vkas
