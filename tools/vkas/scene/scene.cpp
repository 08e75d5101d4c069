#include "scene.hpp"

#include <cmath>
#include <numbers>

namespace vkas_tool {
namespace {

constexpr float kTerrainHalfSize = 60.0f;

float terrainHeight(float x, float z) {
    return 3.0f * std::sin(x * 0.07f) * std::cos(z * 0.06f) + 1.2f * std::sin(x * 0.21f + 1.3f) * std::sin(z * 0.17f + 0.4f) +
           0.35f * std::sin(x * 0.63f + z * 0.41f) * std::cos(z * 0.57f - x * 0.2f);
}

float rockDisplacement(Vec3 p) {
    return 1.0f + 0.18f * std::sin(5.1f * p.x + 1.0f) * std::sin(4.3f * p.y + 2.0f) * std::sin(3.7f * p.z) +
           0.08f * std::sin(11.0f * p.x + 7.0f * p.z);
}

const Mesh* addMesh(Scene& scene, Mesh mesh) {
    scene.meshes.push_back(std::make_unique<Mesh>(std::move(mesh)));
    return scene.meshes.back().get();
}

// Material indices (instance custom indices).
enum : uint32_t { kGround, kStone, kWhite, kRed, kOrange, kYellow, kGreen, kTeal, kBlue, kViolet, kCrystal, kGold };

}  // namespace

uint64_t BlasDesc::primitiveCount() const {
    switch (kind) {
    case PrimitiveKind::Triangles: {
        uint64_t n = 0;
        for (const GeometryDesc& g : geometries) n += g.mesh->triangleCount();
        return n;
    }
    case PrimitiveKind::Spheres: return spheres.size();
    case PrimitiveKind::SweptSpheres: {
        uint64_t n = 0;
        for (const SweptSphereChain& c : chains) n += c.segmentCount();
        return n;
    }
    case PrimitiveKind::ProceduralBoxes: return boxes.size();
    }
    return 0;
}

uint64_t Scene::uniquePrimitives() const {
    uint64_t n = 0;
    for (const BlasDesc& b : blases) n += b.primitiveCount();
    return n;
}

uint64_t Scene::uniqueTriangles() const {
    uint64_t n = 0;
    for (const BlasDesc& b : blases)
        for (const GeometryDesc& g : b.geometries) n += g.mesh->triangleCount();
    return n;
}

uint64_t Scene::instancedTriangles() const {
    std::vector<uint64_t> perBlas;
    for (const BlasDesc& b : blases) {
        uint64_t n = 0;
        for (const GeometryDesc& g : b.geometries) n += g.mesh->triangleCount();
        perBlas.push_back(n);
    }
    uint64_t n = 0;
    for (const InstanceDesc& i : instances) n += perBlas[i.blas];
    return n;
}

Scene makeBuiltinScene(const SceneOptions& options) {
    Scene scene;
    scene.materials = {
        {{0.50f, 0.44f, 0.34f}},  // ground
        {{0.45f, 0.43f, 0.40f}},  // stone
        {{0.85f, 0.85f, 0.82f}},  // white
        {{0.80f, 0.18f, 0.15f}},  // red
        {{0.90f, 0.50f, 0.12f}},  // orange
        {{0.90f, 0.78f, 0.20f}},  // yellow
        {{0.25f, 0.65f, 0.25f}},  // green
        {{0.15f, 0.60f, 0.60f}},  // teal
        {{0.20f, 0.35f, 0.80f}},  // blue
        {{0.55f, 0.25f, 0.75f}},  // violet
        {{0.60f, 0.85f, 0.95f}},  // crystal
        {{0.95f, 0.70f, 0.25f}},  // gold
    };

    const Mesh* terrain = addMesh(scene, makeTerrain(200, kTerrainHalfSize, terrainHeight));
    const Mesh* sphere = addMesh(scene, makeIcosphere(4));
    const Mesh* knot = addMesh(scene, makeTorusKnot(2, 3, 512, 24, 0.22f));
    const Mesh* box = addMesh(scene, makeBox());
    const Mesh* tetrahedra = addMesh(scene, makeTetrahedra(60, 7));
    Mesh rockMesh = makeIcosphere(3, rockDisplacement);
    rockMesh.name = "rock";
    const Mesh* rock = addMesh(scene, std::move(rockMesh));

    // Bottom-level structures. Every index type, several vertex layouts, geometry transforms, several geometries
    // per structure, both pGeometries and ppGeometries.
    enum : uint32_t { kTerrainBlas, kSphereBlas, kKnotBlas, kHouseBlas, kCrystalBlas, kRockBlas, kMonumentBlas };
    scene.blases.push_back({"terrain", {{terrain, VertexLayout::Float3, VK_INDEX_TYPE_UINT32, {}}}, false});
    scene.blases.push_back({"sphere", {{sphere, VertexLayout::Float3Interleaved, VK_INDEX_TYPE_UINT16, {}}}, false});
    scene.blases.push_back({"torus knot", {{knot, VertexLayout::Float4, VK_INDEX_TYPE_UINT32, {}}}, false});
    scene.blases.push_back(
        {"house",
         {
             // walls, a roof made of a box turned 45 degrees, a chimney
             {box, VertexLayout::Half4, VK_INDEX_TYPE_NONE_KHR,
              Affine::translation({0, 0.6f, 0}) * Affine::scale({1.0f, 0.6f, 0.7f})},
             {box, VertexLayout::Half4, VK_INDEX_TYPE_NONE_KHR,
              Affine::translation({0, 1.2f, 0}) * Affine::rotation({1, 0, 0}, std::numbers::pi_v<float> / 4) *
                  Affine::scale({1.08f, 0.55f, 0.55f})},
             {box, VertexLayout::Half4, VK_INDEX_TYPE_NONE_KHR,
              Affine::translation({0.55f, 1.6f, 0.2f}) * Affine::scale({0.1f, 0.35f, 0.1f})},
         },
         true});
    scene.blases.push_back({"crystals",
                            {{tetrahedra, VertexLayout::Float3, VK_INDEX_TYPE_NONE_KHR,
                              Affine::translation({0, 0.9f, 0}) * Affine::scale({0.8f, 1.0f, 0.8f}),
                              0 /* not opaque: vkasTraceRays confirms it */}},
                            false});
    scene.blases.push_back({"rock", {{rock, VertexLayout::Float3, VK_INDEX_TYPE_UINT16, {}}}, false});
    scene.blases.push_back(
        {"monument",
         {
             {box, VertexLayout::Float3, VK_INDEX_TYPE_NONE_KHR,
              Affine::translation({0, 0.5f, 0}) * Affine::scale({0.9f, 0.5f, 0.9f})},
             {box, VertexLayout::Float4, VK_INDEX_TYPE_NONE_KHR,
              Affine::translation({0, 1.8f, 0}) * Affine::scale({0.35f, 0.8f, 0.35f})},
             {sphere, VertexLayout::Float3, VK_INDEX_TYPE_UINT32,
              Affine::translation({0, 3.2f, 0}) * Affine::scale({0.6f, 0.6f, 0.6f})},
         },
         false});

    // Built-in primitives beside the triangles: a cloud of spheres, coils of swept spheres, a stack of crates that
    // are procedural boxes.
    enum : uint32_t { kBubblesBlas = kMonumentBlas + 1, kCoilBlas, kCratesBlas };
    {
        BlasDesc bubbles{"bubbles", {}, false, PrimitiveKind::Spheres};
        Rng sphereRng(options.seed, 29);
        for (int i = 0; i < 160; ++i) {
            const float a = 0.35f * static_cast<float>(i), h = 0.045f * static_cast<float>(i);
            const float r = 0.55f + 0.25f * std::sin(0.5f * a);
            bubbles.spheres.push_back({{r * std::cos(a) + sphereRng.uniform(-0.1f, 0.1f), h,
                                        r * std::sin(a) + sphereRng.uniform(-0.1f, 0.1f)},
                                       sphereRng.uniform(0.08f, 0.22f)});
        }
        scene.blases.push_back(std::move(bubbles));

        BlasDesc coil{"coil", {}, false, PrimitiveKind::SweptSpheres};
        for (int c = 0; c < 3; ++c) {  // three intertwined helices, their radius tapering towards the top
            SweptSphereChain chain;
            for (int k = 0; k <= 96; ++k) {
                const float t = static_cast<float>(k) / 96.0f;
                const float a = 2.0f * std::numbers::pi_v<float> * (3.0f * t + static_cast<float>(c) / 3.0f);
                chain.points.push_back({0.8f * std::cos(a), 4.0f * t, 0.8f * std::sin(a)});
                chain.radii.push_back(0.16f * (1.0f - 0.7f * t));
            }
            coil.chains.push_back(std::move(chain));
        }
        SweptSphereChain post;  // the axis: one cone-like segment
        post.points = {{0, 0, 0}, {0, 4.4f, 0}};
        post.radii = {0.28f, 0.06f};
        coil.chains.push_back(std::move(post));
        scene.blases.push_back(std::move(coil));

        BlasDesc crates{"crates", {}, false, PrimitiveKind::ProceduralBoxes};
        for (int layer = 0; layer < 4; ++layer)
            for (int i = 0; i < 4 - layer; ++i)
                for (int j = 0; j < 4 - layer; ++j) {
                    const Vec3 lo{static_cast<float>(i) + 0.5f * layer - 2.0f, static_cast<float>(layer),
                                  static_cast<float>(j) + 0.5f * layer - 2.0f};
                    crates.boxes.push_back({lo + Vec3{0.04f, 0.0f, 0.04f}, lo + Vec3{0.96f, 0.92f, 0.96f}});
                }
        scene.blases.push_back(std::move(crates));
    }

    auto place = [&](uint32_t blas, float x, float z, float lift, float scale, float yaw, Vec3 tiltAxis, float tilt,
                     uint32_t material, VkGeometryInstanceFlagsKHR flags = 0) {
        InstanceDesc inst;
        inst.blas = blas;
        inst.transform = Affine::translation({x, terrainHeight(x, z) + lift * scale, z}) *
                         Affine::rotation(tiltAxis, tilt) * Affine::rotation({0, 1, 0}, yaw) *
                         Affine::scale({scale, scale, scale});
        inst.customIndex = material;
        inst.flags = flags;
        scene.instances.push_back(inst);
    };

    // The ground, then a few landmarks, then the scattered crowd.
    scene.instances.push_back({kTerrainBlas, Affine{}, kGround, 0xFF, VK_GEOMETRY_INSTANCE_TRIANGLE_FACING_CULL_DISABLE_BIT_KHR});
    place(kKnotBlas, 2.0f, -6.0f, 1.4f, 4.5f, 0.3f, {1, 0, 0}, 0.5f, kGold);
    place(kMonumentBlas, -12.0f, 6.0f, -0.1f, 2.5f, 0.0f, {0, 1, 0}, 0.0f, kWhite);
    place(kMonumentBlas, 14.0f, 2.0f, -0.1f, 2.5f, 0.0f, {0, 1, 0}, 0.0f, kWhite);
    place(kSphereBlas, -4.0f, 10.0f, 0.9f, 2.2f, 0.0f, {0, 1, 0}, 0.0f, kBlue);
    place(kBubblesBlas, -15.0f, 14.0f, 0.2f, 2.0f, 0.0f, {0, 1, 0}, 0.0f, kTeal);
    place(kCoilBlas, 6.0f, 8.0f, -0.1f, 2.0f, 0.4f, {0, 1, 0}, 0.0f, kRed);
    place(kCoilBlas, -20.0f, -4.0f, -0.1f, 1.6f, 1.1f, {0, 1, 0}, 0.0f, kViolet);
    place(kCratesBlas, -5.0f, 0.0f, 0.0f, 1.6f, 0.3f, {0, 1, 0}, 0.0f, kOrange);
    place(kCratesBlas, 20.0f, 12.0f, 0.0f, 1.3f, 1.0f, {0, 1, 0}, 0.0f, kYellow);

    Rng rng(options.seed, 17);
    const uint32_t colours[] = {kRed, kOrange, kYellow, kGreen, kTeal, kBlue, kViolet, kWhite};
    for (uint32_t i = 0; i < options.instanceCount; ++i) {
        float x = rng.uniform(-kTerrainHalfSize + 2, kTerrainHalfSize - 2);
        float z = rng.uniform(-kTerrainHalfSize + 2, kTerrainHalfSize - 2);
        float yaw = rng.uniform(0, 2 * std::numbers::pi_v<float>);
        Vec3 axis{rng.uniform(-1, 1), 0, rng.uniform(-1, 1)};
        uint32_t colour = colours[rng.next() % 8];
        float kind = rng.uniform();
        if (kind < 0.35f) {
            place(kRockBlas, x, z, 0.2f, rng.uniform(0.25f, 0.9f), yaw, axis, rng.uniform(0, 1.5f), kStone);
        } else if (kind < 0.50f) {
            place(kSphereBlas, x, z, 0.85f, rng.uniform(0.2f, 0.6f), yaw, {0, 1, 0}, 0, colour);
        } else if (kind < 0.67f) {
            place(kHouseBlas, x, z, -0.05f, rng.uniform(0.5f, 1.1f), yaw, axis, rng.uniform(0, 0.08f), colour);
        } else if (kind < 0.80f) {
            place(kCrystalBlas, x, z, -0.1f, rng.uniform(0.4f, 1.0f), yaw, axis, rng.uniform(0, 0.2f), kCrystal,
                  (i & 1) ? VK_GEOMETRY_INSTANCE_FORCE_OPAQUE_BIT_KHR : 0);
        } else if (kind < 0.90f) {
            place(kKnotBlas, x, z, 0.9f, rng.uniform(0.3f, 0.7f), yaw, axis, rng.uniform(0, 3.0f), colour);
        } else if (kind < 0.92f) {
            place(kBubblesBlas, x, z, 0.1f, rng.uniform(0.5f, 1.0f), yaw, {0, 1, 0}, 0, colour);
        } else if (kind < 0.94f) {
            place(kCoilBlas, x, z, -0.1f, rng.uniform(0.4f, 0.9f), yaw, {0, 1, 0}, 0, colour);
        } else if (kind < 0.96f) {
            place(kCratesBlas, x, z, 0.0f, rng.uniform(0.3f, 0.6f), yaw, {0, 1, 0}, 0, colour);
        } else {
            place(kMonumentBlas, x, z, -0.05f, rng.uniform(0.4f, 0.8f), yaw, {0, 1, 0}, 0, kWhite);
        }
    }

    scene.camera.position = {-34.0f, 16.0f, 44.0f};
    scene.camera.target = {4.0f, 0.0f, -6.0f};
    scene.camera.verticalFovDegrees = 42.0f;
    scene.sunDirection = normalize({0.55f, 0.75f, 0.40f});
    scene.aoRadius = 2.5f;
    return scene;
}

}  // namespace vkas_tool
