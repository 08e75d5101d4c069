// libFuzzer target: micromaps (VK_EXT_opacity_micromap). The first byte picks what the rest is:
//   even: a serialized micromap (docs/FORMAT.md, "Serialized micromaps") given to vkGetDeviceMicromapCompatibilityEXT
//         and vkCopyMemoryToMicromapEXT, with vkas's UUID pair and a resealed integrity hash when bit 1 is set (so the
//         block's own checks are reached); what loads is copied and serialized again (byte-identical);
//   odd:  a build: usage counts, then triangles, then the states, given to vkGetMicromapBuildSizesEXT and
//         vkBuildMicromapsEXT; what builds must pass the block check (format/micromap_check.hpp).
// Both run on a device with validation on and on one with validation off: whatever the bytes, a command loads or
// builds, or rejects with an error, never reading or writing outside the memory it was given.
#include <vkas/vkas.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "engine/format/micromap_check.hpp"
#include "engine/format/micromap_layout.hpp"
#include "engine/format/micromap_serialize.hpp"

namespace {

VKAPI_ATTR VkBool32 VKAPI_CALL quiet(VkDebugUtilsMessageSeverityFlagBitsEXT, VkDebugUtilsMessageTypeFlagsEXT,
                                     const VkDebugUtilsMessengerCallbackDataEXT*, void*) {
    return VK_FALSE;
}

struct Harness {
    VkDevice device = VK_NULL_HANDLE;
    PFN_vkCreateBuffer createBuffer;
    PFN_vkDestroyBuffer destroyBuffer;
    PFN_vkAllocateMemory allocateMemory;
    PFN_vkFreeMemory freeMemory;
    PFN_vkBindBufferMemory bindBufferMemory;
    PFN_vkCreateMicromapEXT create;
    PFN_vkDestroyMicromapEXT destroy;
    PFN_vkGetMicromapBuildSizesEXT sizes;
    PFN_vkBuildMicromapsEXT build;
    PFN_vkCopyMicromapEXT copy;
    PFN_vkCopyMicromapToMemoryEXT toMemory;
    PFN_vkCopyMemoryToMicromapEXT fromMemory;
    PFN_vkWriteMicromapsPropertiesEXT properties;
    PFN_vkGetDeviceMicromapCompatibilityEXT compatibility;

    explicit Harness(bool validation) {
        VkasDeviceCreateInfo ci{};
        ci.disableValidation = validation ? VK_FALSE : VK_TRUE;
        ci.pfnMessenger = &quiet;
        ci.workerThreadCount = 1;
        if (vkasCreateDevice(&ci, &device) != VK_SUCCESS) std::abort();
#define LOAD(field, name) field = reinterpret_cast<PFN_##name>(vkasGetDeviceProcAddr(device, #name));
        LOAD(createBuffer, vkCreateBuffer)
        LOAD(destroyBuffer, vkDestroyBuffer)
        LOAD(allocateMemory, vkAllocateMemory)
        LOAD(freeMemory, vkFreeMemory)
        LOAD(bindBufferMemory, vkBindBufferMemory)
        LOAD(create, vkCreateMicromapEXT)
        LOAD(destroy, vkDestroyMicromapEXT)
        LOAD(sizes, vkGetMicromapBuildSizesEXT)
        LOAD(build, vkBuildMicromapsEXT)
        LOAD(copy, vkCopyMicromapEXT)
        LOAD(toMemory, vkCopyMicromapToMemoryEXT)
        LOAD(fromMemory, vkCopyMemoryToMicromapEXT)
        LOAD(properties, vkWriteMicromapsPropertiesEXT)
        LOAD(compatibility, vkGetDeviceMicromapCompatibilityEXT)
#undef LOAD
    }

    // A micromap of `size` bytes on its own buffer and memory; freed by release().
    struct Object {
        VkBuffer buffer = VK_NULL_HANDLE;
        VkDeviceMemory memory = VK_NULL_HANDLE;
        VkMicromapEXT micromap = VK_NULL_HANDLE;
    };
    Object make(VkDeviceSize size) {
        Object o;
        VkBufferCreateInfo bi{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
        bi.size = std::max<VkDeviceSize>(size, 64);
        bi.usage = VK_BUFFER_USAGE_MICROMAP_STORAGE_BIT_EXT;
        if (createBuffer(device, &bi, nullptr, &o.buffer) != VK_SUCCESS) std::abort();
        VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, nullptr, bi.size, 0};
        if (allocateMemory(device, &ai, nullptr, &o.memory) != VK_SUCCESS) std::abort();
        if (bindBufferMemory(device, o.buffer, o.memory, 0) != VK_SUCCESS) std::abort();
        VkMicromapCreateInfoEXT ci{VK_STRUCTURE_TYPE_MICROMAP_CREATE_INFO_EXT};
        ci.buffer = o.buffer;
        ci.size = bi.size;
        ci.type = VK_MICROMAP_TYPE_OPACITY_MICROMAP_EXT;
        if (create(device, &ci, nullptr, &o.micromap) != VK_SUCCESS) std::abort();
        return o;
    }
    void release(const Object& o) {
        destroy(device, o.micromap, nullptr);
        destroyBuffer(device, o.buffer, nullptr);
        freeMemory(device, o.memory, nullptr);
    }

    std::vector<uint8_t> serialize(VkMicromapEXT m) {
        VkDeviceSize size = 0;
        if (properties(device, 1, &m, VK_QUERY_TYPE_MICROMAP_SERIALIZATION_SIZE_EXT, 8, &size, 8) != VK_SUCCESS)
            std::abort();
        std::vector<uint8_t> blob(size + 16);
        uint8_t* aligned = blob.data() + (16 - reinterpret_cast<uintptr_t>(blob.data()) % 16) % 16;
        VkCopyMicromapToMemoryInfoEXT info{VK_STRUCTURE_TYPE_COPY_MICROMAP_TO_MEMORY_INFO_EXT};
        info.src = m;
        info.dst.hostAddress = aligned;
        info.mode = VK_COPY_MICROMAP_MODE_SERIALIZE_EXT;
        if (toMemory(device, VK_NULL_HANDLE, &info) != VK_SUCCESS) std::abort();
        return std::vector<uint8_t>(aligned, aligned + size);
    }

    // What loads or builds is checked, copied (clone and, when allowed, compact) and serialized again.
    void exercise(const Object& o, uint64_t usedSize) {
        const std::vector<uint8_t> blob = serialize(o.micromap);
        if (!vkas::format::checkSerializedMicromap(reinterpret_cast<const std::byte*>(blob.data()), blob.size()).ok())
            std::abort();
        const Object clone = make(usedSize);
        VkCopyMicromapInfoEXT ci{VK_STRUCTURE_TYPE_COPY_MICROMAP_INFO_EXT, nullptr, o.micromap, clone.micromap,
                                 VK_COPY_MICROMAP_MODE_CLONE_EXT};
        if (copy(device, VK_NULL_HANDLE, &ci) != VK_SUCCESS) std::abort();
        if (serialize(clone.micromap) != blob) std::abort();
        release(clone);
    }

    void deserialize(std::vector<uint8_t> bytes, bool seal) {
        if (bytes.size() < 64) bytes.resize(64, 0);
        if (seal) {
            std::memcpy(bytes.data(), vkas::serial::kDriverUuidV2, 16);
            std::memcpy(bytes.data() + 16, vkas::serial::kMicromapCompatibilityUuidV1, 16);
            const uint64_t deserialized = bytes.size() - 64, serialized = bytes.size();
            std::memcpy(bytes.data() + 32, &serialized, 8);
            std::memcpy(bytes.data() + 40, &deserialized, 8);
        }
        // The claimed serialized size is what the application vouches for: never more than the input.
        uint64_t claimed;
        std::memcpy(&claimed, bytes.data() + 32, 8);
        if (claimed > bytes.size()) {
            claimed = bytes.size();
            std::memcpy(bytes.data() + 32, &claimed, 8);
        }
        std::vector<uint64_t> storage((bytes.size() + 7) / 8);
        auto* blob = reinterpret_cast<uint8_t*>(storage.data());
        std::memcpy(blob, bytes.data(), bytes.size());
        if (seal) {
            vkas::serial::SerializedMicromapView view;
            view.data = reinterpret_cast<const std::byte*>(blob);
            view.deserializedSize = bytes.size() - 64;
            view.block = view.data + 64;
            vkas::serial::sealMicromapIntegrityHash(view, reinterpret_cast<std::byte*>(blob));
        }
        VkMicromapVersionInfoEXT vi{VK_STRUCTURE_TYPE_MICROMAP_VERSION_INFO_EXT, nullptr, blob};
        VkAccelerationStructureCompatibilityKHR compatible;
        compatibility(device, &vi, &compatible);
        uint64_t deserialized;
        std::memcpy(&deserialized, blob + 40, 8);
        const Object dst = make(std::min<uint64_t>(deserialized, 1 << 20));
        VkCopyMemoryToMicromapInfoEXT info{VK_STRUCTURE_TYPE_COPY_MEMORY_TO_MICROMAP_INFO_EXT};
        info.src.hostAddress = blob;
        info.dst = dst.micromap;
        info.mode = VK_COPY_MICROMAP_MODE_DESERIALIZE_EXT;
        const VkResult r = fromMemory(device, VK_NULL_HANDLE, &info);
        if (r == VK_SUCCESS) {
            if (compatible != VK_ACCELERATION_STRUCTURE_COMPATIBILITY_COMPATIBLE_KHR) std::abort();
            exercise(dst, deserialized);
        }
        release(dst);
    }

    void buildFrom(const uint8_t* p, size_t n) {
        size_t at = 0;
        auto next = [&]() -> uint8_t { return at < n ? p[at++] : 0; };
        std::vector<VkMicromapUsageEXT> usage(next() % 6);
        uint64_t triangles = 0;
        for (auto& u : usage) {
            u.count = next() % 8;
            const uint8_t level = next() % 16;
            u.subdivisionLevel = level >= 7 && level <= 12 ? level % 7 : level;  // 13-15: invalid
            u.format = next() % 4;  // 0, 3: invalid
            triangles += u.count;
        }
        std::vector<VkMicromapTriangleEXT> tris(triangles);
        for (auto& t : tris) {
            const uint8_t level = next() % 16;
            t.subdivisionLevel = uint16_t(level >= 7 && level <= 12 ? level % 7 : level);
            t.format = uint16_t(next() % 4);
            t.dataOffset = next();
        }
        // The states: the rest of the input, padded so that every triangle's states are readable (the extent of the
        // application's memory is not checkable: the harness keeps its promise).
        std::vector<uint8_t> data(p + std::min(at, n), p + n);
        data.resize(data.size() + 256 + 2 * 4096, 0);
        VkMicromapBuildInfoEXT info{VK_STRUCTURE_TYPE_MICROMAP_BUILD_INFO_EXT};
        info.type = VK_MICROMAP_TYPE_OPACITY_MICROMAP_EXT;
        info.flags = VK_BUILD_MICROMAP_ALLOW_COMPACTION_BIT_EXT;
        info.mode = VK_BUILD_MICROMAP_MODE_BUILD_EXT;
        info.usageCountsCount = uint32_t(usage.size());
        info.pUsageCounts = usage.data();
        info.data.hostAddress = data.data();
        info.triangleArray.hostAddress = tris.data();
        info.triangleArrayStride = sizeof(VkMicromapTriangleEXT);
        VkMicromapBuildSizesInfoEXT sizes_{VK_STRUCTURE_TYPE_MICROMAP_BUILD_SIZES_INFO_EXT};
        sizes(device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info, &sizes_);
        const Object dst = make(std::min<uint64_t>(sizes_.micromapSize, 1 << 20));
        info.dstMicromap = dst.micromap;
        if (build(device, VK_NULL_HANDLE, 1, &info) == VK_SUCCESS) {
            uint64_t used;
            VkMicromapEXT m = dst.micromap;
            properties(device, 1, &m, VK_QUERY_TYPE_MICROMAP_COMPACTED_SIZE_EXT, 8, &used, 8);
            exercise(dst, used);
        }
        release(dst);
    }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static Harness validated(true), unvalidated(false);
    if (size == 0) return 0;
    const uint8_t mode = data[0];
    for (Harness* h : {&validated, &unvalidated}) {
        if (mode & 1)
            h->buildFrom(data + 1, size - 1);
        else
            h->deserialize(std::vector<uint8_t>(data + 1, data + size), (mode & 2) != 0);
    }
    return 0;
}
