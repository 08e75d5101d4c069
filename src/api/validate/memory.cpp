#include "api/validate/memory.hpp"

#include <cstdint>

#include "api/validate/parameters.hpp"

namespace vkas {

void checkBufferCreateInfo(Validator& v, const VkBufferCreateInfo& ci) {
    v.check(ci.sType == VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO, "VUID-VkBufferCreateInfo-sType-sType",
            "pCreateInfo->sType is %d.", int(ci.sType));
    checkNextChain(v, ci.pNext, {}, "VUID-VkBufferCreateInfo-pNext-pNext", nullptr, "pCreateInfo");
    v.check(ci.size > 0, "VUID-VkBufferCreateInfo-size-00912", "pCreateInfo->size is 0.");
    constexpr VkBufferCreateFlags kKnownFlags =
        VK_BUFFER_CREATE_SPARSE_BINDING_BIT | VK_BUFFER_CREATE_SPARSE_RESIDENCY_BIT |
        VK_BUFFER_CREATE_SPARSE_ALIASED_BIT | VK_BUFFER_CREATE_PROTECTED_BIT |
        VK_BUFFER_CREATE_DEVICE_ADDRESS_CAPTURE_REPLAY_BIT;
    v.check((ci.flags & ~kKnownFlags) == 0, "VUID-VkBufferCreateInfo-flags-parameter",
            "pCreateInfo->flags 0x%x has bits that are not VkBufferCreateFlagBits of an enabled extension.", ci.flags);
    constexpr VkBufferUsageFlags kKnownUsage =
        VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT | VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT |
        VK_BUFFER_USAGE_STORAGE_TEXEL_BUFFER_BIT | VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT | VK_BUFFER_USAGE_STORAGE_BUFFER_BIT |
        VK_BUFFER_USAGE_INDEX_BUFFER_BIT | VK_BUFFER_USAGE_VERTEX_BUFFER_BIT | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT |
        VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT |
        VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_BIT_KHR |
        VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_STORAGE_BIT_KHR | VK_BUFFER_USAGE_SHADER_BINDING_TABLE_BIT_KHR |
        VK_BUFFER_USAGE_MICROMAP_BUILD_INPUT_READ_ONLY_BIT_EXT | VK_BUFFER_USAGE_MICROMAP_STORAGE_BIT_EXT;
    v.check((ci.usage & ~kKnownUsage) == 0, "VUID-VkBufferCreateInfo-usage-parameter",
            "pCreateInfo->usage 0x%x has bits that are not VkBufferUsageFlagBits of an enabled extension.", ci.usage);
    v.check(ci.usage != 0, "VUID-VkBufferCreateInfo-usage-requiredbitmask", "pCreateInfo->usage is 0.");
    if (!v.check(ci.sharingMode == VK_SHARING_MODE_EXCLUSIVE || ci.sharingMode == VK_SHARING_MODE_CONCURRENT,
                 "VUID-VkBufferCreateInfo-sharingMode-parameter", "pCreateInfo->sharingMode %d is not valid.",
                 int(ci.sharingMode)))
        return;
    if (ci.sharingMode == VK_SHARING_MODE_CONCURRENT) {
        v.check(ci.queueFamilyIndexCount > 1, "VUID-VkBufferCreateInfo-sharingMode-00914",
                "sharingMode is CONCURRENT but queueFamilyIndexCount is %u.", ci.queueFamilyIndexCount);
        if (v.check(ci.pQueueFamilyIndices != nullptr || ci.queueFamilyIndexCount == 0,
                    "VUID-VkBufferCreateInfo-sharingMode-00913",
                    "sharingMode is CONCURRENT but pQueueFamilyIndices is NULL.")) {
            // vkas has one queue family (index 0); the indices must be unique and below the family count.
            for (uint32_t i = 0; i < ci.queueFamilyIndexCount && ci.queueFamilyIndexCount > 1; ++i)
                if (!v.check(ci.pQueueFamilyIndices[i] == 0 && i == 0, "VUID-VkBufferCreateInfo-sharingMode-01419",
                             "pQueueFamilyIndices[%u] is %u: vkas has one queue family, so the indices cannot be unique "
                             "and below 1.",
                             i, ci.pQueueFamilyIndices[i]))
                    break;
        }
    }
    v.check(!(ci.flags & VK_BUFFER_CREATE_SPARSE_BINDING_BIT), "VUID-VkBufferCreateInfo-flags-00915",
            "pCreateInfo->flags has SPARSE_BINDING but the sparseBinding feature is not enabled.");
    v.check(!(ci.flags & VK_BUFFER_CREATE_SPARSE_RESIDENCY_BIT), "VUID-VkBufferCreateInfo-flags-00916",
            "pCreateInfo->flags has SPARSE_RESIDENCY but the sparseResidencyBuffer feature is not enabled.");
    v.check(!(ci.flags & VK_BUFFER_CREATE_SPARSE_ALIASED_BIT), "VUID-VkBufferCreateInfo-flags-00917",
            "pCreateInfo->flags has SPARSE_ALIASED but the sparseResidencyAliased feature is not enabled.");
    if (ci.flags & (VK_BUFFER_CREATE_SPARSE_RESIDENCY_BIT | VK_BUFFER_CREATE_SPARSE_ALIASED_BIT))
        v.check(ci.flags & VK_BUFFER_CREATE_SPARSE_BINDING_BIT, "VUID-VkBufferCreateInfo-flags-00918",
                "pCreateInfo->flags has SPARSE_RESIDENCY or SPARSE_ALIASED without SPARSE_BINDING.");
    v.check(!(ci.flags & VK_BUFFER_CREATE_PROTECTED_BIT), "VUID-VkBufferCreateInfo-flags-01887",
            "pCreateInfo->flags has PROTECTED but the protectedMemory feature is not enabled.");
    v.check(!(ci.flags & VK_BUFFER_CREATE_DEVICE_ADDRESS_CAPTURE_REPLAY_BIT), "VUID-VkBufferCreateInfo-flags-06549",
            "pCreateInfo->flags has DEVICE_ADDRESS_CAPTURE_REPLAY but the bufferDeviceAddressCaptureReplay feature is "
            "not enabled.");
}

void checkMemoryAllocateInfo(Validator& v, const VkMemoryAllocateInfo& ai) {
    v.check(ai.sType == VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, "VUID-VkMemoryAllocateInfo-sType-sType",
            "pAllocateInfo->sType is %d.", int(ai.sType));
    v.check(ai.memoryTypeIndex < 1, "VUID-vkAllocateMemory-pAllocateInfo-01714",
            "pAllocateInfo->memoryTypeIndex %u is not less than memoryTypeCount (1).", ai.memoryTypeIndex);
    v.check(ai.allocationSize > 0, "VUID-VkMemoryAllocateInfo-allocationSize-07897",
            "pAllocateInfo->allocationSize is 0.");
    checkNextChain(v, ai.pNext, {VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO}, "VUID-VkMemoryAllocateInfo-pNext-pNext",
                   "VUID-VkMemoryAllocateInfo-sType-unique", "pAllocateInfo");
}

void checkMemoryAllocateFlagsInfo(Validator& v, const VkMemoryAllocateFlagsInfo& f) {
    constexpr VkMemoryAllocateFlags kKnown = VK_MEMORY_ALLOCATE_DEVICE_MASK_BIT |
                                             VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT |
                                             VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_CAPTURE_REPLAY_BIT;
    v.check((f.flags & ~kKnown) == 0, "VUID-VkMemoryAllocateFlagsInfo-flags-parameter",
            "VkMemoryAllocateFlagsInfo::flags 0x%x has unknown bits.", f.flags);
    if (f.flags & VK_MEMORY_ALLOCATE_DEVICE_MASK_BIT) {
        // vkas is a device group of one physical device: the only valid mask is 1.
        v.check(f.deviceMask != 0, "VUID-VkMemoryAllocateFlagsInfo-deviceMask-00676",
                "VkMemoryAllocateFlagsInfo::deviceMask is 0.");
        v.check((f.deviceMask & ~1u) == 0, "VUID-VkMemoryAllocateFlagsInfo-deviceMask-00675",
                "VkMemoryAllocateFlagsInfo::deviceMask 0x%x names physical devices the device does not "
                "have (it has one).",
                f.deviceMask);
    }
    v.check(!(f.flags & VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_CAPTURE_REPLAY_BIT),
            "VUID-VkMemoryAllocateInfo-flags-03330",
            "VkMemoryAllocateFlagsInfo::flags has DEVICE_ADDRESS_CAPTURE_REPLAY but the "
            "bufferDeviceAddressCaptureReplay feature is not enabled.");
}

}  // namespace vkas
