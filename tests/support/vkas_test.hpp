// Test-support layer: a GoogleTest fixture that creates a vkas device, loads every command through
// vkasGetDeviceProcAddr, watches validation messages, and builds acceleration structures exactly like an
// application would (host memory poisoned with 0xAA, handles as instance references). It also keeps, for every
// structure it builds, the brute-force oracle's view of it.
#pragma once

#include <gtest/gtest.h>
#include <vkas/vkas.h>

#include "device_commands.hpp"  // kit/

#include <array>
#include <cstdint>
#include <cstring>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <random>
#include <string>
#include <vector>

#include "oracle.hpp"

namespace vt {

// ---- Randomness -------------------------------------------------------------------------------------------------
// The seed comes from VKAS_TEST_SEED when set, otherwise from std::random_device; it is printed by every test.
uint64_t chooseSeed();

struct Rng {
    std::mt19937_64 gen;
    explicit Rng(uint64_t seed = 0) : gen(seed) {}
    double uniform(double a, double b) { return std::uniform_real_distribution<double>(a, b)(gen); }
    float uniformf(float a, float b) { return float(uniform(a, b)); }
    uint32_t below(uint32_t n) { return uint32_t(std::uniform_int_distribution<uint64_t>(0, n - 1)(gen)); }
    int32_t range(int32_t lo, int32_t hi) { return std::uniform_int_distribution<int32_t>(lo, hi)(gen); }
    uint32_t u32() { return uint32_t(gen()); }
    bool coin(double p = 0.5) { return uniform(0, 1) < p; }
};

// ---- Commands ---------------------------------------------------------------------------------------------------
// The commands of kit/device_commands.hpp (vkas_kit::Commands, its one list): the tests fetch them as the tool, the
// benchmarks and the fuzzers do.
using Commands = vkas_kit::Commands;

// ---- Math helpers -----------------------------------------------------------------------------------------------
using Float3 = std::array<float, 3>;
// The triangles of a (non-motion) bottom level of triangles, read from its bytes by docs/FORMAT.md (format 2 leaves),
// as 48-byte records in triangle order: 9 floats (v0, v1, v2), geometryIndex, primitiveIndex, flags (u32 each), the
// layout format 1 stored. Tests that look at the records use it, whatever the leaf layout.
std::vector<uint8_t> triangleRecordsOf(const uint8_t* block);

VkTransformMatrixKHR identityTransform();
VkTransformMatrixKHR translation(float x, float y, float z);
// Product a*b of two affine 3x4 transforms.
VkTransformMatrixKHR compose(const VkTransformMatrixKHR& a, const VkTransformMatrixKHR& b);
// Random rotation, per-axis scales in [minScale, maxScale], optional mirroring of one random axis, translation.
VkTransformMatrixKHR randomTransform(Rng& rng, float minScale, float maxScale, bool mirror, float maxTranslation);
Float3 transformPoint(const VkTransformMatrixKHR& m, const Float3& p);
std::string describe(const oracle::Ray& ray);  // hex floats, for reproduction

// ---- Meshes -----------------------------------------------------------------------------------------------------
struct Mesh {
    std::vector<Float3> positions;
    std::vector<uint32_t> indices;  // 3 per triangle
    size_t triangleCount() const { return indices.size() / 3; }
};

// Owns the memory a triangle geometry points to. Vertex data is R32G32B32_SFLOAT. Not copyable.
struct GeometryData {
    std::vector<uint8_t> vertices, indices, transform;
    VkAccelerationStructureGeometryKHR geometry{};
    VkAccelerationStructureBuildRangeInfoKHR range{};
    GeometryData() = default;
    GeometryData(const GeometryData&) = delete;
    GeometryData& operator=(const GeometryData&) = delete;
};
std::unique_ptr<GeometryData> makeGeometry(const Mesh& mesh, VkIndexType indexType, VkGeometryFlagsKHR flags = 0,
                                           const VkTransformMatrixKHR* transform = nullptr);

// ---- Resources --------------------------------------------------------------------------------------------------
constexpr VkBufferUsageFlags kAsBufferUsage =
    VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_STORAGE_BIT_KHR | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT;

struct HostBuffer {
    VkBuffer buffer = VK_NULL_HANDLE;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    uint8_t* mapped = nullptr;
    VkDeviceSize size = 0;
    VkMemoryRequirements requirements{};
};

struct AccelStruct {
    VkAccelerationStructureKHR handle = VK_NULL_HANDLE;
    VkAccelerationStructureTypeKHR type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
    HostBuffer* buffer = nullptr;
    VkDeviceSize offset = 0, size = 0;
    uint8_t poison = 0xAA;  // what the buffer was filled with before the build
    VkAccelerationStructureBuildSizesInfoKHR sizes{};
    std::shared_ptr<const oracle::Blas> blas;    // bottom level: the oracle's copy of the geometry
    std::shared_ptr<const oracle::Scene> scene;  // top level: the oracle's scene
    uint8_t* data() const { return buffer->mapped + offset; }
    uint64_t reference() const { return uint64_t(handle); }
    // A u32 header field at its documented offset (docs/FORMAT.md, "Header"), e.g. 128: the fragment count.
    uint32_t header32(size_t fieldOffset) const {
        uint32_t v;
        std::memcpy(&v, data() + fieldOffset, 4);
        return v;
    }
};

struct BuildOptions {
    VkBuildAccelerationStructureFlagsKHR flags = 0;
    bool usePointers = false;          // BLAS: ppGeometries; TLAS: instances as an array of pointers
    bool createGeneric = false;        // create the structure with VK_ACCELERATION_STRUCTURE_TYPE_GENERIC_KHR
    bool bindAfterCreate = false;      // create the structure before its buffer memory is bound
    uint8_t scratchPoison = 0xAA;
    uint8_t memoryPoison = 0xAA;
    VkDeviceSize asOffset = 0;         // multiple of 256
    uint32_t extraMaxPrimitives = 0;   // the sizes query asks for this many more primitives per geometry
    uint32_t instancePrimitiveOffset = 0;  // TLAS: primitiveOffset of the instance data (multiple of 16)
    // [NV-motion] createFlags of the structure; with CREATE_MOTION_BIT_NV a top level gets a
    // VkAccelerationStructureMotionInfoNV with motionMaxInstances in its pNext chain.
    VkAccelerationStructureCreateFlagsKHR createFlags = 0;
    uint32_t motionMaxInstances = 0;
};

struct Instance {
    VkTransformMatrixKHR transform = identityTransform();
    uint32_t customIndex = 0;  // 24 bits
    uint32_t mask = 0xFF;      // 8 bits
    uint32_t sbtOffset = 0;    // 24 bits
    uint32_t flags = 0;        // 8 bits
    const AccelStruct* blas = nullptr;  // null: accelerationStructureReference = 0 (inactive)
};
// Writes the 64-byte VkAccelerationStructureInstanceKHR with shifts (no bit-fields).
void packInstance(const Instance& instance, uint8_t out[64]);

// A build waiting to be submitted (several can go in one vkBuildAccelerationStructuresKHR call).
struct PreparedBuild {
    AccelStruct* as = nullptr;
    VkAccelerationStructureBuildGeometryInfoKHR info{};
    std::vector<VkAccelerationStructureGeometryKHR> geometries;
    std::vector<const VkAccelerationStructureGeometryKHR*> geometryPointers;
    std::vector<VkAccelerationStructureBuildRangeInfoKHR> ranges;
    std::vector<uint8_t> scratch;
    std::vector<uint8_t> instanceBytes;
    std::vector<uint8_t> instancePointerBytes;
    std::shared_ptr<oracle::Blas> blas;
    std::shared_ptr<oracle::Scene> scene;
};

// ---- Results ----------------------------------------------------------------------------------------------------
struct Hit {
    uint32_t type = 0;
    float t = 0;
    int32_t instanceId = -1, customIndex = -1, geometryIndex = -1, primitiveIndex = -1;
    uint32_t sbtOffset = 0;
    float bary[2] = {0, 0};
    bool frontFace = false;
    bool aabbOpaque = false;  // AABB candidates: CandidateAABBOpaque
    float objectOrigin[3] = {0, 0, 0}, objectDirection[3] = {0, 0, 0};  // ray queries: the object-space ray
    std::string str() const;
};
Hit readHit(const VkasRayQuery& q, bool committed);
// Bit-identical results (type, t, ids, barycentrics, facing).
bool identical(const Hit& a, const Hit& b);
Hit fromBatch(const VkasHit& h);

struct QueryTrace {
    Hit committed;
    std::vector<Hit> candidates;  // in the order Proceed returned them
    std::string problems;         // invariant violations seen during the loop (empty: none)
};

// All: confirm every triangle candidate and generate every AABB candidate where the ray enters the box (as an
// intersection shader for the box itself would). None: neither.
enum class Confirm { All, None };

// Comparison against the oracle (see tests/README in CMakeLists comments): both miss; or vkas's primitive is an
// oracle candidate at the same t (within tolerance) and no required candidate is clearly closer. A miss is
// accepted only when every oracle candidate is optional (within the edge/bound margin).
::testing::AssertionResult matchesClosest(const oracle::Result& expected, const oracle::Ray& ray, const Hit& got);
// Any-hit semantics (TerminateOnFirstHit): vkas's hit may be any candidate.
::testing::AssertionResult matchesAnyHit(const oracle::Result& expected, const oracle::Ray& ray, const Hit& got);

// ---- The fixture ------------------------------------------------------------------------------------------------
class VkasTest : public ::testing::Test {
  public:
    static VKAPI_ATTR VkBool32 VKAPI_CALL messenger(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                    VkDebugUtilsMessageTypeFlagsEXT types,
                                                    const VkDebugUtilsMessengerCallbackDataEXT* data, void* user);

  protected:
    void SetUp() override;
    void TearDown() override;
    // The VkAllocationCallbacks SetUp creates the device with (vkasCreateDeviceWithAllocator); NULL: vkasCreateDevice.
    virtual const VkAllocationCallbacks* deviceAllocator() { return nullptr; }

    VkDevice device = VK_NULL_HANDLE;
    Commands vk;
    uint64_t seed = 0;
    Rng rng;

    // Validation: the test fails in TearDown if an error was reported, unless consumed with takeValidationErrors.
    std::vector<std::string> takeValidationErrors();
    // Objects a test leaves behind are freed by vkasDestroyDevice, which reports them (05137); set this to accept
    // that report instead of failing.
    bool ignoreLeaksAtTeardown = false;
    // Every buffer this fixture created (the valid-usage tests compare their memory before and after a command).
    std::vector<HostBuffer*> allBuffers();

    HostBuffer* createBuffer(VkDeviceSize size, VkBufferUsageFlags usage = kAsBufferUsage, bool bind = true,
                             uint8_t poison = 0xAA);
    void bindBuffer(HostBuffer* buffer, uint8_t poison = 0xAA);
    // Creates a structure of `size` bytes at `offset` in a new buffer that has a 256-byte canary after it.
    AccelStruct* createAccelStruct(VkAccelerationStructureTypeKHR type, VkDeviceSize size, const BuildOptions& opt);
    void destroyAccelStruct(AccelStruct* as);

    std::unique_ptr<PreparedBuild> prepareBlas(const std::vector<VkAccelerationStructureGeometryKHR>& geometries,
                                               const std::vector<VkAccelerationStructureBuildRangeInfoKHR>& ranges,
                                               const BuildOptions& opt = {});
    std::unique_ptr<PreparedBuild> prepareBlas(const std::vector<const GeometryData*>& geometries,
                                               const BuildOptions& opt = {});
    std::unique_ptr<PreparedBuild> prepareTlas(const std::vector<Instance>& instances, const BuildOptions& opt = {});
    // Submits all builds in one vkBuildAccelerationStructuresKHR call and checks the canaries around each.
    void submit(const std::vector<PreparedBuild*>& builds);

    AccelStruct* buildBlas(const std::vector<VkAccelerationStructureGeometryKHR>& geometries,
                           const std::vector<VkAccelerationStructureBuildRangeInfoKHR>& ranges,
                           const BuildOptions& opt = {});
    AccelStruct* buildBlas(const std::vector<const GeometryData*>& geometries, const BuildOptions& opt = {});
    AccelStruct* buildBlas(const GeometryData& geometry, const BuildOptions& opt = {});
    AccelStruct* buildTlas(const std::vector<Instance>& instances, const BuildOptions& opt = {});
    // One identity instance of the BLAS.
    AccelStruct* buildSingleInstanceTlas(const AccelStruct* blas, const BuildOptions& opt = {});

    // Runs a ray query to completion. Every candidate is confirmed or generated (Confirm::All) or none is. Checks
    // the candidate invariants (triangles: t within (tMin, current tMax]; AABBs: t within [tMin, current tMax],
    // each primitive at most once per instance, a box of `scene`; committed NONE before any confirmation; the
    // committed values after a confirm or generate) and records violations in QueryTrace::problems. AABB
    // candidates need `scene` (the boxes) to be generated; without it they are reported as problems.
    QueryTrace query(VkAccelerationStructureKHR tlas, const oracle::Ray& ray, uint32_t flags, uint32_t cullMask,
                     Confirm confirm = Confirm::All, const oracle::Scene* scene = nullptr);
    Hit traceClosest(const AccelStruct* tlas, const oracle::Ray& ray, uint32_t flags = 0, uint32_t cullMask = 0xFF);

    // Random rays around a scene: aimed at random triangles or boxes, at random points of the bounds, from inside,
    // with random direction lengths and sometimes a random [tMin, tMax] window.
    std::vector<oracle::Ray> randomRays(const oracle::Scene& scene, size_t count);
    // Rays from random directions (both sides) at a random interior point of each active triangle and valid AABB of
    // each active instance, at most maxRays (primitives chosen at random when there are more).
    std::vector<oracle::Ray> targetedRays(const oracle::Scene& scene, size_t maxRays);
    // Checks query(), vkasTraceRays closest and any-hit against the oracle for each ray (AABB candidates generated at
    // their entry point by the query; never hit by vkasTraceRays). Returns the number of query hits.
    size_t checkRays(const AccelStruct* tlas, const std::vector<oracle::Ray>& rays, uint32_t flags = 0,
                     uint32_t cullMask = 0xFF, bool alsoBatch = true);

    std::map<uint64_t, std::shared_ptr<const oracle::Blas>> blasRegistry;

  private:
    std::mutex messagesMutex_;
    std::vector<std::string> errors_;
    std::deque<std::unique_ptr<HostBuffer>> buffers_;
    std::deque<std::unique_ptr<AccelStruct>> structures_;
};

}  // namespace vt
