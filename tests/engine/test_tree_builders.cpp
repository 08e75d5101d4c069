// The builders behind the selector (builders/tree_builder.hpp) on their own, on random boxes: each keeps the output
// contract every structure relies on (refs reordered so that leaves are ranges of them, every primitive in exactly
// one leaf of at most maxLeafSize, nodes in preorder, at most maxWideNodeCount(n) of them, depth within
// format::kMaxTreeDepth, child boxes that hold their subtree), and a build spread over threads writes the same bytes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <functional>
#include <thread>
#include <vector>

#include "engine/builders/tree_builder.hpp"
#include "engine/builders/wide_collapse.hpp"
#include "engine/format/sizes.hpp"
#include "engine/util/parallel_for.hpp"
#include "vkas_test.hpp"

namespace {

using namespace vkas;
using format::ChildRef;
using format::Node;

struct TreeBuilders : ::testing::Test {
    uint64_t seed = vt::chooseSeed();
    vt::Rng rng{seed};
    void SetUp() override {
        std::cout << "[   SEED   ] VKAS_TEST_SEED=" << seed << std::endl;
        RecordProperty("VKAS_TEST_SEED", std::to_string(seed));
    }

    // n boxes: clustered, spread, flat, duplicated (equal centroids are the hard case for both builders).
    std::vector<PrimRef> randomRefs(uint32_t n) {
        std::vector<PrimRef> refs(n);
        const uint32_t mode = rng.below(3);
        for (uint32_t i = 0; i < n; ++i) {
            Aabb b;
            Vec3 c{rng.uniformf(-100, 100), rng.uniformf(-100, 100), rng.uniformf(-100, 100)};
            // many duplicates, and zeros of both signs (which a union's order could tell apart)
            if (mode == 1) c = Vec3{float(rng.below(4)), float(rng.below(4)), rng.coin() ? 0.0f : -0.0f};
            const float s = mode == 2 ? 0.0f : rng.uniformf(0.0f, 5.0f);
            b.extend(c);
            b.extend(Vec3{c.x + s, c.y + rng.uniformf(0.0f, s + 1e-3f), c.z});
            setPrimRef(refs[i], i, b);
        }
        return refs;
    }
};

// Checks the tree below `ref` and returns the union of what it holds; counts each primitive's occurrences.
Aabb checkSubtree(const std::vector<Node>& nodes, ChildRef ref, uint32_t parent, uint32_t depth, uint32_t maxLeaf,
                  const std::vector<PrimRef>& refs, std::vector<uint32_t>& seen) {
    EXPECT_LE(depth, format::kMaxTreeDepth);
    Aabb box;
    if (format::isLeaf(ref)) {
        const uint64_t first = format::leafFirst(ref);
        const uint32_t count = format::leafCount(ref);
        EXPECT_GE(count, 1u);
        EXPECT_LE(count, maxLeaf);
        EXPECT_LE(first + count, refs.size());
        for (uint64_t i = first; i < first + count && i < refs.size(); ++i) {
            ++seen[refs[i].index];
            box.extend(Vec3{refs[i].lower[0], refs[i].lower[1], refs[i].lower[2]});
            box.extend(Vec3{refs[i].upper[0], refs[i].upper[1], refs[i].upper[2]});
        }
        return box;
    }
    EXPECT_TRUE(format::isInternal(ref));
    const uint32_t k = format::nodeIndex(ref);
    EXPECT_LT(k, nodes.size());
    if (k >= nodes.size()) return box;
    EXPECT_TRUE(parent == UINT32_MAX || k > parent) << "node " << k << " after its parent " << parent;
    const Node& n = nodes[k];
    for (uint32_t i = 0; i < format::kNodeWidth; ++i) {
        if (n.child[i] == format::kEmptyRef) continue;
        const Aabb c = checkSubtree(nodes, n.child[i], k, depth + 1, maxLeaf, refs, seen);
        EXPECT_TRUE(n.lowerX[i] <= c.lower.x && n.lowerY[i] <= c.lower.y && n.lowerZ[i] <= c.lower.z &&
                    n.upperX[i] >= c.upper.x && n.upperY[i] >= c.upper.y && n.upperZ[i] >= c.upper.z)
            << "node " << k << " slot " << i << " does not hold its subtree";
        // Tight, too: a slot's box is its subtree's union, also where the split was chosen from a sample of the
        // range (BvhBuildSettings::binSampleTarget) and the bounds came from the partition.
        EXPECT_TRUE(n.lowerX[i] == c.lower.x && n.lowerY[i] == c.lower.y && n.lowerZ[i] == c.lower.z &&
                    n.upperX[i] == c.upper.x && n.upperY[i] == c.upper.y && n.upperZ[i] == c.upper.z)
            << "node " << k << " slot " << i << " is larger than its subtree";
        box.extend(c);
    }
    return box;
}

struct Built {
    BvhBuildResult result;
    std::vector<Node> nodes;
    std::vector<PrimRef> refs;
};

Built build(std::vector<PrimRef> refs, const BvhBuildSettings& settings, const ParallelFor* parallel) {
    Built b;
    const uint32_t n = uint32_t(refs.size());
    b.nodes.resize(std::max<uint64_t>(1, maxWideNodeCount(n, settings.maxLeafSize)));
    std::memset(b.nodes.data(), 0, b.nodes.size() * sizeof(Node));
    std::vector<uint64_t> workspace(n * treeWorkspacePerPrimitive(settings) / 8 + 2);  // 16-byte aligned on this platform
    b.result = buildTree(refs.data(), n, settings, b.nodes.data(), reinterpret_cast<std::byte*>(workspace.data()), parallel);
    b.nodes.resize(b.result.nodeCount);
    b.refs = std::move(refs);
    return b;
}

// A ParallelFor on four threads that take indices in an order of their own.
const ParallelFor kFourThreads = [](uint32_t count, const std::function<void(uint32_t)>& fn) {
    std::vector<std::thread> threads;
    for (uint32_t t = 0; t < 4; ++t)
        threads.emplace_back([&, t] {
            for (uint32_t i = count; i-- > 0;)
                if (i % 4 == t) fn(i);
        });
    for (auto& th : threads) th.join();
};

TEST_F(TreeBuilders, both_builders_keep_the_output_contract_and_ignore_threading) {
    const uint32_t sizes[] = {0, 1, 4, 5, 9, 33, 1000, 20000, 150000};
    for (uint32_t n : sizes) {
        for (uint32_t flags : {0u, uint32_t(VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR),
                               uint32_t(VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR)}) {
            for (uint32_t maxLeaf : {format::kMaxPrimitivesPerLeaf, format::kMaxInstancesPerLeaf}) {
                SCOPED_TRACE(::testing::Message() << "n " << n << " flags " << flags << " maxLeaf " << maxLeaf);
                const std::vector<PrimRef> refs = randomRefs(n);
                const BvhBuildSettings settings = buildSettingsFor(maxLeaf, flags);
                const TreeBuilder expected =
                    (flags & VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR)   ? TreeBuilder::Morton
                    : (flags & VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR) ? TreeBuilder::Quality
                                                                                          : TreeBuilder::Sah;
                EXPECT_EQ(settings.builder, expected);
                // Only the default bottom-level build bins samples of large ranges (n 20000 and 150000 do).
                EXPECT_EQ(settings.binSampleTarget != 0, flags == 0 && maxLeaf != format::kMaxInstancesPerLeaf);
                const Built serial = build(refs, settings, nullptr);
                EXPECT_LE(serial.result.nodeCount, maxWideNodeCount(n, maxLeaf));
                std::vector<uint32_t> seen(n, 0);
                if (n == 0) {
                    EXPECT_EQ(serial.result.root, format::kEmptyRef);
                } else {
                    const Aabb all =
                        checkSubtree(serial.nodes, serial.result.root, UINT32_MAX, 0, maxLeaf, serial.refs, seen);
                    EXPECT_TRUE(serial.result.bounds.lower.x <= all.lower.x &&
                                serial.result.bounds.upper.x >= all.upper.x);
                }
                EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](uint32_t s) { return s == 1; }))
                    << "a primitive is in no leaf or in several";
                const Built threaded = build(refs, settings, &kFourThreads);
                ASSERT_EQ(threaded.result.nodeCount, serial.result.nodeCount);
                EXPECT_EQ(threaded.result.root, serial.result.root);
                EXPECT_EQ(std::memcmp(&threaded.result.bounds, &serial.result.bounds, sizeof(Aabb)), 0);
                // (empty vectors may have null data, which memcmp must not get)
                EXPECT_TRUE(serial.nodes.empty() || std::memcmp(threaded.nodes.data(), serial.nodes.data(),
                                                                serial.nodes.size() * sizeof(Node)) == 0);
                EXPECT_TRUE(n == 0 || std::memcmp(threaded.refs.data(), serial.refs.data(), n * sizeof(PrimRef)) == 0);
            }
        }
    }
}

// The cost the quality builder's collapse minimises (builders/wide_collapse.hpp), of a built tree: each internal node's
// area times the node cost, each leaf's area times the leaf cost and its primitives'.
double collapseCost(const Built& b, ChildRef ref, const Aabb& box, const CollapseCosts& c) {
    const double area = box.halfArea();
    if (format::isLeaf(ref)) return area * (c.leaf + c.primitive * format::leafCount(ref));
    const Node& n = b.nodes[format::nodeIndex(ref)];
    double cost = area * c.node;
    for (uint32_t i = 0; i < format::kNodeWidth; ++i) {
        if (n.child[i] == format::kEmptyRef) continue;
        const Aabb slot{{n.lowerX[i], n.lowerY[i], n.lowerZ[i]}, {n.upperX[i], n.upperY[i], n.upperZ[i]}};
        cost += collapseCost(b, n.child[i], slot, c);
    }
    return cost;
}

// The default build's greedy node filling makes its nodes from the same binned splits as the quality builder's
// binary tree (the same ranges, bins and partitions), so its tree is one of those the collapse chooses from: the
// collapse's can only cost less.
TEST_F(TreeBuilders, the_quality_builders_collapse_costs_no_more_than_greedy_node_filling) {
    for (uint32_t n : {5u, 9u, 33u, 1000u, 20000u, 150000u}) {
        for (uint32_t maxLeaf : {format::kMaxPrimitivesPerLeaf, format::kMaxInstancesPerLeaf}) {
            SCOPED_TRACE(::testing::Message() << "n " << n << " maxLeaf " << maxLeaf);
            const std::vector<PrimRef> refs = randomRefs(n);
            const BvhBuildSettings quality = buildSettingsFor(maxLeaf, VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR);
            BvhBuildSettings greedy = quality;
            greedy.builder = TreeBuilder::Sah;
            const Built q = build(refs, quality, nullptr), g = build(refs, greedy, nullptr);
            const double qc = collapseCost(q, q.result.root, q.result.bounds, CollapseCosts{});
            const double gc = collapseCost(g, g.result.root, g.result.bounds, CollapseCosts{});
            EXPECT_LE(qc, gc * (1 + 1e-5)) << "collapse " << qc << ", greedy " << gc;
            std::cout << "  n " << n << " maxLeaf " << maxLeaf << ": collapse cost " << qc << ", greedy " << gc << "\n";
        }
    }
}

TEST(ParallelForChunks, fixed_chunks_cover_the_range_once_whatever_the_threads) {
    for (uint64_t n : {0ull, 1ull, 16383ull, 16384ull, 16385ull, 100000ull}) {
        for (const ParallelFor* parallel : {static_cast<const ParallelFor*>(nullptr), &kFourThreads}) {
            std::vector<uint8_t> hit(n, 0);
            std::vector<uint64_t> begins(chunkCount(n, 16384), UINT64_MAX);
            parallelForChunks(parallel, n, 16384, [&](uint32_t c, uint64_t begin, uint64_t end) {
                begins[c] = begin;
                for (uint64_t i = begin; i < end; ++i) ++hit[i];
            });
            EXPECT_TRUE(std::all_of(hit.begin(), hit.end(), [](uint8_t h) { return h == 1; })) << "n " << n;
            for (size_t c = 0; c < begins.size(); ++c) EXPECT_EQ(begins[c], c * 16384) << "n " << n;
        }
    }
}

}  // namespace
