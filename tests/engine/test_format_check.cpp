// The format's checks of untrusted bytes (format/check.hpp) on their own: a structure the engine builds on plain
// memory passes; each kind of damage a blob can carry is refused with Corrupt, never read past the given size.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "engine/assemble/size_query.hpp"
#include "engine/assemble/structure_build.hpp"
#include "engine/format/check.hpp"
#include "engine/format/inspect.hpp"
#include "engine/format/layout.hpp"
#include "vkas_test.hpp"

namespace {

using namespace vkas;

struct FormatCheck : ::testing::Test {
    uint64_t seed = vt::chooseSeed();
    vt::Rng rng{seed};
    std::vector<float> vertices;
    std::vector<std::byte> block;

    void SetUp() override {
        std::cout << "[   SEED   ] VKAS_TEST_SEED=" << seed << std::endl;
        RecordProperty("VKAS_TEST_SEED", std::to_string(seed));
        // A bottom level of random triangles, built by the engine alone (no device, no handles).
        const uint32_t triangles = 500;
        for (uint32_t i = 0; i < 9 * triangles; ++i) vertices.push_back(rng.uniformf(-10.0f, 10.0f));
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
        info.geometryCount = 1;
        info.pGeometries = &geometry;
        const StructureSizes sizes = structureSizes(info, triangles);
        std::vector<std::byte> scratch(sizes.buildScratchSize);
        block.assign(sizes.structureSize, std::byte{0xAA});
        info.scratchData.hostAddress = scratch.data();
        BuildJob job{&info, &range, block.data(), block.size(), nullptr};
        ASSERT_EQ(buildAccelerationStructure(job), VK_SUCCESS);
        block.resize(format::header(block.data())->usedSize);
    }

    format::Header headerCopy() const {
        format::Header h;
        std::memcpy(&h, block.data(), sizeof h);
        return h;
    }
    format::CheckStatus checkWith(const format::Header& h) {
        std::vector<std::byte> copy = block;
        std::memcpy(copy.data(), &h, sizeof h);
        return format::checkBlock(copy.data(), copy.size()).status;
    }
};

TEST_F(FormatCheck, a_built_structure_passes) {
    EXPECT_TRUE(format::checkBlock(block.data(), block.size()).ok()) << format::checkBlock(block.data(), block.size()).reason;
}

// The format's one reader for the tools (engine/format/inspect.hpp): its counts agree with the header and with a
// walk of its own here, its bytes by part add up, and damaged blocks give a reason instead of reading past them.
TEST_F(FormatCheck, inspection_reads_what_the_build_wrote) {
    format::TreeInspection in;
    ASSERT_EQ(format::inspectTree(block.data(), block.size(), in), nullptr);
    const format::Header h = headerCopy();
    EXPECT_EQ(in.internalNodes, h.nodeCount);
    EXPECT_EQ(in.references, h.recordCount);  // no spatial splits: every record once
    EXPECT_TRUE(in.triangleLeaves);
    EXPECT_EQ(in.headerBytes + in.geometryBytes + in.nodeBytes + in.recordBytes + in.micromapBytes + in.fragmentBytes +
                  in.paddingBytes,
              h.usedSize);
    uint64_t leaves = 0, sized = 0, children = 0;
    for (uint64_t n : in.leavesAtDepth) leaves += n;
    for (size_t n = 0; n < in.leafSizes.size(); ++n) sized += n * in.leafSizes[n];
    for (size_t k = 0; k < in.childrenPerNode.size(); ++k) children += k * in.childrenPerNode[k];
    EXPECT_EQ(leaves, in.leaves);
    EXPECT_EQ(sized, in.references);
    EXPECT_EQ(children, in.internalNodes - 1 + in.leaves);  // every node but the root and every leaf is a child
    EXPECT_GT(in.sahCost(), 1.0);
    std::vector<Aabb> level0;
    ASSERT_EQ(format::boxesAtLevel(block.data(), block.size(), 0, level0), nullptr);
    ASSERT_GE(in.nodesAtDepth.size(), 2u);
    const uint64_t rootChildren = in.nodesAtDepth[1] + (in.leavesAtDepth.size() > 1 ? in.leavesAtDepth[1] : 0);
    EXPECT_EQ(level0.size(), rootChildren);  // level 0: the root node's children
    // Damage: short, wrong magic, a root past the nodes.
    EXPECT_NE(format::inspectTree(block.data(), 100, in), nullptr);
    std::vector<std::byte> copy = block;
    format::Header d = h;
    d.magic ^= 1;
    std::memcpy(copy.data(), &d, sizeof d);
    EXPECT_NE(format::inspectTree(copy.data(), copy.size(), in), nullptr);
    d = h, d.root = format::makeInternalRef(h.nodeCount);
    std::memcpy(copy.data(), &d, sizeof d);
    format::TreeInspection damaged;
    EXPECT_NE(format::inspectTree(copy.data(), copy.size(), damaged), nullptr);
}

TEST_F(FormatCheck, every_kind_of_damage_is_refused) {
    using format::CheckStatus;
    format::Header h = headerCopy();
    h.magic ^= 1;
    EXPECT_EQ(checkWith(h), CheckStatus::Corrupt) << "magic";
    h = headerCopy(), h.version = 99;
    EXPECT_EQ(checkWith(h), CheckStatus::Corrupt) << "version";
    h = headerCopy(), h.usedSize = block.size() + 64;
    EXPECT_EQ(checkWith(h), CheckStatus::Corrupt) << "usedSize beyond the bytes";
    h = headerCopy(), h.nodeCount += 1000;
    EXPECT_EQ(checkWith(h), CheckStatus::Corrupt) << "nodes beyond usedSize";
    h = headerCopy(), h.recordCount += 1;
    EXPECT_EQ(checkWith(h), CheckStatus::Corrupt) << "records beyond usedSize";
    h = headerCopy(), h.root = format::makeInternalRef(h.nodeCount);
    EXPECT_EQ(checkWith(h), CheckStatus::Corrupt) << "root past the nodes";
    h = headerCopy(), h.geometryOffset = 3;
    EXPECT_EQ(checkWith(h), CheckStatus::Corrupt) << "sections out of order";
    // A node that names itself (a loop traversal could not leave) and a leaf past the records.
    {
        std::vector<std::byte> copy = block;
        const format::Header hh = headerCopy();
        auto* nodes = reinterpret_cast<format::Node*>(copy.data() + hh.nodeOffset);
        ASSERT_GT(hh.nodeCount, 0u);
        nodes[0].child[0] = format::makeInternalRef(0);
        EXPECT_EQ(format::checkBlock(copy.data(), copy.size()).status, CheckStatus::Corrupt) << "a loop";
        copy = block;
        nodes = reinterpret_cast<format::Node*>(copy.data() + hh.nodeOffset);
        for (auto& c : nodes[0].child)
            if (format::isLeaf(c)) c = format::makeLeafRef(hh.recordCount, 1);
        for (auto& c : nodes[0].child)
            if (format::isInternal(c)) c = format::makeLeafRef(hh.recordCount, 1);
        EXPECT_EQ(format::checkBlock(copy.data(), copy.size()).status, CheckStatus::Corrupt) << "a leaf past the records";
    }
    // A triangle leaf lane (format 2) naming a geometry or primitive the structure does not have.
    {
        const format::Header hh = headerCopy();
        const auto* nodes = reinterpret_cast<const format::Node*>(block.data() + hh.nodeOffset);
        format::ChildRef leaf = format::kEmptyRef;
        for (uint32_t k = 0; k < hh.nodeCount && leaf == format::kEmptyRef; ++k)
            for (const auto c : nodes[k].child)
                if (format::isLeaf(c)) leaf = c;
        ASSERT_NE(leaf, format::kEmptyRef);
        std::vector<std::byte> copy = block;
        format::MutableTriangleLeaf lanes =
            format::triangleLeaf(copy.data() + hh.recordOffset, format::leafFirst(leaf), format::leafCount(leaf));
        lanes.geometryAndFlags()[lanes.n - 1] += 1;  // geometry 1 of a structure with one
        EXPECT_EQ(format::checkBlock(copy.data(), copy.size()).status, CheckStatus::Corrupt) << "a lane's geometry";
        copy = block;
        lanes = format::triangleLeaf(copy.data() + hh.recordOffset, format::leafFirst(leaf), format::leafCount(leaf));
        lanes.primitiveIndex()[0] = 500;
        EXPECT_EQ(format::checkBlock(copy.data(), copy.size()).status, CheckStatus::Corrupt) << "a lane's primitive";
        // Two leaves over the same records (their rows would overlap): refused even when the counts still add up.
        copy = block;
        auto* mutableNodes = reinterpret_cast<format::Node*>(copy.data() + hh.nodeOffset);
        format::ChildRef* a = nullptr;
        format::ChildRef* b = nullptr;
        for (uint32_t k = 0; k < hh.nodeCount && !b; ++k)
            for (auto& c : mutableNodes[k].child)
                if (format::isLeaf(c) && format::leafCount(c) >= 2) (a ? b : a) = &c;
        ASSERT_NE(b, nullptr);
        const uint32_t na = format::leafCount(*a), nb = format::leafCount(*b);
        *a = format::makeLeafRef(format::leafFirst(*b), na);  // a now starts where b does
        *b = format::makeLeafRef(format::leafFirst(*b), nb);
        EXPECT_EQ(format::checkBlock(copy.data(), copy.size()).status, CheckStatus::Corrupt) << "overlapping leaves";
    }
    // Every truncation: refused, and nothing read past the end (the sanitizer build would see it).
    for (uint64_t size = 0; size < block.size(); size += 1 + size / 8) {
        std::vector<std::byte> cut(block.begin(), block.begin() + size);
        EXPECT_FALSE(format::checkBlock(cut.data(), cut.size()).ok()) << "truncated to " << size;
    }
}

}  // namespace
