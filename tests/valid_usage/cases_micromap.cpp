// Valid-usage cases of VK_EXT_opacity_micromap's host commands: micromap objects, build sizes, builds, copies,
// serialization, the properties query and the compatibility query.
#include <cstdlib>

#include "harness.hpp"

namespace vu {

namespace {

#define CASE(id, ...) c.push_back(Case{id, "", [](Fixture& t, const vt::Commands& vk, VkDevice dev) __VA_ARGS__})
#define CASE_V(id, variant, ...) \
    c.push_back(Case{id, variant, [](Fixture& t, const vt::Commands& vk, VkDevice dev) __VA_ARGS__})

struct Mm {
    PFN_vkCreateMicromapEXT create;
    PFN_vkDestroyMicromapEXT destroy;
    PFN_vkGetMicromapBuildSizesEXT sizes;
    PFN_vkBuildMicromapsEXT build;
    PFN_vkCopyMicromapEXT copy;
    PFN_vkCopyMicromapToMemoryEXT toMemory;
    PFN_vkCopyMemoryToMicromapEXT fromMemory;
    PFN_vkWriteMicromapsPropertiesEXT properties;
    PFN_vkGetDeviceMicromapCompatibilityEXT compatibility;
};
Mm mmOf(VkDevice device) {
#define MM(name) reinterpret_cast<PFN_##name>(vkasGetDeviceProcAddr(device, #name))
    return {MM(vkCreateMicromapEXT),        MM(vkDestroyMicromapEXT),          MM(vkGetMicromapBuildSizesEXT),
            MM(vkBuildMicromapsEXT),        MM(vkCopyMicromapEXT),             MM(vkCopyMicromapToMemoryEXT),
            MM(vkCopyMemoryToMicromapEXT),  MM(vkWriteMicromapsPropertiesEXT), MM(vkGetDeviceMicromapCompatibilityEXT)};
#undef MM
}

void* VKAPI_PTR allocate(void*, size_t size, size_t alignment, VkSystemAllocationScope) {
    return std::aligned_alloc(alignment, (size + alignment - 1) / alignment * alignment);
}
void* VKAPI_PTR reallocate(void*, void*, size_t, size_t, VkSystemAllocationScope) { return nullptr; }
void VKAPI_PTR release(void*, void* p) { std::free(p); }
const VkAllocationCallbacks kCallbacks{nullptr, allocate, reallocate, release, nullptr, nullptr};

constexpr VkDeviceSize kMicromapSize = 4096;

VkMicromapCreateInfoEXT createInfo(VkBuffer buffer, VkDeviceSize size = kMicromapSize) {
    VkMicromapCreateInfoEXT ci{VK_STRUCTURE_TYPE_MICROMAP_CREATE_INFO_EXT};
    ci.buffer = buffer;
    ci.size = size;
    ci.type = VK_MICROMAP_TYPE_OPACITY_MICROMAP_EXT;
    return ci;
}
VkBuffer micromapBuffer(Fixture& t, bool bind = true) {
    return t.createBuffer(kMicromapSize + 256, VK_BUFFER_USAGE_MICROMAP_STORAGE_BIT_EXT, bind)->buffer;
}
VkMicromapEXT newMicromap(Fixture& t, bool bind = true, VkDeviceSize size = kMicromapSize,
                          const VkAllocationCallbacks* callbacks = nullptr) {
    const VkMicromapCreateInfoEXT ci = createInfo(micromapBuffer(t, bind), size);
    VkMicromapEXT m = VK_NULL_HANDLE;
    EXPECT_EQ(mmOf(t.device).create(t.device, &ci, callbacks, &m), VK_SUCCESS);
    return m;
}
VkMicromapEXT otherMicromap(Fixture& t) {
    VkBufferCreateInfo bi{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    bi.size = 4096;
    bi.usage = VK_BUFFER_USAGE_MICROMAP_STORAGE_BIT_EXT;
    VkBuffer buffer = VK_NULL_HANDLE;
    EXPECT_EQ(t.otherVk.vkCreateBuffer(t.other, &bi, nullptr, &buffer), VK_SUCCESS);
    EXPECT_EQ(t.otherVk.vkBindBufferMemory(t.other, buffer, t.otherMemory(), 0), VK_SUCCESS);
    const VkMicromapCreateInfoEXT ci = createInfo(buffer);
    VkMicromapEXT m = VK_NULL_HANDLE;
    EXPECT_EQ(mmOf(t.other).create(t.other, &ci, nullptr, &m), VK_SUCCESS);
    return m;
}

// A valid build: two 2-state level-1 triangles and one 4-state level-2 triangle, in watched host memory.
struct BuildInput {
    VkMicromapUsageEXT* usage;
    VkMicromapTriangleEXT* triangles;
    uint8_t* data;
};
BuildInput buildInput(Fixture& t) {
    const VkMicromapUsageEXT usage[2] = {{2, 1, VK_OPACITY_MICROMAP_FORMAT_2_STATE_EXT},
                                         {1, 2, VK_OPACITY_MICROMAP_FORMAT_4_STATE_EXT}};
    const VkMicromapTriangleEXT triangles[3] = {{0, 1, VK_OPACITY_MICROMAP_FORMAT_2_STATE_EXT},
                                                {1, 1, VK_OPACITY_MICROMAP_FORMAT_2_STATE_EXT},
                                                {2, 2, VK_OPACITY_MICROMAP_FORMAT_4_STATE_EXT}};
    const uint8_t data[8] = {0x5, 0xA, 0x1B, 0x2C, 0x3D, 0x4E, 0, 0};
    return BuildInput{reinterpret_cast<VkMicromapUsageEXT*>(t.hostCopy(usage, sizeof usage)),
                      reinterpret_cast<VkMicromapTriangleEXT*>(t.hostCopy(triangles, sizeof triangles)),
                      t.hostCopy(data, sizeof data)};
}
VkMicromapBuildInfoEXT buildInfo(Fixture& t, VkMicromapEXT dst, BuildInput* out = nullptr) {
    const BuildInput in = buildInput(t);
    if (out) *out = in;
    VkMicromapBuildInfoEXT info{VK_STRUCTURE_TYPE_MICROMAP_BUILD_INFO_EXT};
    info.type = VK_MICROMAP_TYPE_OPACITY_MICROMAP_EXT;
    info.mode = VK_BUILD_MICROMAP_MODE_BUILD_EXT;
    info.dstMicromap = dst;
    info.usageCountsCount = 2;
    info.pUsageCounts = in.usage;
    info.data.hostAddress = in.data;
    info.triangleArray.hostAddress = in.triangles;
    info.triangleArrayStride = sizeof(VkMicromapTriangleEXT);
    return info;
}
VkMicromapEXT builtMicromap(Fixture& t, VkBuildMicromapFlagsEXT flags = VK_BUILD_MICROMAP_ALLOW_COMPACTION_BIT_EXT) {
    VkMicromapEXT m = newMicromap(t);
    VkMicromapBuildInfoEXT info = buildInfo(t, m);
    info.flags = flags;
    EXPECT_EQ(mmOf(t.device).build(t.device, VK_NULL_HANDLE, 1, &info), VK_SUCCESS);
    return m;
}
void build(Fixture& t, const VkMicromapBuildInfoEXT& info, VkDeferredOperationKHR op = VK_NULL_HANDLE) {
    t.call([&] { return R(mmOf(t.device).build(t.device, op, 1, &info)); });
}
void sizes(Fixture& t, const VkMicromapBuildInfoEXT& info, VkMicromapBuildSizesInfoEXT size) {
    auto* out = t.hostObject(size);
    t.call([&] {
        mmOf(t.device).sizes(t.device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info, out);
        return V();
    });
}
VkMicromapBuildSizesInfoEXT sizeInfo() { return {VK_STRUCTURE_TYPE_MICROMAP_BUILD_SIZES_INFO_EXT}; }

void create(Fixture& t, const VkMicromapCreateInfoEXT& ci) {
    auto* out = t.hostObject(VkMicromapEXT(VK_NULL_HANDLE));
    t.call([&] { return R(mmOf(t.device).create(t.device, &ci, nullptr, out)); });
}

VkCopyMicromapInfoEXT cloneInfo(Fixture& t) {
    return {VK_STRUCTURE_TYPE_COPY_MICROMAP_INFO_EXT, nullptr, builtMicromap(t), newMicromap(t),
            VK_COPY_MICROMAP_MODE_CLONE_EXT};
}
void copy(Fixture& t, const VkCopyMicromapInfoEXT& info, VkDeferredOperationKHR op = VK_NULL_HANDLE) {
    t.call([&] { return R(mmOf(t.device).copy(t.device, op, &info)); });
}

uint8_t* blobMemory(Fixture& t, size_t size) {
    uint8_t* p = t.hostCopy(nullptr, size + 32);
    std::memset(p, 0xAA, size + 32);
    return p;
}
uint64_t serializationSize(Fixture& t, VkMicromapEXT m) {
    VkDeviceSize size = 0;
    EXPECT_EQ(mmOf(t.device).properties(t.device, 1, &m, VK_QUERY_TYPE_MICROMAP_SERIALIZATION_SIZE_EXT, sizeof size,
                                        &size, sizeof size),
              VK_SUCCESS);
    return size;
}
VkCopyMicromapToMemoryInfoEXT serializeInfo(Fixture& t) {
    VkCopyMicromapToMemoryInfoEXT info{VK_STRUCTURE_TYPE_COPY_MICROMAP_TO_MEMORY_INFO_EXT};
    info.src = builtMicromap(t);
    info.dst.hostAddress = blobMemory(t, serializationSize(t, info.src));
    info.mode = VK_COPY_MICROMAP_MODE_SERIALIZE_EXT;
    return info;
}
void serialize(Fixture& t, const VkCopyMicromapToMemoryInfoEXT& info, VkDeferredOperationKHR op = VK_NULL_HANDLE) {
    t.call([&] { return R(mmOf(t.device).toMemory(t.device, op, &info)); });
}
// A valid blob, in watched memory, and a fresh micromap to load it into.
VkCopyMemoryToMicromapInfoEXT deserializeInfo(Fixture& t) {
    VkCopyMicromapToMemoryInfoEXT out = serializeInfo(t);
    EXPECT_EQ(mmOf(t.device).toMemory(t.device, VK_NULL_HANDLE, &out), VK_SUCCESS);
    VkCopyMemoryToMicromapInfoEXT info{VK_STRUCTURE_TYPE_COPY_MEMORY_TO_MICROMAP_INFO_EXT};
    info.src.hostAddress = out.dst.hostAddress;
    info.dst = newMicromap(t);
    info.mode = VK_COPY_MICROMAP_MODE_DESERIALIZE_EXT;
    return info;
}
void deserialize(Fixture& t, const VkCopyMemoryToMicromapInfoEXT& info, VkDeferredOperationKHR op = VK_NULL_HANDLE) {
    t.call([&] { return R(mmOf(t.device).fromMemory(t.device, op, &info)); });
}
uint8_t* blobOf(const VkCopyMemoryToMicromapInfoEXT& info) {
    return static_cast<uint8_t*>(const_cast<void*>(info.src.hostAddress));
}

void properties(Fixture& t, uint32_t count, const VkMicromapEXT* micromaps, VkQueryType type, size_t dataSize,
                void* data, size_t stride) {
    t.call([&] { return R(mmOf(t.device).properties(t.device, count, micromaps, type, dataSize, data, stride)); });
}
VkDeviceSize* propertyOut(Fixture& t) { return reinterpret_cast<VkDeviceSize*>(t.hostCopy(nullptr, 64)); }

void compatibility(Fixture& t, const VkMicromapVersionInfoEXT& vi) {
    auto* out = t.hostObject(VK_ACCELERATION_STRUCTURE_COMPATIBILITY_MAX_ENUM_KHR);
    t.call([&] {
        mmOf(t.device).compatibility(t.device, &vi, out);
        return V();
    });
}
VkMicromapVersionInfoEXT versionInfo(Fixture& t) {
    VkCopyMicromapToMemoryInfoEXT out = serializeInfo(t);
    EXPECT_EQ(mmOf(t.device).toMemory(t.device, VK_NULL_HANDLE, &out), VK_SUCCESS);
    return {VK_STRUCTURE_TYPE_MICROMAP_VERSION_INFO_EXT, nullptr, static_cast<const uint8_t*>(out.dst.hostAddress)};
}

const VkMemoryBarrier kStray{VK_STRUCTURE_TYPE_MEMORY_BARRIER};  // a structure no micromap structure extends

}  // namespace

void addMicromapCases(std::vector<Case>& c) {
    // ---- vkCreateMicromapEXT, VkMicromapCreateInfoEXT -----------------------------------------------------------
    CASE("VUID-vkCreateMicromapEXT-device-parameter", {
        const VkMicromapCreateInfoEXT ci = createInfo(micromapBuffer(t));
        auto* out = t.hostObject(VkMicromapEXT(VK_NULL_HANDLE));
        t.call([&] { return R(mmOf(dev).create(t.bogus<VkDevice>(), &ci, nullptr, out)); });
        (void)vk;
    });
    CASE("VUID-vkCreateMicromapEXT-pCreateInfo-parameter", {
        auto* out = t.hostObject(VkMicromapEXT(VK_NULL_HANDLE));
        t.call([&] { return R(mmOf(dev).create(dev, nullptr, nullptr, out)); });
        (void)vk;
    });
    CASE("VUID-vkCreateMicromapEXT-pMicromap-parameter", {
        const VkMicromapCreateInfoEXT ci = createInfo(micromapBuffer(t));
        t.call([&] { return R(mmOf(dev).create(dev, &ci, nullptr, nullptr)); });
        (void)vk;
    });
    CASE("VUID-VkMicromapCreateInfoEXT-sType-sType", {
        VkMicromapCreateInfoEXT ci = createInfo(micromapBuffer(t));
        ci.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR;
        create(t, ci);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkMicromapCreateInfoEXT-pNext-pNext", {
        VkMicromapCreateInfoEXT ci = createInfo(micromapBuffer(t));
        ci.pNext = &kStray;
        create(t, ci);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkMicromapCreateInfoEXT-createFlags-parameter", {
        VkMicromapCreateInfoEXT ci = createInfo(micromapBuffer(t));
        ci.createFlags = 0x2;
        create(t, ci);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkMicromapCreateInfoEXT-type-parameter", {
        VkMicromapCreateInfoEXT ci = createInfo(micromapBuffer(t));
        ci.type = VkMicromapTypeEXT(7);
        create(t, ci);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkMicromapCreateInfoEXT-deviceAddress-07433", {
        VkMicromapCreateInfoEXT ci = createInfo(micromapBuffer(t));
        ci.deviceAddress = 0x10000;
        create(t, ci);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkMicromapCreateInfoEXT-micromapCaptureReplay-11616", {
        VkMicromapCreateInfoEXT ci = createInfo(micromapBuffer(t));
        ci.createFlags = VK_MICROMAP_CREATE_DEVICE_ADDRESS_CAPTURE_REPLAY_BIT_EXT;
        create(t, ci);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkMicromapCreateInfoEXT-offset-07438", {
        VkMicromapCreateInfoEXT ci = createInfo(micromapBuffer(t), 128);
        ci.offset = 128;
        create(t, ci);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkMicromapCreateInfoEXT-offset-07437", {
        VkMicromapCreateInfoEXT ci = createInfo(micromapBuffer(t), kMicromapSize + 512);
        create(t, ci);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkMicromapCreateInfoEXT-buffer-parameter", {
        create(t, createInfo(t.bogus<VkBuffer>()));
        (void)vk, (void)dev;
    });
    CASE("VUID-VkMicromapCreateInfoEXT-buffer-07435", {
        create(t, createInfo(t.createBuffer(kMicromapSize, vt::kAsBufferUsage)->buffer));
        (void)vk, (void)dev;
    });

    // ---- vkDestroyMicromapEXT -------------------------------------------------------------------------------------
    CASE("VUID-vkDestroyMicromapEXT-device-parameter", {
        VkMicromapEXT m = newMicromap(t);
        t.call([&] {
            mmOf(dev).destroy(t.bogus<VkDevice>(), m, nullptr);
            return V();
        });
        (void)vk;
    });
    CASE("VUID-vkDestroyMicromapEXT-micromap-parameter", {
        t.call([&] {
            mmOf(dev).destroy(dev, t.bogus<VkMicromapEXT>(), nullptr);
            return V();
        });
        (void)vk;
    });
    CASE("VUID-vkDestroyMicromapEXT-micromap-parent", {
        VkMicromapEXT m = otherMicromap(t);
        t.call([&] {
            mmOf(dev).destroy(dev, m, nullptr);
            return V();
        });
        (void)vk;
    });
    CASE("VUID-vkDestroyMicromapEXT-micromap-07442", {
        VkMicromapEXT m = newMicromap(t, true, kMicromapSize, &kCallbacks);
        t.call([&] {
            mmOf(dev).destroy(dev, m, nullptr);
            return V();
        });
        mmOf(dev).destroy(dev, m, &kCallbacks);
        (void)vk;
    });
    CASE("VUID-vkDestroyMicromapEXT-micromap-07443", {
        VkMicromapEXT m = newMicromap(t);
        t.call([&] {
            mmOf(dev).destroy(dev, m, &kCallbacks);
            return V();
        });
        (void)vk;
    });

    // ---- vkGetMicromapBuildSizesEXT, VkMicromapBuildSizesInfoEXT ------------------------------------------------
    CASE("VUID-vkGetMicromapBuildSizesEXT-device-parameter", {
        const VkMicromapBuildInfoEXT info = buildInfo(t, VK_NULL_HANDLE);
        auto* out = t.hostObject(sizeInfo());
        t.call([&] {
            mmOf(dev).sizes(t.bogus<VkDevice>(), VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info, out);
            return V();
        });
        (void)vk;
    });
    CASE("VUID-vkGetMicromapBuildSizesEXT-buildType-parameter", {
        const VkMicromapBuildInfoEXT info = buildInfo(t, VK_NULL_HANDLE);
        auto* out = t.hostObject(sizeInfo());
        t.call([&] {
            mmOf(dev).sizes(dev, VkAccelerationStructureBuildTypeKHR(9), &info, out);
            return V();
        });
        (void)vk;
    });
    CASE("VUID-vkGetMicromapBuildSizesEXT-pBuildInfo-parameter", {
        auto* out = t.hostObject(sizeInfo());
        t.call([&] {
            mmOf(dev).sizes(dev, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, nullptr, out);
            return V();
        });
        (void)vk;
    });
    CASE("VUID-vkGetMicromapBuildSizesEXT-pSizeInfo-parameter", {
        const VkMicromapBuildInfoEXT info = buildInfo(t, VK_NULL_HANDLE);
        t.call([&] {
            mmOf(dev).sizes(dev, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info, nullptr);
            return V();
        });
        (void)vk;
    });
    CASE("VUID-VkMicromapBuildSizesInfoEXT-sType-sType", {
        VkMicromapBuildSizesInfoEXT s = sizeInfo();
        s.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR;
        sizes(t, buildInfo(t, VK_NULL_HANDLE), s);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkMicromapBuildSizesInfoEXT-pNext-pNext", {
        VkMicromapBuildSizesInfoEXT s = sizeInfo();
        s.pNext = const_cast<VkMemoryBarrier*>(&kStray);
        sizes(t, buildInfo(t, VK_NULL_HANDLE), s);
        (void)vk, (void)dev;
    });

    // ---- vkBuildMicromapsEXT --------------------------------------------------------------------------------------
    CASE("VUID-vkBuildMicromapsEXT-device-parameter", {
        const VkMicromapBuildInfoEXT info = buildInfo(t, newMicromap(t));
        t.call([&] { return R(mmOf(dev).build(t.bogus<VkDevice>(), VK_NULL_HANDLE, 1, &info)); });
        (void)vk;
    });
    CASE("VUID-vkBuildMicromapsEXT-deferredOperation-parameter", {
        build(t, buildInfo(t, newMicromap(t)), t.bogus<VkDeferredOperationKHR>());
        (void)vk, (void)dev;
    });
    CASE("VUID-vkBuildMicromapsEXT-deferredOperation-parent", {
        build(t, buildInfo(t, newMicromap(t)), t.otherOperation());
        (void)vk, (void)dev;
    });
    CASE("VUID-vkBuildMicromapsEXT-infoCount-arraylength", {
        const VkMicromapBuildInfoEXT info = buildInfo(t, newMicromap(t));
        t.call([&] { return R(mmOf(dev).build(dev, VK_NULL_HANDLE, 0, &info)); });
        (void)vk;
    });
    CASE("VUID-vkBuildMicromapsEXT-pInfos-parameter", {
        t.call([&] { return R(mmOf(dev).build(dev, VK_NULL_HANDLE, 1, nullptr)); });
        (void)vk;
    });
    CASE("VUID-vkBuildMicromapsEXT-mode-07462", {
        VkMicromapBuildInfoEXT info = buildInfo(t, newMicromap(t));
        info.mode = VkBuildMicromapModeEXT(5);
        build(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-vkBuildMicromapsEXT-dstMicromap-07463", {
        build(t, buildInfo(t, t.bogus<VkMicromapEXT>()));
        (void)vk, (void)dev;
    });
    CASE_V("VUID-vkBuildMicromapsEXT-dstMicromap-07463", "other_device", {
        build(t, buildInfo(t, otherMicromap(t)));
        (void)vk, (void)dev;
    });
    CASE("VUID-vkBuildMicromapsEXT-pInfos-07461", {
        build(t, buildInfo(t, newMicromap(t, true, 64)));
        (void)vk, (void)dev;
    });
    CASE_V("VUID-vkBuildMicromapsEXT-pInfos-07461", "triangles_unlike_usage_counts", {
        BuildInput in;
        const VkMicromapBuildInfoEXT info = buildInfo(t, newMicromap(t), &in);
        in.triangles[2].subdivisionLevel = 1;  // the usage counts say level 2
        build(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-vkBuildMicromapsEXT-pInfos-07552", {
        build(t, buildInfo(t, newMicromap(t, false)));
        (void)vk, (void)dev;
    });
    CASE("VUID-vkBuildMicromapsEXT-pInfos-07553", {
        VkMicromapBuildInfoEXT info = buildInfo(t, newMicromap(t));
        info.data.hostAddress = nullptr;
        build(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-vkBuildMicromapsEXT-pInfos-07554", {
        VkMicromapBuildInfoEXT info = buildInfo(t, newMicromap(t));
        info.triangleArray.hostAddress = nullptr;
        build(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-vkBuildMicromapsEXT-dstMicromap-11667", {
        const VkMicromapEXT m = newMicromap(t);
        const VkMicromapBuildInfoEXT infos[2] = {buildInfo(t, m), buildInfo(t, m)};
        t.call([&] { return R(mmOf(dev).build(dev, VK_NULL_HANDLE, 2, infos)); });
        (void)vk;
    });

    // ---- VkMicromapBuildInfoEXT (through vkBuildMicromapsEXT) ---------------------------------------------------
    CASE("VUID-VkMicromapBuildInfoEXT-sType-sType", {
        VkMicromapBuildInfoEXT info = buildInfo(t, newMicromap(t));
        info.sType = VK_STRUCTURE_TYPE_MICROMAP_CREATE_INFO_EXT;
        build(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkMicromapBuildInfoEXT-pNext-pNext", {
        VkMicromapBuildInfoEXT info = buildInfo(t, newMicromap(t));
        info.pNext = &kStray;
        build(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkMicromapBuildInfoEXT-type-parameter", {
        VkMicromapBuildInfoEXT info = buildInfo(t, newMicromap(t));
        info.type = VkMicromapTypeEXT(7);
        build(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkMicromapBuildInfoEXT-flags-parameter", {
        VkMicromapBuildInfoEXT info = buildInfo(t, newMicromap(t));
        info.flags = 0x8;
        build(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkMicromapBuildInfoEXT-pUsageCounts-07516", {
        VkMicromapBuildInfoEXT info = buildInfo(t, newMicromap(t));
        const VkMicromapUsageEXT* pointers[2] = {&info.pUsageCounts[0], &info.pUsageCounts[1]};
        info.ppUsageCounts = reinterpret_cast<const VkMicromapUsageEXT* const*>(t.hostCopy(pointers, sizeof pointers));
        build(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkMicromapBuildInfoEXT-ppUsageCounts-parameter", {
        VkMicromapBuildInfoEXT info = buildInfo(t, newMicromap(t));
        const VkMicromapUsageEXT* pointers[2] = {&info.pUsageCounts[0], nullptr};
        info.ppUsageCounts = reinterpret_cast<const VkMicromapUsageEXT* const*>(t.hostCopy(pointers, sizeof pointers));
        info.pUsageCounts = nullptr;
        build(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkMicromapBuildInfoEXT-format-11652", {
        BuildInput in;
        const VkMicromapBuildInfoEXT info = buildInfo(t, newMicromap(t), &in);
        in.usage[1].format = 3;
        build(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkMicromapBuildInfoEXT-subdivisionLevel-11654", {
        BuildInput in;
        const VkMicromapBuildInfoEXT info = buildInfo(t, newMicromap(t), &in);
        in.usage[0].subdivisionLevel = 13;
        build(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkMicromapBuildInfoEXT-subdivisionLevel-11655", {
        BuildInput in;
        const VkMicromapBuildInfoEXT info = buildInfo(t, newMicromap(t), &in);
        in.usage[1].subdivisionLevel = 13;
        build(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkMicromapBuildInfoEXT-format-11657", {
        BuildInput in;
        const VkMicromapBuildInfoEXT info = buildInfo(t, newMicromap(t), &in);
        in.triangles[1].format = 0;
        build(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkMicromapBuildInfoEXT-subdivisionLevel-11659", {
        BuildInput in;
        const VkMicromapBuildInfoEXT info = buildInfo(t, newMicromap(t), &in);
        in.triangles[0].subdivisionLevel = 13;
        build(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkMicromapBuildInfoEXT-subdivisionLevel-11660", {
        BuildInput in;
        const VkMicromapBuildInfoEXT info = buildInfo(t, newMicromap(t), &in);
        in.triangles[2].subdivisionLevel = 14;
        build(t, info);
        (void)vk, (void)dev;
    });

    // ---- vkCopyMicromapEXT, VkCopyMicromapInfoEXT -----------------------------------------------------------------
    CASE("VUID-vkCopyMicromapEXT-device-parameter", {
        const VkCopyMicromapInfoEXT info = cloneInfo(t);
        t.call([&] { return R(mmOf(dev).copy(t.bogus<VkDevice>(), VK_NULL_HANDLE, &info)); });
        (void)vk;
    });
    CASE("VUID-vkCopyMicromapEXT-deferredOperation-parameter", {
        copy(t, cloneInfo(t), t.bogus<VkDeferredOperationKHR>());
        (void)vk, (void)dev;
    });
    CASE("VUID-vkCopyMicromapEXT-deferredOperation-parent", {
        copy(t, cloneInfo(t), t.otherOperation());
        (void)vk, (void)dev;
    });
    CASE("VUID-vkCopyMicromapEXT-deferredOperation-03678", {
        copy(t, cloneInfo(t), t.pendingOperation());
        (void)vk, (void)dev;
    });
    CASE("VUID-vkCopyMicromapEXT-pInfo-parameter", {
        t.call([&] { return R(mmOf(dev).copy(dev, VK_NULL_HANDLE, nullptr)); });
        (void)vk;
    });
    CASE("VUID-vkCopyMicromapEXT-buffer-07558", {
        VkCopyMicromapInfoEXT info = cloneInfo(t);
        info.src = newMicromap(t, false);
        copy(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-vkCopyMicromapEXT-buffer-07559", {
        VkCopyMicromapInfoEXT info = cloneInfo(t);
        info.dst = newMicromap(t, false);
        copy(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-vkCopyMicromapEXT-src-11670", {
        VkCopyMicromapInfoEXT info = cloneInfo(t);
        info.src = newMicromap(t);
        copy(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkCopyMicromapInfoEXT-sType-sType", {
        VkCopyMicromapInfoEXT info = cloneInfo(t);
        info.sType = VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_INFO_KHR;
        copy(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkCopyMicromapInfoEXT-pNext-pNext", {
        VkCopyMicromapInfoEXT info = cloneInfo(t);
        info.pNext = &kStray;
        copy(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkCopyMicromapInfoEXT-src-parameter", {
        VkCopyMicromapInfoEXT info = cloneInfo(t);
        info.src = t.bogus<VkMicromapEXT>();
        copy(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkCopyMicromapInfoEXT-dst-parameter", {
        VkCopyMicromapInfoEXT info = cloneInfo(t);
        info.dst = t.bogus<VkMicromapEXT>();
        copy(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkCopyMicromapInfoEXT-commonparent", {
        VkCopyMicromapInfoEXT info = cloneInfo(t);
        info.dst = otherMicromap(t);
        copy(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkCopyMicromapInfoEXT-mode-07531", {
        VkCopyMicromapInfoEXT info = cloneInfo(t);
        info.mode = VK_COPY_MICROMAP_MODE_SERIALIZE_EXT;
        copy(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkCopyMicromapInfoEXT-mode-07533", {
        VkCopyMicromapInfoEXT info = cloneInfo(t);
        info.src = builtMicromap(t, 0);
        info.mode = VK_COPY_MICROMAP_MODE_COMPACT_EXT;
        copy(t, info);
        (void)vk, (void)dev;
    });

    // ---- vkCopyMicromapToMemoryEXT, VkCopyMicromapToMemoryInfoEXT -------------------------------------------------
    CASE("VUID-vkCopyMicromapToMemoryEXT-device-parameter", {
        const VkCopyMicromapToMemoryInfoEXT info = serializeInfo(t);
        t.call([&] { return R(mmOf(dev).toMemory(t.bogus<VkDevice>(), VK_NULL_HANDLE, &info)); });
        (void)vk;
    });
    CASE("VUID-vkCopyMicromapToMemoryEXT-deferredOperation-parameter", {
        serialize(t, serializeInfo(t), t.bogus<VkDeferredOperationKHR>());
        (void)vk, (void)dev;
    });
    CASE("VUID-vkCopyMicromapToMemoryEXT-deferredOperation-parent", {
        serialize(t, serializeInfo(t), t.otherOperation());
        (void)vk, (void)dev;
    });
    CASE("VUID-vkCopyMicromapToMemoryEXT-deferredOperation-03678", {
        serialize(t, serializeInfo(t), t.pendingOperation());
        (void)vk, (void)dev;
    });
    CASE("VUID-vkCopyMicromapToMemoryEXT-pInfo-parameter", {
        t.call([&] { return R(mmOf(dev).toMemory(dev, VK_NULL_HANDLE, nullptr)); });
        (void)vk;
    });
    CASE("VUID-vkCopyMicromapToMemoryEXT-buffer-07568", {
        VkCopyMicromapToMemoryInfoEXT info = serializeInfo(t);
        info.src = newMicromap(t, false);
        serialize(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-vkCopyMicromapToMemoryEXT-pInfo-07569", {
        VkCopyMicromapToMemoryInfoEXT info = serializeInfo(t);
        info.dst.hostAddress = nullptr;
        serialize(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-vkCopyMicromapToMemoryEXT-pInfo-07570", {
        VkCopyMicromapToMemoryInfoEXT info = serializeInfo(t);
        info.dst.hostAddress = static_cast<uint8_t*>(info.dst.hostAddress) + 8;
        serialize(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkCopyMicromapToMemoryInfoEXT-sType-sType", {
        VkCopyMicromapToMemoryInfoEXT info = serializeInfo(t);
        info.sType = VK_STRUCTURE_TYPE_COPY_MICROMAP_INFO_EXT;
        serialize(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkCopyMicromapToMemoryInfoEXT-pNext-pNext", {
        VkCopyMicromapToMemoryInfoEXT info = serializeInfo(t);
        info.pNext = &kStray;
        serialize(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkCopyMicromapToMemoryInfoEXT-mode-parameter", {
        VkCopyMicromapToMemoryInfoEXT info = serializeInfo(t);
        info.mode = VkCopyMicromapModeEXT(9);
        serialize(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkCopyMicromapToMemoryInfoEXT-mode-07542", {
        VkCopyMicromapToMemoryInfoEXT info = serializeInfo(t);
        info.mode = VK_COPY_MICROMAP_MODE_CLONE_EXT;
        serialize(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkCopyMicromapToMemoryInfoEXT-src-parameter", {
        VkCopyMicromapToMemoryInfoEXT info = serializeInfo(t);
        info.src = t.bogus<VkMicromapEXT>();
        serialize(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkCopyMicromapToMemoryInfoEXT-src-07540", {
        VkCopyMicromapToMemoryInfoEXT info = serializeInfo(t);
        info.src = newMicromap(t);
        serialize(t, info);
        (void)vk, (void)dev;
    });

    // ---- vkCopyMemoryToMicromapEXT, VkCopyMemoryToMicromapInfoEXT -------------------------------------------------
    CASE("VUID-vkCopyMemoryToMicromapEXT-device-parameter", {
        const VkCopyMemoryToMicromapInfoEXT info = deserializeInfo(t);
        t.call([&] { return R(mmOf(dev).fromMemory(t.bogus<VkDevice>(), VK_NULL_HANDLE, &info)); });
        (void)vk;
    });
    CASE("VUID-vkCopyMemoryToMicromapEXT-deferredOperation-parameter", {
        deserialize(t, deserializeInfo(t), t.bogus<VkDeferredOperationKHR>());
        (void)vk, (void)dev;
    });
    CASE("VUID-vkCopyMemoryToMicromapEXT-deferredOperation-parent", {
        deserialize(t, deserializeInfo(t), t.otherOperation());
        (void)vk, (void)dev;
    });
    CASE("VUID-vkCopyMemoryToMicromapEXT-deferredOperation-03678", {
        deserialize(t, deserializeInfo(t), t.pendingOperation());
        (void)vk, (void)dev;
    });
    CASE("VUID-vkCopyMemoryToMicromapEXT-pInfo-parameter", {
        t.call([&] { return R(mmOf(dev).fromMemory(dev, VK_NULL_HANDLE, nullptr)); });
        (void)vk;
    });
    CASE("VUID-vkCopyMemoryToMicromapEXT-buffer-07565", {
        VkCopyMemoryToMicromapInfoEXT info = deserializeInfo(t);
        info.dst = newMicromap(t, false);
        deserialize(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-vkCopyMemoryToMicromapEXT-pInfo-07563", {
        VkCopyMemoryToMicromapInfoEXT info = deserializeInfo(t);
        info.src.hostAddress = nullptr;
        deserialize(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-vkCopyMemoryToMicromapEXT-pInfo-07564", {
        VkCopyMemoryToMicromapInfoEXT info = deserializeInfo(t);
        info.src.hostAddress = blobOf(info) + 4;
        deserialize(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkCopyMemoryToMicromapInfoEXT-sType-sType", {
        VkCopyMemoryToMicromapInfoEXT info = deserializeInfo(t);
        info.sType = VK_STRUCTURE_TYPE_COPY_MICROMAP_INFO_EXT;
        deserialize(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkCopyMemoryToMicromapInfoEXT-pNext-pNext", {
        VkCopyMemoryToMicromapInfoEXT info = deserializeInfo(t);
        info.pNext = &kStray;
        deserialize(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkCopyMemoryToMicromapInfoEXT-mode-parameter", {
        VkCopyMemoryToMicromapInfoEXT info = deserializeInfo(t);
        info.mode = VkCopyMicromapModeEXT(9);
        deserialize(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkCopyMemoryToMicromapInfoEXT-mode-07548", {
        VkCopyMemoryToMicromapInfoEXT info = deserializeInfo(t);
        info.mode = VK_COPY_MICROMAP_MODE_CLONE_EXT;
        deserialize(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkCopyMemoryToMicromapInfoEXT-dst-parameter", {
        VkCopyMemoryToMicromapInfoEXT info = deserializeInfo(t);
        info.dst = t.bogus<VkMicromapEXT>();
        deserialize(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkCopyMemoryToMicromapInfoEXT-dst-07550", {
        VkCopyMemoryToMicromapInfoEXT info = deserializeInfo(t);
        info.dst = newMicromap(t, true, 64);
        deserialize(t, info);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkCopyMemoryToMicromapInfoEXT-src-07547", {
        VkCopyMemoryToMicromapInfoEXT info = deserializeInfo(t);
        blobOf(info)[64 + 64 + 3 * 8] ^= 0x01;  // a state: caught by the integrity hash
        deserialize(t, info);
        (void)vk, (void)dev;
    });
    c.push_back(Case{"VUID-VkCopyMemoryToMicromapInfoEXT-src-07549", "",
                     [](Fixture& t, const vt::Commands&, VkDevice) {
                         VkCopyMemoryToMicromapInfoEXT info = deserializeInfo(t);
                         blobOf(info)[20] ^= 0x01;  // the compatibility UUID
                         deserialize(t, info);
                     },
                     {}, false, VK_ERROR_INCOMPATIBLE_VERSION_KHR});

    // ---- vkWriteMicromapsPropertiesEXT ----------------------------------------------------------------------------
    CASE("VUID-vkWriteMicromapsPropertiesEXT-device-parameter", {
        const VkMicromapEXT m = builtMicromap(t);
        VkDeviceSize* out = propertyOut(t);
        t.call([&] {
            return R(mmOf(dev).properties(t.bogus<VkDevice>(), 1, &m, VK_QUERY_TYPE_MICROMAP_SERIALIZATION_SIZE_EXT,
                                          8, out, 8));
        });
        (void)vk;
    });
    CASE("VUID-vkWriteMicromapsPropertiesEXT-micromapCount-arraylength", {
        const VkMicromapEXT m = builtMicromap(t);
        properties(t, 0, &m, VK_QUERY_TYPE_MICROMAP_SERIALIZATION_SIZE_EXT, 8, propertyOut(t), 8);
        (void)vk, (void)dev;
    });
    CASE("VUID-vkWriteMicromapsPropertiesEXT-pMicromaps-parameter", {
        const VkMicromapEXT m = t.bogus<VkMicromapEXT>();
        properties(t, 1, &m, VK_QUERY_TYPE_MICROMAP_SERIALIZATION_SIZE_EXT, 8, propertyOut(t), 8);
        (void)vk, (void)dev;
    });
    CASE("VUID-vkWriteMicromapsPropertiesEXT-pMicromaps-parent", {
        const VkMicromapEXT m = otherMicromap(t);
        properties(t, 1, &m, VK_QUERY_TYPE_MICROMAP_SERIALIZATION_SIZE_EXT, 8, propertyOut(t), 8);
        (void)vk, (void)dev;
    });
    CASE("VUID-vkWriteMicromapsPropertiesEXT-queryType-parameter", {
        const VkMicromapEXT m = builtMicromap(t);
        properties(t, 1, &m, VkQueryType(77), 8, propertyOut(t), 8);
        (void)vk, (void)dev;
    });
    CASE("VUID-vkWriteMicromapsPropertiesEXT-queryType-07503", {
        const VkMicromapEXT m = builtMicromap(t);
        properties(t, 1, &m, VK_QUERY_TYPE_ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR, 8, propertyOut(t), 8);
        (void)vk, (void)dev;
    });
    CASE("VUID-vkWriteMicromapsPropertiesEXT-dataSize-arraylength", {
        const VkMicromapEXT m = builtMicromap(t);
        properties(t, 1, &m, VK_QUERY_TYPE_MICROMAP_SERIALIZATION_SIZE_EXT, 0, propertyOut(t), 0);
        (void)vk, (void)dev;
    });
    CASE("VUID-vkWriteMicromapsPropertiesEXT-pData-parameter", {
        const VkMicromapEXT m = builtMicromap(t);
        properties(t, 1, &m, VK_QUERY_TYPE_MICROMAP_SERIALIZATION_SIZE_EXT, 8, nullptr, 8);
        (void)vk, (void)dev;
    });
    CASE("VUID-vkWriteMicromapsPropertiesEXT-dataSize-07576", {
        const VkMicromapEXT m[2] = {builtMicromap(t), builtMicromap(t)};
        properties(t, 2, m, VK_QUERY_TYPE_MICROMAP_SERIALIZATION_SIZE_EXT, 8, propertyOut(t), 8);
        (void)vk, (void)dev;
    });
    CASE("VUID-vkWriteMicromapsPropertiesEXT-queryType-10071", {
        const VkMicromapEXT m = builtMicromap(t);
        properties(t, 1, &m, VK_QUERY_TYPE_MICROMAP_COMPACTED_SIZE_EXT, 16, propertyOut(t), 12);
        (void)vk, (void)dev;
    });
    CASE("VUID-vkWriteMicromapsPropertiesEXT-queryType-10072", {
        const VkMicromapEXT m = builtMicromap(t);
        properties(t, 1, &m, VK_QUERY_TYPE_MICROMAP_SERIALIZATION_SIZE_EXT, 16,
                   reinterpret_cast<uint8_t*>(propertyOut(t)) + 4, 8);
        (void)vk, (void)dev;
    });
    CASE("VUID-vkWriteMicromapsPropertiesEXT-buffer-07577", {
        const VkMicromapEXT m = newMicromap(t, false);
        properties(t, 1, &m, VK_QUERY_TYPE_MICROMAP_SERIALIZATION_SIZE_EXT, 8, propertyOut(t), 8);
        (void)vk, (void)dev;
    });
    CASE("VUID-vkWriteMicromapsPropertiesEXT-pMicromaps-11671", {
        const VkMicromapEXT m = newMicromap(t);
        properties(t, 1, &m, VK_QUERY_TYPE_MICROMAP_SERIALIZATION_SIZE_EXT, 8, propertyOut(t), 8);
        (void)vk, (void)dev;
    });
    CASE("VUID-vkWriteMicromapsPropertiesEXT-pMicromaps-07502", {
        const VkMicromapEXT m = builtMicromap(t, VK_BUILD_MICROMAP_PREFER_FAST_TRACE_BIT_EXT);
        properties(t, 1, &m, VK_QUERY_TYPE_MICROMAP_COMPACTED_SIZE_EXT, 8, propertyOut(t), 8);
        (void)vk, (void)dev;
    });

    // ---- vkGetDeviceMicromapCompatibilityEXT, VkMicromapVersionInfoEXT ------------------------------------------
    CASE("VUID-vkGetDeviceMicromapCompatibilityEXT-device-parameter", {
        const VkMicromapVersionInfoEXT vi = versionInfo(t);
        auto* out = t.hostObject(VK_ACCELERATION_STRUCTURE_COMPATIBILITY_MAX_ENUM_KHR);
        t.call([&] {
            mmOf(dev).compatibility(t.bogus<VkDevice>(), &vi, out);
            return V();
        });
        (void)vk;
    });
    CASE("VUID-vkGetDeviceMicromapCompatibilityEXT-pVersionInfo-parameter", {
        auto* out = t.hostObject(VK_ACCELERATION_STRUCTURE_COMPATIBILITY_MAX_ENUM_KHR);
        t.call([&] {
            mmOf(dev).compatibility(dev, nullptr, out);
            return V();
        });
        (void)vk;
    });
    CASE("VUID-vkGetDeviceMicromapCompatibilityEXT-pCompatibility-parameter", {
        const VkMicromapVersionInfoEXT vi = versionInfo(t);
        t.call([&] {
            mmOf(dev).compatibility(dev, &vi, nullptr);
            return V();
        });
        (void)vk;
    });
    CASE("VUID-VkMicromapVersionInfoEXT-sType-sType", {
        VkMicromapVersionInfoEXT vi = versionInfo(t);
        vi.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_VERSION_INFO_KHR;
        compatibility(t, vi);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkMicromapVersionInfoEXT-pNext-pNext", {
        VkMicromapVersionInfoEXT vi = versionInfo(t);
        vi.pNext = &kStray;
        compatibility(t, vi);
        (void)vk, (void)dev;
    });
    CASE("VUID-VkMicromapVersionInfoEXT-pVersionData-parameter", {
        VkMicromapVersionInfoEXT vi = versionInfo(t);
        vi.pVersionData = nullptr;
        compatibility(t, vi);
        (void)vk, (void)dev;
    });
}

}  // namespace vu
