// Brute-force reference for vkas traversal, written from the spec rules (spec digest sections 2-4 and 6) in
// double precision. It never looks at the acceleration structure: it reads the same application buffers that the
// build reads (geometry fetch + vertex decode) and tests every primitive of every instance for every ray.
#pragma once

#include <vulkan/vulkan_core.h>

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

namespace oracle {

using Vec3 = std::array<double, 3>;

// ---- Vertex formats -------------------------------------------------------------------------------------------
struct FormatInfo {
    VkFormat format;
    const char* name;
    uint32_t components;     // components stored (2, 3 or 4; 4 for the packed 10:10:10:2 format)
    uint32_t componentSize;  // bytes per component; 4 for the packed format (the whole word)
    uint32_t size;           // bytes per vertex
    bool isFloat;            // can hold NaN
    bool packed;
};
// The 16 vertex formats the CTS `format` group uses.
const std::vector<FormatInfo>& vertexFormats();
const FormatInfo& formatInfo(VkFormat format);

double halfToDouble(uint16_t h);
uint16_t floatToHalf(float f);  // round to nearest even

// Decodes one vertex (unaligned read). Returns the position (2-component formats: z = 0; 4th component ignored)
// and whether the raw X component is NaN.
Vec3 decodeVertex(VkFormat format, const void* p, bool* xIsNaN = nullptr);

// ---- Geometry ---------------------------------------------------------------------------------------------------
struct Triangle {
    std::array<Vec3, 3> v;  // object space, after the geometry transform, rounded to float
    bool active = true;
};
struct Geometry {
    bool opaque = false;
    std::vector<Triangle> triangles;  // index = primitive index
};
struct Blas {
    std::vector<Geometry> geometries;  // index = geometry index
    Vec3 lo{0, 0, 0}, hi{-1, -1, -1};  // bounds of active triangles (lo > hi: empty)
    void computeBounds();
};

// Fetches the triangles of one geometry exactly as the spec's fetch rules say (spec digest section 4).
Geometry fetchTriangles(const VkAccelerationStructureGeometryKHR& geometry,
                        const VkAccelerationStructureBuildRangeInfoKHR& range);

// ---- Instances --------------------------------------------------------------------------------------------------
struct Instance {
    double toWorld[3][4];
    double toObject[3][4];
    uint32_t customIndex = 0, mask = 0, sbtOffset = 0, flags = 0;
    uint64_t reference = 0;
    std::shared_ptr<const Blas> blas;  // null: inactive
};
// Decodes a 64-byte VkAccelerationStructureInstanceKHR with shifts; lookup maps a non-zero reference to its BLAS.
Instance decodeInstance(const void* bytes, const std::function<std::shared_ptr<const Blas>(uint64_t)>& lookup);
void invert34(const double m[3][4], double out[3][4]);

struct Scene {
    std::vector<Instance> instances;  // index = instance id
};

// ---- Traversal --------------------------------------------------------------------------------------------------
struct Ray {
    std::array<float, 3> origin{};
    float tMin = 0.0f;
    std::array<float, 3> direction{};
    float tMax = 0.0f;
};

struct Candidate {
    double t = 0;
    double bary[2] = {0, 0};  // weights of vertex 1 and vertex 2
    int32_t instanceId = -1, geometryIndex = -1, primitiveIndex = -1;
    uint32_t customIndex = 0, sbtOffset = 0;
    bool frontFace = false;
    bool facingAmbiguous = false;  // nearly edge-on: facing may come out either way in float
    bool opaque = false;
    // Optional: the ray passes within the tolerance margin of an edge, of tMin/tMax, or of edge-on, so an
    // implementation may report it or not. Required candidates must be found.
    bool optional = false;
    double tTolerance = 0;     // absolute tolerance for comparing t
    double baryTolerance = 0;  // absolute tolerance for comparing barycentrics
    double objectOrigin[3] = {0, 0, 0}, objectDirection[3] = {0, 0, 0};
};

struct Result {
    // Every candidate that survives all culling (mask, skip, facing, opacity culling), required or optional.
    std::vector<Candidate> candidates;
    const Candidate* find(int32_t instanceId, int32_t geometryIndex, int32_t primitiveIndex) const;
    const Candidate* closestRequired() const;
    size_t requiredCount() const;
};

// rayFlags are the SPIR-V RayFlags bits; only the low 8 bits of cullMask are used.
Result trace(const Scene& scene, const Ray& ray, uint32_t rayFlags, uint32_t cullMask);

}  // namespace oracle
