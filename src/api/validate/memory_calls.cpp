#include "api/validate/memory_calls.hpp"

#include "api/validate/memory.hpp"
#include "api/validate/parameters.hpp"
#include "engine/util/pnext_chain.hpp"

namespace vkas {

bool checkCreateBuffer(Validator& v, const Device* dev, const VkBufferCreateInfo* pCreateInfo, VkBuffer* pBuffer) {
    if (!v.enabled()) return true;
    v.check(dev != nullptr, "VUID-vkCreateBuffer-device-parameter", "device is not a valid VkDevice.");
    if (v.check(pCreateInfo != nullptr, "VUID-vkCreateBuffer-pCreateInfo-parameter", "pCreateInfo is NULL."))
        checkBufferCreateInfo(v, *pCreateInfo);
    v.check(pBuffer != nullptr, "VUID-vkCreateBuffer-pBuffer-parameter", "pBuffer is NULL.");
    return !v.failed();
}

bool checkDestroyBuffer(Validator& v, const Device* dev, VkBuffer buffer, const VkAllocationCallbacks* pAllocator) {
    if (!dev) {
        v.fail("VUID-vkDestroyBuffer-device-parameter", "device is not a valid VkDevice.");
        return false;
    }
    if (buffer == VK_NULL_HANDLE) return false;
    if (!v.enabled()) return true;
    const Buffer* b = checkHandle<Buffer>(v, *dev, buffer, ObjectMagic::Buffer, "VUID-vkDestroyBuffer-buffer-parameter",
                                          "VUID-vkDestroyBuffer-buffer-parent", "buffer");
    if (!b) return false;
    checkDestroyAllocator(v, b->allocator, pAllocator, "VUID-vkDestroyBuffer-buffer-00923",
                          "VUID-vkDestroyBuffer-buffer-00924");
    return !v.failed();
}

bool checkGetBufferMemoryRequirements(Validator& v, const Device* dev, VkBuffer buffer,
                                      const VkMemoryRequirements* pMemoryRequirements) {
    if (!dev) {
        v.fail("VUID-vkGetBufferMemoryRequirements-device-parameter", "device is not a valid VkDevice.");
        return false;
    }
    if (!v.enabled()) return true;
    checkHandle<Buffer>(v, *dev, buffer, ObjectMagic::Buffer, "VUID-vkGetBufferMemoryRequirements-buffer-parameter",
                        "VUID-vkGetBufferMemoryRequirements-buffer-parent", "buffer");
    v.check(pMemoryRequirements != nullptr, "VUID-vkGetBufferMemoryRequirements-pMemoryRequirements-parameter",
            "pMemoryRequirements is NULL.");
    return !v.failed();
}

bool checkAllocateMemory(Validator& v, const Device* dev, const VkMemoryAllocateInfo* pAllocateInfo,
                         const VkDeviceMemory* pMemory) {
    if (!v.enabled()) return true;
    v.check(dev != nullptr, "VUID-vkAllocateMemory-device-parameter", "device is not a valid VkDevice.");
    if (v.check(pAllocateInfo != nullptr, "VUID-vkAllocateMemory-pAllocateInfo-parameter", "pAllocateInfo is NULL.")) {
        checkMemoryAllocateInfo(v, *pAllocateInfo);
        if (const auto* f = findInChain<VkMemoryAllocateFlagsInfo>(pAllocateInfo->pNext,
                                                                   VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO))
            checkMemoryAllocateFlagsInfo(v, *f);
    }
    v.check(pMemory != nullptr, "VUID-vkAllocateMemory-pMemory-parameter", "pMemory is NULL.");
    return !v.failed();
}

bool checkFreeMemory(Validator& v, const Device* dev, VkDeviceMemory memory) {
    if (!dev) {
        v.fail("VUID-vkFreeMemory-device-parameter", "device is not a valid VkDevice.");
        return false;
    }
    if (memory == VK_NULL_HANDLE) return false;
    if (v.enabled() && !checkHandle<Memory>(v, *dev, memory, ObjectMagic::Memory, "VUID-vkFreeMemory-memory-parameter",
                                            "VUID-vkFreeMemory-memory-parent", "memory"))
        return false;
    return true;
}

bool checkBindBufferMemory(Validator& v, const Device* dev, VkBuffer buffer, VkDeviceMemory memory,
                           VkDeviceSize memoryOffset, VkDeviceSize alignment) {
    if (!dev) {
        v.fail("VUID-vkBindBufferMemory-device-parameter", "device is not a valid VkDevice.");
        return false;
    }
    if (!v.enabled()) return true;
    Buffer* b = checkHandle<Buffer>(v, *dev, buffer, ObjectMagic::Buffer, "VUID-vkBindBufferMemory-buffer-parameter",
                                    "VUID-vkBindBufferMemory-buffer-parent", "buffer");
    Memory* m = checkHandle<Memory>(v, *dev, memory, ObjectMagic::Memory, "VUID-vkBindBufferMemory-memory-parameter",
                                    "VUID-vkBindBufferMemory-memory-parent", "memory");
    if (b && m) {
        v.check(b->memory == nullptr, "VUID-vkBindBufferMemory-buffer-07459", "buffer is already bound to memory.");
        v.check(memoryOffset < m->size, "VUID-vkBindBufferMemory-memoryOffset-01031",
                "memoryOffset %llu is not less than the memory size %llu.", (unsigned long long)memoryOffset,
                (unsigned long long)m->size);
        v.check(memoryOffset % alignment == 0, "VUID-vkBindBufferMemory-memoryOffset-01036",
                "memoryOffset %llu is not a multiple of the required alignment %llu.",
                (unsigned long long)memoryOffset, (unsigned long long)alignment);
        if (memoryOffset < m->size)
            v.check(b->size <= m->size - memoryOffset, "VUID-vkBindBufferMemory-size-01037",
                    "the buffer's %llu bytes at memoryOffset %llu do not fit in the memory's %llu bytes.",
                    (unsigned long long)b->size, (unsigned long long)memoryOffset, (unsigned long long)m->size);
        // bufferDeviceAddress is enabled: a buffer with SHADER_DEVICE_ADDRESS usage needs memory allocated with
        // VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT (VkMemoryAllocateFlagsInfo).
        if (b->usage & VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT)
            v.check(m->allocateFlags & VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT,
                    "VUID-vkBindBufferMemory-bufferDeviceAddress-03339",
                    "buffer has SHADER_DEVICE_ADDRESS usage but memory was not allocated with "
                    "VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT.");
    }
    return !v.failed();
}

bool checkMapMemory(Validator& v, const Device* dev, VkDeviceMemory memory, VkDeviceSize offset, VkDeviceSize size,
                    VkMemoryMapFlags flags, void** ppData) {
    if (!dev) {
        v.fail("VUID-vkMapMemory-device-parameter", "device is not a valid VkDevice.");
        return false;
    }
    if (!v.enabled()) return true;
    v.check(flags == 0, "VUID-vkMapMemory-flags-zerobitmask", "flags is 0x%x.", flags);
    if (Memory* m = checkHandle<Memory>(v, *dev, memory, ObjectMagic::Memory, "VUID-vkMapMemory-memory-parameter",
                                        "VUID-vkMapMemory-memory-parent", "memory")) {
        v.check(!m->mapped, "VUID-vkMapMemory-memory-00678", "memory is already mapped.");
        v.check(offset < m->size, "VUID-vkMapMemory-offset-00679", "offset %llu is not less than the memory size %llu.",
                (unsigned long long)offset, (unsigned long long)m->size);
        v.check(size == VK_WHOLE_SIZE || (size > 0 && offset < m->size && size <= m->size - offset),
                size == 0 ? "VUID-vkMapMemory-size-00680" : "VUID-vkMapMemory-size-00681",
                "size %llu at offset %llu does not fit in the memory's %llu bytes.", (unsigned long long)size,
                (unsigned long long)offset, (unsigned long long)m->size);
    }
    v.check(ppData != nullptr, "VUID-vkMapMemory-ppData-parameter", "ppData is NULL.");
    return !v.failed();
}

bool checkUnmapMemory(Validator& v, const Device* dev, VkDeviceMemory memory) {
    if (!dev) {
        v.fail("VUID-vkUnmapMemory-device-parameter", "device is not a valid VkDevice.");
        return false;
    }
    if (!v.enabled()) return true;
    if (Memory* m = checkHandle<Memory>(v, *dev, memory, ObjectMagic::Memory, "VUID-vkUnmapMemory-memory-parameter",
                                        "VUID-vkUnmapMemory-memory-parent", "memory"))
        v.check(m->mapped, "VUID-vkUnmapMemory-memory-00689", "memory is not mapped.");
    return !v.failed();
}

bool checkGetBufferDeviceAddress(Validator& v, const Device* dev, const VkBufferDeviceAddressInfo* pInfo) {
    if (!dev) {
        v.fail("VUID-vkGetBufferDeviceAddress-device-parameter", "device is not a valid VkDevice.");
        return false;
    }
    if (!v.enabled()) return true;
    if (v.check(pInfo != nullptr, "VUID-vkGetBufferDeviceAddress-pInfo-parameter", "pInfo is NULL.")) {
        v.check(pInfo->sType == VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO, "VUID-VkBufferDeviceAddressInfo-sType-sType",
                "pInfo->sType is %d.", int(pInfo->sType));
        v.check(pInfo->pNext == nullptr, "VUID-VkBufferDeviceAddressInfo-pNext-pNext", "pInfo->pNext is not NULL.");
        if (Buffer* b = checkHandle<Buffer>(v, *dev, pInfo->buffer, ObjectMagic::Buffer,
                                            "VUID-VkBufferDeviceAddressInfo-buffer-parameter", nullptr, "pInfo->buffer")) {
            v.check(b->memory != nullptr, "VUID-VkBufferDeviceAddressInfo-buffer-02600",
                    "pInfo->buffer is not bound to memory.");
            v.check(b->usage & VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT, "VUID-VkBufferDeviceAddressInfo-buffer-02601",
                    "pInfo->buffer was not created with VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT.");
        }
    }
    return !v.failed();
}

bool checkDestroyDevice(Validator& v, const Device* dev, const VkAllocationCallbacks* pAllocator) {
    if (!dev) {
        v.fail("VUID-vkDestroyDevice-device-parameter", "device is not a valid VkDevice.");
        return false;
    }
    // vkasCreateDeviceWithAllocator's callbacks, or none (vkasCreateDevice).
    if (!v.enabled()) return true;
    checkDestroyAllocator(v, dev->allocator(), pAllocator, "VUID-vkDestroyDevice-device-00379",
                          "VUID-vkDestroyDevice-device-00380");
    return !v.failed();
}

}  // namespace vkas
