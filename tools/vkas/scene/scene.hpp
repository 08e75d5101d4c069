// The built-in scene of `vkas render`: procedural meshes, the bottom-level structures made of them (with vertex
// formats, index types and geometry transforms chosen to exercise the API), and many instances of them.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "meshes.hpp"
#include "vec_math.hpp"

namespace vkas_tool {

// How a geometry's vertices sit in its vertex buffer.
enum class VertexLayout {
    Float3,             // VK_FORMAT_R32G32B32_SFLOAT, stride 12
    Float3Interleaved,  // VK_FORMAT_R32G32B32_SFLOAT, stride 24: position then normal, like a real vertex buffer
    Float4,             // VK_FORMAT_R32G32B32A32_SFLOAT, stride 16 (w = 1, ignored by the build)
    Half4,              // VK_FORMAT_R16G16B16A16_SFLOAT, stride 8 (positions must be exact in half precision)
};

struct GeometryDesc {
    const Mesh* mesh = nullptr;
    VertexLayout layout = VertexLayout::Float3;
    VkIndexType indexType = VK_INDEX_TYPE_NONE_KHR;  // NONE_KHR, UINT16 or UINT32 (mesh must be indexed for the latter)
    std::optional<Affine> transform;                  // the geometry transform (transformData), if any
    VkGeometryFlagsKHR flags = VK_GEOMETRY_OPAQUE_BIT_KHR;
};

// What a bottom-level structure holds: a structure holds one primitive type (VUID 03792).
enum class PrimitiveKind {
    Triangles,        // `geometries`
    Spheres,          // `spheres`: VK_GEOMETRY_TYPE_SPHERES_NV
    SweptSpheres,     // `chains`: VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV, SUCCESSIVE indexing, CHAINED end caps
    ProceduralBoxes,  // `boxes`: VK_GEOMETRY_TYPE_AABBS_KHR, intersected by the renderer's procedural step
};

struct Sphere {
    Vec3 center;
    float radius = 1.0f;
};

// A chain of linear swept spheres: segment k joins points[k] (radius radii[k]) to points[k + 1]. Primitive
// indices number the segments of all chains of a structure in order.
struct SweptSphereChain {
    std::vector<Vec3> points;
    std::vector<float> radii;
    uint32_t segmentCount() const { return points.size() < 2 ? 0u : static_cast<uint32_t>(points.size() - 1); }
};

struct Box {
    Vec3 lo, hi;
};

struct BlasDesc {
    std::string name;
    std::vector<GeometryDesc> geometries;
    bool usePointerArray = false;  // pass the geometries through ppGeometries instead of pGeometries
    PrimitiveKind kind = PrimitiveKind::Triangles;
    std::vector<Sphere> spheres;
    std::vector<SweptSphereChain> chains;
    std::vector<Box> boxes;

    uint64_t primitiveCount() const;  // triangles, spheres, segments or boxes
};

struct InstanceDesc {
    uint32_t blas = 0;
    Affine transform;
    uint32_t customIndex = 0;  // the material
    uint8_t mask = 0xFF;
    VkGeometryInstanceFlagsKHR flags = 0;
};

struct Material {
    Vec3 albedo;
};

struct Camera {
    Vec3 position, target, up{0, 1, 0};
    float verticalFovDegrees = 45.0f;
};

struct Scene {
    std::vector<std::unique_ptr<Mesh>> meshes;  // stable addresses: GeometryDesc points at them
    std::vector<BlasDesc> blases;
    std::vector<InstanceDesc> instances;
    std::vector<Material> materials;
    Camera camera;
    Vec3 sunDirection;  // unit vector towards the sun
    float aoRadius = 2.0f;
    float fogDensity = 0.004f;  // aerial perspective per unit of distance
    float rayTMax = 1.0e4f;     // camera and sun rays end here: past the scene

    uint64_t uniqueTriangles() const;     // triangles in all bottom-level structures
    uint64_t instancedTriangles() const;  // triangles seen through all instances
    uint64_t uniquePrimitives() const;    // primitives of every kind in all bottom-level structures
};

struct SceneOptions {
    uint32_t instanceCount = 2000;  // scattered instances (plus a few landmarks and the terrain)
    uint64_t seed = 1;
};

Scene makeBuiltinScene(const SceneOptions& options);

}  // namespace vkas_tool
