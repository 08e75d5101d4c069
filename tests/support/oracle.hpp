// Brute-force reference for vkas traversal, written from the spec rules (spec digest sections 2-4 and 6) in
// double precision. It never looks at the acceleration structure: it reads the same application buffers that the
// build reads (geometry fetch + vertex decode) and tests every primitive of every instance for every ray.
#pragma once

#include <vkas/vkas_compat.h>  // VK_NV_ray_tracing_linear_swept_spheres on older headers
#include <vulkan/vulkan_core.h>

#include "oracle_micromap.hpp"

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
// A VkAabbPositionsKHR as given. Inactive when minX is NaN; a box with min > max on an axis (invalid input,
// VUIDs 03546-03548) is never hit.
struct Aabb {
    Vec3 lo{0, 0, 0}, hi{0, 0, 0};
    bool active = true;
    bool valid() const { return active && lo[0] <= hi[0] && lo[1] <= hi[1] && lo[2] <= hi[2]; }
};
// [NV-LSS] A sphere (p[0] == p[1], r[0] == r[1], both caps) or a linear swept sphere: the union of the balls
// centred on p[0] + s (p[1] - p[0]) with radius r[0] + s (r[1] - r[0]), s in [0, 1]. cap[k]: the end-caps mode
// leaves the cap at endpoint k on. Inactive when a component of a position or radius is NaN; never hit when a
// radius is negative (invalid input) or both are zero (degenerate).
struct SweptPrimitive {
    std::array<Vec3, 2> p{};  // as decoded, rounded to float
    std::array<double, 2> r{0, 0};
    std::array<bool, 2> cap{true, true};
    bool active = true;
    bool hittable() const { return active && r[0] >= 0 && r[1] >= 0 && (r[0] > 0 || r[1] > 0); }
};
struct Geometry {
    VkGeometryTypeKHR type = VK_GEOMETRY_TYPE_TRIANGLES_KHR;
    bool opaque = false;
    std::shared_ptr<const GeometryMicromap> micromap;  // [EXT-OMM] triangle geometries with an opacity micromap
    std::vector<Triangle> triangles;  // triangle geometries; index = primitive index
    std::vector<Aabb> aabbs;          // AABB geometries; index = primitive index
    std::vector<SweptPrimitive> swept;  // sphere and LSS geometries; index = primitive index
};
struct Blas {
    std::vector<Geometry> geometries;  // index = geometry index
    Vec3 lo{0, 0, 0}, hi{-1, -1, -1};  // bounds of active triangles and valid AABBs (lo > hi: empty)
    void computeBounds();
    std::shared_ptr<const Blas> atTime1;  // [NV-motion] the same geometry with the positions at time 1; null: static
};

// Fetches the triangles of one geometry exactly as the spec's fetch rules say (spec digest section 4).
Geometry fetchTriangles(const VkAccelerationStructureGeometryKHR& geometry,
                        const VkAccelerationStructureBuildRangeInfoKHR& range);
// Fetches the AABBs of one geometry: AABB i at data + primitiveOffset + i * stride.
Geometry fetchAabbs(const VkAccelerationStructureGeometryKHR& geometry,
                    const VkAccelerationStructureBuildRangeInfoKHR& range);
// [NV-LSS] Fetches a sphere or LSS geometry (data in the geometry's pNext chain), written from the spec's range
// rules (support/oracle_spheres.cpp).
Geometry fetchSweptSpheres(const VkAccelerationStructureGeometryKHR& geometry,
                           const VkAccelerationStructureBuildRangeInfoKHR& range);
// Any of them, by geometryType.
Geometry fetchGeometry(const VkAccelerationStructureGeometryKHR& geometry,
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
    bool aabb = false;  // an AABB candidate: t is where the ray enters the box, clamped to tMin
    double t = 0;
    double bary[2] = {0, 0};  // weights of vertex 1 and vertex 2
    int32_t instanceId = -1, geometryIndex = -1, primitiveIndex = -1;
    uint32_t customIndex = 0, sbtOffset = 0;
    bool frontFace = false;
    bool facingAmbiguous = false;  // nearly edge-on: facing may come out either way in float
    bool opaque = false;
    bool opacityAmbiguous = false;  // [EXT-OMM] near a micro-edge between states of different opacity: either
    // Optional: the ray passes within the tolerance margin of an edge, of tMin/tMax, or of edge-on, so an
    // implementation may report it or not. Required candidates must be found.
    bool optional = false;
    double tTolerance = 0;     // absolute tolerance for comparing t
    double tExit = 0;          // AABB candidates: where the ray leaves the box, clamped to tMax
    double baryTolerance = 0;  // absolute tolerance for comparing barycentrics
    double objectOrigin[3] = {0, 0, 0}, objectDirection[3] = {0, 0, 0};
    // [NV-LSS] Sphere and LSS candidates (reported with the triangle intersection types; facingAmbiguous and an
    // infinite baryTolerance). u: the LSS hit value (0 for spheres), within uTolerance.
    VkGeometryTypeKHR sweptType = VK_GEOMETRY_TYPE_TRIANGLES_KHR;  // SPHERES_NV or LINEAR_SWEPT_SPHERES_NV
    double u = 0, uTolerance = 0;
};

// [NV-LSS] Adds the candidates of one sphere/LSS geometry for the object-space ray o + t d (support/oracle_spheres.cpp):
// the entry point into each shape (convex minimisation of the distance to the swept spheres, then bisection), no hit
// when the ray starts inside or enters through an absent cap. `proto` carries the instance fields and opacity.
// scale: the magnitude of the world/object coordinates involved, for the tolerance.
void sweptCandidates(const Geometry& geometry, const Vec3& o, const Vec3& d, double tMin, double tMax, double scale,
                     const Candidate& proto, std::vector<Candidate>& out);

struct Result {
    // Every candidate that survives all culling (mask, skip, facing, opacity culling), required or optional.
    // AABB candidates (aabb = true) are required when the ray passes through the box shrunk by the tolerance
    // margin within [tMin, tMax], optional when it only meets the box grown by it.
    std::vector<Candidate> candidates;
    const Candidate* find(int32_t instanceId, int32_t geometryIndex, int32_t primitiveIndex) const;
    const Candidate* closestRequired() const;
    size_t requiredCount() const;
    // The same result without AABB candidates: what a trace without an intersection shader can hit.
    Result withoutAabbs() const;
};

// The parameters [t0, t1] where the line o + t d is inside the closed box [lo, hi], in double; false (and t0 > t1)
// when it never is. A zero direction component keeps the slab only if o is inside it.
bool boxInterval(const Vec3& o, const Vec3& d, const Vec3& lo, const Vec3& hi, double& t0, double& t1);

// rayFlags are the SPIR-V RayFlags bits; only the low 8 bits of cullMask are used.
Result trace(const Scene& scene, const Ray& ray, uint32_t rayFlags, uint32_t cullMask);

// One triangle of one instance against a ray, tested as trace() tests it, whatever the outcome: for reports that
// say how far a hit an implementation reported is from the oracle's candidates (bench/vs_embree). The instance
// mask, ray flags and facing culling are not applied.
enum class TriangleStatus {
    Candidate,   // trace() lists it (required when inside and inRange, and not nearly edge-on)
    Inactive,    // inactive, or no such instance, geometry or triangle
    EdgeOn,      // the ray is parallel to its plane (or it is degenerate)
    Outside,     // a barycentric weight is below -baryTolerance
    OutOfRange,  // t is outside [tMin - tTolerance, tMax + tTolerance]
};
const char* triangleStatusName(TriangleStatus s);
struct TriangleTest {
    TriangleStatus status = TriangleStatus::Inactive;
    double t = 0;                // the ray's parameter at the triangle's plane (the same in world and object space)
    double bary[3] = {0, 0, 0};  // weights of vertices 0, 1 and 2
    double baryTolerance = 0;    // within this of an edge (a weight of 0), a candidate is optional
    double tTolerance = 0;       // within this of tMin or tMax, a candidate is optional
    double distance[3] = {0, 0, 0};  // signed distance of the hit point from the edge opposite vertex k (object space)
    double scale = 0;            // magnitude of the coordinates involved (origins, transform, hit point, vertices)
    double tolDistance = 0;      // the distance the tolerances allow for (object space): 1e-5 scale; margin k =
                                 // tolDistance / (height k * cosine), at least 1e-5
    double cosine = 0;           // |cos| of the angle between the object-space ray and the triangle's normal
    double dn = 0;               // normal . object direction; < 0: front face (before the instance's flip flag)
    bool inside = false;         // every weight above baryTolerance
    bool inRange = false;        // tMin + tTolerance < t < tMax - tTolerance
};
TriangleTest examineTriangle(const Scene& scene, const Ray& ray, int32_t instanceId, int32_t geometryIndex,
                             int32_t primitiveIndex);

// ---- [NV-motion] VK_NV_ray_tracing_motion_blur --------------------------------------------------------------------
// Motion is evaluated by turning the structures into the static ones they are at a time, then tracing those.
//
// Triangles at time 1: the geometry fetched again with VkAccelerationStructureGeometryMotionTrianglesDataNV's
// vertexData (same format, stride, indexing and transform). A triangle is active when it is at both times.
Geometry fetchTrianglesAtTime1(const VkAccelerationStructureGeometryKHR& geometry,
                               const VkAccelerationStructureBuildRangeInfoKHR& range);
// The BLAS at `time` (positions (1 - time) v0 + time v1, exact in double); a static BLAS is returned as is.
std::shared_ptr<const Blas> blasAt(const std::shared_ptr<const Blas>& blas, double time);

// One VkAccelerationStructureMotionInstanceNV: type 0 static (transform0), 1 matrix (transform0/1, interpolated
// componentwise), 2 SRT (srt0/1: the 16 VkSRTDataNV values, interpolated componentwise, then T * R * S with the
// interpolated quaternion normalized).
struct MotionInstance {
    uint32_t type = 0;
    double transform0[3][4] = {}, transform1[3][4] = {};
    double srt0[16] = {}, srt1[16] = {};
    Instance base;  // ids, mask, flags, reference, BLAS (the transforms are filled in by instanceAt)
};
// Decodes the member of VkAccelerationStructureMotionInstanceDataNV that `type` names, at `payload`.
MotionInstance decodeMotionInstance(uint32_t type, const void* payload,
                                    const std::function<std::shared_ptr<const Blas>(uint64_t)>& lookup);
// The object-to-world matrix T * R * S of 16 VkSRTDataNV values.
void srtMatrix(const double srt[16], double out[3][4]);
// The instance at `time`: its transform and inverse, and its BLAS at that time.
Instance instanceAt(const MotionInstance& instance, double time);

struct MotionScene {
    std::vector<MotionInstance> instances;  // index = instance id
    Scene at(double time) const;
};

}  // namespace oracle
