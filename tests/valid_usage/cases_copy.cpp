// Valid-usage cases: vkCopyAccelerationStructureKHR, serialization (vkCopyAccelerationStructureToMemoryKHR) and
// deserialization (vkCopyMemoryToAccelerationStructureKHR).
#include "harness.hpp"

namespace vu {

namespace {

#define CASE(id, ...) c.push_back(Case{id, "", [](Fixture& t, const vt::Commands& vk, VkDevice dev) __VA_ARGS__})
#define CASE_V(id, variant, ...) \
    c.push_back(Case{id, variant, [](Fixture& t, const vt::Commands& vk, VkDevice dev) __VA_ARGS__})

VkCopyAccelerationStructureInfoKHR cloneInfo(Fixture& t) {
    return {VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_INFO_KHR, nullptr, t.blas->handle, t.unbuilt->handle,
            VK_COPY_ACCELERATION_STRUCTURE_MODE_CLONE_KHR};
}
void copy(Fixture& t, const VkCopyAccelerationStructureInfoKHR& info,
          VkDeferredOperationKHR operation = VK_NULL_HANDLE) {
    t.call([&] { return R(t.vk.vkCopyAccelerationStructureKHR(t.device, operation, &info)); });
}

uint64_t serializationSize(Fixture& t, const vt::AccelStruct* as) {
    VkDeviceSize size = 0;
    EXPECT_EQ(t.vk.vkWriteAccelerationStructuresPropertiesKHR(t.device, 1, &as->handle,
                                                              VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_SIZE_KHR,
                                                              sizeof size, &size, sizeof size),
              VK_SUCCESS);
    return size;
}

// Watched host memory for a serialized blob (16-byte aligned: operator new[] of the fixture).
uint8_t* blobMemory(Fixture& t, size_t size) {
    uint8_t* p = t.hostCopy(nullptr, size + 32);
    std::memset(p, 0xAA, size + 32);
    return p;
}

VkCopyAccelerationStructureToMemoryInfoKHR serializeInfo(Fixture& t) {
    VkCopyAccelerationStructureToMemoryInfoKHR info{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_TO_MEMORY_INFO_KHR};
    info.src = t.blas->handle;
    info.dst.hostAddress = blobMemory(t, serializationSize(t, t.blas));
    info.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_SERIALIZE_KHR;
    return info;
}
void serialize(Fixture& t, const VkCopyAccelerationStructureToMemoryInfoKHR& info,
               VkDeferredOperationKHR operation = VK_NULL_HANDLE) {
    t.call([&] { return R(t.vk.vkCopyAccelerationStructureToMemoryKHR(t.device, operation, &info)); });
}

// A valid blob of `as`, in watched memory, ready to deserialize into a fresh structure.
VkCopyMemoryToAccelerationStructureInfoKHR deserializeInfo(Fixture& t, const vt::AccelStruct* as) {
    const uint64_t size = serializationSize(t, as);
    uint8_t* blob = blobMemory(t, size);
    VkCopyAccelerationStructureToMemoryInfoKHR out{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_TO_MEMORY_INFO_KHR};
    out.src = as->handle;
    out.dst.hostAddress = blob;
    out.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_SERIALIZE_KHR;
    EXPECT_EQ(t.vk.vkCopyAccelerationStructureToMemoryKHR(t.device, VK_NULL_HANDLE, &out), VK_SUCCESS);
    VkCopyMemoryToAccelerationStructureInfoKHR info{VK_STRUCTURE_TYPE_COPY_MEMORY_TO_ACCELERATION_STRUCTURE_INFO_KHR};
    info.src.hostAddress = blob;
    info.dst = t.createAccelStruct(as->type, as->size, {})->handle;
    info.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_DESERIALIZE_KHR;
    return info;
}
void deserialize(Fixture& t, const VkCopyMemoryToAccelerationStructureInfoKHR& info,
                 VkDeferredOperationKHR operation = VK_NULL_HANDLE) {
    t.call([&] { return R(t.vk.vkCopyMemoryToAccelerationStructureKHR(t.device, operation, &info)); });
}
uint8_t* blobOf(const VkCopyMemoryToAccelerationStructureInfoKHR& info) {
    return static_cast<uint8_t*>(const_cast<void*>(info.src.hostAddress));
}

}  // namespace

void addCopyCases(std::vector<Case>& c) {
    // ---- vkCopyAccelerationStructureKHR -------------------------------------------------------------------------
    CASE("VUID-vkCopyAccelerationStructureKHR-device-parameter", {
        auto info = cloneInfo(t);
        t.call([&] { return R(vk.vkCopyAccelerationStructureKHR(t.bogus<VkDevice>(), VK_NULL_HANDLE, &info)); });
        (void)dev;
    });
    CASE("VUID-vkCopyAccelerationStructureKHR-deferredOperation-parameter", {
        copy(t, cloneInfo(t), t.bogus<VkDeferredOperationKHR>());
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkCopyAccelerationStructureKHR-deferredOperation-parent", {
        copy(t, cloneInfo(t), t.otherOperation());
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkCopyAccelerationStructureKHR-deferredOperation-03678", {
        copy(t, cloneInfo(t), t.pendingOperation());
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkCopyAccelerationStructureKHR-pInfo-parameter", {
        t.call([&] { return R(vk.vkCopyAccelerationStructureKHR(dev, VK_NULL_HANDLE, nullptr)); });
    });
    CASE("VUID-VkCopyAccelerationStructureInfoKHR-sType-sType", {
        auto info = cloneInfo(t);
        info.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO;
        copy(t, info);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkCopyAccelerationStructureInfoKHR-pNext-pNext", {
        auto info = cloneInfo(t);
        VkBufferDeviceAddressInfo unrelated{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO};
        info.pNext = &unrelated;
        copy(t, info);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkCopyAccelerationStructureInfoKHR-mode-parameter", {
        auto info = cloneInfo(t);
        info.mode = VkCopyAccelerationStructureModeKHR(99);
        copy(t, info);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkCopyAccelerationStructureInfoKHR-mode-03410", {
        auto info = cloneInfo(t);
        info.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_SERIALIZE_KHR;
        copy(t, info);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkCopyAccelerationStructureInfoKHR-src-parameter", {
        auto info = cloneInfo(t);
        info.src = t.bogus<VkAccelerationStructureKHR>();
        copy(t, info);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkCopyAccelerationStructureInfoKHR-dst-parameter", {
        auto info = cloneInfo(t);
        info.dst = t.bogus<VkAccelerationStructureKHR>();
        copy(t, info);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkCopyAccelerationStructureInfoKHR-commonparent", {
        auto info = cloneInfo(t);
        info.dst = t.otherStructure();
        copy(t, info);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkCopyAccelerationStructureInfoKHR-buffer-03718", {
        auto info = cloneInfo(t);
        info.src = t.unbound->handle;
        copy(t, info);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkCopyAccelerationStructureInfoKHR-buffer-03719", {
        auto info = cloneInfo(t);
        info.dst = t.unbound->handle;
        copy(t, info);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkCopyAccelerationStructureKHR-src-11586", {
        auto info = cloneInfo(t);
        info.src = t.unbuilt->handle;
        info.dst = t.createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, t.blas->size, {})->handle;
        copy(t, info);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkCopyAccelerationStructureInfoKHR-src-03411", {
        auto info = cloneInfo(t);
        info.src = t.plainBlas->handle;  // built without ALLOW_COMPACTION
        info.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_COMPACT_KHR;
        copy(t, info);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkCopyAccelerationStructureInfoKHR-mode-12418", {
        auto info = cloneInfo(t);
        info.dst = t.createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, 256, {})->handle;
        copy(t, info);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkCopyAccelerationStructureInfoKHR-mode-12419", {
        auto info = cloneInfo(t);
        info.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_COMPACT_KHR;
        info.dst = t.createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, 256, {})->handle;
        copy(t, info);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkCopyAccelerationStructureInfoKHR-dst-07791", {
        VkAccelerationStructureCreateInfoKHR ci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
        ci.buffer = t.blas->buffer->buffer;  // on blas's memory, 256 bytes further
        ci.offset = t.blas->offset + 256;
        ci.size = t.blas->size;
        ci.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
        auto info = cloneInfo(t);
        EXPECT_EQ(vk.vkCreateAccelerationStructureKHR(dev, &ci, nullptr, &info.dst), VK_SUCCESS);
        copy(t, info);
    });

    // ---- vkCopyAccelerationStructureToMemoryKHR -------------------------------------------------------------------
    CASE("VUID-vkCopyAccelerationStructureToMemoryKHR-device-parameter", {
        auto info = serializeInfo(t);
        t.call([&] {
            return R(vk.vkCopyAccelerationStructureToMemoryKHR(t.bogus<VkDevice>(), VK_NULL_HANDLE, &info));
        });
        (void)dev;
    });
    CASE("VUID-vkCopyAccelerationStructureToMemoryKHR-deferredOperation-parameter", {
        serialize(t, serializeInfo(t), t.bogus<VkDeferredOperationKHR>());
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkCopyAccelerationStructureToMemoryKHR-deferredOperation-parent", {
        serialize(t, serializeInfo(t), t.otherOperation());
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkCopyAccelerationStructureToMemoryKHR-deferredOperation-03678", {
        serialize(t, serializeInfo(t), t.pendingOperation());
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkCopyAccelerationStructureToMemoryKHR-pInfo-parameter", {
        t.call([&] { return R(vk.vkCopyAccelerationStructureToMemoryKHR(dev, VK_NULL_HANDLE, nullptr)); });
    });
    CASE("VUID-VkCopyAccelerationStructureToMemoryInfoKHR-sType-sType", {
        auto info = serializeInfo(t);
        info.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO;
        serialize(t, info);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkCopyAccelerationStructureToMemoryInfoKHR-pNext-pNext", {
        auto info = serializeInfo(t);
        VkBufferDeviceAddressInfo unrelated{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO};
        info.pNext = &unrelated;
        serialize(t, info);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkCopyAccelerationStructureToMemoryInfoKHR-mode-parameter", {
        auto info = serializeInfo(t);
        info.mode = VkCopyAccelerationStructureModeKHR(99);
        serialize(t, info);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkCopyAccelerationStructureToMemoryInfoKHR-mode-03412", {
        auto info = serializeInfo(t);
        info.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_CLONE_KHR;
        serialize(t, info);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkCopyAccelerationStructureToMemoryInfoKHR-src-parameter", {
        auto info = serializeInfo(t);
        info.src = t.bogus<VkAccelerationStructureKHR>();
        serialize(t, info);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkCopyAccelerationStructureToMemoryInfoKHR-mode-11714", {
        auto info = serializeInfo(t);
        info.src = t.unbound->handle;
        serialize(t, info);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkCopyAccelerationStructureToMemoryInfoKHR-src-04959", {
        auto info = serializeInfo(t);
        info.src = t.unbuilt->handle;
        serialize(t, info);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkCopyAccelerationStructureToMemoryKHR-pInfo-03732", {
        auto info = serializeInfo(t);
        info.dst.hostAddress = nullptr;
        serialize(t, info);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkCopyAccelerationStructureToMemoryKHR-pInfo-03751", {
        auto info = serializeInfo(t);
        info.dst.hostAddress = static_cast<uint8_t*>(info.dst.hostAddress) + 8;
        serialize(t, info);
        (void)vk;
        (void)dev;
    });

    // ---- vkCopyMemoryToAccelerationStructureKHR -------------------------------------------------------------------
    CASE("VUID-vkCopyMemoryToAccelerationStructureKHR-device-parameter", {
        auto info = deserializeInfo(t, t.blas);
        t.call([&] {
            return R(vk.vkCopyMemoryToAccelerationStructureKHR(t.bogus<VkDevice>(), VK_NULL_HANDLE, &info));
        });
        (void)dev;
    });
    CASE("VUID-vkCopyMemoryToAccelerationStructureKHR-deferredOperation-parameter", {
        deserialize(t, deserializeInfo(t, t.blas), t.bogus<VkDeferredOperationKHR>());
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkCopyMemoryToAccelerationStructureKHR-deferredOperation-parent", {
        deserialize(t, deserializeInfo(t, t.blas), t.otherOperation());
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkCopyMemoryToAccelerationStructureKHR-deferredOperation-03678", {
        deserialize(t, deserializeInfo(t, t.blas), t.pendingOperation());
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkCopyMemoryToAccelerationStructureKHR-pInfo-parameter", {
        t.call([&] { return R(vk.vkCopyMemoryToAccelerationStructureKHR(dev, VK_NULL_HANDLE, nullptr)); });
    });
    CASE("VUID-VkCopyMemoryToAccelerationStructureInfoKHR-sType-sType", {
        auto info = deserializeInfo(t, t.blas);
        info.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO;
        deserialize(t, info);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkCopyMemoryToAccelerationStructureInfoKHR-pNext-pNext", {
        auto info = deserializeInfo(t, t.blas);
        VkBufferDeviceAddressInfo unrelated{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO};
        info.pNext = &unrelated;
        deserialize(t, info);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkCopyMemoryToAccelerationStructureInfoKHR-mode-parameter", {
        auto info = deserializeInfo(t, t.blas);
        info.mode = VkCopyAccelerationStructureModeKHR(99);
        deserialize(t, info);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkCopyMemoryToAccelerationStructureInfoKHR-mode-03413", {
        auto info = deserializeInfo(t, t.blas);
        info.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_SERIALIZE_KHR;
        deserialize(t, info);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkCopyMemoryToAccelerationStructureInfoKHR-dst-parameter", {
        auto info = deserializeInfo(t, t.blas);
        info.dst = t.bogus<VkAccelerationStructureKHR>();
        deserialize(t, info);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkCopyMemoryToAccelerationStructureInfoKHR-dst-11717", {
        auto info = deserializeInfo(t, t.blas);
        info.dst = t.unbound->handle;
        deserialize(t, info);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkCopyMemoryToAccelerationStructureKHR-pInfo-03729", {
        auto info = deserializeInfo(t, t.blas);
        info.src.hostAddress = nullptr;
        deserialize(t, info);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkCopyMemoryToAccelerationStructureKHR-pInfo-03750", {
        auto info = deserializeInfo(t, t.blas);
        info.src.hostAddress = static_cast<const uint8_t*>(info.src.hostAddress) + 8;
        deserialize(t, info);
        (void)vk;
        (void)dev;
    });
    c.push_back(Case{"VUID-VkCopyMemoryToAccelerationStructureInfoKHR-pInfo-03414", "",
                     [](Fixture& t, const vt::Commands&, VkDevice) {
                         auto info = deserializeInfo(t, t.blas);
                         blobOf(info)[16] ^= 0x01;  // the compatibility UUID
                         deserialize(t, info);
                     },
                     {}, false, VK_ERROR_INCOMPATIBLE_VERSION_KHR});
    CASE("VUID-VkCopyMemoryToAccelerationStructureInfoKHR-src-04960", {
        auto info = deserializeInfo(t, t.blas);
        blobOf(info)[32] ^= 0x40;  // the total size no longer matches the data
        deserialize(t, info);
        (void)vk;
        (void)dev;
    });
    CASE_V("VUID-VkCopyMemoryToAccelerationStructureInfoKHR-src-04960", "handle_entry", {
        auto info = deserializeInfo(t, t.tlas);
        const uint64_t garbage = 0x123456789ull;
        std::memcpy(blobOf(info) + 56, &garbage, 8);  // the first entry of the handle array
        deserialize(t, info);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkCopyMemoryToAccelerationStructureInfoKHR-dst-03746", {
        auto info = deserializeInfo(t, t.blas);
        info.dst = t.createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, 256, {})->handle;
        deserialize(t, info);
        (void)vk;
        (void)dev;
    });
}

}  // namespace vu
