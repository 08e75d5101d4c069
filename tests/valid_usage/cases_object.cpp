// Valid-usage cases: acceleration-structure objects (create, destroy, address), the build-size query and deferred
// operations.
#include "harness.hpp"

namespace vu {

namespace {

#define CASE(id, ...) c.push_back(Case{id, "", [](Fixture& t, const vt::Commands& vk, VkDevice dev) __VA_ARGS__})
#define CASE_V(id, variant, ...) \
    c.push_back(Case{id, variant, [](Fixture& t, const vt::Commands& vk, VkDevice dev) __VA_ARGS__})
#define CASE_ALSO(id, also, ...) \
    c.push_back(Case{id, "", [](Fixture& t, const vt::Commands& vk, VkDevice dev) __VA_ARGS__, also})

VkAllocationCallbacks someCallbacks() {
    VkAllocationCallbacks a{};
    a.pfnAllocation = [](void*, size_t size, size_t alignment, VkSystemAllocationScope) -> void* {
        return std::aligned_alloc(alignment, (size + alignment - 1) / alignment * alignment);
    };
    a.pfnReallocation = [](void*, void*, size_t, size_t, VkSystemAllocationScope) -> void* { return nullptr; };
    a.pfnFree = [](void*, void* p) { std::free(p); };
    return a;
}

// A valid create info for a bottom-level structure in a fresh buffer of 64 KiB.
VkAccelerationStructureCreateInfoKHR structureInfo(Fixture& t, VkBufferUsageFlags usage = vt::kAsBufferUsage) {
    VkAccelerationStructureCreateInfoKHR ci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
    ci.buffer = t.createBuffer(65536, usage)->buffer;
    ci.size = 4096;
    ci.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
    return ci;
}

void createStructure(Fixture& t, const vt::Commands& vk, VkDevice dev, const VkAccelerationStructureCreateInfoKHR& ci) {
    static VkAccelerationStructureKHR out;
    out = t.bogus<VkAccelerationStructureKHR>();
    t.watch(&out, sizeof out);
    t.call([&] { return R(vk.vkCreateAccelerationStructureKHR(dev, &ci, nullptr, &out)); });
}

VkAccelerationStructureKHR newStructure(Fixture& t, const VkAllocationCallbacks* callbacks = nullptr) {
    auto ci = structureInfo(t);
    VkAccelerationStructureKHR as = VK_NULL_HANDLE;
    EXPECT_EQ(t.vk.vkCreateAccelerationStructureKHR(t.device, &ci, callbacks, &as), VK_SUCCESS);
    return as;
}

// vkGetAccelerationStructureBuildSizesKHR with a broken argument: the output must stay as it was.
void sizes(Fixture& t, const vt::Commands& vk, VkDevice dev, VkAccelerationStructureBuildTypeKHR buildType,
           const VkAccelerationStructureBuildGeometryInfoKHR* info, const uint32_t* counts,
           VkAccelerationStructureBuildSizesInfoKHR* out) {
    if (out) t.watch(out, sizeof *out);
    t.call([&] {
        vk.vkGetAccelerationStructureBuildSizesKHR(dev, buildType, info, counts, out);
        return V();
    });
}

VkAccelerationStructureBuildSizesInfoKHR& sizeOutput() {
    static VkAccelerationStructureBuildSizesInfoKHR out;
    out = {VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
    out.accelerationStructureSize = out.buildScratchSize = out.updateScratchSize = 0xAAAAAAAA;
    return out;
}

}  // namespace

void addObjectCases(std::vector<Case>& c) {
    // ---- vkCreateAccelerationStructureKHR -------------------------------------------------------------------------
    CASE("VUID-vkCreateAccelerationStructureKHR-device-parameter", {
        auto ci = structureInfo(t);
        VkAccelerationStructureKHR out = VK_NULL_HANDLE;
        t.call([&] { return R(vk.vkCreateAccelerationStructureKHR(t.bogus<VkDevice>(), &ci, nullptr, &out)); });
        EXPECT_EQ(out, VK_NULL_HANDLE);
        (void)dev;
    });
    CASE("VUID-vkCreateAccelerationStructureKHR-pCreateInfo-parameter", {
        VkAccelerationStructureKHR out = VK_NULL_HANDLE;
        t.call([&] { return R(vk.vkCreateAccelerationStructureKHR(dev, nullptr, nullptr, &out)); });
        EXPECT_EQ(out, VK_NULL_HANDLE);
    });
    CASE("VUID-vkCreateAccelerationStructureKHR-pAccelerationStructure-parameter", {
        auto ci = structureInfo(t);
        t.call([&] { return R(vk.vkCreateAccelerationStructureKHR(dev, &ci, nullptr, nullptr)); });
    });
    CASE("VUID-VkAccelerationStructureCreateInfoKHR-sType-sType", {
        auto ci = structureInfo(t);
        ci.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO;
        createStructure(t, vk, dev, ci);
    });
    CASE("VUID-VkAccelerationStructureCreateInfoKHR-pNext-pNext", {
        auto ci = structureInfo(t);
        VkBufferDeviceAddressInfo unrelated{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO};
        ci.pNext = &unrelated;
        createStructure(t, vk, dev, ci);
    });
    CASE("VUID-VkAccelerationStructureCreateInfoKHR-sType-unique", {
        auto ci = structureInfo(t);
        VkAccelerationStructureMotionInfoNV second{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_MOTION_INFO_NV};
        VkAccelerationStructureMotionInfoNV first{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_MOTION_INFO_NV, &second};
        first.maxInstances = second.maxInstances = 4;
        ci.pNext = &first;
        ci.type = VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR;
        ci.createFlags = VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV;
        createStructure(t, vk, dev, ci);
    });
    CASE("VUID-VkAccelerationStructureCreateInfoKHR-type-parameter", {
        auto ci = structureInfo(t);
        ci.type = VkAccelerationStructureTypeKHR(9);
        createStructure(t, vk, dev, ci);
    });
    CASE("VUID-VkAccelerationStructureCreateInfoKHR-createFlags-parameter", {
        auto ci = structureInfo(t);
        ci.createFlags = 0x100;
        createStructure(t, vk, dev, ci);
    });
    CASE_ALSO("VUID-vkCreateAccelerationStructureKHR-deviceAddress-03488",
              {"VUID-VkAccelerationStructureCreateInfoKHR-createFlags-03613"}, {
                  auto ci = structureInfo(t);
                  ci.createFlags = VK_ACCELERATION_STRUCTURE_CREATE_DEVICE_ADDRESS_CAPTURE_REPLAY_BIT_KHR;
                  ci.deviceAddress = 0x100000;
                  createStructure(t, vk, dev, ci);
              });
    CASE_ALSO("VUID-VkAccelerationStructureCreateInfoKHR-deviceAddress-03612",
              {"VUID-vkCreateAccelerationStructureKHR-deviceAddress-03488"}, {
                  auto ci = structureInfo(t);
                  ci.deviceAddress = 0x100000;
                  createStructure(t, vk, dev, ci);
              });
    CASE("VUID-VkAccelerationStructureCreateInfoKHR-createFlags-03613", {
        auto ci = structureInfo(t);
        ci.createFlags = VK_ACCELERATION_STRUCTURE_CREATE_DEVICE_ADDRESS_CAPTURE_REPLAY_BIT_KHR;
        createStructure(t, vk, dev, ci);
    });
    CASE("VUID-VkAccelerationStructureCreateInfoKHR-createFlags-04954", {
        auto ci = structureInfo(t);
        ci.type = VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR;
        ci.createFlags = VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV;
        createStructure(t, vk, dev, ci);
    });
    CASE("VUID-VkAccelerationStructureMotionInfoNV-flags-zerobitmask", {
        auto ci = structureInfo(t);
        VkAccelerationStructureMotionInfoNV motion{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_MOTION_INFO_NV};
        motion.maxInstances = 4;
        motion.flags = 1;
        ci.pNext = &motion;
        ci.type = VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR;
        ci.createFlags = VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV;
        createStructure(t, vk, dev, ci);
    });
    CASE("VUID-VkAccelerationStructureCreateInfoKHR-offset-03734", {
        auto ci = structureInfo(t);
        ci.offset = 16;
        createStructure(t, vk, dev, ci);
    });
    CASE("VUID-VkAccelerationStructureCreateInfoKHR-buffer-parameter", {
        auto ci = structureInfo(t);
        ci.buffer = t.bogus<VkBuffer>();
        createStructure(t, vk, dev, ci);
    });
    CASE("VUID-VkAccelerationStructureCreateInfoKHR-buffer-03614", {
        auto ci = structureInfo(t, VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT);
        createStructure(t, vk, dev, ci);
    });
    CASE("VUID-VkAccelerationStructureCreateInfoKHR-offset-03616", {
        auto ci = structureInfo(t);
        ci.offset = 65536 - 256;
        ci.size = 512;
        createStructure(t, vk, dev, ci);
    });

    // ---- vkDestroyAccelerationStructureKHR ------------------------------------------------------------------------
    CASE("VUID-vkDestroyAccelerationStructureKHR-device-parameter", {
        VkAccelerationStructureKHR as = newStructure(t);
        t.call([&] {
            vk.vkDestroyAccelerationStructureKHR(t.bogus<VkDevice>(), as, nullptr);
            return V();
        });
        (void)dev;
    });
    CASE("VUID-vkDestroyAccelerationStructureKHR-accelerationStructure-parameter", {
        t.call([&] {
            vk.vkDestroyAccelerationStructureKHR(dev, t.bogus<VkAccelerationStructureKHR>(), nullptr);
            return V();
        });
    });
    CASE("VUID-vkDestroyAccelerationStructureKHR-accelerationStructure-parent", {
        VkAccelerationStructureKHR as = t.otherStructure();
        t.call([&] {
            vk.vkDestroyAccelerationStructureKHR(dev, as, nullptr);
            return V();
        });
    });
    CASE("VUID-vkDestroyAccelerationStructureKHR-accelerationStructure-02443", {
        static const VkAllocationCallbacks callbacks = someCallbacks();
        VkAccelerationStructureKHR as = newStructure(t, &callbacks);
        t.call([&] {
            vk.vkDestroyAccelerationStructureKHR(dev, as, nullptr);
            return V();
        });
        vk.vkDestroyAccelerationStructureKHR(dev, as, &callbacks);
    });
    CASE("VUID-vkDestroyAccelerationStructureKHR-accelerationStructure-02444", {
        static const VkAllocationCallbacks callbacks = someCallbacks();
        VkAccelerationStructureKHR as = newStructure(t);
        t.call([&] {
            vk.vkDestroyAccelerationStructureKHR(dev, as, &callbacks);
            return V();
        });
        vk.vkDestroyAccelerationStructureKHR(dev, as, nullptr);
    });
    CASE("VUID-vkDestroyBuffer-buffer-00923", {
        static const VkAllocationCallbacks callbacks = someCallbacks();
        VkBufferCreateInfo ci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
        ci.size = 256;
        ci.usage = vt::kAsBufferUsage;
        VkBuffer b = VK_NULL_HANDLE;
        EXPECT_EQ(vk.vkCreateBuffer(dev, &ci, &callbacks, &b), VK_SUCCESS);
        t.call([&] {
            vk.vkDestroyBuffer(dev, b, nullptr);
            return V();
        });
        vk.vkDestroyBuffer(dev, b, &callbacks);
    });
    CASE("VUID-vkDestroyBuffer-buffer-00924", {
        static const VkAllocationCallbacks callbacks = someCallbacks();
        VkBufferCreateInfo ci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
        ci.size = 256;
        ci.usage = vt::kAsBufferUsage;
        VkBuffer b = VK_NULL_HANDLE;
        EXPECT_EQ(vk.vkCreateBuffer(dev, &ci, nullptr, &b), VK_SUCCESS);
        t.call([&] {
            vk.vkDestroyBuffer(dev, b, &callbacks);
            return V();
        });
        vk.vkDestroyBuffer(dev, b, nullptr);
    });

    // ---- vkGetAccelerationStructureDeviceAddressKHR ---------------------------------------------------------------
    CASE("VUID-vkGetAccelerationStructureDeviceAddressKHR-device-parameter", {
        VkAccelerationStructureDeviceAddressInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_DEVICE_ADDRESS_INFO_KHR,
                                                         nullptr, t.blas->handle};
        t.call([&] {
            EXPECT_EQ(vk.vkGetAccelerationStructureDeviceAddressKHR(t.bogus<VkDevice>(), &info), 0u);
            return V();
        });
        (void)dev;
    });
    CASE("VUID-vkGetAccelerationStructureDeviceAddressKHR-pInfo-parameter", {
        t.call([&] {
            EXPECT_EQ(vk.vkGetAccelerationStructureDeviceAddressKHR(dev, nullptr), 0u);
            return V();
        });
    });
    CASE("VUID-VkAccelerationStructureDeviceAddressInfoKHR-sType-sType", {
        VkAccelerationStructureDeviceAddressInfoKHR info{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO, nullptr,
                                                         t.blas->handle};
        t.call([&] {
            EXPECT_EQ(vk.vkGetAccelerationStructureDeviceAddressKHR(dev, &info), 0u);
            return V();
        });
    });
    CASE("VUID-VkAccelerationStructureDeviceAddressInfoKHR-pNext-pNext", {
        VkBufferDeviceAddressInfo unrelated{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO};
        VkAccelerationStructureDeviceAddressInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_DEVICE_ADDRESS_INFO_KHR,
                                                         &unrelated, t.blas->handle};
        t.call([&] {
            EXPECT_EQ(vk.vkGetAccelerationStructureDeviceAddressKHR(dev, &info), 0u);
            return V();
        });
    });
    CASE("VUID-VkAccelerationStructureDeviceAddressInfoKHR-accelerationStructure-parameter", {
        VkAccelerationStructureDeviceAddressInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_DEVICE_ADDRESS_INFO_KHR,
                                                         nullptr, t.bogus<VkAccelerationStructureKHR>()};
        t.call([&] {
            EXPECT_EQ(vk.vkGetAccelerationStructureDeviceAddressKHR(dev, &info), 0u);
            return V();
        });
    });
    CASE("VUID-vkGetAccelerationStructureDeviceAddressKHR-pInfo-09541", {
        VkAccelerationStructureDeviceAddressInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_DEVICE_ADDRESS_INFO_KHR,
                                                         nullptr, t.unbound->handle};
        t.call([&] {
            EXPECT_EQ(vk.vkGetAccelerationStructureDeviceAddressKHR(dev, &info), 0u);
            return V();
        });
    });
    CASE("VUID-vkGetAccelerationStructureDeviceAddressKHR-pInfo-09542", {
        VkAccelerationStructureCreateInfoKHR ci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
        ci.buffer = t.createBuffer(4096, VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_STORAGE_BIT_KHR)->buffer;
        ci.size = 4096;
        ci.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
        VkAccelerationStructureKHR as = VK_NULL_HANDLE;
        EXPECT_EQ(vk.vkCreateAccelerationStructureKHR(dev, &ci, nullptr, &as), VK_SUCCESS);
        VkAccelerationStructureDeviceAddressInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_DEVICE_ADDRESS_INFO_KHR,
                                                         nullptr, as};
        t.call([&] {
            EXPECT_EQ(vk.vkGetAccelerationStructureDeviceAddressKHR(dev, &info), 0u);
            return V();
        });
    });

    // ---- vkGetAccelerationStructureBuildSizesKHR ------------------------------------------------------------------
    CASE("VUID-vkGetAccelerationStructureBuildSizesKHR-device-parameter", {
        auto pb = t.triangleBuild();
        const uint32_t count = 2;
        sizes(t, vk, t.bogus<VkDevice>(), VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &pb->info, &count,
              &sizeOutput());
        (void)dev;
    });
    CASE("VUID-vkGetAccelerationStructureBuildSizesKHR-buildType-parameter", {
        auto pb = t.triangleBuild();
        const uint32_t count = 2;
        sizes(t, vk, dev, VkAccelerationStructureBuildTypeKHR(7), &pb->info, &count, &sizeOutput());
    });
    CASE("VUID-vkGetAccelerationStructureBuildSizesKHR-pBuildInfo-parameter", {
        const uint32_t count = 2;
        sizes(t, vk, dev, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, nullptr, &count, &sizeOutput());
    });
    CASE("VUID-vkGetAccelerationStructureBuildSizesKHR-pMaxPrimitiveCounts-11612", {
        auto pb = t.triangleBuild();
        sizes(t, vk, dev, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &pb->info, nullptr, &sizeOutput());
    });
    CASE("VUID-vkGetAccelerationStructureBuildSizesKHR-pBuildInfo-03785", {
        auto pb = t.instanceBuild();
        const uint32_t count = (1u << 24);  // maxInstanceCount is 2^24 - 1
        sizes(t, vk, dev, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &pb->info, &count, &sizeOutput());
    });
    // The size query applies the build's maxPrimitiveCount rules to pMaxPrimitiveCounts (two geometries whose sum
    // exceeds 2^29 - 1 although each alone does not).
    CASE_V("VUID-VkAccelerationStructureBuildGeometryInfoKHR-type-03795", "size query", {
        std::vector<VkAccelerationStructureGeometryKHR> g{t.tri->geometry, t.tri->geometry};
        std::vector<VkAccelerationStructureBuildRangeInfoKHR> r{t.tri->range, t.tri->range};
        auto pb = t.prepareBlas(g, r);
        const uint32_t counts[2] = {1u << 28, 1u << 28};
        sizes(t, vk, dev, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &pb->info, counts, &sizeOutput());
    });
    CASE_V("VUID-VkAccelerationStructureBuildGeometryInfoKHR-type-03794", "size query", {
        auto pb = t.aabbBuild();
        const uint32_t count = 1u << 29;
        sizes(t, vk, dev, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &pb->info, &count, &sizeOutput());
    });
    CASE("VUID-vkGetAccelerationStructureBuildSizesKHR-pSizeInfo-parameter", {
        auto pb = t.triangleBuild();
        const uint32_t count = 2;
        sizes(t, vk, dev, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &pb->info, &count, nullptr);
    });
    CASE("VUID-VkAccelerationStructureBuildSizesInfoKHR-sType-sType", {
        auto pb = t.triangleBuild();
        const uint32_t count = 2;
        auto& out = sizeOutput();
        out.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO;
        sizes(t, vk, dev, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &pb->info, &count, &out);
    });
    CASE("VUID-VkAccelerationStructureBuildSizesInfoKHR-pNext-pNext", {
        auto pb = t.triangleBuild();
        const uint32_t count = 2;
        static VkBufferDeviceAddressInfo unrelated{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO};
        auto& out = sizeOutput();
        out.pNext = &unrelated;
        sizes(t, vk, dev, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &pb->info, &count, &out);
    });

    // ---- Deferred operations ----------------------------------------------------------------------------------------
    CASE("VUID-vkCreateDeferredOperationKHR-device-parameter", {
        VkDeferredOperationKHR out = VK_NULL_HANDLE;
        t.call([&] { return R(t.deferred.create(t.bogus<VkDevice>(), nullptr, &out)); });
        EXPECT_EQ(out, VK_NULL_HANDLE);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkCreateDeferredOperationKHR-pDeferredOperation-parameter", {
        t.call([&] { return R(t.deferred.create(dev, nullptr, nullptr)); });
        (void)vk;
    });
    CASE("VUID-vkDestroyDeferredOperationKHR-device-parameter", {
        t.call([&] {
            t.deferred.destroy(t.bogus<VkDevice>(), t.op, nullptr);
            return V();
        });
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkDestroyDeferredOperationKHR-operation-parameter", {
        t.call([&] {
            t.deferred.destroy(dev, t.bogus<VkDeferredOperationKHR>(), nullptr);
            return V();
        });
        (void)vk;
    });
    CASE("VUID-vkDestroyDeferredOperationKHR-operation-parent", {
        VkDeferredOperationKHR foreign = t.otherOperation();
        t.call([&] {
            t.deferred.destroy(dev, foreign, nullptr);
            return V();
        });
        (void)vk;
    });
    CASE("VUID-vkDestroyDeferredOperationKHR-operation-03436", {
        VkDeferredOperationKHR pending = t.pendingOperation();
        t.call([&] {
            t.deferred.destroy(dev, pending, nullptr);
            return V();
        });
        (void)vk;
    });
    CASE("VUID-vkDestroyDeferredOperationKHR-operation-03434", {
        static const VkAllocationCallbacks callbacks = someCallbacks();
        VkDeferredOperationKHR operation = VK_NULL_HANDLE;
        EXPECT_EQ(t.deferred.create(dev, &callbacks, &operation), VK_SUCCESS);
        t.call([&] {
            t.deferred.destroy(dev, operation, nullptr);
            return V();
        });
        t.deferred.destroy(dev, operation, &callbacks);
        (void)vk;
    });
    CASE("VUID-vkDestroyDeferredOperationKHR-operation-03435", {
        static const VkAllocationCallbacks callbacks = someCallbacks();
        t.call([&] {
            t.deferred.destroy(dev, t.op, &callbacks);
            return V();
        });
        (void)vk;
    });
    CASE("VUID-vkGetDeferredOperationMaxConcurrencyKHR-device-parameter", {
        t.call([&] {
            EXPECT_EQ(t.deferred.maxConcurrency(t.bogus<VkDevice>(), t.op), 0u);
            return V();
        });
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkGetDeferredOperationMaxConcurrencyKHR-operation-parameter", {
        t.call([&] {
            EXPECT_EQ(t.deferred.maxConcurrency(dev, t.bogus<VkDeferredOperationKHR>()), 0u);
            return V();
        });
        (void)vk;
    });
    CASE("VUID-vkGetDeferredOperationMaxConcurrencyKHR-operation-parent", {
        VkDeferredOperationKHR foreign = t.otherOperation();
        t.call([&] {
            EXPECT_EQ(t.deferred.maxConcurrency(dev, foreign), 0u);
            return V();
        });
        (void)vk;
    });
    CASE("VUID-vkGetDeferredOperationResultKHR-device-parameter", {
        t.call([&] { return R(t.deferred.result(t.bogus<VkDevice>(), t.op)); });
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkGetDeferredOperationResultKHR-operation-parameter", {
        t.call([&] { return R(t.deferred.result(dev, t.bogus<VkDeferredOperationKHR>())); });
        (void)vk;
    });
    CASE("VUID-vkGetDeferredOperationResultKHR-operation-parent", {
        VkDeferredOperationKHR foreign = t.otherOperation();
        t.call([&] { return R(t.deferred.result(dev, foreign)); });
        (void)vk;
    });
    CASE("VUID-vkDeferredOperationJoinKHR-device-parameter", {
        VkDeferredOperationKHR pending = t.pendingOperation();
        t.call([&] { return R(t.deferred.join(t.bogus<VkDevice>(), pending)); });
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkDeferredOperationJoinKHR-operation-parameter", {
        t.call([&] { return R(t.deferred.join(dev, t.bogus<VkDeferredOperationKHR>())); });
        (void)vk;
    });
    CASE("VUID-vkDeferredOperationJoinKHR-operation-parent", {
        VkDeferredOperationKHR foreign = t.otherOperation();
        t.call([&] { return R(t.deferred.join(dev, foreign)); });
        (void)vk;
    });
}

}  // namespace vu
