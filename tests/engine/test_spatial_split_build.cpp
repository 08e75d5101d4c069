// PREFER_FAST_TRACE's spatial splits (builders/spatial_split_builder.hpp, format/fragment_section.hpp) on plain memory:
// a structure of large, overlapping triangles is built with fragments; for random points of every triangle exactly
// one of its records has a region that holds the point, and that record's leaf box holds it too (so a ray through
// the point visits the one fragment that reports it); the sizes query bounds the structure; threads change no byte;
// a damaged fragment section is refused.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <map>
#include <thread>
#include <vector>

#include "engine/assemble/size_query.hpp"
#include "engine/assemble/structure_build.hpp"
#include "engine/format/check.hpp"
#include "engine/format/fragment_section.hpp"
#include "engine/format/layout.hpp"
#include "engine/util/parallel_for.hpp"
#include "vkas_test.hpp"

namespace {

using namespace vkas;
using format::ChildRef;

// A ParallelFor on four threads that take indices in an order of their own.
const ParallelFor kFourThreads = [](uint32_t count, FunctionRef<void(uint32_t)> fn) {
    std::vector<std::thread> threads;
    for (uint32_t t = 0; t < 4; ++t)
        threads.emplace_back([&, t] {
            for (uint32_t i = count; i-- > 0;)
                if (i % 4 == t) fn(i);
        });
    for (auto& th : threads) th.join();
};

struct SpatialSplits : ::testing::Test {
    uint64_t seed = vt::chooseSeed();
    vt::Rng rng{seed};
    std::vector<float> vertices;
    uint32_t triangles = 0;

    void SetUp() override {
        std::cout << "[   SEED   ] VKAS_TEST_SEED=" << seed << std::endl;
        RecordProperty("VKAS_TEST_SEED", std::to_string(seed));
    }

    // Long slivers and large triangles among small ones, all overlapping: the case spatial splits are for.
    void makeTriangles(uint32_t count) {
        triangles = count;
        vertices.clear();
        for (uint32_t i = 0; i < count; ++i) {
            const float c[3] = {rng.uniformf(-10, 10), rng.uniformf(-10, 10), rng.uniformf(-10, 10)};
            const float size = rng.coin(0.2) ? 8.0f : rng.coin(0.5) ? 2.0f : 0.3f;
            const bool sliver = rng.coin(0.5);
            for (int k = 0; k < 3; ++k)
                for (int a = 0; a < 3; ++a) {
                    const float spread = sliver && k == 2 ? 0.05f : size;
                    vertices.push_back(c[a] + rng.uniformf(-spread, spread));
                }
        }
    }

    std::vector<std::byte> build(VkBuildAccelerationStructureFlagsKHR flags, const ParallelFor* parallel,
                                 uint64_t* sizeBound = nullptr) {
        VkAccelerationStructureGeometryKHR geometry{};
        geometry.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR;
        geometry.geometryType = VK_GEOMETRY_TYPE_TRIANGLES_KHR;
        auto& t = geometry.geometry.triangles;
        t.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR;
        t.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
        t.vertexData.hostAddress = vertices.data();
        t.vertexStride = 12;
        t.maxVertex = 3 * triangles - 1;
        t.indexType = VK_INDEX_TYPE_NONE_KHR;
        VkAccelerationStructureBuildRangeInfoKHR range{triangles, 0, 0, 0};
        VkAccelerationStructureBuildGeometryInfoKHR info{};
        info.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR;
        info.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
        info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR;
        info.flags = flags;
        info.geometryCount = 1;
        info.pGeometries = &geometry;
        const StructureSizes sizes = structureSizes(info, triangles);
        std::vector<std::byte> scratch(sizes.buildScratchSize, std::byte{0xAA});
        std::vector<std::byte> block(sizes.structureSize, std::byte{0xAA});
        info.scratchData.hostAddress = scratch.data();
        BuildJob job{&info, &range, block.data(), block.size(), nullptr, parallel};
        EXPECT_EQ(buildAccelerationStructure(job), VK_SUCCESS);
        if (sizeBound) *sizeBound = sizes.structureSize;
        block.resize(format::header(block.data())->usedSize);
        return block;
    }
};

constexpr VkBuildAccelerationStructureFlagsKHR kFastTrace = VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR;

// Every leaf of the tree with the box of the slot (or the root's bounds) that names it.
struct LeafBox {
    ChildRef ref;
    float lower[3], upper[3];
};
std::vector<LeafBox> leavesOf(const std::byte* block) {
    const format::Header& h = *format::header(block);
    std::vector<LeafBox> out;
    if (format::isLeaf(h.root)) out.push_back({h.root, {h.bounds[0], h.bounds[1], h.bounds[2]}, {h.bounds[3], h.bounds[4], h.bounds[5]}});
    const format::Node* nodes = format::nodes(block);
    for (uint32_t k = 0; k < h.nodeCount; ++k)
        for (uint32_t c = 0; c < format::kNodeWidth; ++c)
            if (format::isLeaf(nodes[k].child[c]))
                out.push_back({nodes[k].child[c],
                               {nodes[k].lowerX[c], nodes[k].lowerY[c], nodes[k].lowerZ[c]},
                               {nodes[k].upperX[c], nodes[k].upperY[c], nodes[k].upperZ[c]}});
    return out;
}

TEST_F(SpatialSplits, every_point_of_a_triangle_has_exactly_one_fragment_whose_box_holds_it) {
    makeTriangles(3000);
    uint64_t bound = 0;
    const std::vector<std::byte> block = build(kFastTrace, nullptr, &bound);
    const format::Header& h = *format::header(block.data());
    ASSERT_TRUE(format::checkBlock(block.data(), block.size()).ok()) << format::checkBlock(block.data(), block.size()).reason;
    EXPECT_GT(h.fragmentCount, 0u) << "no triangle was split";
    EXPECT_GT(h.recordCount, h.primitiveCount);
    EXPECT_LE(h.recordCount, h.primitiveCount + h.primitiveCount / 4) << "more cuts than the budget";
    EXPECT_LE(h.usedSize, bound) << "the sizes query does not bound the structure";
    std::cout << "records " << h.recordCount << " for " << h.primitiveCount << " triangles, " << h.fragmentCount
              << " fragments, " << h.usedSize << " of " << bound << " bytes" << std::endl;

    // The records of each primitive, with their leaf boxes.
    struct Record {
        uint32_t index;
        float v[3][3];
        uint32_t flags;
        LeafBox box;
    };
    std::map<uint32_t, std::vector<Record>> byPrimitive;
    const std::byte* records = format::records(block.data());
    for (const LeafBox& leaf : leavesOf(block.data())) {
        const auto view = format::triangleLeaf(records, format::leafFirst(leaf.ref), format::leafCount(leaf.ref));
        for (uint32_t l = 0; l < view.n; ++l) {
            Record r{uint32_t(format::leafFirst(leaf.ref) + l), {}, view.flags(l), leaf};
            view.positions(l, r.v);
            byPrimitive[view.primitiveIndex()[l]].push_back(r);
        }
    }
    ASSERT_EQ(byPrimitive.size(), triangles);
    uint32_t pointsInCutTriangles = 0;
    for (const auto& [primitive, recs] : byPrimitive) {
        ASSERT_FALSE(recs.empty());
        if (recs.size() == 1) {
            EXPECT_FALSE(recs[0].flags & format::kTriangleFragment) << "a lone record flagged as a fragment";
            continue;
        }
        for (const Record& r : recs) {
            ASSERT_TRUE(r.flags & format::kTriangleFragment) << "primitive " << primitive << " stored twice unflagged";
            ASSERT_EQ(std::memcmp(r.v, recs[0].v, sizeof r.v), 0) << "fragments of one triangle differ";
        }
        for (int s = 0; s < 64; ++s) {
            // Points as the trace computes them: float barycentrics, some on the plane of a cut or an edge.
            float b = rng.uniformf(0, 1), c = rng.uniformf(0, 1);
            if (b + c > 1) b = 1 - b, c = 1 - c;
            if (s % 8 == 0) c = 0;
            double p[3];
            for (int a = 0; a < 3; ++a)
                p[a] = double(recs[0].v[0][a]) + double(b) * (double(recs[0].v[1][a]) - recs[0].v[0][a]) +
                       double(c) * (double(recs[0].v[2][a]) - recs[0].v[0][a]);
            uint32_t holders = 0;
            for (const Record& r : recs) {
                const format::FragmentEntry* e = format::findFragment(block.data(), r.index);
                ASSERT_NE(e, nullptr);
                if (!format::fragmentHolds(*e, p)) continue;
                ++holders;
                for (int a = 0; a < 3; ++a) {
                    EXPECT_GE(p[a], r.box.lower[a]) << "primitive " << primitive << " axis " << a;
                    EXPECT_LE(p[a], r.box.upper[a]) << "primitive " << primitive << " axis " << a;
                }
            }
            EXPECT_EQ(holders, 1u) << "primitive " << primitive << " at b=" << b << " c=" << c;
            ++pointsInCutTriangles;
        }
    }
    EXPECT_GT(pointsInCutTriangles, 0u);
}

TEST_F(SpatialSplits, threads_change_no_byte_and_other_flags_make_no_fragments) {
    makeTriangles(2000);
    const std::vector<std::byte> serial = build(kFastTrace, nullptr);
    EXPECT_GT(format::header(serial.data())->fragmentCount, 0u);
    EXPECT_EQ(build(kFastTrace, &kFourThreads), serial);
    for (const VkBuildAccelerationStructureFlagsKHR flags :
         {VkBuildAccelerationStructureFlagsKHR(0),
          VkBuildAccelerationStructureFlagsKHR(kFastTrace | VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR),
          VkBuildAccelerationStructureFlagsKHR(VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR)}) {
        const std::vector<std::byte> block = build(flags, nullptr);
        const format::Header& h = *format::header(block.data());
        EXPECT_EQ(h.fragmentCount, 0u) << flags;
        EXPECT_EQ(h.fragmentOffset, 0u) << flags;
        EXPECT_EQ(h.recordCount, h.primitiveCount) << flags;
    }
}

TEST_F(SpatialSplits, a_small_structure_is_never_cut) {
    makeTriangles(63);  // below the budget's threshold (format/sizes.hpp, spatialSplitBudget)
    const std::vector<std::byte> block = build(kFastTrace, nullptr);
    EXPECT_EQ(format::header(block.data())->fragmentCount, 0u);
    EXPECT_EQ(format::header(block.data())->recordCount, 63u);
}

TEST_F(SpatialSplits, a_damaged_fragment_section_is_refused) {
    makeTriangles(1500);
    const std::vector<std::byte> block = build(kFastTrace, nullptr);
    format::Header h;
    std::memcpy(&h, block.data(), sizeof h);
    ASSERT_GT(h.fragmentCount, 2u);
    ASSERT_TRUE(format::checkBlock(block.data(), block.size()).ok());
    auto entryAt = [&](std::vector<std::byte>& b, uint32_t i) {
        return reinterpret_cast<format::FragmentEntry*>(b.data() + h.fragmentOffset) + i;
    };
    auto refused = [&](const std::function<void(std::vector<std::byte>&)>& damage, const char* what) {
        std::vector<std::byte> copy = block;
        damage(copy);
        const format::CheckResult r = format::checkBlock(copy.data(), copy.size());
        EXPECT_EQ(r.status, format::CheckStatus::Corrupt) << what;
    };
    const uint32_t mid = h.fragmentCount / 2;
    refused([&](auto& b) { std::swap(*entryAt(b, 0), *entryAt(b, 1)); }, "entries out of order");
    refused([&](auto& b) { entryAt(b, mid)->record = h.recordCount; }, "a record outside the array");
    refused([&](auto& b) { entryAt(b, mid)->reserved = 1; }, "a reserved word");
    refused([&](auto& b) { entryAt(b, mid)->upper[1] = entryAt(b, mid)->lower[1]; }, "an empty region");
    refused([&](auto& b) { entryAt(b, mid)->lower[2] = std::nanf(""); }, "a NaN region");
    refused([&](auto& b) { reinterpret_cast<format::Header*>(b.data())->fragmentCount -= 1; }, "a fragment left out");
    refused([&](auto& b) { reinterpret_cast<format::Header*>(b.data())->fragmentCount += 1; }, "count past the section");
    refused([&](auto& b) { reinterpret_cast<format::Header*>(b.data())->fragmentOffset += 16; }, "offset moved");
    refused([&](auto& b) { reinterpret_cast<format::Header*>(b.data())->fragmentOffset = 0; }, "offset cleared");
    refused([&](auto& b) { reinterpret_cast<format::Header*>(b.data())->reserved1 = 7; }, "reserved header word");
    refused(
        [&](auto& b) {
            format::Header* hh = reinterpret_cast<format::Header*>(b.data());
            hh->fragmentCount = 0, hh->fragmentOffset = 0;
        },
        "flagged records without a section");
    // An entry's record that is not flagged: move the first entry onto an unflagged record before the second.
    refused(
        [&](auto& b) {
            format::FragmentEntry* e = entryAt(b, 0);
            if (e->record > 0) e->record -= 1;
            else entryAt(b, 0)->record = entryAt(b, 1)->record;  // then a duplicate, also refused
        },
        "an entry for an unflagged record");
}

}  // namespace
