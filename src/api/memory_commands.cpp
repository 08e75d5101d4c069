// vkCreateBuffer and friends. All memory is host memory: memory type 0 is HOST_VISIBLE | HOST_COHERENT |
// DEVICE_LOCAL, mapping returns the allocation itself, and a buffer's device address is its host address.
#include <cstdlib>
#include <new>

#include "api/device.hpp"
#include "api/entry_points.hpp"
#include "api/object_lifetime.hpp"
#include "api/validate/memory_calls.hpp"
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
    if (!checkCreateBuffer(v, dev, pCreateInfo, pBuffer)) return VK_ERROR_VALIDATION_FAILED_EXT;
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
    if (!checkDestroyBuffer(v, dev, buffer, pAllocator)) return;
    auto* b = fromHandle<Buffer>(buffer);
    if (dev) dev->untrack(b);
    destroyObject(b);
}

VKAPI_ATTR void VKAPI_CALL GetBufferMemoryRequirements(VkDevice device, VkBuffer buffer,
                                                       VkMemoryRequirements* pMemoryRequirements) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkGetBufferMemoryRequirements");
    if (!checkGetBufferMemoryRequirements(v, dev, buffer, pMemoryRequirements)) return;
    const Buffer* b = fromHandle<Buffer>(buffer);
    pMemoryRequirements->size = (b->size + kBufferAlignment - 1) / kBufferAlignment * kBufferAlignment;
    pMemoryRequirements->alignment = kBufferAlignment;
    pMemoryRequirements->memoryTypeBits = 1u;
}

VKAPI_ATTR VkResult VKAPI_CALL AllocateMemory(VkDevice device, const VkMemoryAllocateInfo* pAllocateInfo,
                                              const VkAllocationCallbacks* pAllocator, VkDeviceMemory* pMemory) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkAllocateMemory");
    if (!checkAllocateMemory(v, dev, pAllocateInfo, pMemory)) return VK_ERROR_VALIDATION_FAILED_EXT;
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
    if (!checkFreeMemory(v, dev, memory)) return;
    auto* m = fromHandle<Memory>(memory);
    if (dev) dev->untrack(m);
    std::free(m->data);
    destroyObject(m);
}

VKAPI_ATTR VkResult VKAPI_CALL BindBufferMemory(VkDevice device, VkBuffer buffer, VkDeviceMemory memory,
                                                VkDeviceSize memoryOffset) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkBindBufferMemory");
    if (!checkBindBufferMemory(v, dev, buffer, memory, memoryOffset, kBufferAlignment))
        return VK_ERROR_VALIDATION_FAILED_EXT;
    Buffer* b = fromHandle<Buffer>(buffer);
    b->memory = fromHandle<Memory>(memory);
    b->memoryOffset = memoryOffset;
    return VK_SUCCESS;
}

VKAPI_ATTR VkResult VKAPI_CALL MapMemory(VkDevice device, VkDeviceMemory memory, VkDeviceSize offset,
                                         VkDeviceSize size, VkMemoryMapFlags flags, void** ppData) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkMapMemory");
    if (!checkMapMemory(v, dev, memory, offset, size, flags, ppData)) return VK_ERROR_VALIDATION_FAILED_EXT;
    Memory* m = fromHandle<Memory>(memory);
    m->mapped = true;
    *ppData = m->data + offset;
    return VK_SUCCESS;
}

VKAPI_ATTR void VKAPI_CALL UnmapMemory(VkDevice device, VkDeviceMemory memory) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkUnmapMemory");
    if (!checkUnmapMemory(v, dev, memory)) return;
    fromHandle<Memory>(memory)->mapped = false;
}

VKAPI_ATTR VkDeviceAddress VKAPI_CALL GetBufferDeviceAddress(VkDevice device, const VkBufferDeviceAddressInfo* pInfo) {
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkGetBufferDeviceAddress");
    if (!checkGetBufferDeviceAddress(v, dev, pInfo)) return 0;
    return reinterpret_cast<VkDeviceAddress>(fromHandle<Buffer>(pInfo->buffer)->hostAddress());
}

VKAPI_ATTR void VKAPI_CALL DestroyDevice(VkDevice device, const VkAllocationCallbacks* pAllocator) {
    if (device == VK_NULL_HANDLE) return;
    Device* dev = Device::fromHandle(device);
    Validator v(dev, "vkDestroyDevice");
    if (!checkDestroyDevice(v, dev, pAllocator)) return;
    vkasDestroyDevice(device);
}

}  // namespace vkas::entry
