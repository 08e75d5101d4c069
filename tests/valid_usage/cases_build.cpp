// Valid-usage cases: vkBuildAccelerationStructuresKHR and the structures it takes (build infos, geometries, range
// infos, instances, updates), including the NV motion, sphere and LSS geometry.
#include <limits>

#include "harness.hpp"
#include "meshes.hpp"

namespace vu {

namespace {

#define CASE(id, ...) c.push_back(Case{id, "", [](Fixture& t, const vt::Commands& vk, VkDevice dev) __VA_ARGS__})
#define CASE_V(id, variant, ...) \
    c.push_back(Case{id, variant, [](Fixture& t, const vt::Commands& vk, VkDevice dev) __VA_ARGS__})
#define CASE_ALSO(id, also, ...) \
    c.push_back(Case{id, "", [](Fixture& t, const vt::Commands& vk, VkDevice dev) __VA_ARGS__, also})

using Pb = std::unique_ptr<vt::PreparedBuild>;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

vt::BuildOptions updatable() {
    vt::BuildOptions o;
    o.flags = VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR | VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR;
    return o;
}

vt::BuildOptions roomy() {  // a destination with room to spare, for cases whose sizes change with the rule broken
    vt::BuildOptions o;
    o.extraMaxPrimitives = 64;
    return o;
}

// Makes the one call of a build case.
void run(Fixture& t, vt::PreparedBuild& pb) {
    t.call([&] { return t.build(pb); });
}
void runAll(Fixture& t, const std::vector<vt::PreparedBuild*>& builds) {
    t.call([&] { return t.build(builds); });
}

// A second handle on the memory of `as` (aliasing structures).
VkAccelerationStructureKHR alias(Fixture& t, const vt::AccelStruct* as) {
    VkAccelerationStructureCreateInfoKHR ci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
    ci.buffer = as->buffer->buffer;
    ci.offset = as->offset;
    ci.size = as->size;
    ci.type = as->type;
    VkAccelerationStructureKHR handle = VK_NULL_HANDLE;
    EXPECT_EQ(t.vk.vkCreateAccelerationStructureKHR(t.device, &ci, nullptr, &handle), VK_SUCCESS);
    return handle;
}

VkAccelerationStructureGeometryTrianglesDataKHR& triangles(vt::PreparedBuild& pb, uint32_t g = 0) {
    return pb.geometries[g].geometry.triangles;
}

// Spheres (lss false) or linear swept spheres with 2 primitives, unindexed, R32G32B32 positions and R32 radii.
struct SphereInput {
    VkAccelerationStructureGeometrySpheresDataNV spheres{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_SPHERES_DATA_NV};
    VkAccelerationStructureGeometryLinearSweptSpheresDataNV lss{
        VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_LINEAR_SWEPT_SPHERES_DATA_NV};
};
Pb sphereBuild(Fixture& t, bool lss, const std::function<void(SphereInput&)>& edit = {}) {
    static const float positions[4][3] = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}};
    static const float radii[4] = {0.25f, 0.25f, 0.25f, 0.25f};
    static const uint32_t indices[4] = {0, 1, 2, 3};
    auto* in = t.hostObject(SphereInput{});
    auto fill = [&](auto& d) {
        d.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
        d.vertexData.hostAddress = positions;
        d.vertexStride = 12;
        d.radiusFormat = VK_FORMAT_R32_SFLOAT;
        d.radiusData.hostAddress = radii;
        d.radiusStride = 4;
        d.indexType = VK_INDEX_TYPE_NONE_KHR;
        d.indexStride = 4;
    };
    fill(in->spheres);
    fill(in->lss);
    (void)indices;
    VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
    g.geometryType = lss ? VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV : VK_GEOMETRY_TYPE_SPHERES_NV;
    g.pNext = lss ? static_cast<const void*>(&in->lss) : static_cast<const void*>(&in->spheres);
    VkAccelerationStructureBuildRangeInfoKHR r{};
    r.primitiveCount = 2;
    auto pb = t.prepareBlas(std::vector<VkAccelerationStructureGeometryKHR>{g},
                            std::vector<VkAccelerationStructureBuildRangeInfoKHR>{r}, roomy());
    t.watch(pb->scratch.data(), pb->scratch.size());
    if (edit) edit(*in);  // after the size query and the oracle's copy, which need valid data
    return pb;
}
const uint32_t* sphereIndices() {
    static const uint32_t indices[4] = {0, 1, 2, 3};
    return indices;
}

// The instance bytes of a top-level build (one VkAccelerationStructureInstanceKHR).
VkAccelerationStructureInstanceKHR* firstInstance(vt::PreparedBuild& pb) {
    return reinterpret_cast<VkAccelerationStructureInstanceKHR*>(pb.instanceBytes.data());
}

// An update of blas whose triangle data the case edits (vertices, indices: copies of tri's).
struct UpdateInput {
    Pb pb;
    float* vertices;
    uint32_t* indices;
};
UpdateInput editableUpdate(Fixture& t) {
    UpdateInput u{t.updateBuild(), nullptr, nullptr};
    auto& tr = triangles(*u.pb);
    u.vertices = reinterpret_cast<float*>(t.hostCopy(t.tri->vertices.data(), t.tri->vertices.size()));
    u.indices = reinterpret_cast<uint32_t*>(t.hostCopy(t.tri->indices.data(), t.tri->indices.size()));
    tr.vertexData.hostAddress = u.vertices;
    tr.indexData.hostAddress = u.indices;
    return u;
}

}  // namespace

void addBuildCases(std::vector<Case>& c) {
    // ---- The command's own parameters ------------------------------------------------------------------------------
    CASE("VUID-vkBuildAccelerationStructuresKHR-device-parameter", {
        auto pb = t.triangleBuild();
        const VkAccelerationStructureBuildRangeInfoKHR* ranges = pb->ranges.data();
        t.call([&] {
            return R(vk.vkBuildAccelerationStructuresKHR(t.bogus<VkDevice>(), VK_NULL_HANDLE, 1, &pb->info, &ranges));
        });
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-deferredOperation-parameter", {
        auto pb = t.triangleBuild();
        t.call([&] { return t.build(*pb, t.bogus<VkDeferredOperationKHR>()); });
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-deferredOperation-parent", {
        auto pb = t.triangleBuild();
        VkDeferredOperationKHR foreign = t.otherOperation();
        t.call([&] { return t.build(*pb, foreign); });
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-deferredOperation-03678", {
        VkDeferredOperationKHR pending = t.pendingOperation();
        auto pb = t.triangleBuild();
        t.call([&] { return t.build(*pb, pending); });
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-infoCount-arraylength", {
        auto pb = t.triangleBuild();
        const VkAccelerationStructureBuildRangeInfoKHR* ranges = pb->ranges.data();
        t.call([&] { return R(vk.vkBuildAccelerationStructuresKHR(dev, VK_NULL_HANDLE, 0, &pb->info, &ranges)); });
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-parameter", {
        auto pb = t.triangleBuild();
        const VkAccelerationStructureBuildRangeInfoKHR* ranges = pb->ranges.data();
        t.call([&] { return R(vk.vkBuildAccelerationStructuresKHR(dev, VK_NULL_HANDLE, 1, nullptr, &ranges)); });
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-ppBuildRangeInfos-parameter", {
        auto pb = t.triangleBuild();
        t.call([&] { return R(vk.vkBuildAccelerationStructuresKHR(dev, VK_NULL_HANDLE, 1, &pb->info, nullptr)); });
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-11702", {
        auto pb = t.triangleBuild();
        const VkAccelerationStructureBuildRangeInfoKHR* ranges = nullptr;
        t.call([&] { return R(vk.vkBuildAccelerationStructuresKHR(dev, VK_NULL_HANDLE, 1, &pb->info, &ranges)); });
    });

    // ---- Between infos --------------------------------------------------------------------------------------------
    CASE("VUID-vkBuildAccelerationStructuresKHR-dstAccelerationStructure-03698", {
        auto a = t.triangleBuild(), b = t.triangleBuild();
        b->info.dstAccelerationStructure = a->info.dstAccelerationStructure;
        runAll(t, {a.get(), b.get()});
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-03403", {
        auto update = t.triangleBuild(updatable());  // an update of blas into a new structure
        update->info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR;
        update->info.srcAccelerationStructure = t.blas->handle;
        auto rebuild = t.triangleBuild();
        rebuild->info.dstAccelerationStructure = t.blas->handle;  // ... while another info writes blas
        runAll(t, {update.get(), rebuild.get()});
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-dstAccelerationStructure-03701", {
        auto update = t.triangleBuild(updatable());
        update->info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR;
        update->info.srcAccelerationStructure = t.blas->handle;
        auto rebuild = t.triangleBuild();
        rebuild->info.dstAccelerationStructure = alias(t, t.blas);  // another handle on blas's memory
        runAll(t, {update.get(), rebuild.get()});
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-dstAccelerationStructure-03702", {
        auto a = t.triangleBuild(), b = t.triangleBuild();
        b->info.dstAccelerationStructure = alias(t, a->as);
        runAll(t, {a.get(), b.get()});
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-dstAccelerationStructure-03703", {
        auto pb = t.triangleBuild();
        pb->info.scratchData.hostAddress = pb->as->data();
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE_V("VUID-vkBuildAccelerationStructuresKHR-dstAccelerationStructure-03703", "other_info", {
        auto a = t.triangleBuild(), b = t.triangleBuild();
        a->info.scratchData.hostAddress = b->as->data();
        runAll(t, {a.get(), b.get()});
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-scratchData-03704", {
        auto a = t.triangleBuild(), b = t.triangleBuild();
        b->info.scratchData = a->info.scratchData;
        runAll(t, {a.get(), b.get()});
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-scratchData-03705", {
        auto update = t.triangleBuild(updatable());
        update->info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR;
        update->info.srcAccelerationStructure = t.blas->handle;
        auto other = t.triangleBuild();
        other->info.scratchData.hostAddress = t.blas->data();  // scratch on the update's source
        runAll(t, {update.get(), other.get()});
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-None-03407", {
        auto bottom = t.triangleBuild();
        vt::Instance instance;
        instance.blas = bottom->as;  // the top level references what the other info builds
        t.blasRegistry[bottom->as->reference()] = bottom->blas;
        auto top = t.prepareTlas({instance});
        t.watch(top->scratch.data(), top->scratch.size());
        runAll(t, {bottom.get(), top.get()});
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-dstAccelerationStructure-03706", {
        auto bottom = t.triangleBuild();
        bottom->info.dstAccelerationStructure = alias(t, t.blas);  // writes the memory the instance reads
        auto top = t.instanceBuild();                                // references blas
        runAll(t, {bottom.get(), top.get()});
        (void)vk;
        (void)dev;
    });

    // ---- Per info: mode, destination --------------------------------------------------------------------------------
    CASE("VUID-vkBuildAccelerationStructuresKHR-mode-04628", {
        auto pb = t.triangleBuild();
        pb->info.mode = VkBuildAccelerationStructureModeKHR(7);
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-dstAccelerationStructure-03800", {
        auto pb = t.triangleBuild();
        pb->info.dstAccelerationStructure = t.bogus<VkAccelerationStructureKHR>();
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureBuildGeometryInfoKHR-commonparent", {
        auto pb = t.triangleBuild();
        pb->info.dstAccelerationStructure = t.otherStructure();
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE_V("VUID-VkAccelerationStructureBuildGeometryInfoKHR-commonparent", "update_source", {
        auto pb = t.triangleBuild(updatable());
        pb->info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR;
        pb->info.srcAccelerationStructure = t.otherStructure();
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-03707", {
        auto pb = t.triangleBuild();
        pb->info.dstAccelerationStructure = t.unbound->handle;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-03699", {
        auto pb = t.instanceBuild();
        pb->info.dstAccelerationStructure =
            t.createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, 65536, {})->handle;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-03700", {
        auto pb = t.triangleBuild();
        pb->info.dstAccelerationStructure =
            t.createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, 65536, {})->handle;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-10126", {
        auto pb = t.triangleBuild();
        pb->info.dstAccelerationStructure =
            t.createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, 256, {})->handle;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    // Found by the build fuzzer: with no geometries and no range array, the size check was skipped.
    CASE_V("VUID-vkBuildAccelerationStructuresKHR-pInfos-10126", "no_geometries_no_ranges", {
        auto pb = t.triangleBuild();
        pb->info.geometryCount = 0;
        pb->info.pGeometries = nullptr;
        pb->info.ppGeometries = nullptr;
        pb->info.dstAccelerationStructure =
            t.createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, 128, {})->handle;
        t.call([&] {
            const VkAccelerationStructureBuildRangeInfoKHR* noRanges = nullptr;
            return R(vk.vkBuildAccelerationStructuresKHR(dev, VK_NULL_HANDLE, 1, &pb->info, &noRanges));
        });
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-12244", {
        auto pb = t.triangleBuild();
        pb->info.scratchData.hostAddress = nullptr;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });

    // ---- VkAccelerationStructureBuildGeometryInfoKHR ----------------------------------------------------------------
    CASE("VUID-VkAccelerationStructureBuildGeometryInfoKHR-sType-sType", {
        auto pb = t.triangleBuild();
        pb->info.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureBuildGeometryInfoKHR-pNext-pNext", {
        auto pb = t.triangleBuild();
        static VkBufferDeviceAddressInfo unrelated{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO};
        pb->info.pNext = &unrelated;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureBuildGeometryInfoKHR-flags-parameter", {
        auto pb = t.triangleBuild();
        pb->info.flags |= 0x200;  // ALLOW_DISPLACEMENT_MICROMAP_UPDATE_NV: its extension is not enabled
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureBuildGeometryInfoKHR-type-parameter", {
        auto pb = t.triangleBuild();
        pb->info.type = VkAccelerationStructureTypeKHR(5);
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureBuildGeometryInfoKHR-type-03654", {
        auto pb = t.triangleBuild();
        pb->info.type = VK_ACCELERATION_STRUCTURE_TYPE_GENERIC_KHR;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureBuildGeometryInfoKHR-flags-03796", {
        auto pb = t.triangleBuild();
        pb->info.flags = VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR |
                         VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE_ALSO("VUID-VkAccelerationStructureBuildGeometryInfoKHR-flags-04929",
              {"VUID-VkAccelerationStructureBuildGeometryInfoKHR-type-03654"}, {
                  vt::BuildOptions motion;
                  motion.createFlags = VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV;
                  auto pb = t.triangleBuild(motion);
                  pb->info.type = VK_ACCELERATION_STRUCTURE_TYPE_GENERIC_KHR;
                  pb->info.flags = VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV;
                  run(t, *pb);
                  (void)vk;
                  (void)dev;
              });
    CASE("VUID-VkAccelerationStructureBuildGeometryInfoKHR-pGeometries-03788", {
        auto pb = t.triangleBuild();
        pb->info.ppGeometries = pb->geometryPointers.data();
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureBuildGeometryInfoKHR-ppGeometries-parameter", {
        auto pb = t.triangleBuild();
        static const VkAccelerationStructureGeometryKHR* const none[1] = {nullptr};
        pb->info.pGeometries = nullptr;
        pb->info.ppGeometries = none;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureBuildGeometryInfoKHR-type-03790", {
        auto pb = t.instanceBuild(roomy());
        pb->geometries.push_back(pb->geometries[0]);
        pb->ranges.push_back(pb->ranges[0]);
        pb->info.geometryCount = 2;
        pb->info.pGeometries = pb->geometries.data();
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureBuildGeometryInfoKHR-type-03793", {
        auto pb = t.triangleBuild();
        pb->info.geometryCount = 1u << 24;  // maxGeometryCount is 2^24 - 1; vkas must not read past geometry 0
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureBuildGeometryInfoKHR-type-03789", {
        auto pb = t.instanceBuild(roomy());
        pb->geometries[0] = t.tri->geometry;
        pb->ranges[0] = t.tri->range;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureBuildGeometryInfoKHR-type-03791", {
        auto pb = t.triangleBuild();
        auto top = t.instanceBuild();
        pb->geometries[0] = top->geometries[0];
        pb->ranges[0] = top->ranges[0];
        t.call([&] { return t.build(*pb); });
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureBuildGeometryInfoKHR-type-03792", {
        auto boxes = t.aabbBuild();
        std::vector<VkAccelerationStructureGeometryKHR> g{t.tri->geometry, t.tri->geometry};
        std::vector<VkAccelerationStructureBuildRangeInfoKHR> r{t.tri->range, t.tri->range};
        auto pb = t.prepareBlas(g, r, roomy());
        t.watch(pb->scratch.data(), pb->scratch.size());
        pb->geometries[1] = boxes->geometries[0];  // triangles and AABBs in one bottom level
        pb->ranges[1] = boxes->ranges[0];
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureBuildGeometryInfoKHR-type-03794", {
        auto pb = t.aabbBuild();
        pb->ranges[0].primitiveCount = 1u << 29;  // maxPrimitiveCount is 2^29 - 1; nothing may be read
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureBuildGeometryInfoKHR-type-03795", {
        auto pb = t.triangleBuild();
        pb->ranges[0].primitiveCount = 1u << 29;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureBuildGeometryInfoKHR-dstAccelerationStructure-04927", {
        vt::BuildOptions motion;
        motion.createFlags = VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV;
        auto pb = t.triangleBuild(motion);  // created with CREATE_MOTION, built without MOTION_BIT
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureBuildGeometryInfoKHR-flags-04928", {
        auto pb = t.triangleBuild(roomy());
        pb->info.flags = VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureCreateInfoKHR-createFlags-04955", {
        auto pb = t.triangleBuild(roomy());
        auto* motionData = t.hostObject(VkAccelerationStructureGeometryMotionTrianglesDataNV{
            VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_MOTION_TRIANGLES_DATA_NV});
        motionData->vertexData.hostAddress = t.tri->vertices.data();
        triangles(*pb).pNext = motionData;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });

    // ---- VkAccelerationStructureGeometryKHR -------------------------------------------------------------------------
    CASE("VUID-VkAccelerationStructureGeometryKHR-sType-sType", {
        auto pb = t.triangleBuild();
        pb->geometries[0].sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureGeometryKHR-pNext-pNext", {
        auto pb = t.triangleBuild();
        static VkBufferDeviceAddressInfo unrelated{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO};
        pb->geometries[0].pNext = &unrelated;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE_V("VUID-VkAccelerationStructureGeometryKHR-pNext-pNext", "spheres_without_data", {
        auto pb = sphereBuild(t, false);
        pb->geometries[0].pNext = nullptr;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureGeometryKHR-sType-unique", {
        auto pb = t.triangleBuild();
        auto* second = t.hostObject(VkAccelerationStructureGeometrySpheresDataNV{
            VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_SPHERES_DATA_NV});
        auto* first = t.hostObject(VkAccelerationStructureGeometrySpheresDataNV{
            VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_SPHERES_DATA_NV, second});
        pb->geometries[0].pNext = first;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureGeometryKHR-geometryType-parameter", {
        auto pb = t.triangleBuild();
        pb->geometries[0].geometryType = VkGeometryTypeKHR(99);
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureGeometryKHR-flags-parameter", {
        auto pb = t.triangleBuild();
        pb->geometries[0].flags = 0x80;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });

    // ---- Triangles ---------------------------------------------------------------------------------------------------
    CASE("VUID-VkAccelerationStructureGeometryTrianglesDataKHR-sType-sType", {
        auto pb = t.triangleBuild();
        triangles(*pb).sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureGeometryTrianglesDataKHR-pNext-pNext", {
        auto pb = t.triangleBuild();
        static VkBufferDeviceAddressInfo unrelated{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO};
        triangles(*pb).pNext = &unrelated;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureGeometryTrianglesDataKHR-sType-unique", {
        vt::BuildOptions motion;
        motion.createFlags = VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV;
        motion.flags = VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV;
        motion.extraMaxPrimitives = 64;
        auto pb = t.triangleBuild(motion);
        auto* second = t.hostObject(VkAccelerationStructureGeometryMotionTrianglesDataNV{
            VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_MOTION_TRIANGLES_DATA_NV});
        second->vertexData.hostAddress = t.tri->vertices.data();
        auto* first = t.hostObject(VkAccelerationStructureGeometryMotionTrianglesDataNV{
            VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_MOTION_TRIANGLES_DATA_NV, second});
        first->vertexData.hostAddress = t.tri->vertices.data();
        triangles(*pb).pNext = first;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-11820", {
        vt::BuildOptions motion;
        motion.createFlags = VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV;
        motion.flags = VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV;
        motion.extraMaxPrimitives = 64;
        auto pb = t.triangleBuild(motion);
        auto* motionData = t.hostObject(VkAccelerationStructureGeometryMotionTrianglesDataNV{
            VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_MOTION_TRIANGLES_DATA_NV});
        triangles(*pb).pNext = motionData;  // vertexData.hostAddress NULL
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureGeometryTrianglesDataKHR-vertexFormat-parameter", {
        auto pb = t.triangleBuild();
        triangles(*pb).vertexFormat = VkFormat(999999);
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureGeometryTrianglesDataKHR-vertexFormat-03797", {
        auto pb = t.triangleBuild();
        triangles(*pb).vertexFormat = VK_FORMAT_R8G8B8A8_UINT;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureGeometryTrianglesDataKHR-vertexStride-03735", {
        auto pb = t.triangleBuild();
        triangles(*pb).vertexStride = 14;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureGeometryTrianglesDataKHR-vertexStride-03819", {
        auto pb = t.triangleBuild();
        triangles(*pb).vertexStride = (1ull << 32) + 4;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureGeometryTrianglesDataKHR-indexType-parameter", {
        auto pb = t.triangleBuild();
        triangles(*pb).indexType = VkIndexType(12345);
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureGeometryTrianglesDataKHR-indexType-03798", {
        auto pb = t.triangleBuild();
        triangles(*pb).indexType = VkIndexType(1000265000);  // VK_INDEX_TYPE_UINT8
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-03771", {
        auto pb = t.triangleBuild();
        triangles(*pb).vertexData.hostAddress = nullptr;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-03772", {
        auto pb = t.triangleBuild();
        triangles(*pb).indexData.hostAddress = nullptr;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureBuildRangeInfoKHR-primitiveOffset-03656", {
        auto pb = t.triangleBuild();
        pb->ranges[0].primitiveOffset = 2;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureBuildRangeInfoKHR-primitiveOffset-03657", {
        auto pb = t.plainTriangleBuild();
        pb->ranges[0].primitiveOffset = 2;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureBuildRangeInfoKHR-transformOffset-03658", {
        auto pb = t.triangleBuild();
        triangles(*pb).transformData.hostAddress = t.hostObject(vt::identityTransform());
        pb->ranges[0].transformOffset = 8;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureBuildRangeInfoKHR-None-10775", {
        auto pb = t.plainTriangleBuild();
        triangles(*pb).maxVertex = 4;  // 6 vertices are read
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureBuildRangeInfoKHR-maxVertex-10774", {
        auto pb = t.triangleBuild();
        triangles(*pb).maxVertex = 2;  // the indices go up to 3
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkTransformMatrixKHR-matrix-03799", {
        auto pb = t.triangleBuild();
        VkTransformMatrixKHR flat = vt::identityTransform();
        flat.matrix[2][2] = 0.0f;  // squashes z: not invertible
        triangles(*pb).transformData.hostAddress = t.hostObject(flat);
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE_V("VUID-VkTransformMatrixKHR-matrix-03799", "instance", {
        auto pb = t.instanceBuild();
        std::memset(firstInstance(*pb)->transform.matrix, 0, sizeof(VkTransformMatrixKHR));
        run(t, *pb);
        (void)vk;
        (void)dev;
    });

    // ---- AABBs -----------------------------------------------------------------------------------------------------
    CASE("VUID-VkAccelerationStructureGeometryAabbsDataKHR-sType-sType", {
        auto pb = t.aabbBuild();
        pb->geometries[0].geometry.aabbs.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureGeometryAabbsDataKHR-pNext-pNext", {
        auto pb = t.aabbBuild();
        static VkBufferDeviceAddressInfo unrelated{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO};
        pb->geometries[0].geometry.aabbs.pNext = &unrelated;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureGeometryAabbsDataKHR-stride-03545", {
        auto pb = t.aabbBuild();
        pb->geometries[0].geometry.aabbs.stride = 12;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureGeometryAabbsDataKHR-stride-03820", {
        auto pb = t.aabbBuild();
        pb->geometries[0].geometry.aabbs.stride = (1ull << 32) + 8;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureBuildRangeInfoKHR-primitiveOffset-03659", {
        auto pb = t.aabbBuild();
        pb->ranges[0].primitiveOffset = 4;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-03774", {
        auto pb = t.aabbBuild();
        pb->geometries[0].geometry.aabbs.data.hostAddress = nullptr;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAabbPositionsKHR-minX-03546", {
        auto pb = t.aabbBuild();
        pb->geometries[0].geometry.aabbs.data.hostAddress = t.hostObject(VkAabbPositionsKHR{2, 0, 0, 1, 1, 1});
        pb->ranges[0].primitiveCount = 1;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAabbPositionsKHR-minY-03547", {
        auto pb = t.aabbBuild();
        pb->geometries[0].geometry.aabbs.data.hostAddress = t.hostObject(VkAabbPositionsKHR{0, 2, 0, 1, 1, 1});
        pb->ranges[0].primitiveCount = 1;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAabbPositionsKHR-minZ-03548", {
        auto pb = t.aabbBuild();
        pb->geometries[0].geometry.aabbs.data.hostAddress = t.hostObject(VkAabbPositionsKHR{0, 0, 2, 1, 1, 1});
        pb->ranges[0].primitiveCount = 1;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });

    // ---- Instances ---------------------------------------------------------------------------------------------------
    CASE("VUID-VkAccelerationStructureGeometryInstancesDataKHR-sType-sType", {
        auto pb = t.instanceBuild();
        pb->geometries[0].geometry.instances.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureGeometryInstancesDataKHR-pNext-pNext", {
        auto pb = t.instanceBuild();
        static VkBufferDeviceAddressInfo unrelated{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO};
        pb->geometries[0].geometry.instances.pNext = &unrelated;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureBuildRangeInfoKHR-primitiveOffset-03660", {
        auto pb = t.instanceBuild();
        pb->ranges[0].primitiveOffset = 8;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-03801", {
        auto pb = t.instanceBuild();
        pb->ranges[0].primitiveCount = 1u << 24;  // maxInstanceCount is 2^24 - 1; nothing may be read
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-03778", {
        auto pb = t.instanceBuild();
        pb->geometries[0].geometry.instances.data.hostAddress = nullptr;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE_V("VUID-vkBuildAccelerationStructuresKHR-pInfos-03778", "null_pointer", {
        vt::BuildOptions pointers;
        pointers.usePointers = true;
        auto pb = t.instanceBuild(pointers);
        std::memset(pb->instancePointerBytes.data(), 0, 8);
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-03779", {
        auto pb = t.instanceBuild();
        firstInstance(*pb)->accelerationStructureReference = 0x123456789ull;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-03709", {
        auto pb = t.instanceBuild();
        firstInstance(*pb)->accelerationStructureReference = uint64_t(t.unbound->handle);
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureInstanceKHR-flags-parameter", {
        auto pb = t.instanceBuild();
        firstInstance(*pb)->flags = 0x40;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });

    // ---- Motion instances ------------------------------------------------------------------------------------------
    CASE("VUID-VkAccelerationStructureMotionInstanceNV-type-parameter", {
        auto pb = t.motionInstanceBuild({VK_ACCELERATION_STRUCTURE_MOTION_INSTANCE_TYPE_STATIC_NV},
                              [](auto& m) { m[0].type = VkAccelerationStructureMotionInstanceTypeNV(5); });
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureMotionInstanceNV-flags-zerobitmask", {
        auto pb = t.motionInstanceBuild({VK_ACCELERATION_STRUCTURE_MOTION_INSTANCE_TYPE_STATIC_NV},
                              [](auto& m) { m[0].flags = 1; });
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-04930", {
        auto pb = t.motionInstanceBuild({VK_ACCELERATION_STRUCTURE_MOTION_INSTANCE_TYPE_MATRIX_MOTION_NV}, [](auto& m) {
            m[0].data.matrixMotionInstance.accelerationStructureReference = 0x123456789ull;
        });
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE_V("VUID-VkAccelerationStructureInstanceKHR-flags-parameter", "static_motion", {
        auto pb = t.motionInstanceBuild({VK_ACCELERATION_STRUCTURE_MOTION_INSTANCE_TYPE_STATIC_NV},
                              [](auto& m) { m[0].data.staticInstance.flags = 0x80; });
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureMatrixMotionInstanceNV-flags-parameter", {
        auto pb = t.motionInstanceBuild({VK_ACCELERATION_STRUCTURE_MOTION_INSTANCE_TYPE_MATRIX_MOTION_NV},
                              [](auto& m) { m[0].data.matrixMotionInstance.flags = 0x80; });
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureSRTMotionInstanceNV-flags-parameter", {
        auto pb = t.motionInstanceBuild({VK_ACCELERATION_STRUCTURE_MOTION_INSTANCE_TYPE_SRT_MOTION_NV},
                              [](auto& m) { m[0].data.srtMotionInstance.flags = 0x80; });
        run(t, *pb);
        (void)vk;
        (void)dev;
    });

    // ---- Spheres and linear swept spheres ----------------------------------------------------------------------------
    struct SphereRule {
        const char* sphereVuid;
        const char* lssVuid;
        std::function<void(SphereInput&, bool lss)> edit;
    };
    static const std::vector<SphereRule> sphereRules = {
        {"VUID-VkAccelerationStructureGeometrySpheresDataNV-vertexStride-10431",
         "VUID-VkAccelerationStructureGeometryLinearSweptSpheresDataNV-vertexStride-10421",
         [](SphereInput& in, bool lss) { (lss ? in.lss.vertexStride : in.spheres.vertexStride) = 14; }},
        {"VUID-VkAccelerationStructureGeometrySpheresDataNV-vertexStride-10432",
         "VUID-VkAccelerationStructureGeometryLinearSweptSpheresDataNV-vertexStride-10422",
         [](SphereInput& in, bool lss) { (lss ? in.lss.radiusStride : in.spheres.radiusStride) = (1ull << 32) + 4; }},
        {"VUID-VkAccelerationStructureGeometrySpheresDataNV-vertexFormat-10434",
         "VUID-VkAccelerationStructureGeometryLinearSweptSpheresDataNV-vertexFormat-10423",
         [](SphereInput& in, bool lss) { (lss ? in.lss.vertexFormat : in.spheres.vertexFormat) = VK_FORMAT_R8_UINT; }},
        {"VUID-VkAccelerationStructureGeometrySpheresDataNV-radiusFormat-10435",
         "VUID-VkAccelerationStructureGeometryLinearSweptSpheresDataNV-radiusFormat-10424",
         [](SphereInput& in, bool lss) { (lss ? in.lss.radiusFormat : in.spheres.radiusFormat) = VK_FORMAT_R8_UINT; }},
        {"VUID-VkAccelerationStructureGeometrySpheresDataNV-radiusData-10436",
         "VUID-VkAccelerationStructureGeometryLinearSweptSpheresDataNV-radiusData-10426",
         [](SphereInput& in, bool lss) {
             static const float negative[4] = {0.25f, -1.0f, 0.25f, 0.25f};
             (lss ? in.lss.radiusData : in.spheres.radiusData).hostAddress = negative;
         }},
        {"VUID-VkAccelerationStructureGeometrySpheresDataNV-indexData-10437",
         "VUID-VkAccelerationStructureGeometryLinearSweptSpheresDataNV-indexData-10428",
         [](SphereInput& in, bool lss) {
             (lss ? in.lss.indexType : in.spheres.indexType) = VK_INDEX_TYPE_UINT8_EXT;
             (lss ? in.lss.indexData : in.spheres.indexData).hostAddress = sphereIndices();
         }},
        {"VUID-vkBuildAccelerationStructuresKHR-pInfos-11822", "VUID-vkBuildAccelerationStructuresKHR-pInfos-11826",
         [](SphereInput& in, bool lss) {
             (lss ? in.lss.indexData : in.spheres.indexData).hostAddress = sphereIndices();  // with indexType NONE
         }},
        {"VUID-vkBuildAccelerationStructuresKHR-pInfos-11823", "VUID-vkBuildAccelerationStructuresKHR-pInfos-11827",
         [](SphereInput& in, bool lss) { (lss ? in.lss.indexType : in.spheres.indexType) = VK_INDEX_TYPE_UINT32; }},
        {"VUID-vkBuildAccelerationStructuresKHR-pInfos-11824", "VUID-vkBuildAccelerationStructuresKHR-pInfos-11828",
         [](SphereInput& in, bool lss) { (lss ? in.lss.vertexData : in.spheres.vertexData).hostAddress = nullptr; }},
        {"VUID-vkBuildAccelerationStructuresKHR-pInfos-11825", "VUID-vkBuildAccelerationStructuresKHR-pInfos-11829",
         [](SphereInput& in, bool lss) { (lss ? in.lss.radiusData : in.spheres.radiusData).hostAddress = nullptr; }},
    };
    for (size_t i = 0; i < sphereRules.size(); ++i)
        for (bool lss : {false, true})
            c.push_back(Case{lss ? sphereRules[i].lssVuid : sphereRules[i].sphereVuid, "",
                             [i, lss](Fixture& t, const vt::Commands&, VkDevice) {
                                 auto pb = sphereBuild(t, lss, [&](SphereInput& in) { sphereRules[i].edit(in, lss); });
                                 run(t, *pb);
                             }});
    CASE("VUID-VkAccelerationStructureGeometryLinearSweptSpheresDataNV-indexingMode-parameter", {
        auto pb = sphereBuild(t, true, [](SphereInput& in) { in.lss.indexingMode = VkRayTracingLssIndexingModeNV(7); });
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureGeometryLinearSweptSpheresDataNV-endCapsMode-parameter", {
        auto pb = sphereBuild(t, true,
                              [](SphereInput& in) { in.lss.endCapsMode = VkRayTracingLssPrimitiveEndCapsModeNV(7); });
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-VkAccelerationStructureGeometryLinearSweptSpheresDataNV-indexingMode-10427", {
        auto pb = sphereBuild(t, true, [](SphereInput& in) {
            in.lss.indexingMode = VK_RAY_TRACING_LSS_INDEXING_MODE_SUCCESSIVE_NV;  // needs indices
        });
        run(t, *pb);
        (void)vk;
        (void)dev;
    });

    // ---- Updates -----------------------------------------------------------------------------------------------------
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-04630", {
        auto pb = t.updateBuild();
        pb->info.srcAccelerationStructure = VK_NULL_HANDLE;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-srcAccelerationStructure-04629", {
        auto pb = t.updateBuild();
        pb->info.srcAccelerationStructure = t.bogus<VkAccelerationStructureKHR>();
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-03708", {
        auto pb = t.triangleBuild(updatable());
        pb->info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR;
        pb->info.srcAccelerationStructure = t.unbound->handle;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-03667", {
        auto pb = t.triangleBuild(updatable());
        pb->info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR;
        pb->info.srcAccelerationStructure = t.plainBlas->handle;  // built without ALLOW_UPDATE
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE_V("VUID-vkBuildAccelerationStructuresKHR-pInfos-03667", "never_built", {
        auto pb = t.triangleBuild(updatable());
        pb->info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR;
        pb->info.srcAccelerationStructure = t.unbuilt->handle;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-03668", {
        auto pb = t.updateBuild();
        pb->info.dstAccelerationStructure = alias(t, t.blas);  // not blas, but on blas's memory
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-03760", {
        vt::BuildOptions generic = updatable();
        generic.createGeneric = true;
        auto pb = t.triangleBuild(generic);
        pb->info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR;
        pb->info.srcAccelerationStructure = t.tlas->handle;  // last built as a top level
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-03759", {
        auto pb = t.updateBuild();
        pb->info.flags = VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-03758", {
        auto pb = t.updateBuild();
        pb->geometries.push_back(pb->geometries[0]);
        pb->ranges.push_back(pb->ranges[0]);
        pb->info.geometryCount = 2;
        pb->info.pGeometries = pb->geometries.data();
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-03761", {
        auto pb = t.updateBuild();
        auto boxes = t.aabbBuild();
        pb->geometries[0] = boxes->geometries[0];
        pb->ranges[0] = boxes->ranges[0];
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-03762", {
        auto pb = t.updateBuild();
        pb->geometries[0].flags = VK_GEOMETRY_OPAQUE_BIT_KHR;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-primitiveCount-03769", {
        auto pb = t.updateBuild();
        pb->ranges[0].primitiveCount = 1;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-03763", {
        auto pb = t.updateBuild();
        triangles(*pb).vertexFormat = VK_FORMAT_R32G32B32A32_SFLOAT;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-03764", {
        auto pb = t.updateBuild();
        triangles(*pb).maxVertex = 10;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-03765", {
        auto pb = t.updateBuild();
        triangles(*pb).indexType = VK_INDEX_TYPE_UINT16;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-03766", {
        auto pb = t.updateBuild();
        triangles(*pb).transformData.hostAddress = t.hostObject(vt::identityTransform());
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-03767", {
        const VkTransformMatrixKHR identity = vt::identityTransform();
        auto transformed = vt::makeGeometry(vt::grid(1, 1), VK_INDEX_TYPE_UINT32, 0, &identity);
        vt::AccelStruct* src = t.buildBlas(*transformed, updatable());
        auto pb = t.prepareBlas(std::vector<const vt::GeometryData*>{transformed.get()}, updatable());
        t.watch(pb->scratch.data(), pb->scratch.size());
        pb->info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR;
        pb->info.srcAccelerationStructure = pb->info.dstAccelerationStructure = src->handle;
        triangles(*pb).transformData.hostAddress = nullptr;
        run(t, *pb);
        static std::unique_ptr<vt::GeometryData> keep;
        keep = std::move(transformed);  // the case's data outlives the call
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-03768", {
        auto u = editableUpdate(t);
        std::swap(u.indices[0], u.indices[1]);  // the same vertices, other index values
        run(t, *u.pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-03663", {
        auto u = editableUpdate(t);
        u.vertices[0] = kNaN;  // vertex 0's X: its triangles become inactive
        run(t, *u.pb);
        (void)vk;
        (void)dev;
    });
    CASE_V("VUID-vkBuildAccelerationStructuresKHR-pInfos-03663", "instance", {
        auto pb = t.updateBuild(/*top=*/true);
        firstInstance(*pb)->accelerationStructureReference = 0;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
    CASE("VUID-vkBuildAccelerationStructuresKHR-pInfos-03664", {
        // A structure built with an inactive triangle, updated with it active.
        auto* vertices = reinterpret_cast<float*>(t.hostCopy(t.tri->vertices.data(), t.tri->vertices.size()));
        vertices[0] = kNaN;
        VkAccelerationStructureGeometryKHR g = t.tri->geometry;
        g.geometry.triangles.vertexData.hostAddress = vertices;
        vt::AccelStruct* src = t.buildBlas(std::vector<VkAccelerationStructureGeometryKHR>{g},
                                           std::vector<VkAccelerationStructureBuildRangeInfoKHR>{t.tri->range},
                                           updatable());
        auto pb = t.updateBuild();
        pb->info.srcAccelerationStructure = pb->info.dstAccelerationStructure = src->handle;
        run(t, *pb);
        (void)vk;
        (void)dev;
    });
}

}  // namespace vu
