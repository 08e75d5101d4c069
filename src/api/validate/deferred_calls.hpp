// The valid-usage rules of each command of api/deferred_operation.cpp (vkCreate/DestroyDeferredOperationKHR,
// vkGetDeferredOperationMaxConcurrencyKHR, vkGetDeferredOperationResultKHR, vkDeferredOperationJoinKHR), one
// function a command. Each reports what it finds and returns whether the command may go on. The deferredOperation
// parameter of a deferrable command is checked by checkDeferredOperation (parameters.hpp).
#pragma once

#include <vulkan/vulkan_core.h>

#include "api/deferred_operation.hpp"
#include "api/device.hpp"
#include "api/validate/validator.hpp"

namespace vkas {

// vkCreateDeferredOperationKHR: device and pDeferredOperation. False: return VK_ERROR_VALIDATION_FAILED_EXT.
bool checkCreateDeferredOperation(Validator& v, const Device* dev, const VkDeferredOperationKHR* pDeferredOperation);

// vkDestroyDeferredOperationKHR: device, operation (complete) and the allocator. False: return without destroying
// (also for a NULL operation). `op` is the command's lookup of operation; with validation on it becomes the live
// operation the handle check found.
bool checkDestroyDeferredOperation(Validator& v, const Device* dev, VkDeferredOperationKHR operation,
                                   const VkAllocationCallbacks* pAllocator, DeferredOperation*& op);

// vkGetDeferredOperationMaxConcurrencyKHR: device and operation. False: return 0.
bool checkGetDeferredOperationMaxConcurrency(Validator& v, const Device* dev, VkDeferredOperationKHR operation);

// vkGetDeferredOperationResultKHR: device and operation. False: return VK_ERROR_VALIDATION_FAILED_EXT.
bool checkGetDeferredOperationResult(Validator& v, const Device* dev, VkDeferredOperationKHR operation);

// vkDeferredOperationJoinKHR: device and operation. False: return VK_ERROR_VALIDATION_FAILED_EXT.
bool checkDeferredOperationJoin(Validator& v, const Device* dev, VkDeferredOperationKHR operation);

}  // namespace vkas
