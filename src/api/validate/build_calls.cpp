#include "api/validate/build_calls.hpp"

#include "api/validate/build_infos.hpp"

namespace vkas {

bool checkBuildAccelerationStructuresCall(Validator& v, const Device* dev, VkDeferredOperationKHR deferredOperation,
                                          uint32_t infoCount, const VkAccelerationStructureBuildGeometryInfoKHR* pInfos,
                                          const VkAccelerationStructureBuildRangeInfoKHR* const* ppBuildRangeInfos) {
    if (!v.enabled()) return true;
    if (!v.check(dev != nullptr, "VUID-vkBuildAccelerationStructuresKHR-device-parameter",
                 "device is not a valid VkDevice."))
        return false;
    checkBuildAccelerationStructures(v, *dev, deferredOperation, infoCount, pInfos, ppBuildRangeInfos);
    return !v.failed();
}

}  // namespace vkas
