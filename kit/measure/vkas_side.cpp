#include "vkas_side.hpp"

#include <cstring>
#include <memory>
#include <stdexcept>

namespace vb {
namespace {

void check(VkResult r, const char* what) {
    if (r != VK_SUCCESS && r != VK_OPERATION_DEFERRED_KHR) throw std::runtime_error(std::string("vkas: ") + what + " failed");
}

Hit toHit(const VkasHit& h) {
    Hit r;
    if (h.type == VKAS_COMMITTED_INTERSECTION_NONE) return r;
    r.inst = h.instanceId, r.prim = h.primitiveIndex, r.geom = h.geometryIndex, r.t = h.t, r.u = h.barycentrics[0], r.v = h.barycentrics[1];
    return r;
}

}  // namespace

VkAccelerationStructureGeometryKHR triangleGeometry(const Mesh& m, const float* vertices) {
    VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
    g.geometryType = VK_GEOMETRY_TYPE_TRIANGLES_KHR;
    g.flags = VK_GEOMETRY_OPAQUE_BIT_KHR;
    auto& t = g.geometry.triangles;
    t.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR;
    t.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
    t.vertexData.hostAddress = vertices;
    t.vertexStride = 12;
    t.maxVertex = uint32_t(m.vertexCount() - 1);
    t.indexType = VK_INDEX_TYPE_UINT32;
    t.indexData.hostAddress = m.indices.data();
    return g;
}

std::vector<VkAccelerationStructureInstanceKHR> instanceRecords(const std::vector<Transform>& xs,
                                                                VkAccelerationStructureKHR blas) {
    static const Transform identity = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    std::vector<VkAccelerationStructureInstanceKHR> records(std::max<size_t>(xs.size(), 1));
    for (size_t i = 0; i < records.size(); ++i) {
        VkAccelerationStructureInstanceKHR& r = records[i];
        std::memcpy(r.transform.matrix, xs.empty() ? identity.data() : xs[i].data(), sizeof r.transform.matrix);
        r.instanceCustomIndex = uint32_t(i);
        r.mask = 0xFF;
        r.instanceShaderBindingTableRecordOffset = 0;
        r.flags = 0;
        r.accelerationStructureReference = uint64_t(blas);
    }
    return records;
}

namespace {

VkAccelerationStructureGeometryKHR instances(const std::vector<VkAccelerationStructureInstanceKHR>& records) {
    VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
    g.geometryType = VK_GEOMETRY_TYPE_INSTANCES_KHR;
    g.geometry.instances.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_INSTANCES_DATA_KHR;
    g.geometry.instances.data.hostAddress = records.data();
    return g;
}

}  // namespace

VkasEngine::VkasEngine(uint32_t workerThreadCount, bool validation) try
    : device_(vkas_kit::DeviceOptions{validation, workerThreadCount}), dev_(device_.handle()) {
    static_cast<vkas_kit::Commands&>(*this) = device_.commands();
} catch (const vkas_kit::DeviceError&) {
    throw std::runtime_error("vkas: vkasCreateDevice failed");
}

VkasEngine::~VkasEngine() = default;

VkasEngine::Structure VkasEngine::create(VkAccelerationStructureTypeKHR type, VkDeviceSize size) {
    Structure s;
    VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    bci.size = size;
    bci.usage = VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_STORAGE_BIT_KHR;
    check(vkCreateBuffer(dev_, &bci, nullptr, &s.buffer), "vkCreateBuffer");
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(dev_, s.buffer, &req);
    VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    mai.allocationSize = req.size;
    check(vkAllocateMemory(dev_, &mai, nullptr, &s.memory), "vkAllocateMemory");
    check(vkBindBufferMemory(dev_, s.buffer, s.memory, 0), "vkBindBufferMemory");
    VkAccelerationStructureCreateInfoKHR ci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
    ci.buffer = s.buffer;
    ci.size = size;
    ci.type = type;
    check(vkCreateAccelerationStructureKHR(dev_, &ci, nullptr, &s.as), "vkCreateAccelerationStructureKHR");
    return s;
}

void VkasEngine::destroy(Structure& s) {
    if (s.as) vkDestroyAccelerationStructureKHR(dev_, s.as, nullptr);
    if (s.buffer) vkDestroyBuffer(dev_, s.buffer, nullptr);
    if (s.memory) vkFreeMemory(dev_, s.memory, nullptr);
    s = {};
}

double VkasEngine::run(const VkAccelerationStructureBuildGeometryInfoKHR& info,
                       const VkAccelerationStructureBuildRangeInfoKHR& range, unsigned deferredThreads) {
    const VkAccelerationStructureBuildRangeInfoKHR* pRange = &range;
    if (deferredThreads == 0) {
        const auto t0 = std::chrono::steady_clock::now();
        check(vkBuildAccelerationStructuresKHR(dev_, VK_NULL_HANDLE, 1, &info, &pRange), "vkBuildAccelerationStructuresKHR");
        return msSince(t0);
    }
    VkDeferredOperationKHR op;
    check(vkCreateDeferredOperationKHR(dev_, nullptr, &op), "vkCreateDeferredOperationKHR");
    const auto t0 = std::chrono::steady_clock::now();
    const VkResult r = vkBuildAccelerationStructuresKHR(dev_, op, 1, &info, &pRange);
    if (r == VK_OPERATION_DEFERRED_KHR) {
        auto join = [&] {
            while (vkDeferredOperationJoinKHR(dev_, op) == VK_THREAD_IDLE_KHR) std::this_thread::yield();
        };
        std::vector<std::thread> pool;
        for (unsigned k = 1; k < deferredThreads; ++k) pool.emplace_back(join);
        join();
        for (auto& t : pool) t.join();
    } else {
        check(r, "vkBuildAccelerationStructuresKHR (deferred)");
    }
    const double ms = msSince(t0);
    check(vkGetDeferredOperationResultKHR(dev_, op), "deferred build");
    vkDestroyDeferredOperationKHR(dev_, op, nullptr);
    return ms;
}

uint64_t VkasEngine::compactedSize(const Structure& s) {
    uint64_t size = 0;
    check(vkWriteAccelerationStructuresPropertiesKHR(dev_, 1, &s.as, VK_QUERY_TYPE_ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR,
                                                     sizeof size, &size, sizeof size),
          "vkWriteAccelerationStructuresPropertiesKHR");
    return size;
}

uint64_t VkasEngine::structureSize(const Structure& s) {
    uint64_t size = 0;
    if (vkWriteAccelerationStructuresPropertiesKHR(dev_, 1, &s.as, VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SIZE_KHR, sizeof size,
                                                   &size, sizeof size) != VK_SUCCESS)
        return 0;
    return size;
}

VkasEngine::Build VkasEngine::buildBottom(const Mesh& mesh, VkBuildAccelerationStructureFlagsKHR flags, int reps,
                                          unsigned deferredThreads) {
    const VkAccelerationStructureGeometryKHR g = triangleGeometry(mesh, mesh.vertices.data());
    VkAccelerationStructureBuildGeometryInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
    info.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
    info.flags = flags | VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR;
    info.geometryCount = 1;
    info.pGeometries = &g;
    const uint32_t count = uint32_t(mesh.triangleCount());
    VkAccelerationStructureBuildSizesInfoKHR sizes{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
    vkGetAccelerationStructureBuildSizesKHR(dev_, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info, &count, &sizes);
    Build b;
    b.s = create(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, sizes.accelerationStructureSize);
    if (scratch_.size() < sizes.buildScratchSize) scratch_.resize(sizes.buildScratchSize);
    info.dstAccelerationStructure = b.s.as;
    info.scratchData.hostAddress = scratch_.data();
    b.ms = 1e300;
    for (int r = 0; r < reps; ++r) b.ms = std::min(b.ms, run(info, {count, 0, 0, 0}, deferredThreads));
    b.compactedSize = compactedSize(b.s);
    b.usedSize = structureSize(b.s);
    b.sizeQuery = sizes.accelerationStructureSize;
    b.scratchSize = sizes.buildScratchSize;
    return b;
}

VkasEngine::Build VkasEngine::buildTop(const std::vector<Transform>& xs, VkAccelerationStructureKHR blas,
                                       VkBuildAccelerationStructureFlagsKHR flags, int reps) {
    const auto records = instanceRecords(xs, blas);
    const VkAccelerationStructureGeometryKHR g = instances(records);
    VkAccelerationStructureBuildGeometryInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
    info.type = VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR;
    info.flags = flags | VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR;
    info.geometryCount = 1;
    info.pGeometries = &g;
    const uint32_t count = uint32_t(records.size());
    VkAccelerationStructureBuildSizesInfoKHR sizes{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
    vkGetAccelerationStructureBuildSizesKHR(dev_, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info, &count, &sizes);
    Build b;
    b.s = create(VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, sizes.accelerationStructureSize);
    if (scratch_.size() < sizes.buildScratchSize) scratch_.resize(sizes.buildScratchSize);
    info.dstAccelerationStructure = b.s.as;
    info.scratchData.hostAddress = scratch_.data();
    b.ms = 1e300;
    for (int r = 0; r < reps; ++r) b.ms = std::min(b.ms, run(info, {count, 0, 0, 0}, 0));
    b.compactedSize = compactedSize(b.s);
    b.usedSize = structureSize(b.s);
    b.sizeQuery = sizes.accelerationStructureSize;
    b.scratchSize = sizes.buildScratchSize;
    return b;
}

double VkasEngine::refitBottom(const Structure& s, const Mesh& mesh, const std::vector<float>& moved,
                               VkBuildAccelerationStructureFlagsKHR flags, int reps) {
    VkAccelerationStructureGeometryKHR g = triangleGeometry(mesh, moved.data());
    VkAccelerationStructureBuildGeometryInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
    info.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
    info.flags = flags | VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR;
    info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR;
    info.srcAccelerationStructure = info.dstAccelerationStructure = s.as;
    info.geometryCount = 1;
    info.pGeometries = &g;
    double best = 1e300;
    const int runs = reps % 2 ? reps : reps + 1;  // end on `moved`
    for (int r = 0; r < runs; ++r) {
        g.geometry.triangles.vertexData.hostAddress = r % 2 == 0 ? moved.data() : mesh.vertices.data();
        best = std::min(best, run(info, {uint32_t(mesh.triangleCount()), 0, 0, 0}, 0));
    }
    return best;
}

double VkasEngine::refitTop(const Structure& s, const std::vector<Transform>& xs, const std::vector<Transform>& moved,
                            VkAccelerationStructureKHR blas, VkBuildAccelerationStructureFlagsKHR flags, int reps) {
    const auto original = instanceRecords(xs, blas), changed = instanceRecords(moved, blas);
    VkAccelerationStructureGeometryKHR g = instances(changed);
    VkAccelerationStructureBuildGeometryInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
    info.type = VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR;
    info.flags = flags | VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR;
    info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR;
    info.srcAccelerationStructure = info.dstAccelerationStructure = s.as;
    info.geometryCount = 1;
    info.pGeometries = &g;
    double best = 1e300;
    const int runs = reps % 2 ? reps : reps + 1;
    for (int r = 0; r < runs; ++r) {
        g.geometry.instances.data.hostAddress = r % 2 == 0 ? changed.data() : original.data();
        best = std::min(best, run(info, {uint32_t(changed.size()), 0, 0, 0}, 0));
    }
    return best;
}

SahCost VkasEngine::sah(const Structure& s) {
    void* p = nullptr;
    check(vkMapMemory(dev_, s.memory, 0, VK_WHOLE_SIZE, 0, &p), "vkMapMemory");
    const SahCost c = vkasSah(static_cast<const unsigned char*>(p));
    vkUnmapMemory(dev_, s.memory);
    return c;
}

VkasEngine::RoundTrip VkasEngine::serializeRoundTrip(const Structure& s, uint64_t size, uint64_t usedSize) {
    RoundTrip r;
    check(vkWriteAccelerationStructuresPropertiesKHR(dev_, 1, &s.as, VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_SIZE_KHR,
                                                     sizeof r.blobBytes, &r.blobBytes, sizeof r.blobBytes),
          "vkWriteAccelerationStructuresPropertiesKHR (serialization size)");
    std::vector<unsigned char> blob(r.blobBytes);
    VkCopyAccelerationStructureToMemoryInfoKHR out{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_TO_MEMORY_INFO_KHR};
    out.src = s.as;
    out.dst.hostAddress = blob.data();
    out.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_SERIALIZE_KHR;
    auto t0 = std::chrono::steady_clock::now();
    check(vkCopyAccelerationStructureToMemoryKHR(dev_, VK_NULL_HANDLE, &out), "vkCopyAccelerationStructureToMemoryKHR");
    r.serializeMs = msSince(t0);
    r.s = create(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, size);
    VkCopyMemoryToAccelerationStructureInfoKHR in{VK_STRUCTURE_TYPE_COPY_MEMORY_TO_ACCELERATION_STRUCTURE_INFO_KHR};
    in.src.hostAddress = blob.data();
    in.dst = r.s.as;
    in.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_DESERIALIZE_KHR;
    t0 = std::chrono::steady_clock::now();
    check(vkCopyMemoryToAccelerationStructureKHR(dev_, VK_NULL_HANDLE, &in), "vkCopyMemoryToAccelerationStructureKHR");
    r.deserializeMs = msSince(t0);
    void *a = nullptr, *b = nullptr;
    check(vkMapMemory(dev_, s.memory, 0, VK_WHOLE_SIZE, 0, &a), "vkMapMemory");
    check(vkMapMemory(dev_, r.s.memory, 0, VK_WHOLE_SIZE, 0, &b), "vkMapMemory");
    r.bytesEqual = std::memcmp(a, b, usedSize) == 0;
    vkUnmapMemory(dev_, s.memory);
    vkUnmapMemory(dev_, r.s.memory);
    return r;
}

double VkasEngine::traceBatch(VkAccelerationStructureKHR tlas, bool anyHit, const std::vector<VkasRay>& rays,
                              std::vector<Hit>& hits, int reps) {
    std::vector<VkasHit> out(rays.size());
    double best = 1e300;
    for (int r = 0; r < reps; ++r) {
        const auto t0 = std::chrono::steady_clock::now();
        check(vkasTraceRays(dev_, tlas, anyHit ? VKAS_TRACE_MODE_ANY_HIT : VKAS_TRACE_MODE_CLOSEST_HIT,
                            VKAS_RAY_FLAG_NONE, 0xFF, uint32_t(rays.size()), rays.data(), out.data()),
              "vkasTraceRays");
        best = std::min(best, msSince(t0));
    }
    hits.resize(rays.size());
    for (size_t i = 0; i < rays.size(); ++i) hits[i] = toHit(out[i]);
    return best;
}

double VkasEngine::traceRayQuery(VkAccelerationStructureKHR tlas, bool anyHit, const std::vector<VkasRay>& rays,
                                 std::vector<Hit>& hits, int reps, uint32_t extraFlags) {
    hits.assign(rays.size(), Hit{});
    const uint32_t flags = (anyHit ? VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT : VKAS_RAY_FLAG_NONE) | extraFlags;
    auto q = std::make_unique<VkasRayQuery>();
    double best = 1e300;
    for (int r = 0; r < reps; ++r) {
        const auto t0 = std::chrono::steady_clock::now();
        for (size_t i = 0; i < rays.size(); ++i) {
            const VkasRay& ray = rays[i];
            vkasRayQueryInitialize(q.get(), tlas, flags, 0xFF, ray.origin, ray.tMin, ray.direction, ray.tMax);
            while (vkasRayQueryProceed(q.get())) {
            }
            Hit& h = hits[i];
            if (vkasRayQueryGetIntersectionType(q.get(), VK_TRUE) == VKAS_COMMITTED_INTERSECTION_TRIANGLE) {
                h.t = vkasRayQueryGetIntersectionT(q.get(), VK_TRUE);
                h.inst = vkasRayQueryGetIntersectionInstanceId(q.get(), VK_TRUE);
                h.prim = vkasRayQueryGetIntersectionPrimitiveIndex(q.get(), VK_TRUE);
                float b[2];
                vkasRayQueryGetIntersectionBarycentrics(q.get(), VK_TRUE, b);
                h.u = b[0], h.v = b[1];
            } else {
                h = Hit{};
            }
        }
        best = std::min(best, msSince(t0));
    }
    return best;
}

}  // namespace vb
