// Acceleration-structure building through the Vulkan commands vkas implements: buffers in host memory, the
// sizes query, vkCreateAccelerationStructureKHR and one host vkBuildAccelerationStructuresKHR call per level.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "scene.hpp"
#include "vk_context.hpp"

namespace vkas_tool {

// A VkBuffer bound to its own VkDeviceMemory (memory type 0: host memory) and mapped for its whole life.
class HostBuffer {
public:
    HostBuffer(VkContext& ctx, VkDeviceSize size, VkBufferUsageFlags usage);
    ~HostBuffer();
    HostBuffer(const HostBuffer&) = delete;
    HostBuffer& operator=(const HostBuffer&) = delete;

    VkBuffer buffer() const { return buffer_; }
    VkDeviceSize size() const { return size_; }
    unsigned char* data() const { return static_cast<unsigned char*>(mapped_); }
    VkDeviceAddress address() const { return address_; }

private:
    VkContext& ctx_;
    VkBuffer buffer_ = VK_NULL_HANDLE;
    VkDeviceMemory memory_ = VK_NULL_HANDLE;
    VkDeviceSize size_ = 0;
    void* mapped_ = nullptr;
    VkDeviceAddress address_ = 0;
};

// What the sizes query said about one structure, and what it holds.
struct StructureStats {
    std::string name;
    uint64_t primitives = 0;              // triangles (bottom level) or instances (top level)
    VkDeviceSize size = 0;                // accelerationStructureSize
    VkDeviceSize buildScratchSize = 0;
};

// Acceleration structures built together, sharing one storage buffer (each at its own 256-byte aligned offset).
class StructureSet {
public:
    explicit StructureSet(VkContext& ctx) : ctx_(ctx) {}
    ~StructureSet();
    StructureSet(const StructureSet&) = delete;
    StructureSet& operator=(const StructureSet&) = delete;

    std::vector<VkAccelerationStructureKHR> handles;
    std::vector<VkDeviceSize> offsets;  // where each structure's block starts in `storage`
    std::vector<StructureStats> stats;
    std::unique_ptr<HostBuffer> storage;
    VkDeviceSize scratchBytes = 0;  // scratch buffer used by the build
    VkDeviceSize inputBytes = 0;    // vertex, index, transform or instance data read by the build
    double sizeQueryMs = 0;
    double buildMs = 0;             // the vkBuildAccelerationStructuresKHR call alone

    // The bytes of structure i (docs/FORMAT.md), at the start of its range of the storage buffer.
    const unsigned char* block(size_t i) const { return storage->data() + offsets.at(i); }
    uint64_t totalPrimitives() const;
    VkDeviceSize totalSize() const;

private:
    VkContext& ctx_;
};

VkBuildAccelerationStructureFlagsKHR defaultBuildFlags();

// Builds one bottom-level structure per BlasDesc, all in one vkBuildAccelerationStructuresKHR call.
std::unique_ptr<StructureSet> buildBottomLevel(VkContext& ctx, const std::vector<BlasDesc>& blases,
                                               VkBuildAccelerationStructureFlagsKHR flags);
// Builds the top-level structure over `instances`; InstanceDesc::blas indexes `blases`.
std::unique_ptr<StructureSet> buildTopLevel(VkContext& ctx, const std::vector<InstanceDesc>& instances,
                                            const std::vector<VkAccelerationStructureKHR>& blases,
                                            VkBuildAccelerationStructureFlagsKHR flags);

}  // namespace vkas_tool
