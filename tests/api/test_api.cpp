// Basic API behaviour: commands, buffers and memory, addresses, build sizes, byte copies, determinism, several
// infos in one build call, validation, concurrency.
#include <cmath>
#include <cstring>
#include <thread>

#include "meshes.hpp"

using namespace vt;

namespace {
// A small random scene: a BLAS of random triangles, instanced a few times with random transforms.
struct SmallScene {
    std::unique_ptr<GeometryData> geometry;
    AccelStruct* blas = nullptr;
    AccelStruct* tlas = nullptr;
    std::vector<Instance> instances;
};
}  // namespace

class api : public VkasTest {
  protected:
    SmallScene makeScene(int triangles = 200, int instances = 4, const BuildOptions& opt = {}) {
        SmallScene s;
        s.geometry = makeGeometry(triangleSoup(triangles, rng, 0.3f), VK_INDEX_TYPE_UINT32);
        s.blas = buildBlas(*s.geometry, opt);
        for (int i = 0; i < instances; ++i) {
            Instance inst;
            inst.transform = randomTransform(rng, 0.5f, 2.0f, rng.coin(), 3.0f);
            inst.customIndex = rng.u32() & 0xFFFFFF;
            inst.blas = s.blas;
            s.instances.push_back(inst);
        }
        s.tlas = buildTlas(s.instances, opt);
        return s;
    }
    std::vector<Hit> traceAll(VkAccelerationStructureKHR tlas, const std::vector<oracle::Ray>& rays) {
        std::vector<Hit> out;
        for (const auto& r : rays) out.push_back(query(tlas, r, 0, 0xFF).committed);
        return out;
    }
};

TEST_F(api, proc_addr) {
    // The fixture already loaded every command of the issue; unknown names give NULL.
    EXPECT_EQ(vkasGetDeviceProcAddr(device, "vkNotAVulkanCommand"), nullptr);
    EXPECT_EQ(vkasGetDeviceProcAddr(device, ""), nullptr);
    EXPECT_EQ(reinterpret_cast<void*>(vkasGetDeviceProcAddr(device, "vkCreateBuffer")),
              reinterpret_cast<void*>(vk.vkCreateBuffer));
}

TEST_F(api, features_and_properties) {
    VkPhysicalDeviceAccelerationStructureFeaturesKHR f{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ACCELERATION_STRUCTURE_FEATURES_KHR};
    vkasGetAccelerationStructureFeatures(device, &f);
    EXPECT_EQ(f.accelerationStructure, VK_TRUE);
    EXPECT_EQ(f.accelerationStructureHostCommands, VK_TRUE);
    VkPhysicalDeviceAccelerationStructurePropertiesKHR p{
        VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ACCELERATION_STRUCTURE_PROPERTIES_KHR};
    vkasGetAccelerationStructureProperties(device, &p);
    EXPECT_GE(p.maxGeometryCount, (1ull << 24) - 1);
    EXPECT_GE(p.maxInstanceCount, (1ull << 24) - 1);
    EXPECT_GE(p.maxPrimitiveCount, (1ull << 29) - 1);
    EXPECT_LE(p.maxGeometryCount, 0xFFFFFFFFull);
    EXPECT_LE(p.maxInstanceCount, 0xFFFFFFFFull);
    EXPECT_LE(p.maxPrimitiveCount, 0xFFFFFFFFull);
    EXPECT_GE(p.maxPerStageDescriptorAccelerationStructures, 16u);
    EXPECT_GE(p.maxDescriptorSetAccelerationStructures, 16u);
    EXPECT_LE(p.minAccelerationStructureScratchOffsetAlignment, 256u);
    EXPECT_NE(p.minAccelerationStructureScratchOffsetAlignment, 0u);
    EXPECT_EQ(p.minAccelerationStructureScratchOffsetAlignment & (p.minAccelerationStructureScratchOffsetAlignment - 1), 0u);
}

TEST_F(api, buffer_memory) {
    for (VkDeviceSize size : {VkDeviceSize(1), VkDeviceSize(1000), VkDeviceSize(1 << 20)}) {
        VkBuffer buffer = VK_NULL_HANDLE;
        VkBufferCreateInfo ci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
        ci.size = size;
        ci.usage = kAsBufferUsage | VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
        ASSERT_EQ(vk.vkCreateBuffer(device, &ci, nullptr, &buffer), VK_SUCCESS);
        VkMemoryRequirements req{};
        vk.vkGetBufferMemoryRequirements(device, buffer, &req);
        EXPECT_GE(req.size, size);
        EXPECT_TRUE(req.memoryTypeBits & 1u);
        ASSERT_NE(req.alignment, 0u);
        EXPECT_EQ(req.alignment & (req.alignment - 1), 0u) << "alignment must be a power of two";
        // Bind at a non-zero aligned offset inside a larger allocation.
        VkMemoryAllocateFlagsInfo flagsInfo{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
        flagsInfo.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
        VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
        ai.pNext = &flagsInfo;
        ai.allocationSize = req.size + 3 * req.alignment;
        ai.memoryTypeIndex = 0;
        VkDeviceMemory memory = VK_NULL_HANDLE;
        ASSERT_EQ(vk.vkAllocateMemory(device, &ai, nullptr, &memory), VK_SUCCESS);
        const VkDeviceSize offset = 2 * req.alignment;
        ASSERT_EQ(vk.vkBindBufferMemory(device, buffer, memory, offset), VK_SUCCESS);
        void* p = nullptr;
        ASSERT_EQ(vk.vkMapMemory(device, memory, 0, VK_WHOLE_SIZE, 0, &p), VK_SUCCESS);
        ASSERT_NE(p, nullptr);
        std::memset(p, 0xAA, ai.allocationSize);  // the whole allocation is writable host memory
        VkBufferDeviceAddressInfo bi{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO};
        bi.buffer = buffer;
        EXPECT_EQ(vk.vkGetBufferDeviceAddress(device, &bi), VkDeviceAddress(uintptr_t(p) + offset));
        vk.vkUnmapMemory(device, memory);
        // Mapping at an offset returns the allocation's address plus the offset.
        void* p2 = nullptr;
        ASSERT_EQ(vk.vkMapMemory(device, memory, offset, VK_WHOLE_SIZE, 0, &p2), VK_SUCCESS);
        EXPECT_EQ(uintptr_t(p2), uintptr_t(p) + offset);
        EXPECT_EQ(static_cast<uint8_t*>(p2)[0], 0xAA);
        vk.vkUnmapMemory(device, memory);
        vk.vkDestroyBuffer(device, buffer, nullptr);
        vk.vkFreeMemory(device, memory, nullptr);
    }
}

TEST_F(api, as_device_address) {
    SmallScene s = makeScene(50, 2);
    for (const AccelStruct* as : {s.blas, s.tlas}) {
        VkAccelerationStructureDeviceAddressInfoKHR ai{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_DEVICE_ADDRESS_INFO_KHR};
        ai.accelerationStructure = as->handle;
        const VkDeviceAddress a = vk.vkGetAccelerationStructureDeviceAddressKHR(device, &ai);
        EXPECT_NE(a, 0u);
        EXPECT_EQ(a % 256, 0u);
    }
    // GENERIC structures in one buffer: addresses differ exactly by the difference of their offsets.
    HostBuffer* buf = createBuffer(4096);
    VkAccelerationStructureKHR h[2] = {};
    const VkDeviceSize offsets[2] = {256, 1792};
    VkDeviceAddress addr[2] = {};
    for (int i = 0; i < 2; ++i) {
        VkAccelerationStructureCreateInfoKHR ci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
        ci.buffer = buf->buffer;
        ci.offset = offsets[i];
        ci.size = 1024;
        ci.type = VK_ACCELERATION_STRUCTURE_TYPE_GENERIC_KHR;
        ASSERT_EQ(vk.vkCreateAccelerationStructureKHR(device, &ci, nullptr, &h[i]), VK_SUCCESS);
        VkAccelerationStructureDeviceAddressInfoKHR ai{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_DEVICE_ADDRESS_INFO_KHR};
        ai.accelerationStructure = h[i];
        addr[i] = vk.vkGetAccelerationStructureDeviceAddressKHR(device, &ai);
        EXPECT_EQ(addr[i] % 256, 0u);
    }
    EXPECT_EQ(addr[1] - addr[0], offsets[1] - offsets[0]);
    for (auto x : h) vk.vkDestroyAccelerationStructureKHR(device, x, nullptr);
}

TEST_F(api, clone_by_byte_copy) {
    SmallScene s = makeScene(300, 5);
    const auto rays = randomRays(*s.tlas->scene, 300);
    const auto reference = traceAll(s.tlas->handle, rays);
    // Copy the BLAS's bytes into a structure at another offset of another buffer; a TLAS over the copy must trace
    // identically (the format holds relative offsets only).
    BuildOptions opt;
    opt.asOffset = 768;
    AccelStruct* blasCopy = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, s.blas->size, opt);
    std::memcpy(blasCopy->data(), s.blas->data(), s.blas->size);
    blasRegistry[blasCopy->reference()] = s.blas->blas;
    std::vector<Instance> inst = s.instances;
    for (auto& i : inst) i.blas = blasCopy;
    AccelStruct* tlas2 = buildTlas(inst);
    // The original BLAS's memory is scrambled: nothing may still point into it.
    std::memset(s.blas->data(), 0x55, s.blas->size);
    const auto viaCopy = traceAll(tlas2->handle, rays);
    // A byte copy of the TLAS (still referencing the BLAS copy) traces identically too.
    opt.asOffset = 256;
    AccelStruct* tlasCopy = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, tlas2->size, opt);
    std::memcpy(tlasCopy->data(), tlas2->data(), tlas2->size);
    std::memset(tlas2->data(), 0x55, tlas2->size);
    const auto viaTlasCopy = traceAll(tlasCopy->handle, rays);
    size_t hits = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
        hits += reference[i].type != 0;
        EXPECT_TRUE(identical(reference[i], viaCopy[i])) << describe(rays[i]) << "\n" << reference[i].str() << "\n"
                                                         << viaCopy[i].str();
        EXPECT_TRUE(identical(reference[i], viaTlasCopy[i])) << describe(rays[i]);
    }
    EXPECT_GT(hits, rays.size() / 10) << "the rays should hit the scene";
}

TEST_F(api, deterministic_build) {
    auto geometry = makeGeometry(triangleSoup(500, rng, 0.2f), VK_INDEX_TYPE_UINT16);
    for (VkBuildAccelerationStructureFlagsKHR flags :
         {VkBuildAccelerationStructureFlagsKHR(0), VkBuildAccelerationStructureFlagsKHR(VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR),
          VkBuildAccelerationStructureFlagsKHR(VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR)}) {
        BuildOptions a, b;
        a.flags = b.flags = flags;
        b.asOffset = 512;
        AccelStruct* x = buildBlas(*geometry, a);
        AccelStruct* y = buildBlas(*geometry, b);
        ASSERT_EQ(x->size, y->size);
        EXPECT_EQ(std::memcmp(x->data(), y->data(), x->size), 0) << "two identical builds differ, flags " << flags;
    }
}

TEST_F(api, result_independent_of_scratch_and_memory_contents) {
    auto geometry = makeGeometry(triangleSoup(400, rng, 0.25f), VK_INDEX_TYPE_NONE_KHR);
    BuildOptions a, b;
    b.scratchPoison = 0x00;
    b.memoryPoison = 0xFF;
    AccelStruct* x = buildBlas(*geometry, a);
    AccelStruct* y = buildBlas(*geometry, b);
    AccelStruct* tx = buildSingleInstanceTlas(x, a);
    AccelStruct* ty = buildSingleInstanceTlas(y, b);
    const auto rays = randomRays(*tx->scene, 300);
    const auto hx = traceAll(tx->handle, rays), hy = traceAll(ty->handle, rays);
    for (size_t i = 0; i < rays.size(); ++i) EXPECT_TRUE(identical(hx[i], hy[i])) << describe(rays[i]);
    checkRays(ty, rays);
}

TEST_F(api, multiple_infos_in_one_call) {
    std::vector<std::unique_ptr<GeometryData>> geoms;
    std::vector<std::unique_ptr<PreparedBuild>> builds;
    const VkIndexType types[3] = {VK_INDEX_TYPE_NONE_KHR, VK_INDEX_TYPE_UINT16, VK_INDEX_TYPE_UINT32};
    for (int i = 0; i < 3; ++i) {
        geoms.push_back(makeGeometry(triangleSoup(100 + 50 * i, rng, 0.3f), types[i], i == 1 ? VK_GEOMETRY_OPAQUE_BIT_KHR : 0));
        BuildOptions opt;
        opt.flags = i == 2 ? VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR : 0;
        opt.usePointers = i == 1;
        builds.push_back(prepareBlas(std::vector<const GeometryData*>{geoms.back().get()}, opt));
    }
    submit({builds[0].get(), builds[1].get(), builds[2].get()});
    std::vector<Instance> instances;
    for (int i = 0; i < 6; ++i) {
        Instance inst;
        inst.transform = randomTransform(rng, 0.5f, 1.5f, false, 2.0f);
        inst.blas = builds[i % 3]->as;
        inst.customIndex = uint32_t(i * 7);
        instances.push_back(inst);
    }
    // Two TLASes in one call as well.
    auto t1 = prepareTlas(instances);
    std::vector<Instance> reversed(instances.rbegin(), instances.rend());
    auto t2 = prepareTlas(reversed);
    submit({t1.get(), t2.get()});
    const auto rays = randomRays(*t1->as->scene, 400);
    EXPECT_GT(checkRays(t1->as, rays), 0u);
    checkRays(t2->as, rays);
}

TEST_F(api, build_sizes) {
    auto small = makeGeometry(triangleSoup(64, rng, 0.3f), VK_INDEX_TYPE_UINT32);
    auto big = makeGeometry(triangleSoup(4096, rng, 0.3f), VK_INDEX_TYPE_UINT32);
    auto sizesFor = [&](const GeometryData& g, uint32_t count) {
        VkAccelerationStructureBuildGeometryInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
        info.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
        info.geometryCount = 1;
        info.pGeometries = &g.geometry;
        VkAccelerationStructureBuildSizesInfoKHR s{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
        vk.vkGetAccelerationStructureBuildSizesKHR(device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info, &count, &s);
        return s;
    };
    VkDeviceSize prevAs = 0, prevScratch = 0;
    for (uint32_t n : {1u, 2u, 3u, 7u, 64u, 65u, 1000u, 4096u, 100000u}) {
        const auto s = sizesFor(*big, n);
        EXPECT_GT(s.accelerationStructureSize, 0u);
        EXPECT_GE(s.accelerationStructureSize, prevAs) << "sizes must be monotone in the primitive count (n=" << n << ")";
        EXPECT_GE(s.buildScratchSize, prevScratch) << "n=" << n;
        prevAs = s.accelerationStructureSize;
        prevScratch = s.buildScratchSize;
    }
    // A build with fewer primitives than the query fits; the pointers' contents do not change the sizes.
    EXPECT_EQ(sizesFor(*small, 4096).accelerationStructureSize, sizesFor(*big, 4096).accelerationStructureSize);
    BuildOptions opt;
    opt.extraMaxPrimitives = 4096 - 64;
    AccelStruct* blas = buildBlas(*small, opt);
    AccelStruct* tlas = buildSingleInstanceTlas(blas);
    EXPECT_GT(checkRays(tlas, randomRays(*tlas->scene, 200)), 0u);
    // TLAS sizes: zero instances still give a usable size; monotone.
    VkDeviceSize prev = 0;
    for (uint32_t n : {0u, 1u, 10u, 1000u}) {
        VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
        g.geometryType = VK_GEOMETRY_TYPE_INSTANCES_KHR;
        g.geometry.instances.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_INSTANCES_DATA_KHR;
        VkAccelerationStructureBuildGeometryInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
        info.type = VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR;
        info.geometryCount = 1;
        info.pGeometries = &g;
        VkAccelerationStructureBuildSizesInfoKHR s{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
        vk.vkGetAccelerationStructureBuildSizesKHR(device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info, &n, &s);
        EXPECT_GT(s.accelerationStructureSize, 0u);
        EXPECT_GE(s.accelerationStructureSize, prev);
        prev = s.accelerationStructureSize;
    }
}

TEST_F(api, inputs_unchanged_by_build) {
    auto g = makeGeometry(triangleSoup(300, rng, 0.3f), VK_INDEX_TYPE_UINT16, 0, nullptr);
    const VkTransformMatrixKHR xf = randomTransform(rng, 0.5f, 2.0f, true, 1.0f);
    auto g2 = makeGeometry(triangleSoup(300, rng, 0.3f), VK_INDEX_TYPE_UINT32, 0, &xf);
    const auto v1 = g->vertices, i1 = g->indices, v2 = g2->vertices, i2 = g2->indices, t2 = g2->transform;
    AccelStruct* blas = buildBlas(std::vector<const GeometryData*>{g.get(), g2.get()});
    EXPECT_EQ(v1, g->vertices);
    EXPECT_EQ(i1, g->indices);
    EXPECT_EQ(v2, g2->vertices);
    EXPECT_EQ(i2, g2->indices);
    EXPECT_EQ(t2, g2->transform);
    auto pb = prepareTlas({Instance{identityTransform(), 1, 0xFF, 2, 0, blas}, Instance{translation(1, 2, 3), 3, 0xFF, 4, 0, blas}});
    const auto before = pb->instanceBytes;
    submit({pb.get()});
    EXPECT_EQ(before, pb->instanceBytes);
}

TEST_F(api, concurrent_queries) {
    SmallScene s = makeScene(400, 6);
    const auto rays = randomRays(*s.tlas->scene, 2000);
    const auto reference = traceAll(s.tlas->handle, rays);
    std::vector<std::vector<Hit>> results(4);
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t)
        threads.emplace_back([&, t] {
            for (const auto& r : rays) {
                VkasRayQuery q;
                vkasRayQueryInitialize(&q, s.tlas->handle, 0, 0xFF, r.origin.data(), r.tMin, r.direction.data(), r.tMax);
                while (vkasRayQueryProceed(&q)) vkasRayQueryConfirmIntersection(&q);
                results[t].push_back(readHit(q, true));
            }
        });
    for (auto& th : threads) th.join();
    for (int t = 0; t < 4; ++t)
        for (size_t i = 0; i < rays.size(); ++i)
            ASSERT_TRUE(identical(reference[i], results[t][i])) << "thread " << t << " ray " << describe(rays[i]);
}

TEST_F(api, trace_rays_validation) {
    SmallScene s = makeScene(20, 1);
    std::vector<VkasHit> hits(1);
    std::memset(hits.data(), 0xAA, sizeof(VkasHit));
    EXPECT_EQ(vkasTraceRays(device, s.tlas->handle, VKAS_TRACE_MODE_CLOSEST_HIT, 0, 0xFF, 1, nullptr, hits.data()),
              VK_ERROR_VALIDATION_FAILED_EXT);
    const uint8_t* b = reinterpret_cast<const uint8_t*>(hits.data());
    for (size_t i = 0; i < sizeof(VkasHit); ++i) ASSERT_EQ(b[i], 0xAA) << "nothing may be written on failure";
    takeValidationErrors();  // the failure may be reported through the messenger too
    // rayCount 0 is a no-op.
    EXPECT_EQ(vkasTraceRays(device, s.tlas->handle, VKAS_TRACE_MODE_CLOSEST_HIT, 0, 0xFF, 0, nullptr, nullptr), VK_SUCCESS);
    EXPECT_TRUE(takeValidationErrors().empty());
}

TEST_F(api, validation_reports_generic_build_type) {
    auto g = makeGeometry(triangleSoup(10, rng, 0.3f), VK_INDEX_TYPE_UINT32);
    auto pb = prepareBlas(std::vector<const GeometryData*>{g.get()});
    ASSERT_TRUE(takeValidationErrors().empty());
    VkAccelerationStructureBuildGeometryInfoKHR info = pb->info;
    info.type = VK_ACCELERATION_STRUCTURE_TYPE_GENERIC_KHR;  // VUID-VkAccelerationStructureBuildGeometryInfoKHR-type-03654
    const VkAccelerationStructureBuildRangeInfoKHR* ranges = pb->ranges.data();
    const VkResult r = vk.vkBuildAccelerationStructuresKHR(device, VK_NULL_HANDLE, 1, &info, &ranges);
    const auto errors = takeValidationErrors();
    EXPECT_FALSE(errors.empty()) << "building with type GENERIC must be reported (result " << r << ")";
}

TEST_F(api, instance_packing_matches_vulkan_struct) {
    // The suite's shift-based packing agrees with the compiler's layout of VkAccelerationStructureInstanceKHR.
    Rng r(seed);
    for (int i = 0; i < 100; ++i) {
        VkAccelerationStructureInstanceKHR s{};
        s.transform = randomTransform(r, 0.5f, 2, true, 3);
        s.instanceCustomIndex = r.u32() & 0xFFFFFF;
        s.mask = r.u32() & 0xFF;
        s.instanceShaderBindingTableRecordOffset = r.u32() & 0xFFFFFF;
        s.flags = r.u32() & 0xFF;
        s.accelerationStructureReference = 0;
        Instance in{s.transform, s.instanceCustomIndex, s.mask, s.instanceShaderBindingTableRecordOffset, s.flags, nullptr};
        uint8_t bytes[64];
        packInstance(in, bytes);
        ASSERT_EQ(std::memcmp(bytes, &s, 64), 0);
    }
}

// The oracle and the comparison rule themselves (so that a broken oracle cannot make every test pass).
using oracle_self_check = VkasTest;

TEST_F(oracle_self_check, known_answers) {
    Mesh m;
    m.positions = {{0, 0, 0}, {4, 0, 0}, {0, 4, 0}, {0, 0, -1}, {4, 0, -1}, {0, 4, -1}};
    m.indices = {0, 1, 2, 3, 4, 5};
    auto g = makeGeometry(m, VK_INDEX_TYPE_UINT16);
    AccelStruct* tlas = buildTlas({Instance{translation(1, 0, 0), 3, 0xFF, 4, 0, buildBlas(*g)}});
    oracle::Ray r;
    r.origin = {2, 1, 2};
    r.direction = {0, 0, -2};
    r.tMin = 0;
    r.tMax = 100;
    const oracle::Result res = oracle::trace(*tlas->scene, r, 0, 0xFF);
    ASSERT_EQ(res.candidates.size(), 2u);
    const oracle::Candidate* c = res.closestRequired();
    ASSERT_NE(c, nullptr);
    EXPECT_DOUBLE_EQ(c->t, 1.0);
    EXPECT_EQ(c->primitiveIndex, 0);
    EXPECT_DOUBLE_EQ(c->bary[0], 0.25);  // object-space point (1, 1): weight of vertex 1 = 1/4
    EXPECT_DOUBLE_EQ(c->bary[1], 0.25);
    EXPECT_TRUE(c->frontFace);
    EXPECT_EQ(oracle::trace(*tlas->scene, r, VKAS_RAY_FLAG_CULL_FRONT_FACING_TRIANGLES, 0xFF).candidates.size(), 0u);
    EXPECT_EQ(oracle::trace(*tlas->scene, r, 0, 0).candidates.size(), 0u);
    // The comparison rejects a miss, the farther primitive, and a wrong t; it accepts the right answer.
    Hit good;
    good.type = 1;
    good.t = 1;
    good.instanceId = 0;
    good.customIndex = 3;
    good.sbtOffset = 4;
    good.geometryIndex = 0;
    good.primitiveIndex = 0;
    good.bary[0] = good.bary[1] = 0.25f;
    good.frontFace = true;
    EXPECT_TRUE(matchesClosest(res, r, good));
    EXPECT_TRUE(matchesClosest(res, r, traceClosest(tlas, r)));
    Hit miss;
    EXPECT_FALSE(matchesClosest(res, r, miss));
    Hit far = good;
    far.primitiveIndex = 1;
    far.t = 1.5f;
    EXPECT_FALSE(matchesClosest(res, r, far));
    EXPECT_TRUE(matchesAnyHit(res, r, far));
    Hit wrongT = good;
    wrongT.t = 1.01f;
    EXPECT_FALSE(matchesClosest(res, r, wrongT));
    Hit wrongBary = good;
    wrongBary.bary[0] = 0.3f;
    EXPECT_FALSE(matchesClosest(res, r, wrongBary));
    // A ray exactly through the shared corner is optional for both triangles: a miss is accepted.
    r.origin = {1, 0, 2};
    const oracle::Result edge = oracle::trace(*tlas->scene, r, 0, 0xFF);
    EXPECT_EQ(edge.requiredCount(), 0u);
    EXPECT_TRUE(matchesClosest(edge, r, miss));
}

TEST_F(oracle_self_check, vertex_decode) {
    EXPECT_EQ(oracle::halfToDouble(0x3C00), 1.0);
    EXPECT_EQ(oracle::halfToDouble(0xC000), -2.0);
    EXPECT_EQ(oracle::halfToDouble(0x0001), std::ldexp(1.0, -24));
    EXPECT_TRUE(std::isnan(oracle::halfToDouble(0x7E00)));
    for (float f : {0.0f, 1.0f, -0.5f, 0.333f, 1000.0f, 6.1e-5f})
        EXPECT_NEAR(oracle::halfToDouble(oracle::floatToHalf(f)), f, std::fabs(f) * 1e-3);
    const int8_t s8[3] = {-128, 127, -127};
    const auto v = oracle::decodeVertex(VK_FORMAT_R8G8B8_SNORM, s8);
    EXPECT_EQ(v[0], -1.0);
    EXPECT_EQ(v[1], 1.0);
    EXPECT_EQ(v[2], -1.0);
    const uint32_t packed = 1023u | (0u << 10) | (511u << 20) | (3u << 30);
    const auto p = oracle::decodeVertex(VK_FORMAT_A2B10G10R10_UNORM_PACK32, &packed);
    EXPECT_EQ(p[0], 1.0);
    EXPECT_EQ(p[1], 0.0);
    EXPECT_EQ(p[2], 511.0 / 1023.0);
    const float two[2] = {1.5f, -2.5f};
    const auto q = oracle::decodeVertex(VK_FORMAT_R32G32_SFLOAT, two);
    EXPECT_EQ(q[2], 0.0);
}
