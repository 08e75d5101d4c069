#include "api/validate/deferred_calls.hpp"

#include "api/validate/parameters.hpp"

namespace vkas {

bool checkCreateDeferredOperation(Validator& v, const Device* dev, const VkDeferredOperationKHR* pDeferredOperation) {
    if (!dev) {
        v.fail("VUID-vkCreateDeferredOperationKHR-device-parameter", "device is not a valid VkDevice.");
        return false;
    }
    if (!v.enabled()) return true;
    v.check(pDeferredOperation != nullptr, "VUID-vkCreateDeferredOperationKHR-pDeferredOperation-parameter",
            "pDeferredOperation is NULL.");
    return !v.failed();
}

bool checkDestroyDeferredOperation(Validator& v, const Device* dev, VkDeferredOperationKHR operation,
                                   const VkAllocationCallbacks* pAllocator, DeferredOperation*& op) {
    if (!dev) {
        v.fail("VUID-vkDestroyDeferredOperationKHR-device-parameter", "device is not a valid VkDevice.");
        return false;
    }
    if (operation == VK_NULL_HANDLE) return false;
    if (!v.enabled()) return true;
    op = checkHandle<DeferredOperation>(v, *dev, operation, ObjectMagic::DeferredOperation,
                                        "VUID-vkDestroyDeferredOperationKHR-operation-parameter",
                                        "VUID-vkDestroyDeferredOperationKHR-operation-parent", "operation");
    if (!op) return false;
    v.check(!op->pending(), "VUID-vkDestroyDeferredOperationKHR-operation-03436",
            "operation is not complete: join it until it completes before destroying it.");
    checkDestroyAllocator(v, op->allocator, pAllocator, "VUID-vkDestroyDeferredOperationKHR-operation-03434",
                          "VUID-vkDestroyDeferredOperationKHR-operation-03435");
    return !v.failed();
}

bool checkGetDeferredOperationMaxConcurrency(Validator& v, const Device* dev, VkDeferredOperationKHR operation) {
    if (!dev) {
        v.fail("VUID-vkGetDeferredOperationMaxConcurrencyKHR-device-parameter", "device is not a valid VkDevice.");
        return false;
    }
    return !v.enabled() || checkHandle<DeferredOperation>(v, *dev, operation, ObjectMagic::DeferredOperation,
                                                          "VUID-vkGetDeferredOperationMaxConcurrencyKHR-operation-parameter",
                                                          "VUID-vkGetDeferredOperationMaxConcurrencyKHR-operation-parent",
                                                          "operation");
}

bool checkGetDeferredOperationResult(Validator& v, const Device* dev, VkDeferredOperationKHR operation) {
    if (!dev) {
        v.fail("VUID-vkGetDeferredOperationResultKHR-device-parameter", "device is not a valid VkDevice.");
        return false;
    }
    return !v.enabled() || checkHandle<DeferredOperation>(v, *dev, operation, ObjectMagic::DeferredOperation,
                                                          "VUID-vkGetDeferredOperationResultKHR-operation-parameter",
                                                          "VUID-vkGetDeferredOperationResultKHR-operation-parent",
                                                          "operation");
}

bool checkDeferredOperationJoin(Validator& v, const Device* dev, VkDeferredOperationKHR operation) {
    if (!dev) {
        v.fail("VUID-vkDeferredOperationJoinKHR-device-parameter", "device is not a valid VkDevice.");
        return false;
    }
    return !v.enabled() || checkHandle<DeferredOperation>(v, *dev, operation, ObjectMagic::DeferredOperation,
                                                          "VUID-vkDeferredOperationJoinKHR-operation-parameter",
                                                          "VUID-vkDeferredOperationJoinKHR-operation-parent",
                                                          "operation");
}

}  // namespace vkas
