// The vkas side: builds through vkBuildAccelerationStructuresKHR (optionally deferred and joined by N threads),
// refits, the compacted-size query, the structure's bytes for the SAH cost, and traversal through vkasTraceRays and
// the vkasRayQuery* functions. Validation is off (disableValidation), as in a release application.
#pragma once

#include "common.hpp"
#include "device.hpp"  // kit/: the device and its commands
#include "sah.hpp"

namespace vb {

// What the builds read, also read by the oracle (judge.cpp): the mesh as one opaque triangle geometry (R32G32B32
// vertices, 32-bit indices), and the instance records of `xs` referencing `blas` (one identity instance when xs is
// empty; custom index = instance index, mask 0xFF, no flags).
VkAccelerationStructureGeometryKHR triangleGeometry(const Mesh& mesh, const float* vertices);
std::vector<VkAccelerationStructureInstanceKHR> instanceRecords(const std::vector<Transform>& xs,
                                                                VkAccelerationStructureKHR blas);

class VkasEngine : private vkas_kit::Commands {
public:
    struct Structure {
        VkAccelerationStructureKHR as = VK_NULL_HANDLE;
        VkBuffer buffer = VK_NULL_HANDLE;
        VkDeviceMemory memory = VK_NULL_HANDLE;
    };
    struct Build {
        Structure s;
        double ms = 0;               // best of the repetitions
        uint64_t compactedSize = 0;  // vkWriteAccelerationStructuresPropertiesKHR, COMPACTED_SIZE
        uint64_t usedSize = 0;       // the same, ACCELERATION_STRUCTURE_SIZE (the built structure's size; 0: not known)
        uint64_t sizeQuery = 0;      // vkGetAccelerationStructureBuildSizesKHR's accelerationStructureSize (the buffer)
        uint64_t scratchSize = 0;    // the same query's buildScratchSize (what the build was given)
    };

    // workerThreadCount 0: all cores (vkasTraceRays' worker threads). validation: the device as users get it by
    // default (every ray checked); the benchmarks measure without it unless asked.
    explicit VkasEngine(uint32_t workerThreadCount, bool validation = false);
    ~VkasEngine();
    VkasEngine(const VkasEngine&) = delete;
    VkasEngine& operator=(const VkasEngine&) = delete;

    // A bottom level of the mesh (one opaque geometry), with `flags` | ALLOW_COMPACTION (which changes nothing in
    // vkas's builder; the compacted-size query needs it). deferredThreads 0: no deferral; N: a deferred operation
    // joined by N threads. `vertices` overrides the mesh's positions (same layout).
    Build buildBottom(const Mesh& mesh, VkBuildAccelerationStructureFlagsKHR flags, int reps,
                      unsigned deferredThreads = 0);
    // A top level of `xs` instances of `blas` (an identity instance when xs is empty).
    Build buildTop(const std::vector<Transform>& xs, VkAccelerationStructureKHR blas,
                   VkBuildAccelerationStructureFlagsKHR flags, int reps);
    // In-place refits (MODE_UPDATE) of a structure built with ALLOW_UPDATE, alternating between `moved` and the
    // original inputs, `moved` first and last; returns the best time.
    double refitBottom(const Structure& s, const Mesh& mesh, const std::vector<float>& moved,
                       VkBuildAccelerationStructureFlagsKHR flags, int reps);
    double refitTop(const Structure& s, const std::vector<Transform>& xs, const std::vector<Transform>& moved,
                    VkAccelerationStructureKHR blas, VkBuildAccelerationStructureFlagsKHR flags, int reps);

    SahCost sah(const Structure& s);
    // s serialized to host memory (vkCopyAccelerationStructureToMemoryKHR) and the blob deserialized into a new
    // structure of `size` bytes (vkCopyMemoryToAccelerationStructureKHR): the blob's size, both times, and whether
    // the new structure's first `usedSize` bytes equal the source's.
    struct RoundTrip {
        Structure s;
        uint64_t blobBytes = 0;
        double serializeMs = 0, deserializeMs = 0;
        bool bytesEqual = false;
    };
    RoundTrip serializeRoundTrip(const Structure& s, uint64_t size, uint64_t usedSize);
    void destroy(Structure& s);

    // Batch traversal on the device's worker threads; returns the best time of `reps` calls.
    double traceBatch(VkAccelerationStructureKHR tlas, bool anyHit, const std::vector<VkasRay>& rays,
                      std::vector<Hit>& hits, int reps);
    // Ray queries on the calling thread, one after another; returns the best time. `extraFlags` are added to every
    // query's ray flags (VKAS_RAY_FLAG_NO_OPAQUE: every candidate goes to the application, which drops it).
    double traceRayQuery(VkAccelerationStructureKHR tlas, bool anyHit, const std::vector<VkasRay>& rays,
                         std::vector<Hit>& hits, int reps, uint32_t extraFlags = 0);

private:
    Structure create(VkAccelerationStructureTypeKHR type, VkDeviceSize size);
    double run(const VkAccelerationStructureBuildGeometryInfoKHR& info, const VkAccelerationStructureBuildRangeInfoKHR& range,
               unsigned deferredThreads);
    uint64_t compactedSize(const Structure& s);
    uint64_t structureSize(const Structure& s);  // 0 when the query fails

    vkas_kit::Device device_;
    VkDevice dev_ = VK_NULL_HANDLE;
    std::vector<unsigned char> scratch_;
};

}  // namespace vb
