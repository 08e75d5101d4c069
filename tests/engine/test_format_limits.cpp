// The size arithmetic at the reported limits (issue 17, docs/FORMAT.md "Limits"): at maxPrimitiveCount (2^29 - 1)
// primitives in maxGeometryCount (2^24 - 1) geometries, and maxInstanceCount (2^24 - 1) instances, every size the
// build-sizes query and the builds compute equals FORMAT.md's formulas evaluated in 128-bit arithmetic (no
// wrap-around anywhere in 64 bits), and every count fits the field that stores it. No memory is allocated.
#include <gtest/gtest.h>

#include <vulkan/vulkan_core.h>

#include "api/limits.hpp"
#include "engine/assemble/size_query.hpp"
#include "engine/format/layout.hpp"
#include "engine/format/sizes.hpp"

namespace {

using namespace vkas;
using u128 = unsigned __int128;

constexpr uint64_t kMaxPrimitives = limits::kMaxPrimitiveCount;  // 2^29 - 1
constexpr uint64_t kMaxGeometries = limits::kMaxGeometryCount;   // 2^24 - 1
constexpr uint64_t kMaxInstances = limits::kMaxInstanceCount;    // 2^24 - 1

u128 align64(u128 v) { return (v + 63) / 64 * 64; }

// docs/FORMAT.md, "Build sizes", written out again independently of sizes.cpp.
u128 nodesBound(u128 n, u128 leaf) { return n <= leaf ? 0 : n / (leaf + 1) + (n - 1) / 7 + 1; }
u128 structureSizeFormula(u128 n, u128 g, u128 leaf, u128 record, u128 tail) {
    return align64(align64(256 + 32 * g) + 256 * nodesBound(n, leaf)) + record * n + (n > 0 ? tail : 0);
}
u128 scratchFormula(u128 n, u128 gathered) { return n == 0 ? 0 : 64 + n * (32 + gathered + 48); }

std::string show(u128 v) {
    std::string s;
    do s.insert(s.begin(), char('0' + int(v % 10))), v /= 10; while (v);
    return s;
}

struct Case {
    const char* what;
    format::StructureType type;
    VkGeometryTypeKHR geometry;
    bool motion;
    uint64_t primitives, geometries;
    uint64_t record, tail, gathered;
};

const Case kCases[] = {
    {"triangles", format::StructureType::BottomLevel, VK_GEOMETRY_TYPE_TRIANGLES_KHR, false, kMaxPrimitives, kMaxGeometries,
     format::kTriangleBytes, format::kTriangleTailBytes, sizeof(format::TriangleRecord)},
    {"AABBs", format::StructureType::BottomLevel, VK_GEOMETRY_TYPE_AABBS_KHR, false, kMaxPrimitives, kMaxGeometries,
     sizeof(format::AabbRecord), 0, sizeof(format::TriangleRecord)},
    {"motion triangles", format::StructureType::BottomLevel, VK_GEOMETRY_TYPE_TRIANGLES_KHR, true, kMaxPrimitives,
     kMaxGeometries, sizeof(format::MotionTriangleRecord), 0, sizeof(format::MotionTriangleRecord)},
    {"instances", format::StructureType::TopLevel, VK_GEOMETRY_TYPE_INSTANCES_KHR, false, kMaxInstances, 1,
     sizeof(format::InstanceRecord), 0, sizeof(format::InstanceRecord)},
    {"motion instances", format::StructureType::TopLevel, VK_GEOMETRY_TYPE_INSTANCES_KHR, true, kMaxInstances, 1,
     sizeof(format::MotionInstanceRecord), 0, sizeof(format::MotionInstanceRecord)},
};

TEST(format_limits, node_bound_and_references_fit_their_fields) {
    for (const uint64_t n : {kMaxPrimitives, kMaxPrimitives - 1, uint64_t(1) << 28, uint64_t(5)}) {
        const uint64_t nodes = maxWideNodeCount(n, format::kMaxPrimitivesPerLeaf);
        EXPECT_EQ(u128(nodes), nodesBound(n, format::kMaxPrimitivesPerLeaf)) << n;
        ASSERT_LT(nodes, uint64_t(1) << 32) << "header nodeCount and internal references are 32-bit";
        if (nodes == 0) continue;
        const uint32_t last = uint32_t(nodes - 1);
        EXPECT_TRUE(format::isInternal(format::makeInternalRef(last)));
        EXPECT_EQ(format::nodeIndex(format::makeInternalRef(last)), last);
    }
    EXPECT_EQ(maxWideNodeCount(kMaxPrimitives, format::kMaxPrimitivesPerLeaf), 184070027u);  // docs/FORMAT.md
    // The last leaf of the largest structure: its first record and count round-trip.
    const format::ChildRef leaf = format::makeLeafRef(kMaxPrimitives - 4, 4);
    EXPECT_TRUE(format::isLeaf(leaf));
    EXPECT_EQ(format::leafFirst(leaf), kMaxPrimitives - 4);
    EXPECT_EQ(format::leafCount(leaf), 4u);
    // Geometry indices up to maxGeometryCount - 1 fit a triangle leaf's 24 bits.
    EXPECT_LE(kMaxGeometries - 1, uint64_t(format::kGeometryIndexMask));
    EXPECT_EQ(format::packGeometryAndFlags(uint32_t(kMaxGeometries - 1), 0) & format::kGeometryIndexMask,
              kMaxGeometries - 1);
}

TEST(format_limits, sizes_at_the_limits_equal_the_formulas_without_wrapping) {
    for (const Case& c : kCases) {
        SCOPED_TRACE(c.what);
        const uint32_t leaf = maxLeafSize(c.type);
        const u128 expected = structureSizeFormula(c.primitives, c.geometries, leaf, c.record, c.tail);
        ASSERT_LT(expected, u128(1) << 63) << show(expected);
        EXPECT_EQ(recordSize(c.type, uint32_t(c.geometry == VK_GEOMETRY_TYPE_AABBS_KHR ? 1 : 0), c.motion), c.record);
        const uint64_t size = maxStructureSize(c.type, c.geometry == VK_GEOMETRY_TYPE_AABBS_KHR ? 1 : 0,
                                               uint32_t(c.geometries), c.primitives, c.motion);
        EXPECT_EQ(u128(size), expected) << show(u128(size)) << " vs " << show(expected);

        // The build-sizes query's engine side, from a build info of that kind.
        VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
        g.geometryType = c.geometry;
        VkAccelerationStructureBuildGeometryInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
        info.type = c.type == format::StructureType::TopLevel ? VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR
                                                              : VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
        info.flags = c.motion ? VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV : 0;
        info.geometryCount = uint32_t(c.geometries);
        info.pGeometries = &g;  // the kind is read from geometry 0 (every geometry of a bottom level has its type)
        const StructureSizes s = structureSizes(info, c.primitives);
        EXPECT_EQ(u128(s.structureSize), expected);
        const u128 scratch = scratchFormula(c.primitives, c.gathered);
        ASSERT_LT(scratch, u128(1) << 63);
        EXPECT_EQ(u128(s.buildScratchSize), scratch) << show(u128(s.buildScratchSize)) << " vs " << show(scratch);
        EXPECT_EQ(s.updateScratchSize, 0u);
    }
}

// Sizes grow with the count up to the limit (a query of fewer primitives never asks for more), so a build of
// fewer primitives than queried always fits (docs/FORMAT.md).
TEST(format_limits, sizes_are_monotone_near_the_limit) {
    uint64_t previous = 0;
    for (uint64_t n = kMaxPrimitives - 64; n <= kMaxPrimitives; ++n) {
        const uint64_t size = maxStructureSize(format::StructureType::BottomLevel, 0, 1, n);
        EXPECT_GE(size, previous) << n;
        previous = size;
    }
}

}  // namespace
