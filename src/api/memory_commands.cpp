// vkCreateBuffer and friends. All memory is host memory: memory type 0 is HOST_VISIBLE | HOST_COHERENT |
// DEVICE_LOCAL, mapping returns the allocation itself, and a buffer's device address is its host address.
#include <cstdlib>
#include <new>

#include "api/device.hpp"
#include "api/entry_points.hpp"
#include "api/validation.hpp"

namespace vkas::entry {

namespace {
constexpr VkDeviceSize kMemoryAlignment = 4096;  // allocations start on a page
constexpr VkDeviceSize kBufferAlignment = 256;   // enough for acceleration structures (offset % 256)
}  // namespace

VKAPI_ATTR VkResult VKAPI_CALL CreateBuffer(VkDevice device, const VkBufferCreateInfo* pCreateInfo,
                                            const VkAllocationCallbacks*, VkBuffer* pBuffer) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkCreateBuffer");
    if (v.enabled()) {
        v.check(dev != nullptr, "VUID-vkCreateBuffer-device-parameter", "device is not a valid VkDevice.");
        if (v.check(pCreateInfo != nullptr, "VUID-vkCreateBuffer-pCreateInfo-parameter", "pCreateInfo is NULL.")) {
            v.check(pCreateInfo->sType == VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO, "VUID-VkBufferCreateInfo-sType-sType",
                    "pCreateInfo->sType is %d.", int(pCreateInfo->sType));
            v.check(pCreateInfo->size > 0, "VUID-VkBufferCreateInfo-size-00912", "pCreateInfo->size is 0.");
        }
        v.check(pBuffer != nullptr, "VUID-vkCreateBuffer-pBuffer-parameter", "pBuffer is NULL.");
        if (v.failed()) return VK_ERROR_VALIDATION_FAILED_EXT;
    }
    auto* buffer = new (std::nothrow) Buffer;
    if (!buffer) return VK_ERROR_OUT_OF_HOST_MEMORY;
    buffer->device = dev;
    buffer->size = pCreateInfo->size;
    buffer->usage = pCreateInfo->usage;
    buffer->flags = pCreateInfo->flags;
    dev->track(buffer);
    *pBuffer = toHandle<VkBuffer>(buffer);
    return VK_SUCCESS;
}

VKAPI_ATTR void VKAPI_CALL DestroyBuffer(VkDevice device, VkBuffer buffer, const VkAllocationCallbacks*) {
    Device* dev = Device::fromHandle(device);
    if (buffer == VK_NULL_HANDLE) return;
    Validator v(dev, "vkDestroyBuffer");
    if (v.enabled()) {
        v.check(dev && dev->live<Buffer>(buffer, ObjectMagic::Buffer), "VUID-vkDestroyBuffer-buffer-parameter",
                "buffer 0x%llx is not a live VkBuffer.", (unsigned long long)(uintptr_t)buffer);
        if (v.failed()) return;
    }
    auto* b = fromHandle<Buffer>(buffer);
    if (dev) dev->untrack(b);
    b->magic = ObjectMagic::Dead;
    delete b;
}

VKAPI_ATTR void VKAPI_CALL GetBufferMemoryRequirements(VkDevice device, VkBuffer buffer,
                                                       VkMemoryRequirements* pMemoryRequirements) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkGetBufferMemoryRequirements");
    if (v.enabled()) {
        v.check(dev && dev->live<Buffer>(buffer, ObjectMagic::Buffer),
                "VUID-vkGetBufferMemoryRequirements-buffer-parameter", "buffer is not a live VkBuffer.");
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
                                              const VkAllocationCallbacks*, VkDeviceMemory* pMemory) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkAllocateMemory");
    if (v.enabled()) {
        v.check(dev != nullptr, "VUID-vkAllocateMemory-device-parameter", "device is not a valid VkDevice.");
        if (v.check(pAllocateInfo != nullptr, "VUID-vkAllocateMemory-pAllocateInfo-parameter",
                    "pAllocateInfo is NULL.")) {
            v.check(pAllocateInfo->sType == VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO,
                    "VUID-VkMemoryAllocateInfo-sType-sType", "pAllocateInfo->sType is %d.",
                    int(pAllocateInfo->sType));
            v.check(pAllocateInfo->memoryTypeIndex < 1, "VUID-vkAllocateMemory-pAllocateInfo-01714",
                    "pAllocateInfo->memoryTypeIndex %u is not less than memoryTypeCount (1).",
                    pAllocateInfo->memoryTypeIndex);
            v.check(pAllocateInfo->allocationSize > 0, "VUID-VkMemoryAllocateInfo-allocationSize-07897",
                    "pAllocateInfo->allocationSize is 0.");
        }
        v.check(pMemory != nullptr, "VUID-vkAllocateMemory-pMemory-parameter", "pMemory is NULL.");
        if (v.failed()) return VK_ERROR_VALIDATION_FAILED_EXT;
    }
    VkDeviceSize size = pAllocateInfo->allocationSize;
    VkDeviceSize rounded = (size + kMemoryAlignment - 1) / kMemoryAlignment * kMemoryAlignment;
    if (rounded < size) return VK_ERROR_OUT_OF_HOST_MEMORY;
    auto* memory = new (std::nothrow) Memory;
    if (!memory) return VK_ERROR_OUT_OF_HOST_MEMORY;
    memory->data = static_cast<std::byte*>(std::aligned_alloc(kMemoryAlignment, rounded));
    if (!memory->data) {
        delete memory;
        return VK_ERROR_OUT_OF_HOST_MEMORY;
    }
    memory->device = dev;
    memory->size = size;
    dev->track(memory);
    *pMemory = toHandle<VkDeviceMemory>(memory);
    return VK_SUCCESS;
}

VKAPI_ATTR void VKAPI_CALL FreeMemory(VkDevice device, VkDeviceMemory memory, const VkAllocationCallbacks*) {
    Device* dev = Device::fromHandle(device);
    if (memory == VK_NULL_HANDLE) return;
    Validator v(dev, "vkFreeMemory");
    if (v.enabled()) {
        v.check(dev && dev->live<Memory>(memory, ObjectMagic::Memory), "VUID-vkFreeMemory-memory-parameter",
                "memory is not a live VkDeviceMemory.");
        if (v.failed()) return;
    }
    auto* m = fromHandle<Memory>(memory);
    if (dev) dev->untrack(m);
    std::free(m->data);
    m->magic = ObjectMagic::Dead;
    delete m;
}

VKAPI_ATTR VkResult VKAPI_CALL BindBufferMemory(VkDevice device, VkBuffer buffer, VkDeviceMemory memory,
                                                VkDeviceSize memoryOffset) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkBindBufferMemory");
    Buffer* b = dev ? dev->live<Buffer>(buffer, ObjectMagic::Buffer) : nullptr;
    Memory* m = dev ? dev->live<Memory>(memory, ObjectMagic::Memory) : nullptr;
    if (v.enabled()) {
        v.check(b != nullptr, "VUID-vkBindBufferMemory-buffer-parameter", "buffer is not a live VkBuffer.");
        v.check(m != nullptr, "VUID-vkBindBufferMemory-memory-parameter", "memory is not a live VkDeviceMemory.");
        if (b && m) {
            v.check(b->memory == nullptr, "VUID-vkBindBufferMemory-buffer-07459",
                    "buffer is already bound to memory.");
            v.check(memoryOffset < m->size, "VUID-vkBindBufferMemory-memoryOffset-01031",
                    "memoryOffset %llu is not less than the memory size %llu.", (unsigned long long)memoryOffset,
                    (unsigned long long)m->size);
            v.check(memoryOffset % kBufferAlignment == 0, "VUID-vkBindBufferMemory-memoryOffset-01036",
                    "memoryOffset %llu is not a multiple of the required alignment %llu.",
                    (unsigned long long)memoryOffset, (unsigned long long)kBufferAlignment);
            v.check(memoryOffset < m->size && b->size <= m->size - memoryOffset,
                    "VUID-vkBindBufferMemory-size-01037",
                    "the buffer's %llu bytes at memoryOffset %llu do not fit in the memory's %llu bytes.",
                    (unsigned long long)b->size, (unsigned long long)memoryOffset, (unsigned long long)m->size);
        }
        if (v.failed()) return VK_ERROR_VALIDATION_FAILED_EXT;
    }
    b = fromHandle<Buffer>(buffer);
    b->memory = fromHandle<Memory>(memory);
    b->memoryOffset = memoryOffset;
    return VK_SUCCESS;
}

VKAPI_ATTR VkResult VKAPI_CALL MapMemory(VkDevice device, VkDeviceMemory memory, VkDeviceSize offset,
                                         VkDeviceSize size, VkMemoryMapFlags, void** ppData) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkMapMemory");
    Memory* m = dev ? dev->live<Memory>(memory, ObjectMagic::Memory) : nullptr;
    if (v.enabled()) {
        if (v.check(m != nullptr, "VUID-vkMapMemory-memory-parameter", "memory is not a live VkDeviceMemory.")) {
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
    m = fromHandle<Memory>(memory);
    m->mapped = true;
    *ppData = m->data + offset;
    return VK_SUCCESS;
}

VKAPI_ATTR void VKAPI_CALL UnmapMemory(VkDevice device, VkDeviceMemory memory) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkUnmapMemory");
    Memory* m = dev ? dev->live<Memory>(memory, ObjectMagic::Memory) : nullptr;
    if (v.enabled()) {
        if (v.check(m != nullptr, "VUID-vkUnmapMemory-memory-parameter", "memory is not a live VkDeviceMemory."))
            v.check(m->mapped, "VUID-vkUnmapMemory-memory-00689", "memory is not mapped.");
        if (v.failed()) return;
    }
    fromHandle<Memory>(memory)->mapped = false;
}

VKAPI_ATTR VkDeviceAddress VKAPI_CALL GetBufferDeviceAddress(VkDevice device, const VkBufferDeviceAddressInfo* pInfo) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkGetBufferDeviceAddress");
    if (v.enabled()) {
        if (v.check(pInfo != nullptr, "VUID-vkGetBufferDeviceAddress-pInfo-parameter", "pInfo is NULL.")) {
            Buffer* b = dev ? dev->live<Buffer>(pInfo->buffer, ObjectMagic::Buffer) : nullptr;
            if (v.check(b != nullptr, "VUID-VkBufferDeviceAddressInfo-buffer-parameter",
                        "pInfo->buffer is not a live VkBuffer."))
                v.check(b->memory != nullptr, "VUID-VkBufferDeviceAddressInfo-buffer-02600",
                        "pInfo->buffer is not bound to memory.");
        }
        if (v.failed()) return 0;
    }
    return reinterpret_cast<VkDeviceAddress>(fromHandle<Buffer>(pInfo->buffer)->hostAddress());
}

VKAPI_ATTR void VKAPI_CALL DestroyDevice(VkDevice device, const VkAllocationCallbacks*) { vkasDestroyDevice(device); }

}  // namespace vkas::entry
