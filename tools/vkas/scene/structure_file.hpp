// Serialized structures as files: `vkas inspect` loads one with vkCopyMemoryToAccelerationStructureKHR (which
// checks the UUIDs, the sizes, the XXH3 integrity hash, the tree and every record: the verdict the tool reports), and
// writes one with vkCopyAccelerationStructureToMemoryKHR (--write-blob). The envelope's fields are those of
// docs/FORMAT.md, "Serialized form".
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "as_builder.hpp"
#include "vk_context.hpp"

namespace vkas_tool {

// Whether the file starts like a serialized vkas structure (its driverUUID begins "VKAS-").
bool looksSerialized(const std::string& path);

struct SerializedHeader {
    std::string driverUuid, compatibilityUuid;  // 16 ASCII bytes each
    uint64_t serializedSize = 0, deserializedSize = 0, handleCount = 0;
    int layout = 0;  // 1 or 2 (driverUUID VKAS-DRIVER-FMT1 / VKAS-SERIALIZED2); 0 unknown
};

// A structure deserialized from a file, in a buffer of its own (block at offset 0).
struct LoadedStructure {
    SerializedHeader header;
    uint64_t fileSize = 0;
    std::unique_ptr<HostBuffer> storage;
    VkAccelerationStructureKHR handle = VK_NULL_HANDLE;
    VkContext* ctx = nullptr;
    LoadedStructure() = default;
    LoadedStructure(LoadedStructure&& o) noexcept
        : header(o.header), fileSize(o.fileSize), storage(std::move(o.storage)), handle(o.handle), ctx(o.ctx) {
        o.handle = VK_NULL_HANDLE;
    }
    LoadedStructure& operator=(LoadedStructure&&) = delete;
    ~LoadedStructure();
    const unsigned char* block() const { return storage->data(); }
    size_t blockSize() const { return static_cast<size_t>(storage->size()); }
};

// Throws InputError naming the file and the problem (truncated, incompatible, corrupted, ...). The context must
// collect messages (DeviceOptions::collectMessages), so that vkas's own report becomes part of that message.
// Top-level blobs are loaded with their handle array zeroed: the bottom levels they referred to are not in the file,
// so every instance is inactive in the loaded copy (its tree and records are still inspected).
LoadedStructure loadSerialized(VkContext& ctx, const std::string& path);

// vkWriteAccelerationStructuresPropertiesKHR of one structure (VK_QUERY_TYPE_ACCELERATION_STRUCTURE_*).
uint64_t queryStructureProperty(VkContext& ctx, VkAccelerationStructureKHR as, VkQueryType type);

// Serializes `as` and writes the blob to `path` (throws std::runtime_error when it cannot).
uint64_t writeSerialized(VkContext& ctx, VkAccelerationStructureKHR as, const std::string& path);

}  // namespace vkas_tool
