// CTS `update` and `instance_update`: VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR refits a structure built with
// ALLOW_UPDATE to new inputs (moved vertices, boxes, geometry transforms, instance definitions), in place
// (src == dst) or into another structure, and from a compacted copy. Every result is checked against the
// brute-force oracle on the new inputs. Also: a triangle collapsed to a point in the build is hit again once the
// update gives it area; an update with the build's inputs traces identically; and every update VUID is reported
// alone, with the destination untouched.
#include <chrono>
#include <cmath>
#include <cstring>
#include <iostream>
#include <limits>

#include "meshes.h"

using namespace vt;

namespace {

constexpr VkBuildAccelerationStructureFlagsKHR kAllowUpdate = VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR;
const float kNaN = std::numeric_limits<float>::quiet_NaN();

double seconds(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Vertex data of a mesh in one of several vertex formats (non-indexed or indexed like makeGeometry).
struct FormattedGeometry {
    std::vector<uint8_t> vertices, indices, transform;
    VkAccelerationStructureGeometryKHR geometry{};
    VkAccelerationStructureBuildRangeInfoKHR range{};
};

void encodeVertex(VkFormat format, const Float3& p, uint8_t* out) {
    auto snorm16 = [](float f) { return int16_t(std::lround(std::clamp(f, -1.0f, 1.0f) * 32767.0f)); };
    auto snorm8 = [](float f) { return int8_t(std::lround(std::clamp(f, -1.0f, 1.0f) * 127.0f)); };
    switch (format) {
        case VK_FORMAT_R32G32B32_SFLOAT: std::memcpy(out, p.data(), 12); break;
        case VK_FORMAT_R32G32B32A32_SFLOAT: {
            const float v[4] = {p[0], p[1], p[2], 1.0f};
            std::memcpy(out, v, 16);
            break;
        }
        case VK_FORMAT_R64G64B64_SFLOAT: {
            const double v[3] = {p[0], p[1], p[2]};
            std::memcpy(out, v, 24);
            break;
        }
        case VK_FORMAT_R16G16B16A16_SNORM: {
            const int16_t v[4] = {snorm16(p[0]), snorm16(p[1]), snorm16(p[2]), 0};
            std::memcpy(out, v, 8);
            break;
        }
        case VK_FORMAT_R8G8B8A8_SNORM: {
            const int8_t v[4] = {snorm8(p[0]), snorm8(p[1]), snorm8(p[2]), 0};
            std::memcpy(out, v, 4);
            break;
        }
        default: FAIL() << "format " << format;
    }
}
uint32_t formatSize(VkFormat f) {
    switch (f) {
        case VK_FORMAT_R32G32B32A32_SFLOAT: return 16;
        case VK_FORMAT_R64G64B64_SFLOAT: return 24;
        case VK_FORMAT_R16G16B16A16_SNORM: return 8;
        case VK_FORMAT_R8G8B8A8_SNORM: return 4;
        default: return 12;
    }
}

std::unique_ptr<FormattedGeometry> makeFormatted(const Mesh& mesh, VkFormat format, VkIndexType indexType,
                                                 VkGeometryFlagsKHR flags, const VkTransformMatrixKHR* transform,
                                                 uint32_t firstVertex = 0) {
    auto g = std::make_unique<FormattedGeometry>();
    const uint32_t stride = formatSize(format);
    auto& tri = g->geometry.geometry.triangles;
    g->geometry.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR;
    g->geometry.geometryType = VK_GEOMETRY_TYPE_TRIANGLES_KHR;
    g->geometry.flags = flags;
    tri.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR;
    tri.vertexFormat = format;
    tri.vertexStride = stride;
    tri.indexType = indexType;
    std::vector<Float3> verts;
    if (indexType == VK_INDEX_TYPE_NONE_KHR) {
        for (uint32_t i : mesh.indices) verts.push_back(mesh.positions[i]);
    } else {
        verts = mesh.positions;
        const uint32_t size = indexType == VK_INDEX_TYPE_UINT16 ? 2 : 4;
        g->indices.resize(std::max<size_t>(mesh.indices.size() * size, 4));
        for (size_t i = 0; i < mesh.indices.size(); ++i) {
            if (size == 2) {
                const uint16_t v = uint16_t(mesh.indices[i]);
                std::memcpy(g->indices.data() + 2 * i, &v, 2);
            } else {
                std::memcpy(g->indices.data() + 4 * i, &mesh.indices[i], 4);
            }
        }
        tri.indexData.hostAddress = g->indices.data();
    }
    // Room for firstVertex up to 8; maxVertex does not depend on firstVertex (an update must keep it: 03764).
    g->vertices.assign((verts.size() + 8) * stride, 0xAA);
    for (size_t i = 0; i < verts.size(); ++i) encodeVertex(format, verts[i], g->vertices.data() + (firstVertex + i) * stride);
    tri.vertexData.hostAddress = g->vertices.data();
    tri.maxVertex = uint32_t(verts.size() + 7);
    if (transform) {
        g->transform.resize(sizeof(VkTransformMatrixKHR));
        std::memcpy(g->transform.data(), transform, sizeof(VkTransformMatrixKHR));
        tri.transformData.hostAddress = g->transform.data();
    }
    g->range.primitiveCount = uint32_t(mesh.triangleCount());
    g->range.firstVertex = firstVertex;
    return g;
}

// Moves every vertex by a random offset of up to `amount` (a deformation that keeps the index buffer).
Mesh deform(const Mesh& m, Rng& rng, float amount) {
    Mesh out = m;
    for (auto& p : out.positions)
        for (float& c : p) c += rng.uniformf(-amount, amount);
    return out;
}

std::vector<VkAabbPositionsKHR> randomBoxes(Rng& rng, size_t n, float extent, double inactiveFraction) {
    std::vector<VkAabbPositionsKHR> boxes(n);
    for (auto& b : boxes) {
        const float x = rng.uniformf(-extent, extent), y = rng.uniformf(-extent, extent), z = rng.uniformf(-extent, extent);
        const float s = rng.uniformf(0.05f, 0.4f);
        b = {x, y, z, x + s, y + rng.uniformf(0.05f, 0.4f), z + rng.uniformf(0.0f, 0.4f)};
        if (rng.coin(inactiveFraction)) b.minX = kNaN;
    }
    return boxes;
}

VkAccelerationStructureGeometryKHR aabbGeometry(const std::vector<VkAabbPositionsKHR>& boxes, VkGeometryFlagsKHR flags) {
    VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
    g.geometryType = VK_GEOMETRY_TYPE_AABBS_KHR;
    g.flags = flags;
    g.geometry.aabbs.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_AABBS_DATA_KHR;
    g.geometry.aabbs.data.hostAddress = boxes.data();
    g.geometry.aabbs.stride = sizeof(VkAabbPositionsKHR);
    return g;
}

}  // namespace

class update : public VkasTest {
  protected:
    // An UPDATE of `src` with new inputs, into `dst` (nullptr: a fresh structure of src's size; src: in place).
    // On success the oracle's view of the destination follows the new inputs.
    AccelStruct* updateBlas(AccelStruct* src, AccelStruct* dst, const std::vector<VkAccelerationStructureGeometryKHR>& geometries,
                            const std::vector<VkAccelerationStructureBuildRangeInfoKHR>& ranges, const BuildOptions& opt) {
        auto pb = prepareBlas(geometries, ranges, opt);
        return submitUpdate(*pb, src, dst);
    }
    AccelStruct* updateTlas(AccelStruct* src, AccelStruct* dst, const std::vector<Instance>& instances,
                            const BuildOptions& opt) {
        auto pb = prepareTlas(instances, opt);
        return submitUpdate(*pb, src, dst);
    }
    AccelStruct* submitUpdate(PreparedBuild& pb, AccelStruct* src, AccelStruct* dst) {
        EXPECT_EQ(pb.as->sizes.updateScratchSize, 0u);  // a refit needs no scratch
        pb.info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR;
        pb.info.srcAccelerationStructure = src->handle;
        pb.info.scratchData.hostAddress = nullptr;
        if (dst) {
            pb.as = dst;
            pb.info.dstAccelerationStructure = dst->handle;
        }
        submit({&pb});
        return pb.as;
    }
    // A byte copy of [0, usedSize) through vkCopyAccelerationStructureKHR COMPACT into a structure of that size.
    AccelStruct* compactCopy(AccelStruct* src) {
        uint64_t used;
        std::memcpy(&used, src->data() + 16, 8);
        AccelStruct* dst = createAccelStruct(src->type, (used + 255) / 256 * 256, {});
        VkCopyAccelerationStructureInfoKHR ci{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_INFO_KHR};
        ci.src = src->handle;
        ci.dst = dst->handle;
        ci.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_COMPACT_KHR;
        EXPECT_EQ(vk.vkCopyAccelerationStructureKHR(device, VK_NULL_HANDLE, &ci), VK_SUCCESS);
        dst->blas = src->blas;
        dst->scene = src->scene;
        if (src->blas) blasRegistry[dst->reference()] = src->blas;
        return dst;
    }
    void checkBlas(const AccelStruct* blas, size_t rays = 150) {
        AccelStruct* tlas = buildSingleInstanceTlas(blas);
        checkRays(tlas, targetedRays(*tlas->scene, rays));
        checkRays(tlas, randomRays(*tlas->scene, rays / 2));
    }
};

// ---- bottom level -----------------------------------------------------------------------------------------------

// CTS update.cpu.*.vertices (and .transform): deform a mesh, refit in place and into another structure, for every
// index type and several vertex formats, with and without a geometry transform; and once more from the refitted
// structure.
TEST_F(update, triangles_vertices) {
    const VkFormat formats[] = {VK_FORMAT_R32G32B32_SFLOAT, VK_FORMAT_R32G32B32A32_SFLOAT, VK_FORMAT_R64G64B64_SFLOAT,
                                VK_FORMAT_R16G16B16A16_SNORM, VK_FORMAT_R8G8B8A8_SNORM};
    for (VkFormat format : formats)
        for (VkIndexType it : {VK_INDEX_TYPE_NONE_KHR, VK_INDEX_TYPE_UINT16, VK_INDEX_TYPE_UINT32})
            for (int transformed = 0; transformed < 2; ++transformed)
                for (int inPlace = 0; inPlace < 2; ++inPlace) {
                    SCOPED_TRACE(testing::Message() << "format " << format << " index " << it << " transform "
                                                    << transformed << " inPlace " << inPlace);
                    Mesh m = triangleSoup(200, rng, 0.3f);
                    for (auto& p : m.positions)
                        for (float& c : p) c *= 0.7f;  // room for the deformation within [-1, 1] (SNORM)
                    VkTransformMatrixKHR t0 = randomTransform(rng, 0.5f, 2.0f, rng.coin(), 3.0f);
                    auto g0 = makeFormatted(m, format, it, VK_GEOMETRY_OPAQUE_BIT_KHR, transformed ? &t0 : nullptr, 3);
                    BuildOptions opt;
                    opt.flags = kAllowUpdate | (rng.coin() ? VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR : 0);
                    opt.usePointers = rng.coin();
                    AccelStruct* blas = buildBlas({g0->geometry}, {g0->range}, opt);
                    checkBlas(blas, 60);
                    // Deformed vertices, a new transform, another firstVertex (allowed to change since 1.3.289).
                    VkTransformMatrixKHR t1 = randomTransform(rng, 0.5f, 2.0f, rng.coin(), 3.0f);
                    auto g1 = makeFormatted(deform(m, rng, 0.25f), format, it, VK_GEOMETRY_OPAQUE_BIT_KHR,
                                            transformed ? &t1 : nullptr, 7);
                    AccelStruct* out = updateBlas(blas, inPlace ? blas : nullptr, {g1->geometry}, {g1->range}, opt);
                    checkBlas(out, 100);
                    // A second update, from the refitted structure.
                    auto g2 = makeFormatted(deform(m, rng, 0.25f), format, it, VK_GEOMETRY_OPAQUE_BIT_KHR,
                                            transformed ? &t0 : nullptr, 0);
                    AccelStruct* out2 = updateBlas(out, inPlace ? out : nullptr, {g2->geometry}, {g2->range}, opt);
                    checkBlas(out2, 100);
                    if (HasFailure()) return;
                }
}

// Several geometries, large moves (the refitted tree is poor but exact), inactive triangles staying inactive.
TEST_F(update, triangles_many_geometries_and_inactive) {
    for (int round = 0; round < 4; ++round) {
        std::vector<Mesh> meshes;
        std::vector<std::unique_ptr<GeometryData>> data;
        std::vector<const GeometryData*> ptrs;
        const int geometries = 1 + int(rng.below(5));
        for (int g = 0; g < geometries; ++g) {
            Mesh m = triangleSoup(50 + int(rng.below(300)), rng, 0.4f);
            for (size_t i = 0; i < m.indices.size(); i += 3)  // some inactive triangles (NaN X in one vertex)
                if (rng.coin(0.05)) {
                    m.positions.push_back({kNaN, 0, 0});
                    m.indices[i + rng.below(3)] = uint32_t(m.positions.size() - 1);
                }
            meshes.push_back(m);
            data.push_back(makeGeometry(m, rng.coin() ? VK_INDEX_TYPE_UINT32 : VK_INDEX_TYPE_UINT16,
                                        rng.coin() ? VK_GEOMETRY_OPAQUE_BIT_KHR : 0));
            ptrs.push_back(data.back().get());
        }
        BuildOptions opt;
        opt.flags = kAllowUpdate;
        AccelStruct* blas = buildBlas(ptrs, opt);
        std::vector<VkAccelerationStructureGeometryKHR> geoms;
        std::vector<VkAccelerationStructureBuildRangeInfoKHR> ranges;
        std::vector<std::unique_ptr<GeometryData>> moved;
        for (int g = 0; g < geometries; ++g) {
            Mesh m = deform(meshes[g], rng, round < 2 ? 0.1f : 2.0f);  // NaN stays NaN
            moved.push_back(makeGeometry(m, data[g]->geometry.geometry.triangles.indexType, data[g]->geometry.flags));
            geoms.push_back(moved.back()->geometry);
            ranges.push_back(moved.back()->range);
        }
        AccelStruct* out = updateBlas(blas, round % 2 ? blas : nullptr, geoms, ranges, opt);
        checkBlas(out, 200);
        if (HasFailure()) return;
    }
}

// CTS update.cpu.*.degenerate: a triangle collapsed to a point in the first build is hit once an update gives it
// area again, and missed again once an update collapses it.
TEST_F(update, degenerate_revival) {
    for (int inPlace = 0; inPlace < 2; ++inPlace) {
        Mesh m;
        m.positions = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {2, 2, 0}, {2, 2, 0}, {2, 2, 0}};
        m.indices = {0, 1, 2, 3, 4, 5};  // triangle 1 is a point at (2, 2, 0)
        auto g0 = makeGeometry(m, VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
        BuildOptions opt;
        opt.flags = kAllowUpdate;
        AccelStruct* blas = buildBlas(*g0, opt);
        oracle::Ray ray;
        ray.origin = {2.5f, 2.25f, 1.0f};
        ray.direction = {0, 0, -1};
        ray.tMax = 10;
        EXPECT_EQ(traceClosest(buildSingleInstanceTlas(blas), ray).type, 0u);
        Mesh real = m;
        real.positions[3] = {2, 2, 0}, real.positions[4] = {3, 2, 0}, real.positions[5] = {3, 3, 0};
        auto g1 = makeGeometry(real, VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
        AccelStruct* out = updateBlas(blas, inPlace ? blas : nullptr, {g1->geometry}, {g1->range}, opt);
        AccelStruct* tlas = buildSingleInstanceTlas(out);
        const Hit h = traceClosest(tlas, ray);
        EXPECT_EQ(h.type, 1u);
        EXPECT_EQ(h.primitiveIndex, 1);
        checkRays(tlas, targetedRays(*tlas->scene, 50));
        // Collapsed again (to a line this time): never hit.
        Mesh line = m;
        line.positions[3] = {2, 2, 0}, line.positions[4] = {3, 3, 0}, line.positions[5] = {2.5f, 2.5f, 0};
        auto g2 = makeGeometry(line, VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
        AccelStruct* out2 = updateBlas(out, inPlace ? out : nullptr, {g2->geometry}, {g2->range}, opt);
        AccelStruct* tlas2 = buildSingleInstanceTlas(out2);
        EXPECT_EQ(traceClosest(tlas2, ray).type, 0u);
        checkRays(tlas2, randomRays(*tlas2->scene, 50));
    }
}

// An update with the build's own inputs gives the build's bytes (the node boxes are the same min/max of the same
// record boxes; only the sign of a zero coordinate could differ, and no box test can tell it) and traces
// identically.
TEST_F(update, unchanged_inputs_trace_identically) {
    Mesh m = icosphere(3);
    auto g = makeGeometry(m, VK_INDEX_TYPE_UINT32, 0, nullptr);
    BuildOptions opt;
    opt.flags = kAllowUpdate;
    AccelStruct* blas = buildBlas(*g, opt);
    uint64_t used;
    std::memcpy(&used, blas->data() + 16, 8);
    const std::vector<uint8_t> before(blas->data(), blas->data() + used);
    AccelStruct* other = updateBlas(blas, nullptr, {g->geometry}, {g->range}, opt);
    auto sameStructure = [&](const uint8_t* a, const uint8_t* b) {
        for (uint64_t i = 0; i < used; i += 4) {
            if (std::memcmp(a + i, b + i, 4) == 0) continue;
            float fa, fb;
            std::memcpy(&fa, a + i, 4), std::memcpy(&fb, b + i, 4);
            if (fa == 0.0f && fb == 0.0f) continue;  // +0 against -0
            return ::testing::AssertionFailure() << "byte " << i << " differs";
        }
        return ::testing::AssertionSuccess();
    };
    EXPECT_TRUE(sameStructure(before.data(), other->data()));
    AccelStruct* self = updateBlas(blas, blas, {g->geometry}, {g->range}, opt);
    EXPECT_TRUE(sameStructure(before.data(), self->data()));
    // Traces identically: the two structures give bit-identical hits.
    AccelStruct* t1 = buildSingleInstanceTlas(other);
    AccelStruct* t2 = buildSingleInstanceTlas(self);
    for (const auto& ray : randomRays(*t1->scene, 300)) {
        const Hit a = traceClosest(t1, ray), b = traceClosest(t2, ray);
        EXPECT_TRUE(identical(a, b)) << a.str() << " vs " << b.str();
    }
    checkRays(t1, targetedRays(*t1->scene, 100));
}

// CTS update.cpu.compact.*: an update of a compacted structure (a byte copy of [0, usedSize)).
TEST_F(update, compacted_source) {
    Mesh m = terrain(24, rng);
    auto g0 = makeGeometry(m, VK_INDEX_TYPE_UINT16, VK_GEOMETRY_OPAQUE_BIT_KHR);
    BuildOptions opt;
    opt.flags = kAllowUpdate | VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR;
    AccelStruct* blas = buildBlas(*g0, opt);
    AccelStruct* compact = compactCopy(blas);
    Mesh moved = deform(m, rng, 0.3f);
    auto g1 = makeGeometry(moved, VK_INDEX_TYPE_UINT16, VK_GEOMETRY_OPAQUE_BIT_KHR);
    // In place, and into another structure of the compacted size.
    AccelStruct* other = createAccelStruct(compact->type, compact->size, {});
    AccelStruct* out = updateBlas(compact, other, {g1->geometry}, {g1->range}, opt);
    checkBlas(out);
    AccelStruct* self = updateBlas(compact, compact, {g1->geometry}, {g1->range}, opt);
    checkBlas(self);
}

// AABBs: moved and resized boxes, inactive boxes staying inactive.
TEST_F(update, aabbs) {
    for (int round = 0; round < 6; ++round) {
        std::vector<VkAabbPositionsKHR> boxes = randomBoxes(rng, 20 + rng.below(400), 2.0f, 0.1);
        const auto g0 = aabbGeometry(boxes, rng.coin() ? VK_GEOMETRY_OPAQUE_BIT_KHR : 0);
        VkAccelerationStructureBuildRangeInfoKHR r{};
        r.primitiveCount = uint32_t(boxes.size());
        BuildOptions opt;
        opt.flags = kAllowUpdate;
        AccelStruct* blas = buildBlas({g0}, {r}, opt);
        std::vector<VkAabbPositionsKHR> moved = boxes;
        for (auto& b : moved) {
            if (std::isnan(b.minX)) continue;
            const float d[3] = {rng.uniformf(-1, 1), rng.uniformf(-1, 1), rng.uniformf(-1, 1)};
            b.minX += d[0], b.maxX += d[0] + rng.uniformf(0, 0.3f);
            b.minY += d[1], b.maxY += d[1];
            b.minZ += d[2], b.maxZ += d[2];
        }
        const auto g1 = aabbGeometry(moved, g0.flags);
        AccelStruct* out = updateBlas(blas, round % 2 ? blas : nullptr, {g1}, {r}, opt);
        checkBlas(out, 200);
        if (HasFailure()) return;
    }
}

// ---- top level (CTS instance_update) ------------------------------------------------------------------------------

// New transforms, masks, custom indices, SBT offsets, flags and referenced bottom levels; inactive instances stay
// inactive. In place and into a fresh structure.
TEST_F(update, instance_update) {
    Mesh sphere = icosphere(2), knot = torusKnot(64, 8);
    auto ga = makeGeometry(sphere, VK_INDEX_TYPE_UINT16, VK_GEOMETRY_OPAQUE_BIT_KHR);
    auto gb = makeGeometry(knot, VK_INDEX_TYPE_UINT32, 0);
    std::vector<VkAabbPositionsKHR> boxes = randomBoxes(rng, 30, 1.0f, 0.0);
    const auto gc = aabbGeometry(boxes, VK_GEOMETRY_OPAQUE_BIT_KHR);
    VkAccelerationStructureBuildRangeInfoKHR rc{};
    rc.primitiveCount = uint32_t(boxes.size());
    AccelStruct* blases[3] = {buildBlas(*ga), buildBlas(*gb), buildBlas({gc}, {rc})};
    auto randomInstance = [&](Instance& in) {
        in.transform = randomTransform(rng, 0.3f, 1.5f, rng.coin(0.2), 8.0f);
        in.customIndex = rng.u32() & 0xFFFFFF;
        in.mask = rng.coin(0.8) ? 0xFF : rng.u32() & 0xFF;
        in.sbtOffset = rng.u32() & 0xFFFFFF;
        in.flags = (rng.u32() & 0x3) | (rng.coin() ? (rng.coin() ? 0x4 : 0x8) : 0);  // never FORCE_OPAQUE and NO_OPAQUE
        in.blas = blases[rng.below(3)];
    };
    for (int round = 0; round < 6; ++round) {
        const size_t n = 1 + rng.below(60);
        std::vector<Instance> instances(n);
        for (auto& in : instances) {
            randomInstance(in);
            if (rng.coin(0.1)) in.blas = nullptr;  // inactive
        }
        BuildOptions opt;
        opt.flags = kAllowUpdate;
        opt.usePointers = rng.coin();
        AccelStruct* tlas = buildTlas(instances, opt);
        for (auto& in : instances)
            if (in.blas) randomInstance(in);
        AccelStruct* out = updateTlas(tlas, round % 2 ? tlas : nullptr, instances, opt);
        checkRays(out, randomRays(*out->scene, 150));
        checkRays(out, targetedRays(*out->scene, 150));
        checkRays(out, randomRays(*out->scene, 100), 0, 0x0F);
        if (HasFailure()) return;
    }
}

// CTS instance_update.update_in_place then copy: the refitted structure copied (CLONE) traces like the original.
TEST_F(update, instance_update_then_copy) {
    auto g = makeGeometry(icosphere(2), VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
    AccelStruct* blas = buildBlas(*g);
    std::vector<Instance> instances(8);
    for (auto& in : instances) in.transform = randomTransform(rng, 0.5f, 1.0f, false, 5.0f), in.blas = blas;
    BuildOptions opt;
    opt.flags = kAllowUpdate | VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR;
    AccelStruct* tlas = buildTlas(instances, opt);
    for (auto& in : instances) in.transform = randomTransform(rng, 0.5f, 1.0f, false, 5.0f);
    updateTlas(tlas, tlas, instances, opt);
    AccelStruct* copy = createAccelStruct(tlas->type, tlas->size, {});
    VkCopyAccelerationStructureInfoKHR ci{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_INFO_KHR};
    ci.src = tlas->handle;
    ci.dst = copy->handle;
    ci.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_CLONE_KHR;
    ASSERT_EQ(vk.vkCopyAccelerationStructureKHR(device, VK_NULL_HANDLE, &ci), VK_SUCCESS);
    copy->scene = tlas->scene;
    checkRays(copy, randomRays(*copy->scene, 200));
    // And a compacted copy of the TLAS updates again.
    AccelStruct* compact = compactCopy(tlas);
    for (auto& in : instances) in.transform = randomTransform(rng, 0.5f, 1.0f, false, 5.0f);
    AccelStruct* out = updateTlas(compact, compact, instances, opt);
    checkRays(out, randomRays(*out->scene, 200));
}

// A refitted bottom level, then the top level updated: the instance boxes follow the new bottom-level bounds.
TEST_F(update, blas_then_tlas) {
    Mesh m = icosphere(2);
    auto g0 = makeGeometry(m, VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
    BuildOptions opt;
    opt.flags = kAllowUpdate;
    AccelStruct* blas = buildBlas(*g0, opt);
    std::vector<Instance> instances(5);
    for (auto& in : instances) in.transform = randomTransform(rng, 0.5f, 1.0f, false, 4.0f), in.blas = blas;
    AccelStruct* tlas = buildTlas(instances, opt);
    Mesh big = m;
    for (auto& p : big.positions)
        for (float& c : p) c *= 2.5f;
    auto g1 = makeGeometry(big, VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
    updateBlas(blas, blas, {g1->geometry}, {g1->range}, opt);
    AccelStruct* out = updateTlas(tlas, tlas, instances, opt);
    checkRays(out, targetedRays(*out->scene, 200));
    checkRays(out, randomRays(*out->scene, 200));
}

// ---- refit cost ---------------------------------------------------------------------------------------------------

// 2^20 triangles: a refit costs a small fraction of a build (printed; docs/PERFORMANCE.md "Refit").
TEST_F(update, refit_cost_1m_triangles) {
    const int n = 512;  // 512 x 1024 quads = 2^20 triangles
    Mesh m = grid(n, 2 * n);
    for (auto& p : m.positions) p[2] = 0.1f * std::sin(p[0] * 0.3f) * std::cos(p[1] * 0.2f);
    auto g0 = makeGeometry(m, VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
    ASSERT_EQ(g0->range.primitiveCount, 1u << 20);
    BuildOptions opt;
    opt.flags = kAllowUpdate;
    auto pb = prepareBlas({g0.get()}, opt);
    auto t0 = std::chrono::steady_clock::now();
    submit({pb.get()});
    const double build = seconds(t0);
    AccelStruct* blas = pb->as;
    Mesh moved = m;
    for (auto& p : moved.positions) p[2] += 0.05f * std::sin(p[0] * 0.7f + p[1]);
    auto g1 = makeGeometry(moved, VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
    auto pu = prepareBlas({g1.get()}, opt);
    t0 = std::chrono::steady_clock::now();
    submitUpdate(*pu, blas, blas);
    const double refit = seconds(t0);
    std::cout << "  2^20 triangles: build " << build << " s, refit in place " << refit << " s (" << refit / build
              << " of a build), validation included" << std::endl;
    EXPECT_LT(refit, build * 0.5);
    AccelStruct* tlas = buildSingleInstanceTlas(blas);
    for (int k = 0; k < 200; ++k) {
        oracle::Ray r;
        r.origin = {rng.uniformf(1, float(n) - 1), rng.uniformf(1, float(2 * n) - 1), 1.0f};
        r.direction = {0, 0, -1};
        r.tMax = 10;
        const Hit h = traceClosest(tlas, r);
        ASSERT_EQ(h.type, 1u);
    }
}

// ---- valid usage ----------------------------------------------------------------------------------------------------

class update_validation : public update {
  protected:
    struct Fixture {
        Mesh mesh;
        std::unique_ptr<GeometryData> data;
        AccelStruct* blas = nullptr;
        BuildOptions opt;
    };
    Fixture makeFixture(VkBuildAccelerationStructureFlagsKHR flags = kAllowUpdate, bool transform = false) {
        Fixture f;
        f.mesh = triangleSoup(40, rng, 0.3f);
        f.mesh.positions.push_back({kNaN, 0, 0});  // triangle 0 is inactive
        f.mesh.indices[0] = uint32_t(f.mesh.positions.size() - 1);
        const VkTransformMatrixKHR t = identityTransform();
        f.data = makeGeometry(f.mesh, VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR, transform ? &t : nullptr);
        f.opt.flags = flags;
        f.blas = buildBlas(*f.data, f.opt);
        return f;
    }
    // Runs one UPDATE (src into dst) and returns the validation messages; checks that dst was not written.
    std::vector<std::string> tryUpdate(VkAccelerationStructureKHR src, AccelStruct* dst,
                                       VkAccelerationStructureBuildGeometryInfoKHR info,
                                       const std::vector<VkAccelerationStructureBuildRangeInfoKHR>& ranges) {
        EXPECT_TRUE(takeValidationErrors().empty());
        info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR;
        info.srcAccelerationStructure = src;
        info.dstAccelerationStructure = dst->handle;
        info.scratchData.hostAddress = nullptr;
        const std::vector<uint8_t> before(dst->buffer->mapped, dst->buffer->mapped + dst->buffer->size);
        const VkAccelerationStructureBuildRangeInfoKHR* r = ranges.data();
        EXPECT_EQ(vk.vkBuildAccelerationStructuresKHR(device, VK_NULL_HANDLE, 1, &info, &r),
                  VK_ERROR_VALIDATION_FAILED_EXT);
        EXPECT_EQ(std::memcmp(before.data(), dst->buffer->mapped, before.size()), 0) << "dst was written";
        return takeValidationErrors();
    }
    VkAccelerationStructureBuildGeometryInfoKHR blasInfo(const std::vector<VkAccelerationStructureGeometryKHR>& g,
                                                         VkBuildAccelerationStructureFlagsKHR flags) {
        VkAccelerationStructureBuildGeometryInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
        info.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
        info.flags = flags;
        info.geometryCount = uint32_t(g.size());
        info.pGeometries = g.data();
        return info;
    }
    static bool only(const std::vector<std::string>& errors, const char* vuid) {
        return errors.size() == 1 && errors[0].find(vuid) != std::string::npos;
    }
};

#define EXPECT_ONLY(errors, vuid)                                                       \
    do {                                                                                \
        const auto e_ = (errors);                                                       \
        EXPECT_TRUE(only(e_, vuid)) << vuid << ": got " << e_.size() << " messages"     \
                                    << (e_.empty() ? std::string() : ": " + e_[0]);     \
    } while (0)

TEST_F(update_validation, source) {
    Fixture f = makeFixture();
    std::vector<VkAccelerationStructureGeometryKHR> g{f.data->geometry};
    const auto info = blasInfo(g, f.opt.flags);
    AccelStruct* dst = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, f.blas->size, {});
    EXPECT_ONLY(tryUpdate(VK_NULL_HANDLE, dst, info, {f.data->range}), "VUID-vkBuildAccelerationStructuresKHR-pInfos-04630");
    AccelStruct* dead = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, 4096, {});
    const VkAccelerationStructureKHR deadHandle = dead->handle;
    destroyAccelStruct(dead);
    EXPECT_ONLY(tryUpdate(deadHandle, dst, info, {f.data->range}),
                "VUID-vkBuildAccelerationStructuresKHR-srcAccelerationStructure-04629");
    {
        // A structure whose buffer has no memory: create it by hand.
        HostBuffer* b = createBuffer(f.blas->size, kAsBufferUsage, false);
        VkAccelerationStructureCreateInfoKHR ci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
        ci.buffer = b->buffer;
        ci.size = f.blas->size;
        ci.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
        VkAccelerationStructureKHR h;
        ASSERT_EQ(vk.vkCreateAccelerationStructureKHR(device, &ci, nullptr, &h), VK_SUCCESS);
        EXPECT_ONLY(tryUpdate(h, dst, info, {f.data->range}), "VUID-vkBuildAccelerationStructuresKHR-pInfos-03708");
        vk.vkDestroyAccelerationStructureKHR(device, h, nullptr);
    }
    AccelStruct* unbuilt = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, f.blas->size, {});
    EXPECT_ONLY(tryUpdate(unbuilt->handle, dst, info, {f.data->range}),
                "VUID-vkBuildAccelerationStructuresKHR-pInfos-03667");
    Fixture noUpdate = makeFixture(0);
    EXPECT_ONLY(tryUpdate(noUpdate.blas->handle, dst, blasInfo(g, 0), {f.data->range}),
                "VUID-vkBuildAccelerationStructuresKHR-pInfos-03667");
    // dst too small for the source's usedSize (and for a build).
    AccelStruct* tiny = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, 256, {});
    EXPECT_ONLY(tryUpdate(f.blas->handle, tiny, info, {f.data->range}),
                "VUID-vkBuildAccelerationStructuresKHR-pInfos-10126");
}

TEST_F(update_validation, aliasing) {
    Fixture f = makeFixture();
    std::vector<VkAccelerationStructureGeometryKHR> g{f.data->geometry};
    // A second structure over the second half of the source's buffer range: src != dst, memory overlaps.
    const VkDeviceSize size = f.blas->size;
    HostBuffer* b = createBuffer(2 * size + 512);
    VkAccelerationStructureCreateInfoKHR ci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
    ci.buffer = b->buffer;
    ci.size = size;
    ci.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
    VkAccelerationStructureKHR a, c;
    ASSERT_EQ(vk.vkCreateAccelerationStructureKHR(device, &ci, nullptr, &a), VK_SUCCESS);
    ci.offset = (size / 2 + 255) / 256 * 256;
    ASSERT_EQ(vk.vkCreateAccelerationStructureKHR(device, &ci, nullptr, &c), VK_SUCCESS);
    // Build into a.
    auto pb = prepareBlas({f.data.get()}, f.opt);
    pb->info.dstAccelerationStructure = a;
    const VkAccelerationStructureBuildRangeInfoKHR* r = pb->ranges.data();
    ASSERT_EQ(vk.vkBuildAccelerationStructuresKHR(device, VK_NULL_HANDLE, 1, &pb->info, &r), VK_SUCCESS);
    AccelStruct view;
    view.handle = c;
    view.buffer = b;
    view.offset = ci.offset;
    view.size = size;
    const auto errors = tryUpdate(a, &view, blasInfo(g, f.opt.flags), {f.data->range});
    EXPECT_ONLY(errors, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03668");
    vk.vkDestroyAccelerationStructureKHR(device, a, nullptr);
    vk.vkDestroyAccelerationStructureKHR(device, c, nullptr);
}

TEST_F(update_validation, must_match_last_build) {
    Fixture f = makeFixture();
    AccelStruct* dst = f.blas;  // in place: nothing may be written either
    const auto& base = f.data->geometry;
    auto expectOnly = [&](std::vector<VkAccelerationStructureGeometryKHR> g,
                          std::vector<VkAccelerationStructureBuildRangeInfoKHR> r,
                          VkBuildAccelerationStructureFlagsKHR flags, const char* vuid) {
        SCOPED_TRACE(vuid);
        EXPECT_ONLY(tryUpdate(f.blas->handle, dst, blasInfo(g, flags), r), vuid);
    };
    const auto range = f.data->range;
    // 03758 geometryCount.
    expectOnly({base, base}, {range, range}, f.opt.flags, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03758");
    // 03759 flags.
    expectOnly({base}, {range}, f.opt.flags | VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR,
               "VUID-vkBuildAccelerationStructuresKHR-pInfos-03759");
    // 03761 geometryType: AABBs instead of triangles, same count.
    std::vector<VkAabbPositionsKHR> boxes(range.primitiveCount, VkAabbPositionsKHR{0, 0, 0, 1, 1, 1});
    boxes[0].minX = kNaN;
    expectOnly({aabbGeometry(boxes, base.flags)}, {range}, f.opt.flags,
               "VUID-vkBuildAccelerationStructuresKHR-pInfos-03761");
    // 03762 geometry flags.
    {
        auto g = base;
        g.flags = 0;
        expectOnly({g}, {range}, f.opt.flags, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03762");
    }
    // 03763 vertexFormat: the same positions as R32G32B32A32_SFLOAT.
    auto wide = makeFormatted(f.mesh, VK_FORMAT_R32G32B32A32_SFLOAT, VK_INDEX_TYPE_UINT32, base.flags, nullptr);
    wide->geometry.geometry.triangles.maxVertex = base.geometry.triangles.maxVertex;
    expectOnly({wide->geometry}, {range}, f.opt.flags, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03763");
    // 03764 maxVertex.
    {
        auto g = base;
        g.geometry.triangles.maxVertex = base.geometry.triangles.maxVertex + 1;
        std::vector<uint8_t> more(f.data->vertices);
        more.resize(more.size() + 12, 0);
        g.geometry.triangles.vertexData.hostAddress = more.data();
        expectOnly({g}, {range}, f.opt.flags, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03764");
    }
    // 03765 indexType: the same index values as UINT16.
    auto narrow = makeFormatted(f.mesh, VK_FORMAT_R32G32B32_SFLOAT, VK_INDEX_TYPE_UINT16, base.flags, nullptr);
    narrow->geometry.geometry.triangles.maxVertex = base.geometry.triangles.maxVertex;
    expectOnly({narrow->geometry}, {range}, f.opt.flags, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03765");
    // 03766: a transform now, none in the build.
    {
        const VkTransformMatrixKHR t = identityTransform();
        auto g = base;
        g.geometry.triangles.transformData.hostAddress = &t;
        expectOnly({g}, {range}, f.opt.flags, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03766");
    }
    // 03767: no transform now, one in the build.
    {
        Fixture t = makeFixture(kAllowUpdate, true);
        auto g = t.data->geometry;
        g.geometry.triangles.transformData.hostAddress = nullptr;
        EXPECT_ONLY(tryUpdate(t.blas->handle, t.blas, blasInfo({g}, t.opt.flags), {t.data->range}),
                    "VUID-vkBuildAccelerationStructuresKHR-pInfos-03767");
    }
    // 03768: index values changed (triangle 1 names its corners in another order).
    {
        std::vector<uint8_t> idx(f.data->indices);
        uint32_t a, b;
        std::memcpy(&a, idx.data() + 12, 4), std::memcpy(&b, idx.data() + 16, 4);
        std::memcpy(idx.data() + 12, &b, 4), std::memcpy(idx.data() + 16, &a, 4);
        auto g = base;
        g.geometry.triangles.indexData.hostAddress = idx.data();
        expectOnly({g}, {range}, f.opt.flags, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03768");
    }
    // 03769 primitiveCount.
    {
        auto r = range;
        r.primitiveCount -= 1;
        expectOnly({base}, {r}, f.opt.flags, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03769");
    }
    // 03663: an active triangle made inactive.
    {
        std::vector<uint8_t> v(f.data->vertices);
        uint32_t i2;
        std::memcpy(&i2, f.data->indices.data() + 4 * 3 * 5, 4);  // a vertex of triangle 5
        std::memcpy(v.data() + 12 * i2, &kNaN, 4);
        auto g = base;
        g.geometry.triangles.vertexData.hostAddress = v.data();
        expectOnly({g}, {range}, f.opt.flags, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03663");
    }
    // 03664: the inactive triangle 0 made active.
    {
        std::vector<uint8_t> v(f.data->vertices);
        const float zero = 0.5f;
        std::memcpy(v.data() + 12 * (f.mesh.positions.size() - 1), &zero, 4);
        auto g = base;
        g.geometry.triangles.vertexData.hostAddress = v.data();
        expectOnly({g}, {range}, f.opt.flags, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03664");
    }
    // 03760 type: a top-level update of a bottom-level source (into a GENERIC destination).
    {
        auto blas = buildBlas(*f.data);
        Instance in;
        in.blas = blas;
        auto pb = prepareTlas({in}, {});
        BuildOptions generic;
        generic.createGeneric = true;
        AccelStruct* gdst = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, f.blas->size, generic);
        auto info = pb->info;
        info.flags = f.opt.flags;
        EXPECT_ONLY(tryUpdate(f.blas->handle, gdst, info, pb->ranges), "VUID-vkBuildAccelerationStructuresKHR-pInfos-03760");
    }
    // Still updatable after all that: nothing was written.
    checkBlas(f.blas, 50);
}

TEST_F(update_validation, instance_activity) {
    auto g = makeGeometry(icosphere(1), VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
    AccelStruct* blas = buildBlas(*g);
    std::vector<Instance> instances(4);
    for (auto& in : instances) in.blas = blas;
    instances[2].blas = nullptr;
    BuildOptions opt;
    opt.flags = kAllowUpdate;
    AccelStruct* tlas = buildTlas(instances, opt);
    {
        auto changed = instances;
        changed[1].blas = nullptr;
        auto pb = prepareTlas(changed, opt);
        EXPECT_ONLY(tryUpdate(tlas->handle, tlas, pb->info, pb->ranges), "VUID-vkBuildAccelerationStructuresKHR-pInfos-03663");
    }
    {
        auto changed = instances;
        changed[2].blas = blas;
        auto pb = prepareTlas(changed, opt);
        EXPECT_ONLY(tryUpdate(tlas->handle, tlas, pb->info, pb->ranges), "VUID-vkBuildAccelerationStructuresKHR-pInfos-03664");
    }
    {
        auto changed = instances;
        changed.pop_back();
        auto pb = prepareTlas(changed, opt);
        EXPECT_ONLY(tryUpdate(tlas->handle, tlas, pb->info, pb->ranges), "VUID-vkBuildAccelerationStructuresKHR-pInfos-03769");
    }
    checkRays(tlas, randomRays(*tlas->scene, 50));
}

// Another element's destination overlapping an update's source (03701), and an update's source being another
// element's destination (03403).
TEST_F(update_validation, between_infos) {
    Fixture f = makeFixture();
    auto pb = prepareBlas({f.data.get()}, f.opt);  // a build into pb->as
    std::vector<VkAccelerationStructureGeometryKHR> g{f.data->geometry};
    VkAccelerationStructureBuildGeometryInfoKHR infos[2] = {blasInfo(g, f.opt.flags), pb->info};
    infos[0].mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR;
    infos[0].srcAccelerationStructure = f.blas->handle;
    infos[0].dstAccelerationStructure = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, f.blas->size, {})->handle;
    infos[1].dstAccelerationStructure = f.blas->handle;
    const VkAccelerationStructureBuildRangeInfoKHR* r[2] = {&f.data->range, &f.data->range};
    EXPECT_EQ(vk.vkBuildAccelerationStructuresKHR(device, VK_NULL_HANDLE, 2, infos, r), VK_ERROR_VALIDATION_FAILED_EXT);
    const auto errors = takeValidationErrors();
    ASSERT_EQ(errors.size(), 1u) << (errors.empty() ? "" : errors[0]);
    EXPECT_NE(errors[0].find("VUID-vkBuildAccelerationStructuresKHR-dstAccelerationStructure-03403"), std::string::npos);
}
