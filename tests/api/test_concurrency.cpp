// Reliability under threads (issue 20): vkas used from many threads at once, as the Vulkan threading rules allow
// (docs/API.md "Host synchronization"). Deferred builds, copies and serializations joined from many threads; ray
// queries and vkasTraceRays batches on shared structures while other threads build, update, compact, serialize,
// deserialize and destroy other structures of the same device; several devices at once. Every hit is checked
// against the brute-force oracle, every structure's serialized bytes against a single-threaded build's. The test
// outcome never depends on timing: the threads run fixed amounts of work. Run under ThreadSanitizer by
// scripts/run-tests.sh (step tsan, build-tsan/ with VKAS_TSAN=ON). Every test prints its seed.
#include <atomic>
#include <cstring>
#include <iostream>
#include <thread>

#include "host_kit.hpp"
#include "meshes.hpp"

using namespace vt;

namespace {

constexpr uint32_t kClosest = 0;
constexpr uint32_t kFirstHit = VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT;

class concurrency : public ::testing::Test {
  protected:
    void SetUp() override {
        seed = chooseSeed();
        rng = Rng(seed);
        std::cout << "[   SEED   ] VKAS_TEST_SEED=" << seed << std::endl;
        RecordProperty("VKAS_TEST_SEED", std::to_string(seed));
    }
    void TearDown() override {
        if (HasFailure()) std::cout << "[   SEED   ] replay with VKAS_TEST_SEED=" << seed << std::endl;
    }
    uint64_t seed = 0;
    Rng rng;
};

// A scene over `blases`: `count` instances with random transforms, custom indices and SBT offsets.
std::vector<hk::InstanceDesc> randomInstances(Rng& rng, const std::vector<const hk::Structure*>& blases, uint32_t count,
                                              float spread) {
    std::vector<hk::InstanceDesc> out(count);
    for (uint32_t i = 0; i < count; ++i) {
        out[i].transform = randomTransform(rng, 0.5f, 1.5f, rng.coin(0.2), spread);
        out[i].customIndex = rng.u32() & 0xFFFFFF;
        out[i].sbtOffset = rng.u32() & 0xFF;
        out[i].blas = blases[i % blases.size()];
    }
    return out;
}

}  // namespace

// The same bottom and top levels built, copied, compacted, serialized and deserialized by deferred operations, four
// at a time, each joined by 2 to 4 threads: every result equals the single-threaded one.
TEST_F(concurrency, deferred_operations_joined_from_many_threads) {
    hk::Device d(2);
    auto geometry = hk::triangles(terrain(110, rng));  // 24,200 triangles: the builder splits the work into tasks
    const VkBuildAccelerationStructureFlagsKHR flags =
        VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR | VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR;
    auto reference = hk::buildBlas(d, {geometry.get()}, flags);
    const auto blob = hk::serialize(d, *reference);
    const auto bytes = hk::structureBytes(*reference);
    const auto compactBlob = hk::serialize(d, *hk::compactStructure(d, *reference));
    const auto instances = randomInstances(rng, {reference.get()}, 400, 30.0f);
    auto referenceTlas = hk::buildTlas(d, instances, 0);
    const auto tlasBlob = hk::canonicalBlob(hk::serialize(d, *referenceTlas));

    std::atomic<uint32_t> done{0};
    hk::parallel(4, [&](uint32_t task) {
        const uint32_t join = 2 + task % 3;
        for (int round = 0; round < 2; ++round) {
            auto built = hk::buildBlas(d, {geometry.get()}, flags, join);
            if (hk::serialize(d, *built, join) != blob) hk::fail("deferred build: serialized bytes differ");
            auto clone = hk::cloneStructure(d, *built, join);
            if (hk::structureBytes(*clone) != bytes) hk::fail("deferred clone: bytes differ");
            auto compact = hk::compactStructure(d, *clone, join);
            if (hk::serialize(d, *compact) != compactBlob) hk::fail("deferred compaction: serialized bytes differ");
            auto loaded = hk::deserialize(d, blob, VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, join);
            if (hk::structureBytes(*loaded) != bytes) hk::fail("deferred deserialization: bytes differ");
            std::vector<hk::InstanceDesc> mine = instances;
            for (auto& inst : mine) inst.blas = built.get();
            auto tlas = hk::buildTlas(d, mine, 0, join);
            if (hk::canonicalBlob(hk::serialize(d, *tlas, join)) != tlasBlob) hk::fail("deferred top level: bytes differ");
            ++done;
        }
    });
    EXPECT_EQ(done.load(), 8u);
    d.checkNoErrors("after the deferred operations");
}

// Readers trace shared structures (ray queries and vkasTraceRays, closest and first hit) while writers build,
// update, compact, serialize, deserialize and destroy their own structures on the same device, and trace those.
TEST_F(concurrency, shared_reads_while_other_structures_change) {
    hk::Device d(2);
    auto soup = hk::triangles(triangleSoup(1500, rng, 0.3f));
    auto mixedTriangles = hk::triangles(icosphere(2), 0);  // non-opaque: confirmed by the queries
    auto boxes = hk::aabbs(hk::randomBoxes(rng, 200, 1.0f, 0.2f));
    auto sharedA = hk::buildBlas(d, {soup.get()}, VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR);
    auto sharedB = hk::buildBlas(d, {mixedTriangles.get(), soup.get()}, 0);
    auto sharedC = hk::buildBlas(d, {boxes.get()}, 0);
    auto sharedTlas = hk::buildTlas(d, randomInstances(rng, {sharedA.get(), sharedB.get(), sharedC.get()}, 24, 6.0f), 0);
    const auto rays = hk::randomRays(*sharedTlas->scene, rng, 300);
    const auto expectedClosest = hk::expectedResults(*sharedTlas->scene, rays, kClosest);
    const auto expectedFirst = hk::expectedResults(*sharedTlas->scene, rays, kFirstHit);
    // The first answers: later ones must be bit-identical (traversal is deterministic).
    const auto firstQueries = hk::rayQueries(sharedTlas->handle, rays, kClosest);
    EXPECT_GT(hk::checkHits(expectedClosest, rays, firstQueries, true, "ray queries"), 0u);
    const auto firstBatch = hk::batchTrace(d, sharedTlas->handle, rays, VKAS_TRACE_MODE_CLOSEST_HIT, kClosest);
    hk::checkHits(expectedClosest, rays, firstBatch, true, "batch");

    const uint32_t readers = 3, writers = 3;
    std::vector<uint64_t> seeds;
    for (uint32_t w = 0; w < writers; ++w) seeds.push_back(rng.gen());
    hk::parallel(readers + writers, [&](uint32_t t) {
        if (t < readers) {
            for (int round = 0; round < 4; ++round) {
                const auto q = hk::rayQueries(sharedTlas->handle, rays, kClosest);
                const auto b = hk::batchTrace(d, sharedTlas->handle, rays, VKAS_TRACE_MODE_CLOSEST_HIT, kClosest);
                const auto a = hk::batchTrace(d, sharedTlas->handle, rays, VKAS_TRACE_MODE_ANY_HIT, 0);
                const auto qa = hk::rayQueries(sharedTlas->handle, rays, kFirstHit);
                hk::checkHits(expectedFirst, rays, a, false, "batch any-hit");
                hk::checkHits(expectedFirst, rays, qa, false, "ray queries, first hit");
                for (size_t i = 0; i < rays.size(); ++i)
                    if (!identical(q[i], firstQueries[i]) || !identical(b[i], firstBatch[i]))
                        hk::fail("ray " + std::to_string(i) + ": a concurrent trace differs from the first one: " +
                                 q[i].str() + " / " + b[i].str() + " vs " + firstQueries[i].str());
            }
            return;
        }
        Rng local(seeds[t - readers]);
        for (int round = 0; round < 3; ++round) {
            auto g = hk::triangles(triangleSoup(400 + int(local.below(400)), local, 0.3f));
            auto bx = hk::aabbs(hk::randomBoxes(local, 50, 1.0f, 0.2f));
            const VkBuildAccelerationStructureFlagsKHR flags = VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR |
                                                               VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR;
            auto blas = hk::buildBlas(d, {g.get()}, flags, round == 1 ? 2 : 0);
            auto boxBlas = hk::buildBlas(d, {bx.get()}, VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR);
            hk::jitter(*g, local, 0.01f);
            hk::jitter(*bx, local, 0.01f);
            hk::updateBlas(d, *blas, {g.get()}, true);
            auto movedBoxes = hk::updateBlas(d, *boxBlas, {bx.get()}, false, round == 2 ? 3 : 0);
            auto compact = hk::compactStructure(d, *blas);
            const auto blob = hk::serialize(d, *compact);
            if (hk::compatibility(d, blob) != VK_ACCELERATION_STRUCTURE_COMPATIBILITY_COMPATIBLE_KHR)
                hk::fail("a blob of this device is not compatible with it");
            auto loaded = hk::deserialize(d, blob, VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR);
            if (hk::serialize(d, *loaded) != blob) hk::fail("serialize(deserialize(blob)) != blob");
            loaded->blas = compact->blas;
            blas.reset();  // destroyed while the readers trace
            boxBlas.reset();
            auto tlas = hk::buildTlas(d, randomInstances(local, {loaded.get(), sharedA.get(), movedBoxes.get()}, 6, 3.0f),
                                      VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR);
            const auto mine = hk::randomRays(*tlas->scene, local, 60);
            hk::checkHits(hk::expectedResults(*tlas->scene, mine, kClosest), mine, hk::rayQueries(tlas->handle, mine, kClosest),
                          true, "writer's ray queries");
            auto moved = randomInstances(local, {loaded.get(), sharedA.get(), movedBoxes.get()}, 6, 3.0f);
            auto updated = hk::updateTlas(d, *tlas, moved, false);
            const auto mine2 = hk::randomRays(*updated->scene, local, 60);
            hk::checkHits(hk::expectedResults(*updated->scene, mine2, kClosest), mine2,
                          hk::batchTrace(d, updated->handle, mine2, VKAS_TRACE_MODE_CLOSEST_HIT, kClosest), true,
                          "writer's batch after a top-level update");
        }
    });
    d.checkNoErrors("after the concurrent reads and writes");
}

// Four devices at once, each created, used and destroyed on its own thread (two threads a device), from the same
// inputs: the same bytes everywhere, and the blobs of one device load on another.
TEST_F(concurrency, many_devices_at_once) {
    const uint32_t devices = 4;
    auto geometry = hk::triangles(torusKnot(96, 12));
    auto boxes = hk::aabbs(hk::randomBoxes(rng, 300, 2.0f, 0.3f));
    std::vector<hk::InstanceDesc> instances = randomInstances(rng, {nullptr}, 30, 8.0f);
    std::vector<std::vector<uint8_t>> blasBlobs(devices), tlasBlobs(devices);
    const uint64_t raySeed = rng.gen();
    hk::parallel(devices, [&](uint32_t i) {
        hk::Device d(1 + i % 2);
        std::unique_ptr<hk::Structure> blas, aabbBlas;
        hk::parallel(2, [&](uint32_t half) {  // two threads of one device build at once
            if (half == 0)
                blas = hk::buildBlas(d, {geometry.get()}, 0, i % 2 ? 2 : 0);
            else
                aabbBlas = hk::buildBlas(d, {boxes.get()}, VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR);
        });
        auto mine = instances;
        for (size_t k = 0; k < mine.size(); ++k) mine[k].blas = k % 3 ? blas.get() : aabbBlas.get();
        auto tlas = hk::buildTlas(d, mine, 0, i % 2 ? 0 : 3);
        blasBlobs[i] = hk::serialize(d, *blas);
        tlasBlobs[i] = hk::canonicalBlob(hk::serialize(d, *tlas));
        Rng local(raySeed);
        const auto rays = hk::randomRays(*tlas->scene, local, 150);
        const auto expected = hk::expectedResults(*tlas->scene, rays, kClosest);
        hk::checkHits(expected, rays, hk::rayQueries(tlas->handle, rays, kClosest), true, "ray queries");
        hk::checkHits(expected, rays, hk::batchTrace(d, tlas->handle, rays, VKAS_TRACE_MODE_CLOSEST_HIT, kClosest), true,
                      "batch");
        tlas.reset();
        blas.reset();
        aabbBlas.reset();
        d.checkNoErrors("on one of several devices");
    });
    for (uint32_t i = 1; i < devices; ++i) {
        EXPECT_TRUE(blasBlobs[i] == blasBlobs[0]) << "device " << i << ": bottom-level blob differs from device 0's";
        EXPECT_TRUE(tlasBlobs[i] == tlasBlobs[0]) << "device " << i << ": top-level blob differs from device 0's";
    }
    // A bottom-level blob of one device loads on another, on two threads each.
    hk::Device a(1), b(1);
    hk::parallel(2, [&](uint32_t i) {
        hk::Device& d = i ? a : b;
        if (hk::compatibility(d, blasBlobs[0]) != VK_ACCELERATION_STRUCTURE_COMPATIBILITY_COMPATIBLE_KHR)
            hk::fail("blob not compatible with another device");
        auto loaded = hk::deserialize(d, blasBlobs[0], VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, 2);
        if (hk::serialize(d, *loaded) != blasBlobs[0]) hk::fail("blob changed by a round trip through another device");
    });
    a.checkNoErrors("device a");
    b.checkNoErrors("device b");
}
