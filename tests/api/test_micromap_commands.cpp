// VK_EXT_opacity_micromap's host commands through the public API: build sizes, builds of every format and level,
// byte-identical rebuilds, deferred builds, clones, compaction, the properties query, serialization round trips,
// corrupted serialized data, the compatibility query, the committed serialized micromaps and object lifetime.
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "engine/format/micromap_check.hpp"
#include "engine/format/micromap_layout.hpp"
#include "engine/format/micromap_serialize.hpp"
#include "vkas_test.hpp"

#ifndef VKAS_TEST_DATA_DIR
#define VKAS_TEST_DATA_DIR "tests/data"
#endif

namespace {

using namespace vt;
namespace fmt = vkas::format;

constexpr VkBufferUsageFlags kMicromapUsage = VK_BUFFER_USAGE_MICROMAP_STORAGE_BIT_EXT;
constexpr uint8_t kPoison = 0xAA;

// The application's side of a build: triangles, their states and the usage counts.
struct MicromapInput {
    std::vector<VkMicromapTriangleEXT> triangles;
    std::vector<uint8_t> data;
    std::vector<VkMicromapUsageEXT> usage;
    VkBuildMicromapFlagsEXT flags = 0;

    // Appends a triangle of that format and level whose states are state(j), at a data offset `gap` bytes after the
    // previous triangle's (the build repacks them).
    template <class StateFn>
    void add(uint16_t format, uint16_t level, StateFn state, uint32_t gap = 0) {
        data.resize(data.size() + gap, 0x5C);
        VkMicromapTriangleEXT t{uint32_t(data.size()), level, format};
        const uint64_t n = fmt::microTriangleCount(level);
        std::vector<uint8_t> bytes(fmt::opacityTriangleDataBytes(level, format), 0);
        for (uint64_t j = 0; j < n; ++j) {
            const uint32_t s = state(j) & (format == fmt::kOpacityFormat2State ? 1u : 3u);
            if (format == fmt::kOpacityFormat2State)
                bytes[j >> 3] |= uint8_t(s << (j & 7));
            else
                bytes[j >> 2] |= uint8_t(s << (2 * (j & 3)));
        }
        data.insert(data.end(), bytes.begin(), bytes.end());
        triangles.push_back(t);
        for (auto& u : usage)
            if (u.format == format && u.subdivisionLevel == level) {
                ++u.count;
                return;
            }
        usage.push_back({1, level, format});
    }
};

struct TestMicromap {
    VkMicromapEXT handle = VK_NULL_HANDLE;
    HostBuffer* buffer = nullptr;
    VkDeviceSize offset = 0, size = 0;
    uint8_t* data() const { return buffer->mapped + offset; }
};

struct MicromapCommands {
    PFN_vkCreateMicromapEXT create = nullptr;
    PFN_vkDestroyMicromapEXT destroy = nullptr;
    PFN_vkGetMicromapBuildSizesEXT sizes = nullptr;
    PFN_vkBuildMicromapsEXT build = nullptr;
    PFN_vkCopyMicromapEXT copy = nullptr;
    PFN_vkCopyMicromapToMemoryEXT toMemory = nullptr;
    PFN_vkCopyMemoryToMicromapEXT fromMemory = nullptr;
    PFN_vkWriteMicromapsPropertiesEXT properties = nullptr;
    PFN_vkGetDeviceMicromapCompatibilityEXT compatibility = nullptr;
    PFN_vkCreateDeferredOperationKHR createOperation = nullptr;
    PFN_vkDestroyDeferredOperationKHR destroyOperation = nullptr;
    PFN_vkDeferredOperationJoinKHR join = nullptr;
    PFN_vkGetDeferredOperationResultKHR operationResult = nullptr;
};

// A serialized micromap in 16-byte aligned host memory.
struct MicromapBlob {
    std::vector<uint64_t> storage;
    size_t size = 0;
    void allocate(size_t n) {
        storage.assign((n + 7) / 8 + 2, 0xAAAAAAAAAAAAAAAAull);
        size = n;
    }
    uint8_t* data() { return reinterpret_cast<uint8_t*>(storage.data()); }
    const uint8_t* data() const { return reinterpret_cast<const uint8_t*>(storage.data()); }
};

class MicromapTest : public VkasTest {
  protected:
    MicromapCommands mm;
    std::vector<std::unique_ptr<TestMicromap>> micromaps;

    void SetUp() override {
        VkasTest::SetUp();
        if (HasFatalFailure()) return;
#define MM_LOAD(field, name)                                                                      \
    mm.field = reinterpret_cast<PFN_##name>(vkasGetDeviceProcAddr(device, #name));                \
    ASSERT_NE(reinterpret_cast<void*>(mm.field), nullptr) << "vkasGetDeviceProcAddr(" #name ") is NULL";
        MM_LOAD(create, vkCreateMicromapEXT)
        MM_LOAD(destroy, vkDestroyMicromapEXT)
        MM_LOAD(sizes, vkGetMicromapBuildSizesEXT)
        MM_LOAD(build, vkBuildMicromapsEXT)
        MM_LOAD(copy, vkCopyMicromapEXT)
        MM_LOAD(toMemory, vkCopyMicromapToMemoryEXT)
        MM_LOAD(fromMemory, vkCopyMemoryToMicromapEXT)
        MM_LOAD(properties, vkWriteMicromapsPropertiesEXT)
        MM_LOAD(compatibility, vkGetDeviceMicromapCompatibilityEXT)
        MM_LOAD(createOperation, vkCreateDeferredOperationKHR)
        MM_LOAD(destroyOperation, vkDestroyDeferredOperationKHR)
        MM_LOAD(join, vkDeferredOperationJoinKHR)
        MM_LOAD(operationResult, vkGetDeferredOperationResultKHR)
#undef MM_LOAD
    }
    void TearDown() override {
        for (auto& m : micromaps)
            if (m->handle != VK_NULL_HANDLE) mm.destroy(device, m->handle, nullptr);
        micromaps.clear();
        VkasTest::TearDown();
    }

    // A micromap of `size` bytes at `offset` of a new buffer poisoned with kPoison, with a 256-byte canary after it.
    TestMicromap* createMicromap(VkDeviceSize size, VkDeviceSize offset = 0) {
        auto m = std::make_unique<TestMicromap>();
        m->buffer = createBuffer(offset + size + 256, kMicromapUsage, true, kPoison);
        m->offset = offset;
        m->size = size;
        VkMicromapCreateInfoEXT ci{VK_STRUCTURE_TYPE_MICROMAP_CREATE_INFO_EXT};
        ci.buffer = m->buffer->buffer;
        ci.offset = offset;
        ci.size = size;
        ci.type = VK_MICROMAP_TYPE_OPACITY_MICROMAP_EXT;
        EXPECT_EQ(mm.create(device, &ci, nullptr, &m->handle), VK_SUCCESS);
        micromaps.push_back(std::move(m));
        return micromaps.back().get();
    }
    void destroyMicromap(TestMicromap* m) {
        mm.destroy(device, m->handle, nullptr);
        m->handle = VK_NULL_HANDLE;
    }

    static VkMicromapBuildInfoEXT buildInfo(const MicromapInput& in, VkMicromapEXT dst) {
        VkMicromapBuildInfoEXT info{VK_STRUCTURE_TYPE_MICROMAP_BUILD_INFO_EXT};
        info.type = VK_MICROMAP_TYPE_OPACITY_MICROMAP_EXT;
        info.flags = in.flags;
        info.mode = VK_BUILD_MICROMAP_MODE_BUILD_EXT;
        info.dstMicromap = dst;
        info.usageCountsCount = uint32_t(in.usage.size());
        info.pUsageCounts = in.usage.data();
        info.data.hostAddress = in.data.data();
        info.triangleArray.hostAddress = in.triangles.data();
        info.triangleArrayStride = sizeof(VkMicromapTriangleEXT);
        return info;
    }
    VkMicromapBuildSizesInfoEXT sizesOf(const MicromapInput& in) {
        VkMicromapBuildSizesInfoEXT s{VK_STRUCTURE_TYPE_MICROMAP_BUILD_SIZES_INFO_EXT};
        const VkMicromapBuildInfoEXT info = buildInfo(in, VK_NULL_HANDLE);
        mm.sizes(device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info, &s);
        return s;
    }
    // Size query, creation, build; checks the canary and that nothing after usedSize was written.
    TestMicromap* build(const MicromapInput& in, VkDeviceSize offset = 0, VkDeferredOperationKHR op = VK_NULL_HANDLE) {
        const VkMicromapBuildSizesInfoEXT s = sizesOf(in);
        TestMicromap* m = createMicromap(s.micromapSize, offset);
        const VkMicromapBuildInfoEXT info = buildInfo(in, m->handle);
        if (op == VK_NULL_HANDLE) {
            EXPECT_EQ(mm.build(device, VK_NULL_HANDLE, 1, &info), VK_SUCCESS);
        } else {
            EXPECT_EQ(mm.build(device, op, 1, &info), VK_OPERATION_DEFERRED_KHR);
            VkResult r;
            while ((r = mm.join(device, op)) == VK_THREAD_IDLE_KHR) {
            }
            EXPECT_EQ(mm.operationResult(device, op), VK_SUCCESS);
        }
        const auto* h = reinterpret_cast<const fmt::MicromapHeader*>(m->data());
        EXPECT_EQ(h->usedSize, s.micromapSize) << "usedSize is exact";
        for (VkDeviceSize k = 0; k < 256; ++k) EXPECT_EQ(m->data()[m->size + k], kPoison) << "canary byte " << k;
        for (VkDeviceSize k = 0; k < offset; ++k) EXPECT_EQ(m->buffer->mapped[k], kPoison) << "byte before " << k;
        return m;
    }
    // The states of every triangle of the micromap at `block` equal the input's.
    static ::testing::AssertionResult holdsStates(const uint8_t* block, const MicromapInput& in) {
        const auto* b = reinterpret_cast<const std::byte*>(block);
        const fmt::MicromapHeader* h = fmt::micromapHeader(b);
        if (h->magic != fmt::kMicromapMagic) return ::testing::AssertionFailure() << "not a micromap";
        if (h->triangleCount != in.triangles.size())
            return ::testing::AssertionFailure() << "triangleCount " << h->triangleCount;
        const fmt::MicromapTriangle* tris = fmt::micromapTriangles(b);
        for (size_t i = 0; i < in.triangles.size(); ++i) {
            const VkMicromapTriangleEXT& t = in.triangles[i];
            if (tris[i].format != t.format || tris[i].subdivisionLevel != t.subdivisionLevel)
                return ::testing::AssertionFailure() << "triangle " << i << " format/level";
            const std::byte* got = fmt::micromapData(b) + tris[i].dataOffset;
            const auto* want = reinterpret_cast<const std::byte*>(in.data.data()) + t.dataOffset;
            for (uint64_t j = 0; j < fmt::microTriangleCount(t.subdivisionLevel); ++j)
                if (fmt::opacityState(got, t.format, j) != fmt::opacityState(want, t.format, j))
                    return ::testing::AssertionFailure() << "triangle " << i << " micro-triangle " << j;
        }
        return ::testing::AssertionSuccess();
    }
    uint64_t property(const TestMicromap* m, VkQueryType type) {
        VkDeviceSize v = 0;
        EXPECT_EQ(mm.properties(device, 1, &m->handle, type, sizeof v, &v, sizeof v), VK_SUCCESS);
        return v;
    }
    MicromapBlob serialize(const TestMicromap* m) {
        MicromapBlob blob;
        blob.allocate(property(m, VK_QUERY_TYPE_MICROMAP_SERIALIZATION_SIZE_EXT));
        VkCopyMicromapToMemoryInfoEXT info{VK_STRUCTURE_TYPE_COPY_MICROMAP_TO_MEMORY_INFO_EXT};
        info.src = m->handle;
        info.dst.hostAddress = blob.data();
        info.mode = VK_COPY_MICROMAP_MODE_SERIALIZE_EXT;
        EXPECT_EQ(mm.toMemory(device, VK_NULL_HANDLE, &info), VK_SUCCESS);
        return blob;
    }
    VkResult deserialize(const MicromapBlob& blob, TestMicromap* dst) {
        VkCopyMemoryToMicromapInfoEXT info{VK_STRUCTURE_TYPE_COPY_MEMORY_TO_MICROMAP_INFO_EXT};
        info.src.hostAddress = blob.data();
        info.dst = dst->handle;
        info.mode = VK_COPY_MICROMAP_MODE_DESERIALIZE_EXT;
        return mm.fromMemory(device, VK_NULL_HANDLE, &info);
    }
    VkResult copy(const TestMicromap* src, const TestMicromap* dst, VkCopyMicromapModeEXT mode) {
        VkCopyMicromapInfoEXT info{VK_STRUCTURE_TYPE_COPY_MICROMAP_INFO_EXT, nullptr, src->handle, dst->handle, mode};
        return mm.copy(device, VK_NULL_HANDLE, &info);
    }

    // Random triangles of random formats and levels up to maxLevel, with random gaps between their states.
    MicromapInput randomInput(uint32_t triangles, uint16_t maxLevel) {
        MicromapInput in;
        for (uint32_t i = 0; i < triangles; ++i) {
            const uint16_t format = rng.coin() ? fmt::kOpacityFormat2State : fmt::kOpacityFormat4State;
            const uint16_t level = uint16_t(rng.below(maxLevel + 1u));
            Rng states(rng.u32());
            in.add(format, level, [&](uint64_t) { return states.u32(); }, rng.below(4));
        }
        // Shuffle the usage counts' order and split one of them: the sum is what counts.
        if (in.usage.size() > 1) std::swap(in.usage.front(), in.usage.back());
        if (!in.usage.empty() && in.usage[0].count > 1) {
            in.usage[0].count -= 1;
            in.usage.push_back({1, in.usage[0].subdivisionLevel, in.usage[0].format});
        }
        return in;
    }
};

// ---- Host commands ------------------------------------------------------------------------------------------------
using opacity_micromap_host_commands = MicromapTest;

TEST_F(opacity_micromap_host_commands, commands_and_limits_are_reported) {
    VkPhysicalDeviceOpacityMicromapFeaturesEXT features{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_OPACITY_MICROMAP_FEATURES_EXT};
    VkPhysicalDeviceAccelerationStructureFeaturesKHR as{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ACCELERATION_STRUCTURE_FEATURES_KHR,
                                                        &features};
    vkasGetAccelerationStructureFeatures(device, &as);
    EXPECT_EQ(features.micromap, VK_TRUE);
    EXPECT_EQ(features.micromapHostCommands, VK_TRUE);
    EXPECT_EQ(features.micromapCaptureReplay, VK_FALSE);
    VkPhysicalDeviceOpacityMicromapPropertiesEXT limits{
        VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_OPACITY_MICROMAP_PROPERTIES_EXT};
    VkPhysicalDeviceAccelerationStructurePropertiesKHR asp{
        VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ACCELERATION_STRUCTURE_PROPERTIES_KHR, &limits};
    vkasGetAccelerationStructureProperties(device, &asp);
    EXPECT_EQ(limits.maxOpacity2StateSubdivisionLevel, 12u);
    EXPECT_EQ(limits.maxOpacity4StateSubdivisionLevel, 12u);
    // The device commands are not implemented (as for acceleration structures).
    for (const char* name : {"vkCmdBuildMicromapsEXT", "vkCmdCopyMicromapEXT", "vkCmdCopyMicromapToMemoryEXT",
                             "vkCmdCopyMemoryToMicromapEXT", "vkCmdWriteMicromapsPropertiesEXT"})
        EXPECT_EQ(vkasGetDeviceProcAddr(device, name), nullptr) << name;
}

TEST_F(opacity_micromap_host_commands, build_sizes_follow_the_usage_counts) {
    for (uint16_t format : {fmt::kOpacityFormat2State, fmt::kOpacityFormat4State})
        for (uint16_t level = 0; level <= 12; ++level) {
            const uint32_t count = 1 + rng.below(5);
            MicromapInput in;
            in.usage.push_back({count, level, format});
            const VkMicromapBuildSizesInfoEXT s = sizesOf(in);
            const uint64_t bits = (uint64_t(1) << (2 * level)) * (format == fmt::kOpacityFormat4State ? 2 : 1);
            EXPECT_EQ(s.micromapSize, 64 + count * (8 + (bits + 7) / 8)) << format << " " << level;
            EXPECT_EQ(s.buildScratchSize, 0u);
            EXPECT_EQ(s.discardable, VK_TRUE);
            // ppUsageCounts gives the same sizes.
            const VkMicromapUsageEXT* pointer = &in.usage[0];
            VkMicromapBuildInfoEXT info = buildInfo(in, VK_NULL_HANDLE);
            info.pUsageCounts = nullptr;
            info.ppUsageCounts = &pointer;
            VkMicromapBuildSizesInfoEXT s2{VK_STRUCTURE_TYPE_MICROMAP_BUILD_SIZES_INFO_EXT};
            mm.sizes(device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_OR_DEVICE_KHR, &info, &s2);
            EXPECT_EQ(s2.micromapSize, s.micromapSize);
        }
    MicromapInput empty;
    EXPECT_EQ(sizesOf(empty).micromapSize, 64u);
}

TEST_F(opacity_micromap_host_commands, every_format_and_level_builds) {
    for (uint16_t format : {fmt::kOpacityFormat2State, fmt::kOpacityFormat4State})
        for (uint16_t level = 0; level <= 12; ++level) {
            MicromapInput in;
            Rng states(rng.u32());
            // Level 12 4-state (4 MiB of states) once; smaller levels a few times.
            const uint32_t triangles = level >= 10 ? 1 : 1 + rng.below(3);
            for (uint32_t t = 0; t < triangles; ++t) in.add(format, level, [&](uint64_t) { return states.u32(); }, 3);
            TestMicromap* m = build(in, 256 * rng.below(3));
            EXPECT_TRUE(holdsStates(m->data(), in)) << format << " " << level;
            EXPECT_TRUE(fmt::checkMicromapBlock(reinterpret_cast<const std::byte*>(m->data()), m->size).ok());
            destroyMicromap(m);
        }
}

TEST_F(opacity_micromap_host_commands, random_builds_are_deterministic) {
    for (int round = 0; round < 20; ++round) {
        MicromapInput in = randomInput(1 + rng.below(64), 6);
        in.flags = rng.coin() ? VK_BUILD_MICROMAP_ALLOW_COMPACTION_BIT_EXT : VK_BUILD_MICROMAP_PREFER_FAST_TRACE_BIT_EXT;
        TestMicromap* a = build(in);
        TestMicromap* b = build(in, 512);
        ASSERT_TRUE(holdsStates(a->data(), in));
        EXPECT_EQ(0, std::memcmp(a->data(), b->data(), a->size)) << "the same inputs give the same bytes";
        // A triangle array with a larger stride reads the same triangles.
        std::vector<uint8_t> strided(in.triangles.size() * 24, 0xEE);
        for (size_t i = 0; i < in.triangles.size(); ++i) std::memcpy(&strided[24 * i], &in.triangles[i], 8);
        TestMicromap* c = createMicromap(a->size);
        VkMicromapBuildInfoEXT info = buildInfo(in, c->handle);
        info.triangleArray.hostAddress = strided.data();
        info.triangleArrayStride = 24;
        ASSERT_EQ(mm.build(device, VK_NULL_HANDLE, 1, &info), VK_SUCCESS);
        EXPECT_EQ(0, std::memcmp(a->data(), c->data(), a->size));
    }
}

TEST_F(opacity_micromap_host_commands, deferred_build_equals_direct_build) {
    VkDeferredOperationKHR op;
    ASSERT_EQ(mm.createOperation(device, nullptr, &op), VK_SUCCESS);
    for (int round = 0; round < 5; ++round) {
        const MicromapInput in = randomInput(1 + rng.below(200), 8);
        TestMicromap* direct = build(in);
        TestMicromap* deferred = build(in, 0, op);
        EXPECT_EQ(0, std::memcmp(direct->data(), deferred->data(), direct->size));
    }
    // Several infos in one deferred call.
    const MicromapInput a = randomInput(30, 5), b = randomInput(40, 5);
    TestMicromap* ma = createMicromap(sizesOf(a).micromapSize);
    TestMicromap* mb = createMicromap(sizesOf(b).micromapSize);
    const VkMicromapBuildInfoEXT infos[2] = {buildInfo(a, ma->handle), buildInfo(b, mb->handle)};
    ASSERT_EQ(mm.build(device, op, 2, infos), VK_OPERATION_DEFERRED_KHR);
    while (mm.join(device, op) == VK_THREAD_IDLE_KHR) {
    }
    EXPECT_EQ(mm.operationResult(device, op), VK_SUCCESS);
    EXPECT_TRUE(holdsStates(ma->data(), a));
    EXPECT_TRUE(holdsStates(mb->data(), b));
    mm.destroyOperation(device, op, nullptr);
}

TEST_F(opacity_micromap_host_commands, clone_is_a_byte_copy_and_compaction_is_exact) {
    MicromapInput in = randomInput(50, 7);
    in.flags = VK_BUILD_MICROMAP_ALLOW_COMPACTION_BIT_EXT;
    TestMicromap* src = build(in);
    const uint64_t used = reinterpret_cast<const fmt::MicromapHeader*>(src->data())->usedSize;
    EXPECT_EQ(property(src, VK_QUERY_TYPE_MICROMAP_COMPACTED_SIZE_EXT), used);
    EXPECT_EQ(property(src, VK_QUERY_TYPE_MICROMAP_SERIALIZATION_SIZE_EXT), used + 64);

    TestMicromap* clone = createMicromap(src->size + 1024, 256);
    ASSERT_EQ(copy(src, clone, VK_COPY_MICROMAP_MODE_CLONE_EXT), VK_SUCCESS);
    EXPECT_EQ(0, std::memcmp(src->data(), clone->data(), used));
    for (VkDeviceSize k = used; k < clone->size; ++k) ASSERT_EQ(clone->data()[k], kPoison) << "written past usedSize";
    EXPECT_TRUE(holdsStates(clone->data(), in));

    TestMicromap* compact = createMicromap(used);
    ASSERT_EQ(copy(clone, compact, VK_COPY_MICROMAP_MODE_COMPACT_EXT), VK_SUCCESS);
    EXPECT_EQ(0, std::memcmp(src->data(), compact->data(), used));
    EXPECT_EQ(property(compact, VK_QUERY_TYPE_MICROMAP_COMPACTED_SIZE_EXT), used);

    // Several micromaps in one query, with a stride.
    VkDeviceSize values[4] = {1, 2, 3, 4};
    const VkMicromapEXT handles[2] = {src->handle, compact->handle};
    ASSERT_EQ(mm.properties(device, 2, handles, VK_QUERY_TYPE_MICROMAP_SERIALIZATION_SIZE_EXT, sizeof values, values,
                            2 * sizeof(VkDeviceSize)),
              VK_SUCCESS);
    EXPECT_EQ(values[0], used + 64);
    EXPECT_EQ(values[1], 2u);
    EXPECT_EQ(values[2], used + 64);
    EXPECT_EQ(values[3], 4u);
}

TEST_F(opacity_micromap_host_commands, destroyed_micromaps_and_device_teardown) {
    const MicromapInput in = randomInput(10, 3);
    TestMicromap* m = build(in);
    destroyMicromap(m);
    // A micromap left alive is freed by vkasDestroyDevice, which reports it (05137).
    TestMicromap* leaked = build(in);
    leaked->handle = VK_NULL_HANDLE;  // not destroyed in TearDown
    ignoreLeaksAtTeardown = true;
}

// ---- Serialization ------------------------------------------------------------------------------------------------
using opacity_micromap_serialization = MicromapTest;

TEST_F(opacity_micromap_serialization, round_trip_into_a_fresh_micromap) {
    for (int round = 0; round < 10; ++round) {
        MicromapInput in = randomInput(1 + rng.below(100), 6);
        in.flags = VK_BUILD_MICROMAP_ALLOW_COMPACTION_BIT_EXT;
        TestMicromap* src = build(in);
        const MicromapBlob blob = serialize(src);
        ASSERT_EQ(blob.size, src->size + 64);
        for (size_t k = blob.size; k < blob.size + 8; ++k) ASSERT_EQ(blob.data()[k], 0xAA) << "written past the blob";
        // The header the spec defines, then vkas's sizes.
        VkMicromapVersionInfoEXT vi{VK_STRUCTURE_TYPE_MICROMAP_VERSION_INFO_EXT, nullptr, blob.data()};
        VkAccelerationStructureCompatibilityKHR c = VK_ACCELERATION_STRUCTURE_COMPATIBILITY_MAX_ENUM_KHR;
        mm.compatibility(device, &vi, &c);
        EXPECT_EQ(c, VK_ACCELERATION_STRUCTURE_COMPATIBILITY_COMPATIBLE_KHR);
        TestMicromap* dst = createMicromap(src->size + 256 * rng.below(2));
        ASSERT_EQ(deserialize(blob, dst), VK_SUCCESS);
        EXPECT_EQ(0, std::memcmp(src->data(), dst->data(), src->size));
        for (VkDeviceSize k = src->size; k < dst->size; ++k) ASSERT_EQ(dst->data()[k], kPoison);
        // The loaded micromap serializes to the same bytes and copies like a built one.
        const MicromapBlob again = serialize(dst);
        EXPECT_EQ(0, std::memcmp(blob.data(), again.data(), blob.size));
        TestMicromap* compact = createMicromap(src->size);
        EXPECT_EQ(copy(dst, compact, VK_COPY_MICROMAP_MODE_COMPACT_EXT), VK_SUCCESS);
        EXPECT_TRUE(holdsStates(compact->data(), in));
    }
}

TEST_F(opacity_micromap_serialization, compatibility_compares_both_uuids) {
    TestMicromap* m = build(randomInput(4, 2));
    const MicromapBlob blob = serialize(m);
    for (size_t k = 0; k < 32; ++k) {
        std::vector<uint8_t> header(blob.data(), blob.data() + 32);
        header[k] ^= 0x01;
        VkMicromapVersionInfoEXT vi{VK_STRUCTURE_TYPE_MICROMAP_VERSION_INFO_EXT, nullptr, header.data()};
        VkAccelerationStructureCompatibilityKHR c = VK_ACCELERATION_STRUCTURE_COMPATIBILITY_COMPATIBLE_KHR;
        mm.compatibility(device, &vi, &c);
        EXPECT_EQ(c, VK_ACCELERATION_STRUCTURE_COMPATIBILITY_INCOMPATIBLE_KHR) << "byte " << k;
    }
    // A structure's serialized header is not a micromap's.
    std::vector<uint8_t> header(blob.data(), blob.data() + 32);
    std::memcpy(header.data() + 16, vkas::serial::kCompatibilityUuidV2, 16);
    VkMicromapVersionInfoEXT vi{VK_STRUCTURE_TYPE_MICROMAP_VERSION_INFO_EXT, nullptr, header.data()};
    VkAccelerationStructureCompatibilityKHR c;
    mm.compatibility(device, &vi, &c);
    EXPECT_EQ(c, VK_ACCELERATION_STRUCTURE_COMPATIBILITY_INCOMPATIBLE_KHR);
}

TEST_F(opacity_micromap_serialization, every_byte_flip_is_rejected) {
    MicromapInput in;
    in.add(fmt::kOpacityFormat2State, 2, [](uint64_t j) { return uint32_t(j * 5 + 1); });
    in.add(fmt::kOpacityFormat4State, 1, [](uint64_t j) { return uint32_t(j + 2); });
    in.add(fmt::kOpacityFormat4State, 3, [](uint64_t j) { return uint32_t(j * 3); });
    TestMicromap* src = build(in);
    const MicromapBlob blob = serialize(src);
    TestMicromap* dst = createMicromap(src->size);
    const std::vector<uint8_t> before(dst->data(), dst->data() + dst->size);
    const uint64_t dataOffset = reinterpret_cast<const fmt::MicromapHeader*>(src->data())->dataOffset;
    for (size_t k = 0; k < blob.size; ++k) {
        MicromapBlob bad = blob;
        bad.data()[k] ^= 0xFF;
        const VkResult r = deserialize(bad, dst);
        const std::vector<std::string> errors = takeValidationErrors();
        ASSERT_EQ(errors.size(), 1u) << "byte " << k;
        if (k < 32) {
            EXPECT_EQ(r, VK_ERROR_INCOMPATIBLE_VERSION_KHR) << "byte " << k;
            EXPECT_NE(errors[0].find("VUID-VkCopyMemoryToMicromapInfoEXT-src-07549"), std::string::npos) << errors[0];
        } else {
            EXPECT_EQ(r, VK_ERROR_VALIDATION_FAILED_EXT) << "byte " << k;
            EXPECT_NE(errors[0].find("VUID-VkCopyMemoryToMicromapInfoEXT-src-07547"), std::string::npos) << errors[0];
        }
        ASSERT_EQ(0, std::memcmp(before.data(), dst->data(), dst->size)) << "byte " << k << " wrote the micromap";
        // With the hash sealed again the block's own checks must catch it (the states themselves are free).
        if (k >= vkas::serial::kMicromapBlockOffset) {
            vkas::serial::SerializedMicromapView view;
            view.data = reinterpret_cast<const std::byte*>(bad.data());
            view.deserializedSize = src->size;
            view.block = view.data + vkas::serial::kMicromapBlockOffset;
            vkas::serial::sealMicromapIntegrityHash(view, reinterpret_cast<std::byte*>(bad.data()));
            const bool inStates = k - vkas::serial::kMicromapBlockOffset >= dataOffset;
            const auto check = fmt::checkSerializedMicromap(reinterpret_cast<const std::byte*>(bad.data()), bad.size);
            EXPECT_EQ(check.ok(), inStates) << "byte " << k << ": " << check.reason;
        }
    }
    // A truncated extent: the header's size is what the blob vouches for, and it is checked against the sizes.
    for (size_t size = 0; size < blob.size; ++size)
        EXPECT_FALSE(fmt::checkSerializedMicromap(reinterpret_cast<const std::byte*>(blob.data()), size).ok()) << size;
    EXPECT_TRUE(fmt::checkSerializedMicromap(reinterpret_cast<const std::byte*>(blob.data()), blob.size).ok());
}

// ---- The committed serialized micromaps ---------------------------------------------------------------------------
// tests/data/serialized_micromap_v1_{2state,4state}.bin were written by DISABLED_generate from the fixed inputs
// below. Every blob written by any release loads in every later release, with the same states.
MicromapInput goldenInput(uint16_t format) {
    MicromapInput in;
    in.flags = VK_BUILD_MICROMAP_ALLOW_COMPACTION_BIT_EXT;
    for (uint16_t level = 0; level <= 3; ++level)
        in.add(format, level, [=](uint64_t j) { return uint32_t(j * 7 + level * 3 + (j >> 2)); }, level);
    return in;
}
const char* goldenFile(uint16_t format) {
    return format == fmt::kOpacityFormat2State ? "serialized_micromap_v1_2state.bin" : "serialized_micromap_v1_4state.bin";
}

TEST_F(opacity_micromap_serialization, DISABLED_generate) {
    // Run with --gtest_also_run_disabled_tests and VKAS_WRITE_TEST_DATA=<dir> to write the files.
    const char* dir = std::getenv("VKAS_WRITE_TEST_DATA");
    ASSERT_NE(dir, nullptr) << "set VKAS_WRITE_TEST_DATA to the output directory";
    for (uint16_t format : {fmt::kOpacityFormat2State, fmt::kOpacityFormat4State}) {
        const MicromapBlob blob = serialize(build(goldenInput(format)));
        std::ofstream(std::string(dir) + "/" + goldenFile(format), std::ios::binary)
            .write(reinterpret_cast<const char*>(blob.data()), std::streamsize(blob.size));
    }
}

TEST_F(opacity_micromap_serialization, committed_blobs_load_with_their_states) {
    for (uint16_t format : {fmt::kOpacityFormat2State, fmt::kOpacityFormat4State}) {
        std::ifstream f(std::string(VKAS_TEST_DATA_DIR) + "/" + goldenFile(format), std::ios::binary);
        ASSERT_TRUE(f) << goldenFile(format);
        const std::vector<char> bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
        MicromapBlob blob;
        blob.allocate(bytes.size());
        std::memcpy(blob.data(), bytes.data(), bytes.size());
        VkMicromapVersionInfoEXT vi{VK_STRUCTURE_TYPE_MICROMAP_VERSION_INFO_EXT, nullptr, blob.data()};
        VkAccelerationStructureCompatibilityKHR c;
        mm.compatibility(device, &vi, &c);
        EXPECT_EQ(c, VK_ACCELERATION_STRUCTURE_COMPATIBILITY_COMPATIBLE_KHR);
        uint64_t deserialized;
        std::memcpy(&deserialized, blob.data() + 40, 8);
        ASSERT_EQ(blob.size, deserialized + 64);
        TestMicromap* m = createMicromap(deserialized);
        ASSERT_EQ(deserialize(blob, m), VK_SUCCESS);
        const MicromapInput in = goldenInput(format);
        EXPECT_TRUE(holdsStates(m->data(), in)) << goldenFile(format);
        EXPECT_EQ(property(m, VK_QUERY_TYPE_MICROMAP_COMPACTED_SIZE_EXT), deserialized);
        // Today's build of the same inputs serializes to the committed bytes.
        const MicromapBlob now = serialize(build(in));
        ASSERT_EQ(now.size, blob.size);
        EXPECT_EQ(0, std::memcmp(now.data(), blob.data(), blob.size)) << goldenFile(format);
    }
}

}  // namespace
