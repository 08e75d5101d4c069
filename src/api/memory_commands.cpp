// vkCreateBuffer and friends. All memory is host memory: memory type 0 is HOST_VISIBLE | HOST_COHERENT |
// DEVICE_LOCAL, mapping returns the allocation itself, and a buffer's device address is its host address.
#include <cstdlib>
#include <new>

#include "api/device.hpp"
#include "api/entry_points.hpp"
#include "api/object_lifetime.hpp"
#include "api/validate/memory.hpp"
#include "api/validate/parameters.hpp"
#include "engine/util/pnext_chain.hpp"

namespace vkas::entry {

namespace {
constexpr VkDeviceSize kMemoryAlignment = 4096;  // allocations start on a page
constexpr VkDeviceSize kBufferAlignment = 256;   // enough for acceleration structures (offset % 256)
// The VkMemoryAllocateFlagsInfo in an allocation's pNext chain, or nullptr.
const VkMemoryAllocateFlagsInfo* allocateFlagsInfo(const VkMemoryAllocateInfo& ai) {
    return findInChain<VkMemoryAllocateFlagsInfo>(ai.pNext, VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO);
}
}  // namespace

VKAPI_ATTR VkResult VKAPI_CALL CreateBuffer(VkDevice device, const VkBufferCreateInfo* pCreateInfo,
                                            const VkAllocationCallbacks* pAllocator, VkBuffer* pBuffer) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkCreateBuffer");
    if (v.enabled()) {
        v.check(dev != nullptr, "VUID-vkCreateBuffer-device-parameter", "device is not a valid VkDevice.");
        if (v.check(pCreateInfo != nullptr, "VUID-vkCreateBuffer-pCreateInfo-parameter", "pCreateInfo is NULL."))
            checkBufferCreateInfo(v, *pCreateInfo);
        v.check(pBuffer != nullptr, "VUID-vkCreateBuffer-pBuffer-parameter", "pBuffer is NULL.");
        if (v.failed()) return VK_ERROR_VALIDATION_FAILED_EXT;
    }
    auto* buffer = createObject<Buffer>(pAllocator, dev->allocator());
    if (!buffer) return VK_ERROR_OUT_OF_HOST_MEMORY;
    buffer->device = dev;
    buffer->size = pCreateInfo->size;
    buffer->usage = pCreateInfo->usage;
    buffer->flags = pCreateInfo->flags;
    if (!dev->track(buffer)) {
        destroyObject(buffer);
        return VK_ERROR_OUT_OF_HOST_MEMORY;
    }
    *pBuffer = toHandle<VkBuffer>(buffer);
    return VK_SUCCESS;
}

VKAPI_ATTR void VKAPI_CALL DestroyBuffer(VkDevice device, VkBuffer buffer, const VkAllocationCallbacks* pAllocator) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkDestroyBuffer");
    if (!dev) return v.fail("VUID-vkDestroyBuffer-device-parameter", "device is not a valid VkDevice.");
    if (buffer == VK_NULL_HANDLE) return;
    if (v.enabled()) {
        const Buffer* b = checkHandle<Buffer>(v, *dev, buffer, ObjectMagic::Buffer, "VUID-vkDestroyBuffer-buffer-parameter",
                                              "VUID-vkDestroyBuffer-buffer-parent", "buffer");
        if (!b) return;
        checkDestroyAllocator(v, b->allocator, pAllocator, "VUID-vkDestroyBuffer-buffer-00923",
                              "VUID-vkDestroyBuffer-buffer-00924");
        if (v.failed()) return;
    }
    auto* b = fromHandle<Buffer>(buffer);
    if (dev) dev->untrack(b);
    destroyObject(b);
}

VKAPI_ATTR void VKAPI_CALL GetBufferMemoryRequirements(VkDevice device, VkBuffer buffer,
                                                       VkMemoryRequirements* pMemoryRequirements) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkGetBufferMemoryRequirements");
    if (!dev) return v.fail("VUID-vkGetBufferMemoryRequirements-device-parameter", "device is not a valid VkDevice.");
    if (v.enabled()) {
        checkHandle<Buffer>(v, *dev, buffer, ObjectMagic::Buffer, "VUID-vkGetBufferMemoryRequirements-buffer-parameter",
                            "VUID-vkGetBufferMemoryRequirements-buffer-parent", "buffer");
        v.check(pMemoryRequirements != nullptr, "VUID-vkGetBufferMemoryRequirements-pMemoryRequirements-parameter",
                "pMemoryRequirements is NULL.");
        if (v.failed()) return;
    }
    const Buffer* b = fromHandle<Buffer>(buffer);
    pMemoryRequirements->size = (b->size + kBufferAlignment - 1) / kBufferAlignment * kBufferAlignment;
    pMemoryRequirements->alignment = kBufferAlignment;
    pMemoryRequirements->memoryTypeBits = 1u;
}

VKAPI_ATTR VkResult VKAPI_CALL AllocateMemory(VkDevice device, const VkMemoryAllocateInfo* pAllocateInfo,
                                              const VkAllocationCallbacks* pAllocator, VkDeviceMemory* pMemory) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkAllocateMemory");
    if (v.enabled()) {
        v.check(dev != nullptr, "VUID-vkAllocateMemory-device-parameter", "device is not a valid VkDevice.");
        if (v.check(pAllocateInfo != nullptr, "VUID-vkAllocateMemory-pAllocateInfo-parameter",
                    "pAllocateInfo is NULL.")) {
            checkMemoryAllocateInfo(v, *pAllocateInfo);
            if (const auto* f = allocateFlagsInfo(*pAllocateInfo)) checkMemoryAllocateFlagsInfo(v, *f);
        }
        v.check(pMemory != nullptr, "VUID-vkAllocateMemory-pMemory-parameter", "pMemory is NULL.");
        if (v.failed()) return VK_ERROR_VALIDATION_FAILED_EXT;
    }
    VkDeviceSize size = pAllocateInfo->allocationSize;
    VkDeviceSize rounded = (size + kMemoryAlignment - 1) / kMemoryAlignment * kMemoryAlignment;
    if (rounded < size) return VK_ERROR_OUT_OF_HOST_MEMORY;
    auto* memory = createObject<Memory>(pAllocator, dev->allocator());
    if (!memory) return VK_ERROR_OUT_OF_HOST_MEMORY;
    memory->data = static_cast<std::byte*>(std::aligned_alloc(kMemoryAlignment, rounded));
    memory->device = dev;
    memory->size = size;
    if (const auto* f = allocateFlagsInfo(*pAllocateInfo)) memory->allocateFlags = f->flags;
    if (!memory->data || !dev->track(memory)) {
        std::free(memory->data);
        destroyObject(memory);
        return VK_ERROR_OUT_OF_HOST_MEMORY;
    }
    *pMemory = toHandle<VkDeviceMemory>(memory);
    return VK_SUCCESS;
}

VKAPI_ATTR void VKAPI_CALL FreeMemory(VkDevice device, VkDeviceMemory memory, const VkAllocationCallbacks*) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkFreeMemory");
    if (!dev) return v.fail("VUID-vkFreeMemory-device-parameter", "device is not a valid VkDevice.");
    if (memory == VK_NULL_HANDLE) return;
    if (v.enabled() && !checkHandle<Memory>(v, *dev, memory, ObjectMagic::Memory, "VUID-vkFreeMemory-memory-parameter",
                                            "VUID-vkFreeMemory-memory-parent", "memory"))
        return;
    auto* m = fromHandle<Memory>(memory);
    if (dev) dev->untrack(m);
    std::free(m->data);
    destroyObject(m);
}

VKAPI_ATTR VkResult VKAPI_CALL BindBufferMemory(VkDevice device, VkBuffer buffer, VkDeviceMemory memory,
                                                VkDeviceSize memoryOffset) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkBindBufferMemory");
    if (!dev) {
        v.fail("VUID-vkBindBufferMemory-device-parameter", "device is not a valid VkDevice.");
        return VK_ERROR_VALIDATION_FAILED_EXT;
    }
    if (v.enabled()) {
        Buffer* b = checkHandle<Buffer>(v, *dev, buffer, ObjectMagic::Buffer, "VUID-vkBindBufferMemory-buffer-parameter",
                                        "VUID-vkBindBufferMemory-buffer-parent", "buffer");
        Memory* m = checkHandle<Memory>(v, *dev, memory, ObjectMagic::Memory, "VUID-vkBindBufferMemory-memory-parameter",
                                        "VUID-vkBindBufferMemory-memory-parent", "memory");
        if (b && m) {
            v.check(b->memory == nullptr, "VUID-vkBindBufferMemory-buffer-07459",
                    "buffer is already bound to memory.");
            v.check(memoryOffset < m->size, "VUID-vkBindBufferMemory-memoryOffset-01031",
                    "memoryOffset %llu is not less than the memory size %llu.", (unsigned long long)memoryOffset,
                    (unsigned long long)m->size);
            v.check(memoryOffset % kBufferAlignment == 0, "VUID-vkBindBufferMemory-memoryOffset-01036",
                    "memoryOffset %llu is not a multiple of the required alignment %llu.",
                    (unsigned long long)memoryOffset, (unsigned long long)kBufferAlignment);
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
        if (v.failed()) return VK_ERROR_VALIDATION_FAILED_EXT;
    }
    Buffer* b = fromHandle<Buffer>(buffer);
    b->memory = fromHandle<Memory>(memory);
    b->memoryOffset = memoryOffset;
    return VK_SUCCESS;
}

VKAPI_ATTR VkResult VKAPI_CALL MapMemory(VkDevice device, VkDeviceMemory memory, VkDeviceSize offset,
                                         VkDeviceSize size, VkMemoryMapFlags flags, void** ppData) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkMapMemory");
    if (!dev) {
        v.fail("VUID-vkMapMemory-device-parameter", "device is not a valid VkDevice.");
        return VK_ERROR_VALIDATION_FAILED_EXT;
    }
    if (v.enabled()) {
        v.check(flags == 0, "VUID-vkMapMemory-flags-zerobitmask", "flags is 0x%x.", flags);
        if (Memory* m = checkHandle<Memory>(v, *dev, memory, ObjectMagic::Memory, "VUID-vkMapMemory-memory-parameter",
                                            "VUID-vkMapMemory-memory-parent", "memory")) {
            v.check(!m->mapped, "VUID-vkMapMemory-memory-00678", "memory is already mapped.");
            v.check(offset < m->size, "VUID-vkMapMemory-offset-00679",
                    "offset %llu is not less than the memory size %llu.", (unsigned long long)offset,
                    (unsigned long long)m->size);
            v.check(size == VK_WHOLE_SIZE || (size > 0 && offset < m->size && size <= m->size - offset),
                    size == 0 ? "VUID-vkMapMemory-size-00680" : "VUID-vkMapMemory-size-00681",
                    "size %llu at offset %llu does not fit in the memory's %llu bytes.", (unsigned long long)size,
                    (unsigned long long)offset, (unsigned long long)m->size);
        }
        v.check(ppData != nullptr, "VUID-vkMapMemory-ppData-parameter", "ppData is NULL.");
        if (v.failed()) return VK_ERROR_VALIDATION_FAILED_EXT;
    }
    Memory* m = fromHandle<Memory>(memory);
    m->mapped = true;
    *ppData = m->data + offset;
    return VK_SUCCESS;
}

VKAPI_ATTR void VKAPI_CALL UnmapMemory(VkDevice device, VkDeviceMemory memory) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkUnmapMemory");
    if (!dev) return v.fail("VUID-vkUnmapMemory-device-parameter", "device is not a valid VkDevice.");
    if (v.enabled()) {
        if (Memory* m = checkHandle<Memory>(v, *dev, memory, ObjectMagic::Memory, "VUID-vkUnmapMemory-memory-parameter",
                                            "VUID-vkUnmapMemory-memory-parent", "memory"))
            v.check(m->mapped, "VUID-vkUnmapMemory-memory-00689", "memory is not mapped.");
        if (v.failed()) return;
    }
    fromHandle<Memory>(memory)->mapped = false;
}

VKAPI_ATTR VkDeviceAddress VKAPI_CALL GetBufferDeviceAddress(VkDevice device, const VkBufferDeviceAddressInfo* pInfo) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkGetBufferDeviceAddress");
    if (!dev) {
        v.fail("VUID-vkGetBufferDeviceAddress-device-parameter", "device is not a valid VkDevice.");
        return 0;
    }
    if (v.enabled()) {
        if (v.check(pInfo != nullptr, "VUID-vkGetBufferDeviceAddress-pInfo-parameter", "pInfo is NULL.")) {
            v.check(pInfo->sType == VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO,
                    "VUID-VkBufferDeviceAddressInfo-sType-sType", "pInfo->sType is %d.", int(pInfo->sType));
            v.check(pInfo->pNext == nullptr, "VUID-VkBufferDeviceAddressInfo-pNext-pNext", "pInfo->pNext is not NULL.");
            if (Buffer* b = checkHandle<Buffer>(v, *dev, pInfo->buffer, ObjectMagic::Buffer,
                                                "VUID-VkBufferDeviceAddressInfo-buffer-parameter", nullptr,
                                                "pInfo->buffer")) {
                v.check(b->memory != nullptr, "VUID-VkBufferDeviceAddressInfo-buffer-02600",
                        "pInfo->buffer is not bound to memory.");
                v.check(b->usage & VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT,
                        "VUID-VkBufferDeviceAddressInfo-buffer-02601",
                        "pInfo->buffer was not created with VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT.");
            }
        }
        if (v.failed()) return 0;
    }
    return reinterpret_cast<VkDeviceAddress>(fromHandle<Buffer>(pInfo->buffer)->hostAddress());
}

VKAPI_ATTR void VKAPI_CALL DestroyDevice(VkDevice device, const VkAllocationCallbacks* pAllocator) {
    if (device == VK_NULL_HANDLE) return;
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkDestroyDevice");
    if (!dev) return v.fail("VUID-vkDestroyDevice-device-parameter", "device is not a valid VkDevice.");
    // vkasCreateDeviceWithAllocator's callbacks, or none (vkasCreateDevice).
    if (v.enabled()) {
        checkDestroyAllocator(v, dev->allocator(), pAllocator, "VUID-vkDestroyDevice-device-00379",
                              "VUID-vkDestroyDevice-device-00380");
        if (v.failed()) return;
    }
    vkasDestroyDevice(device);
}

}  // namespace vkas::entry
