// One differential-conformance case: a scene description and a ray set that two implementations (vkas's host
// commands and a real Vulkan driver, Mesa's lavapipe) build and trace independently, and the per-ray result
// records both produce. Everything here is plain data so that each side builds from the very same bytes.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstdint>
#include <string>
#include <vector>

namespace diff {

// ---- Scene ------------------------------------------------------------------------------------------------------
// All application data (vertices, indices, geometry transforms, AABBs) lives in one byte blob; geometries refer to
// it by offset. A side copies the blob into memory of its own and turns offsets into addresses (vkas: host
// addresses; lavapipe: buffer device addresses). Offsets respect the spec's alignment rules.
struct TriangleData {
    VkFormat vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
    uint64_t vertexOffset = 0;  // blob offset of vertexData
    uint64_t vertexStride = 12;
    uint32_t maxVertex = 0;
    VkIndexType indexType = VK_INDEX_TYPE_NONE_KHR;
    uint64_t indexOffset = 0;  // blob offset of indexData (unused for VK_INDEX_TYPE_NONE_KHR)
    bool hasTransform = false;
    uint64_t transformOffset = 0;  // blob offset of a VkTransformMatrixKHR (16-byte aligned)
};

struct AabbData {
    uint64_t dataOffset = 0;  // blob offset of the VkAabbPositionsKHR array (8-byte aligned)
    uint64_t stride = 24;     // multiple of 8
};

struct Geometry {
    VkGeometryTypeKHR type = VK_GEOMETRY_TYPE_TRIANGLES_KHR;  // TRIANGLES or AABBS
    VkGeometryFlagsKHR flags = 0;
    TriangleData triangles;
    AabbData aabbs;
    VkAccelerationStructureBuildRangeInfoKHR range{};  // primitiveCount, primitiveOffset, firstVertex, transformOffset
};

struct Blas {
    std::vector<Geometry> geometries;  // at least one; a range may have primitiveCount 0
    VkBuildAccelerationStructureFlagsKHR buildFlags = 0;  // may include ALLOW_DATA_ACCESS (0x800, position fetch)
};

struct Instance {
    VkTransformMatrixKHR transform{};
    uint32_t customIndex = 0;  // 24 bits
    uint32_t mask = 0xFF;      // 8 bits
    uint32_t sbtOffset = 0;    // 24 bits
    uint32_t flags = 0;        // 8 bits, VkGeometryInstanceFlagsKHR
    int32_t blas = -1;         // index into Scene::blases; -1: accelerationStructureReference = 0 (inactive)
};

struct Scene {
    std::vector<uint8_t> blob;
    std::vector<Blas> blases;
    std::vector<Instance> instances;  // may be empty (an empty TLAS)
    VkBuildAccelerationStructureFlagsKHR tlasFlags = 0;
    std::string name;  // what the generator made, for messages
};

// The Vulkan description of a geometry whose blob starts at `blobAddress` (a device address, or a host address
// stored in the same union). Throws std::invalid_argument for a type other than triangles or AABBs.
VkAccelerationStructureGeometryKHR vulkanGeometry(const Geometry& geometry, uint64_t blobAddress);

// Writes the 64-byte VkAccelerationStructureInstanceKHR field by field: the C bit-fields of the header have an
// implementation-defined layout, the spec's is low bits first.
void packInstance(const Instance& instance, uint64_t reference, uint8_t out[64]);

// ---- Rays -------------------------------------------------------------------------------------------------------
// What the ray program (below) does with each ray.
enum Mode : uint32_t {
    kModeClosest = 0,  // confirm / generate by the deterministic rules; report the committed intersection
    kModeCount = 1,    // confirm and generate nothing; count and record every candidate
};

// std430 layout, shared with the GLSL shader (48 bytes).
struct Ray {
    float origin[3];
    float tMin;
    float direction[3];
    float tMax;
    uint32_t flags;     // SPIR-V RayFlags (gl_RayFlags*EXT)
    uint32_t cullMask;  // low 8 bits used
    uint32_t mode;      // Mode
    uint32_t reserved;
};
static_assert(sizeof(Ray) == 48);

// ---- Results ----------------------------------------------------------------------------------------------------
constexpr uint32_t kMaxRecordedCandidates = 32;

struct CandidateRecord {
    uint32_t type;  // 0 triangle, 1 AABB (candidate intersection type)
    uint32_t instanceId;
    uint32_t geometryIndex;
    uint32_t primitiveIndex;
};

// std430 layout, shared with the GLSL shader (608 bytes). Fields a result does not define are 0.
struct Result {
    uint32_t committedType;  // 0 none, 1 triangle, 2 generated
    uint32_t instanceId;
    uint32_t customIndex;
    uint32_t sbtOffset;
    uint32_t geometryIndex;
    uint32_t primitiveIndex;
    uint32_t frontFace;       // triangles only (1 front)
    uint32_t candidateCount;  // number of times Proceed returned true
    float t;
    float barycentrics[2];    // triangles only
    uint32_t positionsValid;  // 1 when positions were fetched
    float positions[3][4];    // committed triangle's vertex positions (xyz; w = 0), position fetch
    CandidateRecord candidates[kMaxRecordedCandidates];  // the first candidates, in the order Proceed returned them
};
static_assert(sizeof(Result) == 608);

// ---- Procedural tables ------------------------------------------------------------------------------------------
// The ray program's AABB step needs each AABB's box. Both sides read it from these tables (never from their
// acceleration structure): box = boxes[geometryFirstBox[blasFirstGeometry[instanceBlas[instanceId]] + geometryIndex]
// + primitiveIndex]. Also blasFlags[blas] bit 0: the BLAS was built with ALLOW_DATA_ACCESS (position fetch allowed).
struct ProceduralTables {
    std::vector<uint32_t> instanceBlas;       // per instance; 0xFFFFFFFF for a null reference
    std::vector<uint32_t> blasFirstGeometry;  // per BLAS: index of its first geometry in geometryFirstBox
    std::vector<uint32_t> blasFlags;          // per BLAS
    std::vector<uint32_t> geometryFirstBox;   // per (BLAS, geometry): first box; 0 for triangle geometries
    std::vector<float> boxes;                 // 8 floats per box: minX minY minZ 0 maxX maxY maxZ 0
};
ProceduralTables makeProceduralTables(const Scene& scene);

// ---- The ray program ----------------------------------------------------------------------------------------------
// Both sides run exactly this, per ray (shader: tests/conformance/shaders/ray_program.comp; vkas: vkas_side.cpp):
//
//   initialize(q, tlas, ray.flags, ray.cullMask, ray.origin, ray.tMin, ray.direction, ray.tMax)
//   while (proceed(q)) {
//       record candidate (first kMaxRecordedCandidates), candidateCount++
//       if (ray.mode == kModeCount) continue;
//       if (candidate type == triangle) {
//           if (confirmRule(candidate instanceId, geometryIndex, primitiveIndex)) confirm(q)
//       } else {  // AABB
//           in float, no contraction:
//           o, d = candidate object-space ray origin and direction
//           box  = the AABB from the procedural tables
//           t0 = (box.min - o) / d; t1 = (box.max - o) / d      (componentwise)
//           tNear = max(max(min(t0.x,t1.x), min(t0.y,t1.y)), min(t0.z,t1.z))
//           tFar  = min(min(max(t0.x,t1.x), max(t0.y,t1.y)), max(t0.z,t1.z))
//           tHit  = max(tNear, ray.tMin)
//           limit = committed type == none ? ray.tMax : committed t
//           if (generateRule(ids) && tHit <= tFar && tHit <= limit) generate(q, tHit)
//       }
//   }
//   write the committed values; positions only for committed triangles whose BLAS allows data access.
inline bool confirmRule(uint32_t instanceId, uint32_t geometryIndex, uint32_t primitiveIndex) {
    return (primitiveIndex * 3u + geometryIndex * 5u + instanceId * 7u) % 4u != 0u;
}
inline bool generateRule(uint32_t instanceId, uint32_t geometryIndex, uint32_t primitiveIndex) {
    return (primitiveIndex + geometryIndex * 2u + instanceId) % 3u != 2u;
}

}  // namespace diff
