// Host kit: a small, GoogleTest-free toolbox over the vkas C API for programs that drive vkas from many threads
// (tests/api/test_concurrency.cpp, tests/stress/stress.cpp). It owns devices, structures and their memory, builds
// bottom levels of triangles or AABBs and top levels of instances, updates, copies (clone, compact), serializes and
// deserializes, optionally through a VkDeferredOperationKHR joined by N threads, and checks ray queries and
// vkasTraceRays batches against the brute-force oracle (oracle.hpp) with the test suite's comparison
// (vt::matchesClosest / vt::matchesAnyHit). Every failure throws hk::Failure with a description; hk::parallel runs
// functions on threads and rethrows the first failure on the calling thread.
//
// Threading: a Device may be used from any number of threads (vkas's commands are thread-safe except for the
// externally synchronized parameters, docs/API.md "Host synchronization"). A Structure is externally synchronized:
// one thread at a time may build into, update, copy into or destroy it; any number may read it (trace, serialize,
// copy from) while no thread writes it.
#pragma once

#include "device.hpp"  // kit/
#include "vkas_test.hpp"

#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace hk {

struct Failure : std::runtime_error {
    using std::runtime_error::runtime_error;
};
[[noreturn]] void fail(const std::string& what);
// Throws unless got == want.
void expect(VkResult got, VkResult want, const char* what);
class Device;
// The same, with the device's pending validation messages in the description.
void expect(Device* device, VkResult got, VkResult want, const char* what);

// Runs fn(0) .. fn(n - 1) on n threads (fn(0) on the calling thread) and rethrows the first exception.
void parallel(uint32_t n, const std::function<void(uint32_t)>& fn);

class Device {
  public:
    // workerThreads: VkasDeviceCreateInfo::workerThreadCount (0: all cores). Validation stays on; its error messages
    // are collected (errors()).
    explicit Device(uint32_t workerThreads = 2);
    ~Device();
    Device(const Device&) = delete;
    Device& operator=(const Device&) = delete;

    VkDevice handle = VK_NULL_HANDLE;
    vkas_kit::Commands vk;  // kit/device_commands.hpp (the deferred-operation commands included)

    // Validation errors reported so far (and cleared).
    std::vector<std::string> takeErrors();
    // Throws when validation reported an error.
    void checkNoErrors(const char* when);

  private:
    static VKAPI_ATTR VkBool32 VKAPI_CALL messenger(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                    VkDebugUtilsMessageTypeFlagsEXT types,
                                                    const VkDebugUtilsMessengerCallbackDataEXT* data, void* user);
    std::mutex mutex_;
    std::vector<std::string> errors_;
    std::optional<vkas_kit::Device> device_;  // created last: the messenger may run while it is created
};

// A structure with its own buffer and memory (memory type 0, mapped), destroyed with it.
struct Structure {
    Device* device = nullptr;
    VkAccelerationStructureTypeKHR type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
    VkBuildAccelerationStructureFlagsKHR flags = 0;  // of its last build
    VkBuffer buffer = VK_NULL_HANDLE;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    uint8_t* mapped = nullptr;
    VkDeviceSize size = 0;
    VkDeviceSize updateScratchSize = 0;
    VkAccelerationStructureKHR handle = VK_NULL_HANDLE;
    std::shared_ptr<const oracle::Blas> blas;    // bottom level: what the oracle sees
    std::shared_ptr<const oracle::Scene> scene;  // top level
    uint64_t reference() const { return uint64_t(handle); }
    VkDeviceAddress address() const;
    Structure() = default;
    Structure(const Structure&) = delete;
    Structure& operator=(const Structure&) = delete;
    ~Structure();
};
std::unique_ptr<Structure> createStructure(Device& device, VkAccelerationStructureTypeKHR type, VkDeviceSize size);
// The structure's bytes [0, usedSize) (docs/FORMAT.md header).
std::vector<uint8_t> structureBytes(const Structure& s);

// The application data of one bottom-level geometry (R32G32B32 vertices with uint32 indices, or AABBs).
struct Geometry {
    std::vector<float> positions;
    std::vector<uint32_t> indices;
    std::vector<VkAabbPositionsKHR> boxes;
    VkGeometryFlagsKHR flags = 0;
    VkAccelerationStructureGeometryKHR geometry{};
    VkAccelerationStructureBuildRangeInfoKHR range{};
    bool isAabbs() const { return !boxes.empty(); }
    void refresh();  // points `geometry` at the vectors again (after they change)
};
std::unique_ptr<Geometry> triangles(const vt::Mesh& mesh, VkGeometryFlagsKHR flags = VK_GEOMETRY_OPAQUE_BIT_KHR);
std::unique_ptr<Geometry> aabbs(std::vector<VkAabbPositionsKHR> boxes, VkGeometryFlagsKHR flags = VK_GEOMETRY_OPAQUE_BIT_KHR);
std::vector<VkAabbPositionsKHR> randomBoxes(vt::Rng& rng, uint32_t count, float extent, float size);
// Moves every vertex (or box) by a small random amount, keeping the topology (for MODE_UPDATE).
void jitter(Geometry& g, vt::Rng& rng, float amount);

struct InstanceDesc {
    VkTransformMatrixKHR transform = vt::identityTransform();
    uint32_t customIndex = 0, mask = 0xFF, sbtOffset = 0, flags = 0;
    const Structure* blas = nullptr;  // null: inactive
};

// `join`: 0 runs the command without a deferred operation; n >= 1 hands it to a new VkDeferredOperationKHR joined by
// n threads (the calling one and n - 1 more; each joins again after VK_THREAD_IDLE_KHR), then checks the result.
std::unique_ptr<Structure> buildBlas(Device& d, const std::vector<const Geometry*>& geometries,
                                     VkBuildAccelerationStructureFlagsKHR flags, uint32_t join = 0);
std::unique_ptr<Structure> buildTlas(Device& d, const std::vector<InstanceDesc>& instances,
                                     VkBuildAccelerationStructureFlagsKHR flags, uint32_t join = 0);
// MODE_UPDATE of `src` (built with ALLOW_UPDATE) with the same geometries' current data: in place (returns null) or
// into a new structure (returned).
std::unique_ptr<Structure> updateBlas(Device& d, Structure& src, const std::vector<const Geometry*>& geometries,
                                      bool inPlace, uint32_t join = 0);
std::unique_ptr<Structure> updateTlas(Device& d, Structure& src, const std::vector<InstanceDesc>& instances,
                                      bool inPlace, uint32_t join = 0);

// Runs command(op) (op is VK_NULL_HANDLE when join == 0) as `join` says; the command returns what the Vulkan
// command returned.
void runDeferred(Device& d, uint32_t join, const std::function<VkResult(VkDeferredOperationKHR)>& command,
                 const char* what);

VkDeviceSize queryProperty(Device& d, const Structure& s, VkQueryType type);
std::unique_ptr<Structure> cloneStructure(Device& d, const Structure& src, uint32_t join = 0);
// Compacted-size query, then COMPACT into a structure of that size (src built with ALLOW_COMPACTION).
std::unique_ptr<Structure> compactStructure(Device& d, const Structure& src, uint32_t join = 0);
// vkCopyAccelerationStructureToMemoryKHR; the blob's size is the serialization-size query's.
std::vector<uint8_t> serialize(Device& d, const Structure& src, uint32_t join = 0);
VkAccelerationStructureCompatibilityKHR compatibility(Device& d, const std::vector<uint8_t>& blob);
// vkCopyMemoryToAccelerationStructureKHR into a new structure of the blob's deserialized size.
std::unique_ptr<Structure> deserialize(Device& d, const std::vector<uint8_t>& blob, VkAccelerationStructureTypeKHR type,
                                       uint32_t join = 0);
// The blob with its handle array (device addresses of the referenced bottom levels, which differ between runs)
// zeroed: equal for structures built alike.
std::vector<uint8_t> canonicalBlob(std::vector<uint8_t> blob);

// ---- Rays -------------------------------------------------------------------------------------------------------
// Rays aimed at random interior points of random primitives of the scene's active instances (from random
// directions, both sides), with some random rays through its bounds.
std::vector<oracle::Ray> randomRays(const oracle::Scene& scene, vt::Rng& rng, size_t count);
// What the oracle says for each ray (flags: SPIR-V ray flags; AABB candidates removed: the kit never generates
// intersections).
std::vector<oracle::Result> expectedResults(const oracle::Scene& scene, const std::vector<oracle::Ray>& rays,
                                            uint32_t flags);
// One ray query per ray, every triangle candidate confirmed, AABB candidates left alone; the committed hits.
std::vector<vt::Hit> rayQueries(VkAccelerationStructureKHR tlas, const std::vector<oracle::Ray>& rays, uint32_t flags);
// vkasTraceRays (throws when it does not return VK_SUCCESS).
std::vector<vt::Hit> batchTrace(Device& d, VkAccelerationStructureKHR tlas, const std::vector<oracle::Ray>& rays,
                                VkasTraceMode mode, uint32_t flags);
// Compares each hit with the oracle (closest: matchesClosest, otherwise matchesAnyHit); throws with the first
// difference, prefixed with `what`. Returns the number of hits.
size_t checkHits(const std::vector<oracle::Result>& expected, const std::vector<oracle::Ray>& rays,
                 const std::vector<vt::Hit>& hits, bool closest, const std::string& what);

// Reads VmRSS of /proc/self/status, in bytes (0 when unavailable).
uint64_t residentBytes();

}  // namespace hk
