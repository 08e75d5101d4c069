// The Vulkan objects vkas implements. Non-dispatchable handles are pointers to these structs; each starts with
// a magic word so validation can tell a live object of the right type from anything else it is handed.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstddef>
#include <cstdint>

namespace vkas {

class Device;

enum class ObjectMagic : uint32_t {
    Memory = 0x4D454D31,                 // "MEM1"
    Buffer = 0x42554631,                 // "BUF1"
    AccelerationStructure = 0x41435331,  // "ACS1"
    DeferredOperation = 0x44464F31,      // "DFO1"
    Micromap = 0x4D4D5031,               // "MMP1"
    Dead = 0xDEADDEAD,
};

struct Memory {
    ObjectMagic magic = ObjectMagic::Memory;
    Device* device = nullptr;
    std::byte* data = nullptr;
    VkDeviceSize size = 0;
    bool mapped = false;
    VkMemoryAllocateFlags allocateFlags = 0;  // VkMemoryAllocateFlagsInfo::flags at allocation
    VkAllocationCallbacks allocator{};  // the pAllocator of vkAllocateMemory (zero: none)
    VkAllocationCallbacks memoryCallbacks{};  // what this struct\'s memory came from (createObject)
};

struct Buffer {
    ObjectMagic magic = ObjectMagic::Buffer;
    Device* device = nullptr;
    VkDeviceSize size = 0;
    VkBufferUsageFlags usage = 0;
    VkBufferCreateFlags flags = 0;
    Memory* memory = nullptr;
    VkDeviceSize memoryOffset = 0;
    VkAllocationCallbacks allocator{};  // the pAllocator of vkCreateBuffer (zero: none)
    VkAllocationCallbacks memoryCallbacks{};  // what this struct\'s memory came from (createObject)

    std::byte* hostAddress() const { return memory ? memory->data + memoryOffset : nullptr; }
};

struct AccelerationStructure {
    ObjectMagic magic = ObjectMagic::AccelerationStructure;
    Device* device = nullptr;
    Buffer* buffer = nullptr;
    VkDeviceSize offset = 0;
    VkDeviceSize size = 0;
    VkAccelerationStructureTypeKHR type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
    VkAccelerationStructureCreateFlagsKHR createFlags = 0;
    bool constructed = false;  // a build or copy has written it
    VkAllocationCallbacks allocator{};  // the pAllocator of vkCreateAccelerationStructureKHR (zero: none)
    VkAllocationCallbacks memoryCallbacks{};  // what this struct\'s memory came from (createObject)

    // The structure's block: where its bytes live, or nullptr while its buffer has no memory.
    std::byte* block() const {
        std::byte* base = buffer ? buffer->hostAddress() : nullptr;
        return base ? base + offset : nullptr;
    }
};

// VK_EXT_opacity_micromap: a micromap lives in a buffer like an acceleration structure (engine/format/micromap_layout.hpp).
struct Micromap {
    ObjectMagic magic = ObjectMagic::Micromap;
    Device* device = nullptr;
    Buffer* buffer = nullptr;
    VkDeviceSize offset = 0;
    VkDeviceSize size = 0;
    VkMicromapTypeEXT type = VK_MICROMAP_TYPE_OPACITY_MICROMAP_EXT;
    VkMicromapCreateFlagsEXT createFlags = 0;
    bool constructed = false;  // a build or copy has written it
    VkAllocationCallbacks allocator{};  // the pAllocator of vkCreateMicromapEXT (zero: none)
    VkAllocationCallbacks memoryCallbacks{};  // what this struct\'s memory came from (createObject)

    std::byte* block() const {
        std::byte* base = buffer ? buffer->hostAddress() : nullptr;
        return base ? base + offset : nullptr;
    }
};

template <class T, class H>
inline T* fromHandle(H handle) {
    return reinterpret_cast<T*>(handle);
}
template <class H, class T>
inline H toHandle(T* object) {
    return reinterpret_cast<H>(object);
}

}  // namespace vkas
