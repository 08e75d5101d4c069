// CTS `acceleration_structures.host_threading` and the `build.cpuht_*` cases: builds handed to a
// VkDeferredOperationKHR (VK_KHR_deferred_host_operations) and completed by 1 to 8 joined threads. Checks the
// operation's states and results, that nothing runs before a thread joins, and that the structure's bytes are the
// same as a build without deferral whatever the number of threads. Every test prints its seed.
#include <algorithm>
#include <atomic>
#include <cstring>
#include <string>
#include <thread>

#include "api/deferred_operation.hpp"

#include "meshes.hpp"
#include "vkas_test.hpp"

using namespace vt;

namespace {

// The header's usedSize (docs/FORMAT.md): bytes 16-23 of a structure.
uint64_t usedSize(const AccelStruct* as) {
    uint64_t used;
    std::memcpy(&used, as->data() + 16, sizeof used);
    return used;
}

std::vector<uint8_t> structureBytes(const AccelStruct* as) {
    return std::vector<uint8_t>(as->data(), as->data() + usedSize(as));
}

}  // namespace

class host_threading : public VkasTest {
  protected:
    void SetUp() override {
        VkasTest::SetUp();
#define LOAD(name) name = reinterpret_cast<PFN_##name>(vkasGetDeviceProcAddr(device, #name)); ASSERT_NE(name, nullptr);
        LOAD(vkCreateDeferredOperationKHR)
        LOAD(vkDestroyDeferredOperationKHR)
        LOAD(vkGetDeferredOperationMaxConcurrencyKHR)
        LOAD(vkGetDeferredOperationResultKHR)
        LOAD(vkDeferredOperationJoinKHR)
#undef LOAD
    }

    VkDeferredOperationKHR createOperation() {
        VkDeferredOperationKHR op = VK_NULL_HANDLE;
        EXPECT_EQ(vkCreateDeferredOperationKHR(device, nullptr, &op), VK_SUCCESS);
        return op;
    }

    // Defers the builds on `op`, checks that nothing ran, then joins with `threads` threads (each joins again after
    // VK_THREAD_IDLE_KHR) and checks the join results. Registers the results like VkasTest::submit.
    void buildDeferred(const std::vector<PreparedBuild*>& builds, VkDeferredOperationKHR op, uint32_t threads) {
        std::vector<VkAccelerationStructureBuildGeometryInfoKHR> infos;
        std::vector<const VkAccelerationStructureBuildRangeInfoKHR*> ranges;
        for (auto* b : builds) infos.push_back(b->info), ranges.push_back(b->ranges.data());
        ASSERT_EQ(vk.vkBuildAccelerationStructuresKHR(device, op, uint32_t(infos.size()), infos.data(), ranges.data()),
                  VK_OPERATION_DEFERRED_KHR);
        // Pending: nothing has run until a thread joins.
        EXPECT_EQ(vkGetDeferredOperationResultKHR(device, op), VK_NOT_READY);
        EXPECT_GT(vkGetDeferredOperationMaxConcurrencyKHR(device, op), 0u);
        for (auto* b : builds)
            EXPECT_TRUE(std::all_of(b->as->data(), b->as->data() + 64, [&](uint8_t x) { return x == b->as->poison; }))
                << "the deferred build wrote its destination before any thread joined";

        std::vector<VkResult> results(threads);
        std::atomic<uint32_t> idleJoins{0};
        auto joiner = [&](uint32_t t) {
            VkResult r;
            while ((r = vkDeferredOperationJoinKHR(device, op)) == VK_THREAD_IDLE_KHR) {
                ++idleJoins;
                std::this_thread::yield();
            }
            results[t] = r;
        };
        std::vector<std::thread> pool;
        for (uint32_t t = 1; t < threads; ++t) pool.emplace_back(joiner, t);
        joiner(0);
        for (auto& th : pool) th.join();
        uint32_t successes = 0;
        for (VkResult r : results) {
            EXPECT_TRUE(r == VK_SUCCESS || r == VK_THREAD_DONE_KHR) << "join returned " << r;
            successes += r == VK_SUCCESS;
        }
        EXPECT_GE(successes, 1u) << "no joined thread saw the operation complete";
        EXPECT_EQ(vkGetDeferredOperationResultKHR(device, op), VK_SUCCESS);
        EXPECT_EQ(vkGetDeferredOperationMaxConcurrencyKHR(device, op), 0u);
        // Joining a complete operation reports it complete.
        EXPECT_EQ(vkDeferredOperationJoinKHR(device, op), VK_SUCCESS);
        for (auto* b : builds) {
            if (b->blas) {
                b->as->blas = b->blas;
                blasRegistry[b->as->reference()] = b->blas;
            }
            if (b->scene) b->as->scene = b->scene;
        }
    }

    // The serialized form of a structure (vkCopyAccelerationStructureToMemoryKHR), at a 16-byte aligned address.
    std::vector<uint8_t> serializedBytes(const AccelStruct* as) {
        uint64_t size = 0;
        if (vk.vkWriteAccelerationStructuresPropertiesKHR(device, 1, &as->handle,
                                                          VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_SIZE_KHR,
                                                          sizeof size, &size, sizeof size) != VK_SUCCESS)
            return {};
        std::vector<uint64_t> storage(size_t(size + 7) / 8);
        VkCopyAccelerationStructureToMemoryInfoKHR info{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_TO_MEMORY_INFO_KHR};
        info.src = as->handle;
        info.dst.hostAddress = storage.data();
        info.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_SERIALIZE_KHR;
        if (vk.vkCopyAccelerationStructureToMemoryKHR(device, VK_NULL_HANDLE, &info) != VK_SUCCESS) return {};
        const auto* bytes = reinterpret_cast<const uint8_t*>(storage.data());
        return std::vector<uint8_t>(bytes, bytes + size);
    }

    PFN_vkCreateDeferredOperationKHR vkCreateDeferredOperationKHR = nullptr;
    PFN_vkDestroyDeferredOperationKHR vkDestroyDeferredOperationKHR = nullptr;
    PFN_vkGetDeferredOperationMaxConcurrencyKHR vkGetDeferredOperationMaxConcurrencyKHR = nullptr;
    PFN_vkGetDeferredOperationResultKHR vkGetDeferredOperationResultKHR = nullptr;
    PFN_vkDeferredOperationJoinKHR vkDeferredOperationJoinKHR = nullptr;
};

TEST_F(host_threading, new_operation_is_complete) {
    VkDeferredOperationKHR op = createOperation();
    EXPECT_EQ(vkGetDeferredOperationResultKHR(device, op), VK_SUCCESS);
    EXPECT_EQ(vkGetDeferredOperationMaxConcurrencyKHR(device, op), 0u);
    EXPECT_EQ(vkDeferredOperationJoinKHR(device, op), VK_SUCCESS);
    vkDestroyDeferredOperationKHR(device, op, nullptr);
    EXPECT_TRUE(takeValidationErrors().empty());
}

// The same large bottom-level and top-level builds with 1, 2, 3, 4 and 8 joined threads: byte-identical to the
// build without deferral, and correct by the oracle.
TEST_F(host_threading, deterministic_across_joined_threads) {
    const Mesh mesh = terrain(200, rng);  // 80,000 triangles: the builder splits the work into tasks
    auto geometry = makeGeometry(mesh, VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
    AccelStruct* reference = buildBlas(*geometry);
    const std::vector<uint8_t> expected = structureBytes(reference);
    std::vector<Instance> instances(20000);
    for (auto& inst : instances) {
        inst.transform = randomTransform(rng, 0.01f, 0.05f, rng.coin(0.2), 50.0f);
        inst.customIndex = rng.u32() & 0xFFFFFF;
        inst.blas = reference;
    }
    AccelStruct* referenceTlas = buildTlas(instances);
    const std::vector<uint8_t> expectedTlas = structureBytes(referenceTlas);

    VkDeferredOperationKHR op = createOperation();
    for (uint32_t threads : {1u, 2u, 3u, 4u, 8u}) {
        SCOPED_TRACE("joined threads: " + std::to_string(threads));
        auto blas = prepareBlas({geometry.get()});
        buildDeferred({blas.get()}, op, threads);
        EXPECT_TRUE(structureBytes(blas->as) == expected) << "bottom level differs from the build without deferral";
        auto tlas = prepareTlas(instances);
        buildDeferred({tlas.get()}, op, threads);
        EXPECT_TRUE(structureBytes(tlas->as) == expectedTlas) << "top level differs from the build without deferral";
        if (threads == 3) {
            AccelStruct* single = buildSingleInstanceTlas(blas->as);
            checkRays(single, randomRays(*single->scene, 300));
        }
    }
    vkDestroyDeferredOperationKHR(device, op, nullptr);
    EXPECT_TRUE(takeValidationErrors().empty());
}

// build fast_build: PREFER_FAST_BUILD structures (the Morton-code builder), bottom and top level, deferred and
// completed by 1 to 8 joined threads: byte-identical to the build without deferral.
TEST_F(host_threading, fast_build_deterministic_across_joined_threads) {
    const Mesh mesh = terrain(150, rng);  // 45,000 triangles
    auto geometry = makeGeometry(mesh, VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
    BuildOptions fast;
    fast.flags = VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR;
    AccelStruct* reference = buildBlas(*geometry, fast);
    const std::vector<uint8_t> expected = structureBytes(reference);
    std::vector<Instance> instances(12000);
    for (auto& inst : instances) {
        inst.transform = randomTransform(rng, 0.01f, 0.05f, rng.coin(0.2), 50.0f);
        inst.blas = reference;
    }
    AccelStruct* referenceTlas = buildTlas(instances, fast);
    const std::vector<uint8_t> expectedTlas = structureBytes(referenceTlas);

    VkDeferredOperationKHR op = createOperation();
    for (uint32_t threads : {1u, 2u, 3u, 8u}) {
        SCOPED_TRACE("joined threads: " + std::to_string(threads));
        auto blas = prepareBlas({geometry.get()}, fast);
        buildDeferred({blas.get()}, op, threads);
        EXPECT_TRUE(structureBytes(blas->as) == expected) << "bottom level differs from the build without deferral";
        auto tlas = prepareTlas(instances, fast);
        buildDeferred({tlas.get()}, op, threads);
        EXPECT_TRUE(structureBytes(tlas->as) == expectedTlas) << "top level differs from the build without deferral";
    }
    AccelStruct* single = buildSingleInstanceTlas(reference);
    checkRays(single, randomRays(*single->scene, 300));
    vkDestroyDeferredOperationKHR(device, op, nullptr);
    EXPECT_TRUE(takeValidationErrors().empty());
}

// cpuht: many bottom-level builds in one deferred call, spread over the joined threads.
TEST_F(host_threading, many_infos_one_operation) {
    std::vector<std::unique_ptr<GeometryData>> geometries;
    std::vector<std::unique_ptr<PreparedBuild>> builds;
    std::vector<PreparedBuild*> pointers;
    for (int i = 0; i < 24; ++i) {
        geometries.push_back(makeGeometry(triangleSoup(200 + 100 * i, rng, 0.2f), VK_INDEX_TYPE_UINT32,
                                          i % 2 ? VK_GEOMETRY_OPAQUE_BIT_KHR : 0));
        builds.push_back(prepareBlas({geometries.back().get()}));
        pointers.push_back(builds.back().get());
    }
    VkDeferredOperationKHR op = createOperation();
    buildDeferred(pointers, op, 4);
    std::vector<Instance> instances;
    for (auto& b : builds) {
        Instance inst;
        inst.transform = randomTransform(rng, 0.5f, 1.5f, false, 4.0f);
        inst.blas = b->as;
        instances.push_back(inst);
    }
    AccelStruct* tlas = buildTlas(instances);
    EXPECT_GT(checkRays(tlas, randomRays(*tlas->scene, 600)), 0u);
    vkDestroyDeferredOperationKHR(device, op, nullptr);
    EXPECT_TRUE(takeValidationErrors().empty());
}

TEST_F(host_threading, validation) {
    auto geometry = makeGeometry(triangleSoup(500, rng, 0.2f), VK_INDEX_TYPE_UINT32);
    auto blas = prepareBlas({geometry.get()});
    VkDeferredOperationKHR op = createOperation();
    const VkAccelerationStructureBuildRangeInfoKHR* ranges = blas->ranges.data();
    ASSERT_EQ(vk.vkBuildAccelerationStructuresKHR(device, op, 1, &blas->info, &ranges), VK_OPERATION_DEFERRED_KHR);
    // Destroying a pending operation: reported, and the operation survives.
    vkDestroyDeferredOperationKHR(device, op, nullptr);
    auto errors = takeValidationErrors();
    ASSERT_EQ(errors.size(), 1u);
    EXPECT_NE(errors[0].find("VUID-vkDestroyDeferredOperationKHR-operation-03436"), std::string::npos) << errors[0];
    // Deferring another command on it while pending: reported, nothing deferred.
    auto other = prepareBlas({geometry.get()});
    const VkAccelerationStructureBuildRangeInfoKHR* otherRanges = other->ranges.data();
    EXPECT_EQ(vk.vkBuildAccelerationStructuresKHR(device, op, 1, &other->info, &otherRanges),
              VK_ERROR_VALIDATION_FAILED_EXT);
    errors = takeValidationErrors();
    ASSERT_EQ(errors.size(), 1u);
    EXPECT_NE(errors[0].find("VUID-vkBuildAccelerationStructuresKHR-deferredOperation-03678"), std::string::npos)
        << errors[0];
    EXPECT_EQ(vkDeferredOperationJoinKHR(device, op), VK_SUCCESS);
    EXPECT_EQ(vkGetDeferredOperationResultKHR(device, op), VK_SUCCESS);
    // Not a deferred operation at all.
    EXPECT_EQ(vk.vkBuildAccelerationStructuresKHR(device, reinterpret_cast<VkDeferredOperationKHR>(blas->as->handle), 1,
                                                  &other->info, &otherRanges),
              VK_ERROR_VALIDATION_FAILED_EXT);
    errors = takeValidationErrors();
    ASSERT_EQ(errors.size(), 1u);
    EXPECT_NE(errors[0].find("VUID-vkBuildAccelerationStructuresKHR-deferredOperation-parameter"), std::string::npos)
        << errors[0];
    vkDestroyDeferredOperationKHR(device, op, nullptr);
    EXPECT_TRUE(takeValidationErrors().empty());
}

// Copies, serialization and deserialization handed to a deferred operation: nothing happens before a join, and the
// result is the same as without deferral.
TEST_F(host_threading, deferred_copy_serialize_deserialize) {
    auto geometry = makeGeometry(triangleSoup(3000, rng, 0.2f), VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
    BuildOptions opt;
    opt.flags = VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR;
    AccelStruct* blas = buildBlas(*geometry, opt);
    AccelStruct* tlas = buildSingleInstanceTlas(blas);
    const std::vector<uint8_t> original = structureBytes(blas);
    VkDeferredOperationKHR op = createOperation();
    auto joinAll = [&](uint32_t threads) {
        std::vector<std::thread> pool;
        std::atomic<uint32_t> successes{0};
        for (uint32_t t = 0; t < threads; ++t)
            pool.emplace_back([&] {
                VkResult r;
                while ((r = vkDeferredOperationJoinKHR(device, op)) == VK_THREAD_IDLE_KHR) std::this_thread::yield();
                successes += r == VK_SUCCESS;
            });
        for (auto& th : pool) th.join();
        EXPECT_GE(successes.load(), 1u);
        EXPECT_EQ(vkGetDeferredOperationResultKHR(device, op), VK_SUCCESS);
    };

    // CLONE.
    AccelStruct* clone = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, blas->size, {});
    VkCopyAccelerationStructureInfoKHR copy{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_INFO_KHR};
    copy.src = blas->handle;
    copy.dst = clone->handle;
    copy.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_CLONE_KHR;
    ASSERT_EQ(vk.vkCopyAccelerationStructureKHR(device, op, &copy), VK_OPERATION_DEFERRED_KHR);
    EXPECT_EQ(clone->data()[0], clone->poison) << "the deferred copy ran before any thread joined";
    joinAll(2);
    EXPECT_TRUE(structureBytes(clone) == original);

    // SERIALIZE, compared with a serialization without deferral.
    const size_t blobSize = original.size() + 4096;
    std::vector<uint8_t> direct(blobSize + 64, 0), deferred(blobSize + 64, 0);
    auto aligned = [](std::vector<uint8_t>& v) {
        return reinterpret_cast<uint8_t*>((reinterpret_cast<uintptr_t>(v.data()) + 63) & ~uintptr_t(63));
    };
    VkCopyAccelerationStructureToMemoryInfoKHR ser{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_TO_MEMORY_INFO_KHR};
    ser.src = blas->handle;
    ser.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_SERIALIZE_KHR;
    ser.dst.hostAddress = aligned(direct);
    ASSERT_EQ(vk.vkCopyAccelerationStructureToMemoryKHR(device, VK_NULL_HANDLE, &ser), VK_SUCCESS);
    ser.dst.hostAddress = aligned(deferred);
    ASSERT_EQ(vk.vkCopyAccelerationStructureToMemoryKHR(device, op, &ser), VK_OPERATION_DEFERRED_KHR);
    joinAll(3);
    uint64_t serializedSize;
    std::memcpy(&serializedSize, aligned(direct) + 32, 8);
    ASSERT_LE(serializedSize, blobSize);
    EXPECT_EQ(std::memcmp(aligned(direct), aligned(deferred), size_t(serializedSize)), 0);

    // DESERIALIZE into a new structure, which then traces like the original.
    AccelStruct* loaded = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, blas->size, {});
    VkCopyMemoryToAccelerationStructureInfoKHR de{VK_STRUCTURE_TYPE_COPY_MEMORY_TO_ACCELERATION_STRUCTURE_INFO_KHR};
    de.src.hostAddress = aligned(deferred);
    de.dst = loaded->handle;
    de.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_DESERIALIZE_KHR;
    ASSERT_EQ(vk.vkCopyMemoryToAccelerationStructureKHR(device, op, &de), VK_OPERATION_DEFERRED_KHR);
    joinAll(1);
    EXPECT_TRUE(structureBytes(loaded) == original);
    loaded->blas = blas->blas;
    blasRegistry[loaded->reference()] = blas->blas;
    AccelStruct* loadedTlas = buildSingleInstanceTlas(loaded);
    const auto rays = randomRays(*tlas->scene, 200);
    for (const auto& r : rays) EXPECT_TRUE(identical(traceClosest(tlas, r), traceClosest(loadedTlas, r)));
    vkDestroyDeferredOperationKHR(device, op, nullptr);
    EXPECT_TRUE(takeValidationErrors().empty());
}

// Every geometry type: a deferred build joined by 1, 2, 3, 8 and all hardware threads serializes to the same bytes
// as the build without deferral (the serialized form holds the whole structure, so equal blobs mean equal
// structures).
TEST_F(host_threading, serialized_bytes_independent_of_threads_for_every_geometry_type) {
    const uint32_t n = 20000;  // above the size at which builds split into tasks
    std::vector<float> positions, radii, positions1;
    std::vector<VkAabbPositionsKHR> boxes;
    for (uint32_t i = 0; i < 3 * n; ++i) {
        const float x = rng.uniformf(-10, 10), y = rng.uniformf(-10, 10), z = rng.uniformf(-10, 10);
        positions.insert(positions.end(), {x, y, z});
        positions1.insert(positions1.end(), {x + rng.uniformf(-0.1f, 0.1f), y, z + rng.uniformf(-0.1f, 0.1f)});
        radii.push_back(rng.uniformf(0.01f, 0.1f));
    }
    for (uint32_t i = 0; i < n; ++i) {
        const float x = rng.uniformf(-10, 10), y = rng.uniformf(-10, 10), z = rng.uniformf(-10, 10);
        boxes.push_back({x, y, z, x + rng.uniformf(0.01f, 0.2f), y + rng.uniformf(0.01f, 0.2f), z + rng.uniformf(0.01f, 0.2f)});
    }
    struct Kind {
        const char* name;
        VkAccelerationStructureGeometryKHR geometry;
        uint32_t primitives;
        BuildOptions options;
    };
    std::vector<Kind> kinds;
    VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
    // Triangles: a soup (3 vertices each), and the same with time-1 positions (motion).
    g.geometryType = VK_GEOMETRY_TYPE_TRIANGLES_KHR;
    auto& t = g.geometry.triangles;
    t.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR;
    t.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
    t.vertexData.hostAddress = positions.data();
    t.vertexStride = 12;
    t.maxVertex = 3 * n - 1;
    t.indexType = VK_INDEX_TYPE_NONE_KHR;
    kinds.push_back({"triangles", g, n, {}});
    VkAccelerationStructureGeometryMotionTrianglesDataNV motion{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_MOTION_TRIANGLES_DATA_NV};
    motion.vertexData.hostAddress = positions1.data();
    VkAccelerationStructureGeometryKHR gm = g;
    gm.geometry.triangles.pNext = &motion;
    BuildOptions motionOptions;
    motionOptions.flags = VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV;
    motionOptions.createFlags = VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV;
    kinds.push_back({"motion triangles", gm, n, motionOptions});
    // AABBs.
    VkAccelerationStructureGeometryKHR ga{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
    ga.geometryType = VK_GEOMETRY_TYPE_AABBS_KHR;
    ga.geometry.aabbs.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_AABBS_DATA_KHR;
    ga.geometry.aabbs.data.hostAddress = boxes.data();
    ga.geometry.aabbs.stride = sizeof(VkAabbPositionsKHR);
    kinds.push_back({"aabbs", ga, n, {}});
    // Spheres and linear swept spheres (LIST of pairs without indices).
    VkAccelerationStructureGeometrySpheresDataNV spheres{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_SPHERES_DATA_NV};
    spheres.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
    spheres.vertexData.hostAddress = positions.data();
    spheres.vertexStride = 12;
    spheres.radiusFormat = VK_FORMAT_R32_SFLOAT;
    spheres.radiusData.hostAddress = radii.data();
    spheres.radiusStride = 4;
    spheres.indexType = VK_INDEX_TYPE_NONE_KHR;
    VkAccelerationStructureGeometryKHR gs{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR, &spheres};
    gs.geometryType = VK_GEOMETRY_TYPE_SPHERES_NV;
    kinds.push_back({"spheres", gs, n, {}});
    VkAccelerationStructureGeometryLinearSweptSpheresDataNV lss{
        VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_LINEAR_SWEPT_SPHERES_DATA_NV};
    lss.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
    lss.vertexData.hostAddress = positions.data();
    lss.vertexStride = 12;
    lss.radiusFormat = VK_FORMAT_R32_SFLOAT;
    lss.radiusData.hostAddress = radii.data();
    lss.radiusStride = 4;
    lss.indexType = VK_INDEX_TYPE_NONE_KHR;
    lss.indexingMode = VK_RAY_TRACING_LSS_INDEXING_MODE_LIST_NV;
    lss.endCapsMode = VK_RAY_TRACING_LSS_PRIMITIVE_END_CAPS_MODE_CHAINED_NV;
    VkAccelerationStructureGeometryKHR gl{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR, &lss};
    gl.geometryType = VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV;
    kinds.push_back({"linear swept spheres", gl, n, {}});

    const uint32_t hardware = std::max(1u, std::thread::hardware_concurrency());
    VkDeferredOperationKHR op = createOperation();
    std::vector<AccelStruct*> built;
    for (const Kind& k : kinds) {
        SCOPED_TRACE(k.name);
        VkAccelerationStructureBuildRangeInfoKHR range{k.primitives, 0, 0, 0};
        AccelStruct* reference = buildBlas({k.geometry}, {range}, k.options);
        const std::vector<uint8_t> expected = serializedBytes(reference);
        ASSERT_FALSE(expected.empty());
        for (uint32_t threads : {1u, 2u, 3u, 8u, hardware}) {
            auto b = prepareBlas({k.geometry}, {range}, k.options);
            buildDeferred({b.get()}, op, threads);
            EXPECT_TRUE(serializedBytes(b->as) == expected) << threads << " joined threads";
        }
        built.push_back(reference);
    }
    // A top level over all of them, and a motion top level, the same way.
    std::vector<Instance> instances;
    for (uint32_t i = 0; i < 12000; ++i) {
        Instance inst;
        inst.transform = randomTransform(rng, 0.05f, 0.2f, rng.coin(0.2), 100.0f);
        inst.blas = built[i % built.size()];
        instances.push_back(inst);
    }
    AccelStruct* referenceTlas = buildTlas(instances);
    const std::vector<uint8_t> expectedTlas = serializedBytes(referenceTlas);
    for (uint32_t threads : {1u, 2u, 3u, 8u, hardware}) {
        auto b = prepareTlas(instances);
        buildDeferred({b.get()}, op, threads);
        EXPECT_TRUE(serializedBytes(b->as) == expectedTlas) << "top level, " << threads << " joined threads";
    }
    vkDestroyDeferredOperationKHR(device, op, nullptr);
    EXPECT_TRUE(takeValidationErrors().empty());
}

// The order in which the joined threads are handed the work of an operation (api/deferred_operation.hpp), seen on
// one joined thread: a thread that waits for the items it spread runs only those and the items spread below them,
// never another task's or a sibling's, which would hold up the rest of the work waiting for it. `spreads` says what
// the operation's two tasks do; the log is what one joined thread ran, in order.
namespace {
std::vector<std::string> runOnOneThread(VkDevice device, VkDeferredOperationKHR handle,
                                        PFN_vkDeferredOperationJoinKHR join, bool nested) {
    auto* op = vkas::fromHandle<vkas::DeferredOperation>(handle);
    std::vector<std::string> log;
    const vkas::ParallelFor& spread = op->parallelFor();
    {
        vkas::ScopedHostMemory memory(op->stateMemory());
        vkas::HostVector<vkas::DeferredOperation::Task> tasks;
        tasks.emplace_back([&log, &spread, nested] {
            log.push_back("task0");
            spread(2, [&](uint32_t i) {
                log.push_back("x" + std::to_string(i));
                if (nested && i == 0) {
                    spread(2, [&](uint32_t j) { log.push_back("y" + std::to_string(j)); });
                    log.push_back("x0 done");
                }
            });
        });
        tasks.emplace_back([&log] { log.push_back("task1"); });
        op->start(std::move(tasks), [] { return VK_SUCCESS; }, 1);
    }
    VkResult r;
    while ((r = join(device, handle)) == VK_THREAD_IDLE_KHR) {}
    EXPECT_EQ(r, VK_SUCCESS);
    return log;
}
}  // namespace

TEST_F(host_threading, waiting_thread_runs_only_work_below_it) {
    VkDeferredOperationKHR op = createOperation();
    // Before, the waiting thread took the next queued item: task1 ran inside task0's spread, and x1 inside x0's.
    EXPECT_EQ(runOnOneThread(device, op, vkDeferredOperationJoinKHR, false),
              (std::vector<std::string>{"task0", "x0", "x1", "task1"}));
    EXPECT_EQ(runOnOneThread(device, op, vkDeferredOperationJoinKHR, true),
              (std::vector<std::string>{"task0", "x0", "y0", "y1", "x0 done", "x1", "task1"}));
    vkDestroyDeferredOperationKHR(device, op, nullptr);
    EXPECT_TRUE(takeValidationErrors().empty());
}

// Nested spreads three deep, of random widths, joined by 4 threads: every item runs exactly once and the operation
// completes (a waiting thread that may not help elsewhere must never wait for work nobody can take).
TEST_F(host_threading, nested_spreads_complete_on_joined_threads) {
    VkDeferredOperationKHR handle = createOperation();
    auto* op = vkas::fromHandle<vkas::DeferredOperation>(handle);
    const vkas::ParallelFor& spread = op->parallelFor();
    for (int round = 0; round < 20; ++round) {
        const uint32_t w0 = 1 + rng.below(8), w1 = 1 + rng.below(8), w2 = 1 + rng.below(8);
        std::atomic<uint32_t> leaves{0};
        {
            vkas::ScopedHostMemory memory(op->stateMemory());
            vkas::HostVector<vkas::DeferredOperation::Task> tasks;
            for (int t = 0; t < 3; ++t)
                tasks.emplace_back([&] {
                    spread(w0, [&](uint32_t) {
                        spread(w1, [&](uint32_t) { spread(w2, [&](uint32_t) { ++leaves; }); });
                    });
                });
            op->start(std::move(tasks), [] { return VK_SUCCESS; }, 1);
        }
        std::vector<std::thread> pool;
        for (int t = 0; t < 4; ++t)
            pool.emplace_back([&] {
                while (vkDeferredOperationJoinKHR(device, handle) == VK_THREAD_IDLE_KHR) std::this_thread::yield();
            });
        for (auto& th : pool) th.join();
        ASSERT_EQ(leaves.load(), 3 * w0 * w1 * w2) << "round " << round;
        ASSERT_EQ(vkGetDeferredOperationResultKHR(device, handle), VK_SUCCESS);
    }
    vkDestroyDeferredOperationKHR(device, handle, nullptr);
    EXPECT_TRUE(takeValidationErrors().empty());
}
