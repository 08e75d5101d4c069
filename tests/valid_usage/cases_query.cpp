// Valid-usage cases: vkWriteAccelerationStructuresPropertiesKHR, vkGetDeviceAccelerationStructureCompatibilityKHR,
// the host ray queries (the SPIR-V ray-query rules) and vkas's batch calls.
#include <array>
#include <limits>

#include "harness.hpp"

namespace vu {

namespace {

#define CASE(id, ...) c.push_back(Case{id, "", [](Fixture& t, const vt::Commands& vk, VkDevice dev) __VA_ARGS__})
#define CASE_V(id, variant, ...) \
    c.push_back(Case{id, variant, [](Fixture& t, const vt::Commands& vk, VkDevice dev) __VA_ARGS__})

// vkWriteAccelerationStructuresPropertiesKHR into watched memory.
void properties(Fixture& t, std::vector<VkAccelerationStructureKHR> structures, VkQueryType type, size_t dataSize,
                size_t stride, size_t misalign = 0, uint32_t count = UINT32_MAX) {
    uint8_t* data = t.hostCopy(nullptr, 64 + dataSize);
    std::memset(data, 0xAA, 64 + dataSize);
    if (count == UINT32_MAX) count = uint32_t(structures.size());
    t.call([&] {
        return R(t.vk.vkWriteAccelerationStructuresPropertiesKHR(t.device, count, structures.data(), type, dataSize,
                                                                 data + misalign, stride));
    });
}

constexpr VkQueryType kCompacted = VK_QUERY_TYPE_ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR;
constexpr VkQueryType kSerialization = VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_SIZE_KHR;
constexpr VkQueryType kSize = VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SIZE_KHR;
constexpr VkQueryType kPointers = VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_BOTTOM_LEVEL_POINTERS_KHR;

void compatibility(Fixture& t, const VkAccelerationStructureVersionInfoKHR* info, bool output = true) {
    auto* out = t.hostObject(VkAccelerationStructureCompatibilityKHR(0x7AAAAAAA));
    t.call([&] {
        t.vk.vkGetDeviceAccelerationStructureCompatibilityKHR(t.device, info, output ? out : nullptr);
        return V();
    });
}

// Initializes a query with a broken ray; the query must then traverse nothing.
void initialize(Fixture& t, VkAccelerationStructureKHR topLevel, uint32_t flags, std::array<float, 3> origin,
                float tMin, std::array<float, 3> direction, float tMax) {
    VkasRayQuery q;
    t.call([&] {
        vkasRayQueryInitialize(&q, topLevel, flags, 0xFF, origin.data(), tMin, direction.data(), tMax);
        return V();
    });
    EXPECT_EQ(vkasRayQueryProceed(&q), VK_FALSE) << "an invalid query must traverse nothing";
    EXPECT_EQ(vkasRayQueryGetIntersectionType(&q, VK_TRUE), uint32_t(VKAS_COMMITTED_INTERSECTION_NONE));
}

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

// A ray at the quad (z = 0, [0,1]^2) from above.
constexpr std::array<float, 3> kOrigin{0.25f, 0.5f, 1.0f};
constexpr std::array<float, 3> kDown{0.0f, 0.0f, -1.0f};

// vkasTraceRays / vkasTraceRaysProcedural into watched hits.
void trace(Fixture& t, VkDevice device, VkAccelerationStructureKHR topLevel, VkasTraceMode mode, uint32_t flags,
           const std::vector<VkasRay>& rays, bool procedural = false, bool nullRays = false) {
    auto* hits = reinterpret_cast<VkasHit*>(t.hostCopy(nullptr, sizeof(VkasHit) * std::max<size_t>(rays.size(), 1)));
    const uint32_t count = uint32_t(std::max<size_t>(rays.size(), 1));
    const VkasRay* pRays = nullRays ? nullptr : rays.data();
    t.call([&] {
        if (procedural)
            return R(vkasTraceRaysProcedural(device, topLevel, mode, flags, 0xFF, count, pRays, hits, nullptr, nullptr));
        return R(vkasTraceRays(device, topLevel, mode, flags, 0xFF, count, pRays, hits));
    });
}
VkasRay downRay(float tMin = 0.0f, float tMax = 10.0f) {
    VkasRay r{};
    std::memcpy(r.origin, kOrigin.data(), 12);
    std::memcpy(r.direction, kDown.data(), 12);
    r.tMin = tMin;
    r.tMax = tMax;
    return r;
}

// A built bottom level of the fixture's two boxes.
vt::AccelStruct* boxBlas(Fixture& t) {
    VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
    g.geometryType = VK_GEOMETRY_TYPE_AABBS_KHR;
    g.geometry.aabbs.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_AABBS_DATA_KHR;
    g.geometry.aabbs.data.hostAddress = t.boxes.data();
    g.geometry.aabbs.stride = sizeof(VkAabbPositionsKHR);
    VkAccelerationStructureBuildRangeInfoKHR r{};
    r.primitiveCount = uint32_t(t.boxes.size());
    return t.buildBlas(std::vector<VkAccelerationStructureGeometryKHR>{g},
                       std::vector<VkAccelerationStructureBuildRangeInfoKHR>{r});
}

}  // namespace

void addQueryCases(std::vector<Case>& c) {
    // ---- vkWriteAccelerationStructuresPropertiesKHR ---------------------------------------------------------------
    CASE("VUID-vkWriteAccelerationStructuresPropertiesKHR-device-parameter", {
        VkDeviceSize out = 0;
        t.call([&] {
            return R(vk.vkWriteAccelerationStructuresPropertiesKHR(t.bogus<VkDevice>(), 1, &t.blas->handle,
                                                                   kSerialization, 8, &out, 8));
        });
        (void)dev;
    });
    CASE("VUID-vkWriteAccelerationStructuresPropertiesKHR-accelerationStructureCount-arraylength", {
        properties(t, {t.blas->handle}, kSerialization, 8, 8, 0, /*count=*/0);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkWriteAccelerationStructuresPropertiesKHR-pAccelerationStructures-parameter", {
        VkDeviceSize out = 0;
        t.call([&] { return R(vk.vkWriteAccelerationStructuresPropertiesKHR(dev, 1, nullptr, kSerialization, 8, &out, 8)); });
    });
    CASE_V("VUID-vkWriteAccelerationStructuresPropertiesKHR-pAccelerationStructures-parameter", "unknown_handle", {
        properties(t, {t.bogus<VkAccelerationStructureKHR>()}, kSerialization, 8, 8);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkWriteAccelerationStructuresPropertiesKHR-pAccelerationStructures-parent", {
        properties(t, {t.otherStructure()}, kSerialization, 8, 8);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkWriteAccelerationStructuresPropertiesKHR-dataSize-arraylength", {
        properties(t, {t.blas->handle}, kSerialization, 0, 0);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkWriteAccelerationStructuresPropertiesKHR-pData-parameter", {
        t.call([&] {
            return R(vk.vkWriteAccelerationStructuresPropertiesKHR(dev, 1, &t.blas->handle, kSerialization, 8, nullptr, 8));
        });
    });
    CASE("VUID-vkWriteAccelerationStructuresPropertiesKHR-queryType-parameter", {
        properties(t, {t.blas->handle}, VkQueryType(12345), 8, 8);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkWriteAccelerationStructuresPropertiesKHR-queryType-06742", {
        properties(t, {t.blas->handle}, VK_QUERY_TYPE_OCCLUSION, 8, 8);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkWriteAccelerationStructuresPropertiesKHR-queryType-03448", {
        properties(t, {t.blas->handle}, kCompacted, 16, 12);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkWriteAccelerationStructuresPropertiesKHR-queryType-03449", {
        properties(t, {t.blas->handle}, kCompacted, 8, 8, /*misalign=*/4);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkWriteAccelerationStructuresPropertiesKHR-queryType-03450", {
        properties(t, {t.blas->handle}, kSerialization, 16, 12);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkWriteAccelerationStructuresPropertiesKHR-queryType-03451", {
        properties(t, {t.blas->handle}, kSerialization, 8, 8, 4);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkWriteAccelerationStructuresPropertiesKHR-queryType-06731", {
        properties(t, {t.blas->handle}, kSize, 16, 12);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkWriteAccelerationStructuresPropertiesKHR-queryType-06732", {
        properties(t, {t.blas->handle}, kSize, 8, 8, 4);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkWriteAccelerationStructuresPropertiesKHR-queryType-06733", {
        properties(t, {t.tlas->handle}, kPointers, 16, 12);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkWriteAccelerationStructuresPropertiesKHR-queryType-06734", {
        properties(t, {t.tlas->handle}, kPointers, 8, 8, 4);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkWriteAccelerationStructuresPropertiesKHR-dataSize-03452", {
        properties(t, {t.blas->handle, t.tlas->handle}, kSerialization, 8, 8);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkWriteAccelerationStructuresPropertiesKHR-buffer-03736", {
        properties(t, {t.unbound->handle}, kSerialization, 8, 8);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkWriteAccelerationStructuresPropertiesKHR-pAccelerationStructures-11591", {
        properties(t, {t.unbuilt->handle}, kSerialization, 8, 8);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkWriteAccelerationStructuresPropertiesKHR-accelerationStructures-03431", {
        properties(t, {t.plainBlas->handle}, kCompacted, 8, 8);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkWriteAccelerationStructuresPropertiesKHR-pAccelerationStructures-12425", {
        properties(t, {t.blas->handle}, kPointers, 8, 8);
        (void)vk;
        (void)dev;
    });

    // ---- vkGetDeviceAccelerationStructureCompatibilityKHR ---------------------------------------------------------
    CASE("VUID-vkGetDeviceAccelerationStructureCompatibilityKHR-device-parameter", {
        static const uint8_t version[32] = {};
        VkAccelerationStructureVersionInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_VERSION_INFO_KHR, nullptr,
                                                   version};
        auto* out = t.hostObject(VkAccelerationStructureCompatibilityKHR(0x7AAAAAAA));
        t.call([&] {
            vk.vkGetDeviceAccelerationStructureCompatibilityKHR(t.bogus<VkDevice>(), &info, out);
            return V();
        });
        (void)dev;
    });
    CASE("VUID-vkGetDeviceAccelerationStructureCompatibilityKHR-pVersionInfo-parameter", {
        compatibility(t, nullptr);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkGetDeviceAccelerationStructureCompatibilityKHR-pCompatibility-parameter", {
        static const uint8_t version[32] = {};
        VkAccelerationStructureVersionInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_VERSION_INFO_KHR, nullptr,
                                                   version};
        compatibility(t, &info, false);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureVersionInfoKHR-sType-sType", {
        static const uint8_t version[32] = {};
        VkAccelerationStructureVersionInfoKHR info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO, nullptr, version};
        compatibility(t, &info);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureVersionInfoKHR-pNext-pNext", {
        static const uint8_t version[32] = {};
        VkBufferDeviceAddressInfo unrelated{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO};
        VkAccelerationStructureVersionInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_VERSION_INFO_KHR,
                                                   &unrelated, version};
        compatibility(t, &info);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureVersionInfoKHR-pVersionData-parameter", {
        VkAccelerationStructureVersionInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_VERSION_INFO_KHR, nullptr,
                                                   nullptr};
        compatibility(t, &info);
        (void)vk;
        (void)dev;
    });

    // ---- Host ray queries (OpRayQueryInitializeKHR and friends) ---------------------------------------------------
    CASE("VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06348", {
        initialize(t, t.tlas->handle, 0, {kNaN, 0.5f, 1.0f}, 0.0f, kDown, 10.0f);
        (void)vk;
        (void)dev;
    });
    CASE_V("VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06348", "direction", {
        initialize(t, t.tlas->handle, 0, kOrigin, 0.0f, {0.0f, kInf, -1.0f}, 10.0f);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06351", {
        initialize(t, t.tlas->handle, 0, kOrigin, kNaN, kDown, 10.0f);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06349", {
        initialize(t, t.tlas->handle, 0, kOrigin, -1.0f, kDown, 10.0f);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06350", {
        initialize(t, t.tlas->handle, 0, kOrigin, 5.0f, kDown, 1.0f);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06891", {
        initialize(t, t.tlas->handle, VKAS_RAY_FLAG_OPAQUE | VKAS_RAY_FLAG_NO_OPAQUE, kOrigin, 0.0f, kDown, 10.0f);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06890", {
        initialize(t, t.tlas->handle,
                   VKAS_RAY_FLAG_CULL_BACK_FACING_TRIANGLES | VKAS_RAY_FLAG_CULL_FRONT_FACING_TRIANGLES, kOrigin,
                   0.0f, kDown, 10.0f);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06889", {
        initialize(t, t.tlas->handle, VKAS_RAY_FLAG_SKIP_TRIANGLES | VKAS_RAY_FLAG_SKIP_AABBS, kOrigin, 0.0f, kDown,
                   10.0f);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06352", {
        initialize(t, t.blas->handle, 0, kOrigin, 0.0f, kDown, 10.0f);  // a bottom level
        (void)vk;
        (void)dev;
    });
    CASE_V("VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06352", "unknown_handle", {
        initialize(t, t.bogus<VkAccelerationStructureKHR>(), 0, kOrigin, 0.0f, kDown, 10.0f);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-RuntimeSpirv-OpTraceRayMotionNV-06366", {
        VkasRayQuery q;
        t.call([&] {
            vkasRayQueryInitializeMotion(&q, t.tlas->handle, 0, 0xFF, kOrigin.data(), 0.0f, kDown.data(), 10.0f, 2.0f);
            return V();
        });
        EXPECT_EQ(vkasRayQueryProceed(&q), VK_FALSE);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-RuntimeSpirv-OpRayQueryGenerateIntersectionKHR-06353", {
        vt::Instance instance;
        instance.blas = boxBlas(t);
        vt::AccelStruct* top = t.buildTlas({instance});
        VkasRayQuery q;
        const std::array<float, 3> above{0.5f, 0.5f, 5.0f};
        vkasRayQueryInitialize(&q, top->handle, 0, 0xFF, above.data(), 0.0f, kDown.data(), 10.0f);
        ASSERT_EQ(vkasRayQueryProceed(&q), VK_TRUE);
        ASSERT_EQ(vkasRayQueryGetIntersectionType(&q, VK_FALSE), uint32_t(VKAS_CANDIDATE_INTERSECTION_AABB));
        t.call([&] {
            vkasRayQueryGenerateIntersection(&q, 20.0f);  // beyond RayTmax
            return V();
        });
        while (vkasRayQueryProceed(&q)) {
        }
        EXPECT_EQ(vkasRayQueryGetIntersectionType(&q, VK_TRUE), uint32_t(VKAS_COMMITTED_INTERSECTION_NONE));
        (void)vk;
        (void)dev;
    });
    CASE("VUID-RuntimeSpirv-OpRayQueryGenerateIntersectionKHR-06354", {
        auto pb = t.motionInstanceBuild({VK_ACCELERATION_STRUCTURE_MOTION_INSTANCE_TYPE_STATIC_NV}, {}, boxBlas(t));
        ASSERT_EQ(t.build(*pb).result, VK_SUCCESS);
        VkasRayQuery q;
        const std::array<float, 3> above{0.5f, 0.5f, 5.0f};
        vkasRayQueryInitialize(&q, pb->as->handle, 0, 0xFF, above.data(), 0.0f, kDown.data(), 10.0f);
        ASSERT_EQ(vkasRayQueryProceed(&q), VK_TRUE);
        t.call([&] {
            vkasRayQueryGenerateIntersection(&q, 4.0f);
            return V();
        });
        while (vkasRayQueryProceed(&q)) {
        }
        EXPECT_EQ(vkasRayQueryGetIntersectionType(&q, VK_TRUE), uint32_t(VKAS_COMMITTED_INTERSECTION_NONE));
        (void)vk;
        (void)dev;
    });
    CASE("VUID-RuntimeSpirv-flags-08761", {
        VkasRayQuery q;
        vkasRayQueryInitialize(&q, t.tlas->handle, 0, 0xFF, kOrigin.data(), 0.0f, kDown.data(), 10.0f);
        while (vkasRayQueryProceed(&q)) vkasRayQueryConfirmIntersection(&q);
        ASSERT_EQ(vkasRayQueryGetIntersectionType(&q, VK_TRUE), uint32_t(VKAS_COMMITTED_INTERSECTION_TRIANGLE));
        auto* out = reinterpret_cast<float(*)[3]>(t.hostCopy(nullptr, 36));
        t.call([&] {
            vkasRayQueryGetIntersectionTriangleVertexPositions(&q, VK_TRUE, out);  // blas lacks ALLOW_DATA_ACCESS
            return V();
        });
        (void)vk;
        (void)dev;
    });

    // ---- vkasTraceRays and vkasTraceRaysProcedural ----------------------------------------------------------------
    for (bool procedural : {false, true}) {
        const std::string cmd = procedural ? "vkasTraceRaysProcedural" : "vkasTraceRays";
        c.push_back(Case{"VUID-" + cmd + "-device-parameter", "", [procedural](Fixture& t, const vt::Commands&, VkDevice) {
                             trace(t, t.bogus<VkDevice>(), t.tlas->handle, VKAS_TRACE_MODE_CLOSEST_HIT, 0, {downRay()},
                                   procedural);
                         }});
        c.push_back(Case{"VUID-" + cmd + "-topLevel-parameter", "", [procedural](Fixture& t, const vt::Commands&, VkDevice dev) {
                             trace(t, dev, t.bogus<VkAccelerationStructureKHR>(), VKAS_TRACE_MODE_CLOSEST_HIT, 0,
                                   {downRay()}, procedural);
                         }});
        c.push_back(Case{"VUID-" + cmd + "-mode-parameter", "", [procedural](Fixture& t, const vt::Commands&, VkDevice dev) {
                             trace(t, dev, t.tlas->handle, VkasTraceMode(7), 0, {downRay()}, procedural);
                         }});
        c.push_back(Case{"VUID-" + cmd + "-pRays-parameter", "", [procedural](Fixture& t, const vt::Commands&, VkDevice dev) {
                             trace(t, dev, t.tlas->handle, VKAS_TRACE_MODE_CLOSEST_HIT, 0, {downRay()}, procedural,
                                   /*nullRays=*/true);
                         }});
    }
    CASE_V("VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06350", "batch", {
        trace(t, dev, t.tlas->handle, VKAS_TRACE_MODE_CLOSEST_HIT, 0, {downRay(), downRay(5.0f, 1.0f)});
        (void)vk;
    });
    CASE_V("VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06889", "batch", {
        trace(t, dev, t.tlas->handle, VKAS_TRACE_MODE_ANY_HIT, VKAS_RAY_FLAG_SKIP_TRIANGLES | VKAS_RAY_FLAG_SKIP_AABBS,
              {downRay()});
        (void)vk;
    });
    CASE_V("VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06352", "batch", {
        trace(t, dev, t.blas->handle, VKAS_TRACE_MODE_CLOSEST_HIT, 0, {downRay()});
        (void)vk;
    });
}

}  // namespace vu
