// CTS `operations`, `header_bottom_address`, `device_compability_khr` and `query_pool_results` (host side), plus
// the checks on untrusted serialized data and the committed format-version-1 blob:
//  - vkCopyAccelerationStructureKHR CLONE / COMPACT and serialization round trips of bottom levels (triangles,
//    AABBs, spheres, linear swept spheres, motion triangles) and top levels (static and motion): every copy traces
//    exactly like its original (every candidate and the committed hit, bit for bit), and against the oracle;
//  - compacted sizes are the real used size, far below the size-query bound;
//  - the serialized header (UUIDs, sizes, handle count, handle array of device addresses in instance order, the
//    XXH3-64 integrity hash recomputed here with xxHash itself) and deserialization into other bottom levels through
//    the handle array, as the spec's procedure does it (patched addresses, originals destroyed, bottom levels built
//    only after the top level was loaded);
//  - every vkWriteAccelerationStructuresPropertiesKHR query type, strides, and the valid-usage rules;
//  - corrupted and truncated blobs rejected with validation on and off: every single-bit flip of small blobs,
//    thousands of random corruptions of large ones, and each structural check behind a resealed hash;
//  - the committed blobs of serialized layouts 1 and 2 load and trace.
#include <cinttypes>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <algorithm>
#include <fstream>
#include <iostream>
#include <iomanip>
#include <sstream>

#include <xxhash.h>

#include "engine/format/serialize.hpp"  // serializeBlock's two hash schedules, compared below
#include "meshes.hpp"

using namespace vt;

namespace {

constexpr size_t kHeader = 56;

uint64_t load64(const uint8_t* p) {
    uint64_t v;
    std::memcpy(&v, p, 8);
    return v;
}
void store64(uint8_t* p, uint64_t v) { std::memcpy(p, &v, 8); }
uint32_t load32(const uint8_t* p) {
    uint32_t v;
    std::memcpy(&v, p, 4);
    return v;
}
void store32(uint8_t* p, uint32_t v) { std::memcpy(p, &v, 4); }

bool hasVuid(const std::vector<std::string>& errors, const std::string& vuid) {
    for (const auto& e : errors)
        if (e.find(vuid) != std::string::npos) return true;
    return false;
}
std::string joined(const std::vector<std::string>& errors) {
    std::string s;
    for (const auto& e : errors) s += "\n  " + e;
    return s;
}

// A serialized blob in 64-byte aligned memory.
struct Blob {
    std::vector<uint8_t> storage;
    uint8_t* data = nullptr;
    size_t size = 0;
    void allocate(size_t n, uint8_t fill = 0xCD) {
        storage.assign(n + 64, fill);
        auto p = reinterpret_cast<uintptr_t>(storage.data());
        data = storage.data() + ((64 - p % 64) % 64);
        size = n;
    }
    Blob() = default;
    Blob(const Blob& o) { *this = o; }
    Blob& operator=(const Blob& o) {
        if (this == &o) return *this;
        allocate(o.size);
        std::memcpy(data, o.data, o.size);
        return *this;
    }
    uint64_t serializedSize() const { return load64(data + 32); }
    uint64_t deserializedSize() const { return load64(data + 40); }
    uint64_t handleCount() const { return load64(data + 48); }
    uint64_t handle(size_t k) const { return load64(data + kHeader + 8 * k); }
    void setHandle(size_t k, uint64_t v) { store64(data + kHeader + 8 * k, v); }
    // Serialized layout 2 (driverUUID "VKAS-SERIALIZED2") puts a u64 XXH3-64 hash between handles and block.
    bool layout2() const { return std::memcmp(data, "VKAS-SERIALIZED2", 16) == 0; }
    uint8_t* hashField() { return data + kHeader + 8 * handleCount(); }
    uint64_t storedHash() const { return load64(data + kHeader + 8 * handleCount()); }
    uint8_t* payload() { return data + kHeader + 8 * handleCount() + (layout2() ? 8 : 0); }
    const uint8_t* payload() const { return const_cast<Blob*>(this)->payload(); }
    // docs/FORMAT.md: XXH3-64 (seed 0) of the header's 56 bytes followed by the block; computed here with xxHash
    // directly, not through vkas.
    uint64_t computedHash() const {
        XXH3_state_t* st = XXH3_createState();
        XXH3_64bits_reset(st);
        XXH3_64bits_update(st, data, kHeader);
        XXH3_64bits_update(st, payload(), deserializedSize());
        const uint64_t h = XXH3_64bits_digest(st);
        XXH3_freeState(st);
        return h;
    }
    // After a deliberate change of hashed bytes: the hash that makes the change reach the structural checks.
    void reseal() {
        // Only where the fields still describe bytes inside the blob (a mutated count or size may not).
        if (!layout2() || handleCount() > size / 8 || deserializedSize() > size) return;
        if (kHeader + 8 * handleCount() + 8 + deserializedSize() <= size) store64(hashField(), computedHash());
    }
};

// Header fields of a structure's block (docs/FORMAT.md).
struct BlockHeader {
    uint32_t type, buildFlags;
    uint64_t usedSize, root;
    uint32_t geometryCount, primitiveCount, recordCount, nodeCount;
    uint64_t geometryOffset, nodeOffset, recordOffset;
    uint32_t primitiveType;
};
BlockHeader readBlockHeader(const uint8_t* b) {
    BlockHeader h;
    h.type = load32(b + 8);
    h.buildFlags = load32(b + 12);
    h.usedSize = load64(b + 16);
    h.root = load64(b + 24);
    h.geometryCount = load32(b + 56);
    h.primitiveCount = load32(b + 60);
    h.recordCount = load32(b + 64);
    h.nodeCount = load32(b + 68);
    h.geometryOffset = load64(b + 72);
    h.nodeOffset = load64(b + 80);
    h.recordOffset = load64(b + 88);
    h.primitiveType = load32(b + 96);
    return h;
}

// Every candidate a ray query returns (triangles confirmed, AABBs generated at their entry t), then the committed
// hit: the full observable behaviour of a structure for one ray.
std::vector<Hit> traceAll(VkAccelerationStructureKHR tlas, const oracle::Ray& r, uint32_t flags, float time) {
    std::vector<Hit> out;
    VkasRayQuery q;
    vkasRayQueryInitializeMotion(&q, tlas, flags, 0xFF, r.origin.data(), r.tMin, r.direction.data(), r.tMax, time);
    int guard = 0;
    while (vkasRayQueryProceed(&q) && ++guard < 100000) {
        Hit c = readHit(q, false);
        out.push_back(c);
        if (c.type == VKAS_CANDIDATE_INTERSECTION_TRIANGLE)
            vkasRayQueryConfirmIntersection(&q);
        else
            vkasRayQueryGenerateIntersection(&q, std::max(c.t, r.tMin));
    }
    out.push_back(readHit(q, true));
    return out;
}

}  // namespace

// ---- Shared fixture ----------------------------------------------------------------------------------------------
class OperationsTest : public VkasTest {
  protected:
    uint64_t queryValue(const AccelStruct* as, VkQueryType type) {
        uint64_t v = ~0ull;
        VkAccelerationStructureKHR h = as->handle;
        EXPECT_EQ(vk.vkWriteAccelerationStructuresPropertiesKHR(device, 1, &h, type, sizeof v, &v, sizeof v),
                  VK_SUCCESS);
        return v;
    }
    uint64_t usedSize(const AccelStruct* as) { return load64(as->data() + 16); }
    // What the serialized handle array holds for a bottom level: its device address.
    uint64_t address(const AccelStruct* as) {
        VkAccelerationStructureDeviceAddressInfoKHR ai{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_DEVICE_ADDRESS_INFO_KHR};
        ai.accelerationStructure = as->handle;
        return vk.vkGetAccelerationStructureDeviceAddressKHR(device, &ai);
    }

    // A copy of `src` (CLONE or COMPACT) into a new structure of `dstSize` bytes (0: the query's size). The copy
    // shares the original's oracle view; a bottom level is registered under its own reference.
    AccelStruct* copyOf(const AccelStruct* src, VkCopyAccelerationStructureModeKHR mode, VkDeviceSize dstSize = 0,
                        const BuildOptions& opt = {}) {
        if (dstSize == 0)
            dstSize = queryValue(src, mode == VK_COPY_ACCELERATION_STRUCTURE_MODE_COMPACT_KHR
                                          ? VK_QUERY_TYPE_ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR
                                          : VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SIZE_KHR);
        AccelStruct* dst = createAccelStruct(src->type, dstSize, opt);
        VkCopyAccelerationStructureInfoKHR info{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_INFO_KHR};
        info.src = src->handle;
        info.dst = dst->handle;
        info.mode = mode;
        EXPECT_EQ(vk.vkCopyAccelerationStructureKHR(device, VK_NULL_HANDLE, &info), VK_SUCCESS);
        adopt(dst, src);
        return dst;
    }
    void adopt(AccelStruct* dst, const AccelStruct* src) {
        dst->blas = src->blas;
        dst->scene = src->scene;
        dst->sizes = src->sizes;
        if (dst->blas) blasRegistry[dst->reference()] = dst->blas;
    }

    Blob serialize(const AccelStruct* src) {
        Blob b;
        const uint64_t n = queryValue(src, VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_SIZE_KHR);
        b.allocate(n);
        VkCopyAccelerationStructureToMemoryInfoKHR info{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_TO_MEMORY_INFO_KHR};
        info.src = src->handle;
        info.dst.hostAddress = b.data;
        info.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_SERIALIZE_KHR;
        EXPECT_EQ(vk.vkCopyAccelerationStructureToMemoryKHR(device, VK_NULL_HANDLE, &info), VK_SUCCESS);
        EXPECT_EQ(b.serializedSize(), n);
        // The canary after the blob is untouched.
        for (size_t i = n; i < b.storage.size() - size_t(b.data - b.storage.data()); ++i)
            if (b.data[i] != 0xCD) {
                ADD_FAILURE() << "serialization wrote past its size";
                break;
            }
        return b;
    }
    VkResult deserializeInto(const Blob& b, AccelStruct* dst) {
        VkCopyMemoryToAccelerationStructureInfoKHR info{VK_STRUCTURE_TYPE_COPY_MEMORY_TO_ACCELERATION_STRUCTURE_INFO_KHR};
        info.src.hostAddress = b.data;
        info.dst = dst->handle;
        info.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_DESERIALIZE_KHR;
        return vk.vkCopyMemoryToAccelerationStructureKHR(device, VK_NULL_HANDLE, &info);
    }
    AccelStruct* deserialize(const Blob& b, const AccelStruct* original, const BuildOptions& opt = {}) {
        AccelStruct* dst = createAccelStruct(original->type, b.deserializedSize(), opt);
        EXPECT_EQ(deserializeInto(b, dst), VK_SUCCESS);
        adopt(dst, original);
        return dst;
    }

    // Compares every candidate and committed hit of `a` and `b` on `rays` (times at random when `motion`).
    void expectSameTraces(const AccelStruct* a, const AccelStruct* b, const std::vector<oracle::Ray>& rays,
                          bool motion = false) {
        size_t hits = 0;
        for (size_t i = 0; i < rays.size(); ++i) {
            const float time = motion ? rng.uniformf(0, 1) : 0.0f;
            const uint32_t flags = rng.coin(0.2) ? VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT : 0;
            const auto ta = traceAll(a->handle, rays[i], flags, time);
            const auto tb = traceAll(b->handle, rays[i], flags, time);
            bool same = ta.size() == tb.size();
            for (size_t k = 0; same && k < ta.size(); ++k) same = identical(ta[k], tb[k]);
            if (!same) {
                ADD_FAILURE() << "ray " << i << " " << describe(rays[i]) << " time " << time << ": original gives "
                              << ta.size() << " events ending " << ta.back().str() << ", copy " << tb.size()
                              << " ending " << tb.back().str();
                return;
            }
            hits += ta.back().type != 0;
        }
        EXPECT_GT(hits, rays.size() / 50) << "too few hits to compare anything";
    }

    // Random rays at the world bounds of a scene given by its instances' boxes: origin outside, aimed inside.
    std::vector<oracle::Ray> raysAt(const Float3& lo, const Float3& hi, size_t n) {
        std::vector<oracle::Ray> rays;
        for (size_t i = 0; i < n; ++i) {
            oracle::Ray r;
            Float3 target;
            for (int k = 0; k < 3; ++k) target[k] = rng.uniformf(lo[k], hi[k]);
            Float3 dir;
            double len = 0;
            for (int k = 0; k < 3; ++k) {
                dir[k] = rng.uniformf(-1, 1);
                len += double(dir[k]) * dir[k];
            }
            len = std::sqrt(std::max(len, 1e-6));
            for (int k = 0; k < 3; ++k) {
                dir[k] = float(dir[k] / len);
                r.origin[k] = target[k] - 20.0f * dir[k];
            }
            r.direction = dir;
            r.tMin = 0;
            r.tMax = rng.coin(0.1) ? 20.0f : 100.0f;
            rays.push_back(r);
        }
        return rays;
    }

    // ---- Scenes of every primitive kind ------------------------------------------------------------------------
    std::vector<std::unique_ptr<GeometryData>> keep;
    std::deque<std::vector<uint8_t>> keepBytes;  // deque: references stay valid
    std::vector<std::unique_ptr<VkAccelerationStructureGeometrySpheresDataNV>> keepSpheres;
    std::vector<std::unique_ptr<VkAccelerationStructureGeometryLinearSweptSpheresDataNV>> keepLss;
    std::vector<std::unique_ptr<VkAccelerationStructureGeometryMotionTrianglesDataNV>> keepMotion;

    AccelStruct* trianglesBlas(VkBuildAccelerationStructureFlagsKHR flags, uint32_t extra = 0) {
        Mesh m = rng.coin() ? icosphere(2) : triangleSoup(200, rng, 0.6f);
        keep.push_back(makeGeometry(m, rng.coin() ? VK_INDEX_TYPE_UINT32 : VK_INDEX_TYPE_UINT16,
                                    rng.coin() ? VK_GEOMETRY_OPAQUE_BIT_KHR : 0));
        BuildOptions opt;
        opt.flags = flags;
        opt.extraMaxPrimitives = extra;
        return buildBlas(*keep.back(), opt);
    }
    AccelStruct* aabbsBlas(VkBuildAccelerationStructureFlagsKHR flags) {
        const uint32_t n = 150;
        keepBytes.emplace_back(n * 24);
        auto& bytes = keepBytes.back();
        for (uint32_t i = 0; i < n; ++i) {
            float box[6];
            for (int k = 0; k < 3; ++k) {
                const float c = rng.uniformf(-1, 1), e = rng.uniformf(0.01f, 0.1f);
                box[k] = c - e;
                box[k + 3] = c + e;
            }
            std::memcpy(bytes.data() + 24 * i, box, 24);
        }
        VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
        g.geometryType = VK_GEOMETRY_TYPE_AABBS_KHR;
        g.flags = rng.coin() ? VK_GEOMETRY_OPAQUE_BIT_KHR : 0;
        g.geometry.aabbs.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_AABBS_DATA_KHR;
        g.geometry.aabbs.data.hostAddress = bytes.data();
        g.geometry.aabbs.stride = 24;
        VkAccelerationStructureBuildRangeInfoKHR r{n, 0, 0, 0};
        BuildOptions opt;
        opt.flags = flags;
        return buildBlas({g}, {r}, opt);
    }
    // Spheres or linear swept spheres (LIST, chained caps): R32G32B32 positions, R32 radii, no indices.
    AccelStruct* sweptBlas(bool lss, VkBuildAccelerationStructureFlagsKHR flags) {
        const uint32_t n = 120, vertices = lss ? 2 * n : n;
        keepBytes.emplace_back(vertices * 12);
        auto& pos = keepBytes.back();
        keepBytes.emplace_back(vertices * 4);
        auto& rad = keepBytes.back();
        for (uint32_t i = 0; i < vertices; ++i) {
            float p[3];
            for (int k = 0; k < 3; ++k) p[k] = rng.uniformf(-1, 1);
            if (lss && i % 2 == 1)  // a short segment from the previous point
                for (int k = 0; k < 3; ++k) {
                    float prev;
                    std::memcpy(&prev, pos.data() + 12 * (i - 1) + 4 * k, 4);
                    p[k] = prev + rng.uniformf(-0.2f, 0.2f);
                }
            const float r = rng.uniformf(0.02f, 0.08f);
            std::memcpy(pos.data() + 12 * i, p, 12);
            std::memcpy(rad.data() + 4 * i, &r, 4);
        }
        VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
        g.flags = rng.coin() ? VK_GEOMETRY_OPAQUE_BIT_KHR : 0;
        if (lss) {
            auto d = std::make_unique<VkAccelerationStructureGeometryLinearSweptSpheresDataNV>();
            *d = {};
            d->sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_LINEAR_SWEPT_SPHERES_DATA_NV;
            d->vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
            d->vertexData.hostAddress = pos.data();
            d->vertexStride = 12;
            d->radiusFormat = VK_FORMAT_R32_SFLOAT;
            d->radiusData.hostAddress = rad.data();
            d->radiusStride = 4;
            d->indexType = VK_INDEX_TYPE_NONE_KHR;
            d->indexingMode = VK_RAY_TRACING_LSS_INDEXING_MODE_LIST_NV;
            d->endCapsMode = VK_RAY_TRACING_LSS_PRIMITIVE_END_CAPS_MODE_CHAINED_NV;
            g.geometryType = VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV;
            g.pNext = d.get();
            keepLss.push_back(std::move(d));
        } else {
            auto d = std::make_unique<VkAccelerationStructureGeometrySpheresDataNV>();
            *d = {};
            d->sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_SPHERES_DATA_NV;
            d->vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
            d->vertexData.hostAddress = pos.data();
            d->vertexStride = 12;
            d->radiusFormat = VK_FORMAT_R32_SFLOAT;
            d->radiusData.hostAddress = rad.data();
            d->radiusStride = 4;
            d->indexType = VK_INDEX_TYPE_NONE_KHR;
            g.geometryType = VK_GEOMETRY_TYPE_SPHERES_NV;
            g.pNext = d.get();
            keepSpheres.push_back(std::move(d));
        }
        VkAccelerationStructureBuildRangeInfoKHR r{n, 0, 0, 0};
        BuildOptions opt;
        opt.flags = flags;
        return buildBlas({g}, {r}, opt);
    }
    // Motion triangles: positions at time 1 displaced from time 0.
    AccelStruct* motionTrianglesBlas(VkBuildAccelerationStructureFlagsKHR flags) {
        Mesh m = triangleSoup(150, rng, 0.5f);
        keep.push_back(makeGeometry(m, VK_INDEX_TYPE_UINT32));
        GeometryData& gd = *keep.back();
        keepBytes.emplace_back(gd.vertices);
        auto& moved = keepBytes.back();
        for (size_t i = 0; i + 4 <= moved.size(); i += 4) {
            float f;
            std::memcpy(&f, moved.data() + i, 4);
            f += rng.uniformf(-0.1f, 0.1f);
            std::memcpy(moved.data() + i, &f, 4);
        }
        auto md = std::make_unique<VkAccelerationStructureGeometryMotionTrianglesDataNV>();
        *md = {};
        md->sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_MOTION_TRIANGLES_DATA_NV;
        md->vertexData.hostAddress = moved.data();
        gd.geometry.geometry.triangles.pNext = md.get();
        keepMotion.push_back(std::move(md));
        BuildOptions opt;
        opt.flags = flags | VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV;
        opt.createFlags = VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV;
        return buildBlas(gd, opt);
    }
    // Instances of `blases` on a 3x3x3 lattice with random transforms, a few inactive.
    std::vector<Instance> latticeInstances(const std::vector<const AccelStruct*>& blases, size_t count) {
        std::vector<Instance> out;
        for (size_t i = 0; i < count; ++i) {
            Instance inst;
            const float x = float(i % 3) * 3.0f, y = float((i / 3) % 3) * 3.0f, z = float(i / 9) * 3.0f;
            inst.transform = compose(translation(x, y, z), randomTransform(rng, 0.7f, 1.3f, rng.coin(0.2), 0.3f));
            inst.customIndex = rng.u32() & 0xFFFFFF;
            inst.mask = 0xFF;
            inst.sbtOffset = rng.u32() & 0xFFFFFF;
            inst.flags = rng.coin(0.3) ? VK_GEOMETRY_INSTANCE_TRIANGLE_FACING_CULL_DISABLE_BIT_KHR : 0;
            inst.blas = (i % 7 == 5) ? nullptr : blases[rng.below(uint32_t(blases.size()))];
            out.push_back(inst);
        }
        return out;
    }
    // Rays through random points near random lattice points (where the instances are).
    std::vector<oracle::Ray> latticeRays(size_t n) {
        std::vector<oracle::Ray> rays;
        for (size_t i = 0; i < n; ++i) {
            const Float3 c = {3.0f * float(rng.below(3)), 3.0f * float(rng.below(3)), 3.0f * float(rng.below(3))};
            auto r = raysAt({c[0] - 1.2f, c[1] - 1.2f, c[2] - 1.2f}, {c[0] + 1.2f, c[1] + 1.2f, c[2] + 1.2f}, 1);
            rays.push_back(r[0]);
        }
        return rays;
    }

    // A motion top level (VkAccelerationStructureMotionInstanceNV, 160-byte stride) of static and matrix-motion
    // instances of `blases`.
    AccelStruct* motionTlas(const std::vector<const AccelStruct*>& blases, size_t count,
                            VkBuildAccelerationStructureFlagsKHR flags) {
        keepBytes.emplace_back(160 * count, 0);
        auto& bytes = keepBytes.back();
        for (size_t i = 0; i < count; ++i) {
            VkAccelerationStructureMotionInstanceNV mi;
            std::memset(&mi, 0, sizeof mi);
            const float x = float(i % 3) * 3.0f, y = float((i / 3) % 3) * 3.0f;
            const uint64_t ref = blases[i % blases.size()]->reference();
            if (i % 2 == 0) {
                mi.type = VK_ACCELERATION_STRUCTURE_MOTION_INSTANCE_TYPE_STATIC_NV;
                auto& s = mi.data.staticInstance;
                s.transform = translation(x, y, 0);
                s.mask = 0xFF;
                s.instanceCustomIndex = uint32_t(i);
                s.accelerationStructureReference = ref;
            } else {
                mi.type = VK_ACCELERATION_STRUCTURE_MOTION_INSTANCE_TYPE_MATRIX_MOTION_NV;
                auto& s = mi.data.matrixMotionInstance;
                s.transformT0 = translation(x, y, 0);
                s.transformT1 = compose(translation(x + 0.5f, y, 0.3f), randomTransform(rng, 0.8f, 1.2f, false, 0));
                s.mask = 0xFF;
                s.instanceCustomIndex = uint32_t(i);
                s.accelerationStructureReference = ref;
            }
            std::memcpy(bytes.data() + 160 * i, &mi, sizeof mi);
        }
        VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
        g.geometryType = VK_GEOMETRY_TYPE_INSTANCES_KHR;
        g.geometry.instances.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_INSTANCES_DATA_KHR;
        g.geometry.instances.data.hostAddress = bytes.data();
        VkAccelerationStructureBuildGeometryInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
        info.type = VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR;
        info.flags = flags | VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV;
        info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR;
        info.geometryCount = 1;
        info.pGeometries = &g;
        const uint32_t n = uint32_t(count);
        VkAccelerationStructureBuildSizesInfoKHR sizes{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
        vk.vkGetAccelerationStructureBuildSizesKHR(device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info, &n,
                                                   &sizes);
        BuildOptions opt;
        opt.createFlags = VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV;
        opt.motionMaxInstances = n;
        AccelStruct* as = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, sizes.accelerationStructureSize, opt);
        as->sizes = sizes;
        std::vector<uint8_t> scratch(sizes.buildScratchSize);
        info.dstAccelerationStructure = as->handle;
        info.scratchData.hostAddress = scratch.data();
        VkAccelerationStructureBuildRangeInfoKHR range{n, 0, 0, 0};
        const VkAccelerationStructureBuildRangeInfoKHR* pr = &range;
        EXPECT_EQ(vk.vkBuildAccelerationStructuresKHR(device, VK_NULL_HANDLE, 1, &info, &pr), VK_SUCCESS);
        return as;
    }
};

// ---- operations: copy, compaction, serialization ----------------------------------------------------------------
enum class Kind { Triangles, Aabbs, Spheres, Lss, MotionTriangles };
const char* kindName(Kind k) {
    switch (k) {
        case Kind::Triangles: return "triangles";
        case Kind::Aabbs: return "aabbs";
        case Kind::Spheres: return "spheres";
        case Kind::Lss: return "lss";
        default: return "motion_triangles";
    }
}
enum class Op { Copy, Compaction, Serialization };
const char* opName(Op o) { return o == Op::Copy ? "copy" : o == Op::Compaction ? "compaction" : "serialization"; }

struct OperationParam {
    Op op;
    bool top;
    Kind kind;
};

class operations : public OperationsTest, public ::testing::WithParamInterface<OperationParam> {
  protected:
    AccelStruct* blasOf(Kind kind, VkBuildAccelerationStructureFlagsKHR flags) {
        switch (kind) {
            case Kind::Triangles: return trianglesBlas(flags, 64);  // a loose size bound: compaction shrinks
            case Kind::Aabbs: return aabbsBlas(flags);
            case Kind::Spheres: return sweptBlas(false, flags);
            case Kind::Lss: return sweptBlas(true, flags);
            default: return motionTrianglesBlas(flags);
        }
    }
    AccelStruct* apply(Op op, const AccelStruct* src) {
        switch (op) {
            case Op::Copy: return copyOf(src, VK_COPY_ACCELERATION_STRUCTURE_MODE_CLONE_KHR);
            case Op::Compaction: {
                AccelStruct* c = copyOf(src, VK_COPY_ACCELERATION_STRUCTURE_MODE_COMPACT_KHR);
                EXPECT_EQ(c->size, usedSize(src));
                EXPECT_LE(c->size, src->size);
                return c;
            }
            default: {
                Blob b = serialize(src);
                EXPECT_EQ(b.deserializedSize(), usedSize(src));
                BuildOptions opt;
                opt.createFlags = (readBlockHeader(src->data()).buildFlags & VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV)
                                      ? VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV
                                      : 0;
                if (opt.createFlags && src->type == VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR)
                    opt.motionMaxInstances = 16;
                return deserialize(b, src, opt);
            }
        }
    }
};

TEST_P(operations, trace_identically) {
    const OperationParam p = GetParam();
    const VkBuildAccelerationStructureFlagsKHR flags =
        VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR |
        (rng.coin() ? VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR : 0);
    std::vector<const AccelStruct*> blases;
    for (int i = 0; i < 3; ++i) blases.push_back(blasOf(p.kind, flags));
    const bool motion = p.kind == Kind::MotionTriangles;
    const std::vector<oracle::Ray> rays = latticeRays(400);
    if (!p.top) {
        // The copies of the bottom levels under the same instances trace like the originals.
        std::vector<const AccelStruct*> copies;
        for (const AccelStruct* b : blases) copies.push_back(apply(p.op, b));
        auto instances = latticeInstances(blases, 20);
        auto copied = instances;
        for (auto& inst : copied)
            if (inst.blas)
                for (size_t k = 0; k < blases.size(); ++k)
                    if (inst.blas == blases[k]) inst.blas = copies[k];
        const AccelStruct* a = buildTlas(instances);
        const AccelStruct* b = buildTlas(copied);
        expectSameTraces(a, b, rays, motion);
        if (p.kind == Kind::Triangles) checkRays(b, latticeRays(200));
        return;
    }
    // Top level: the copy refers to the same bottom levels.
    const AccelStruct* tlas = motion ? motionTlas(blases, 12, flags) : buildTlas(latticeInstances(blases, 27), {
        .flags = flags});
    const AccelStruct* copy = apply(p.op, tlas);
    expectSameTraces(tlas, copy, rays, motion);
    if (p.kind == Kind::Triangles) checkRays(copy, latticeRays(200));
    // A copy of the copy too.
    const AccelStruct* again = apply(p.op, copy);
    expectSameTraces(tlas, again, latticeRays(100), motion);
}

std::vector<OperationParam> operationParams() {
    std::vector<OperationParam> out;
    for (Op op : {Op::Copy, Op::Compaction, Op::Serialization})
        for (bool top : {true, false})
            for (Kind k : {Kind::Triangles, Kind::Aabbs, Kind::Spheres, Kind::Lss, Kind::MotionTriangles})
                out.push_back({op, top, k});
    return out;
}
INSTANTIATE_TEST_SUITE_P(, operations, ::testing::ValuesIn(operationParams()),
                         [](const ::testing::TestParamInfo<OperationParam>& i) {
                             return std::string(opName(i.param.op)) + "_" +
                                    (i.param.top ? "top_acceleration_structure_" : "bottom_acceleration_structure_") +
                                    kindName(i.param.kind);
                         });

class operations_misc : public OperationsTest {};

TEST_F(operations_misc, compacted_size_is_the_used_size) {
    // A bound that is far too loose: many more primitives reserved than built.
    AccelStruct* blas = trianglesBlas(VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR, 2000);
    const uint64_t compacted = queryValue(blas, VK_QUERY_TYPE_ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR);
    EXPECT_EQ(compacted, usedSize(blas));
    EXPECT_LT(compacted * 4, blas->size) << "compacted " << compacted << " of " << blas->size;
    AccelStruct* c = copyOf(blas, VK_COPY_ACCELERATION_STRUCTURE_MODE_COMPACT_KHR);
    EXPECT_EQ(0, std::memcmp(c->data(), blas->data(), compacted)) << "a compacted copy is a byte copy";
    // Nothing after the compacted size (the structure's range ends there) was written: the canary holds.
    for (VkDeviceSize i = c->offset + c->size; i < c->buffer->size; ++i)
        ASSERT_EQ(c->buffer->mapped[i], c->poison);
    checkRays(buildSingleInstanceTlas(c), randomRays(*buildSingleInstanceTlas(blas)->scene, 300));
}

TEST_F(operations_misc, empty_structures) {
    AccelStruct* blas = buildBlas(std::vector<VkAccelerationStructureGeometryKHR>{},
                                  std::vector<VkAccelerationStructureBuildRangeInfoKHR>{},
                                  {.flags = VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR});
    AccelStruct* tlas = buildTlas({}, {.flags = VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR});
    for (AccelStruct* as : {blas, tlas}) {
        AccelStruct* c = copyOf(as, VK_COPY_ACCELERATION_STRUCTURE_MODE_COMPACT_KHR);
        EXPECT_EQ(0, std::memcmp(c->data(), as->data(), usedSize(as)));
        Blob b = serialize(as);
        EXPECT_EQ(b.handleCount(), 0u);
        deserialize(b, as);
    }
    const Hit h = traceClosest(copyOf(tlas, VK_COPY_ACCELERATION_STRUCTURE_MODE_CLONE_KHR),
                               oracle::Ray{{0, 0, -5}, 0, {0, 0, 1}, 10});
    EXPECT_EQ(h.type, 0u);
}

TEST_F(operations_misc, compacted_copy_stays_updatable) {
    Mesh m = icosphere(2);
    auto g = makeGeometry(m, VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
    BuildOptions opt;
    opt.flags = VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR | VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR;
    auto pb = prepareBlas({g.get()}, opt);
    submit({pb.get()});
    AccelStruct* c = copyOf(pb->as, VK_COPY_ACCELERATION_STRUCTURE_MODE_COMPACT_KHR);
    EXPECT_EQ(readBlockHeader(c->data()).buildFlags & VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR,
              uint32_t(VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR));
    // Move every vertex and update the compacted structure in place (src == dst).
    const auto original = g->vertices;
    for (size_t i = 0; i + 4 <= g->vertices.size(); i += 4) {
        float f;
        std::memcpy(&f, g->vertices.data() + i, 4);
        f = f * 1.5f + 0.25f;
        std::memcpy(g->vertices.data() + i, &f, 4);
    }
    VkAccelerationStructureBuildGeometryInfoKHR info = pb->info;
    info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR;
    info.srcAccelerationStructure = c->handle;
    info.dstAccelerationStructure = c->handle;
    std::vector<uint8_t> scratch(std::max<VkDeviceSize>(pb->as->sizes.updateScratchSize, 1));
    info.scratchData.hostAddress = scratch.data();
    const VkAccelerationStructureBuildRangeInfoKHR* pr = pb->ranges.data();
    ASSERT_EQ(vk.vkBuildAccelerationStructuresKHR(device, VK_NULL_HANDLE, 1, &info, &pr), VK_SUCCESS)
        << joined(takeValidationErrors());
    // The updated compacted structure traces like a fresh build of the moved mesh.
    AccelStruct* fresh = buildBlas(*g, {.flags = opt.flags});
    c->blas = fresh->blas;
    blasRegistry[c->reference()] = fresh->blas;
    const AccelStruct* a = buildSingleInstanceTlas(c);
    const AccelStruct* b = buildSingleInstanceTlas(fresh);
    checkRays(a, randomRays(*b->scene, 300));
}

// ---- The serialized header ----------------------------------------------------------------------------------------
TEST_F(operations_misc, serialized_header) {
    AccelStruct* blas = trianglesBlas(0);
    AccelStruct* blas2 = aabbsBlas(0);
    std::vector<Instance> instances = latticeInstances({blas, blas2}, 11);
    AccelStruct* tlas = buildTlas(instances);
    for (AccelStruct* as : {blas, tlas}) {
        Blob b = serialize(as);
        EXPECT_EQ(0, std::memcmp(b.data, "VKAS-SERIALIZED2", 16));
        EXPECT_EQ(0, std::memcmp(b.data + 16, "VKAS-AS-FORMAT-2", 16));
        const uint64_t used = usedSize(as);
        EXPECT_EQ(b.deserializedSize(), used);
        const uint64_t n = as == tlas ? instances.size() : 0;
        EXPECT_EQ(b.handleCount(), n);
        EXPECT_EQ(b.serializedSize(), kHeader + 8 * n + 8 + used);
        EXPECT_EQ(queryValue(as, VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_SIZE_KHR), b.serializedSize());
        // Spec: handles "matching the values returned by vkGetAccelerationStructureDeviceAddressKHR": slot k holds
        // the device address of instance k's bottom level (0 for inactive ones), never the handle value.
        for (size_t k = 0; k < n; ++k) {
            EXPECT_EQ(b.handle(k), instances[k].blas ? address(instances[k].blas) : 0u) << "slot " << k;
            if (instances[k].blas) {
                EXPECT_NE(b.handle(k), instances[k].blas->reference()) << "slot " << k;
            }
        }
        // The integrity hash is XXH3-64 of the header's 56 bytes and the block.
        EXPECT_EQ(b.storedHash(), b.computedHash());
        // The payload is the block, with the instance references zeroed.
        if (as == blas) {
            EXPECT_EQ(0, std::memcmp(b.payload(), as->data(), used));
        }
        if (as == tlas) {
            const BlockHeader h = readBlockHeader(as->data());
            for (uint32_t r = 0; r < h.recordCount; ++r)
                EXPECT_EQ(load64(b.payload() + h.recordOffset + 128 * r + 104), 0u);
        }
    }
}

// Serialization hashes a large block either on a second processor while it copies, or chunk by chunk after copying
// each (one processor): the two schedules must write the same bytes, and the same as the command.
TEST_F(operations_misc, hash_schedules_write_the_same_bytes) {
    keep.push_back(makeGeometry(triangleSoup(30000, rng, 0.05f), VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR));
    AccelStruct* big = buildBlas(*keep.back());
    AccelStruct* tlas = buildTlas(latticeInstances({big}, 12000));
    for (AccelStruct* as : {big, tlas}) {
        ASSERT_GE(usedSize(as), 1u << 20) << "small enough for one schedule only";
        const Blob viaCommand = serialize(as);
        const uint64_t addressOfBig = address(big);
        const auto toAddress = [](const void* context, uint64_t) { return *static_cast<const uint64_t*>(context); };
        Blob a = viaCommand, f = viaCommand;
        std::memset(a.data, 0x5A, a.size);
        std::memset(f.data, 0xA5, f.size);
        vkas::serial::serializeBlock(reinterpret_cast<const std::byte*>(as->data()), reinterpret_cast<std::byte*>(a.data),
                                     toAddress, &addressOfBig, vkas::serial::HashSchedule::Alongside);
        vkas::serial::serializeBlock(reinterpret_cast<const std::byte*>(as->data()), reinterpret_cast<std::byte*>(f.data),
                                     toAddress, &addressOfBig, vkas::serial::HashSchedule::Fused);
        EXPECT_EQ(0, std::memcmp(a.data, f.data, a.size));
        EXPECT_EQ(0, std::memcmp(a.data, viaCommand.data, a.size));
        EXPECT_EQ(f.storedHash(), f.computedHash());
    }
}

// ---- header_bottom_address ---------------------------------------------------------------------------------------
// The CTS procedure, as the spec describes deserialization: serialize the bottom levels and the top level, read the
// bottom levels' addresses from the top level's handle array, load new bottom levels, write their addresses over the
// old ones, destroy the originals, load the top level: it traces exactly as before.
enum class Sharing { Same, Different, Mix };
class header_bottom_address : public OperationsTest, public ::testing::WithParamInterface<Sharing> {
  protected:
    struct Scene {
        std::vector<AccelStruct*> blases;
        std::vector<const GeometryData*> geometry;  // blases[i] was built from geometry[i]
        std::vector<Instance> instances;
        AccelStruct* tlas = nullptr;
    };
    // Builds `g` into the existing (created, not yet built) structure `dst`.
    void buildInto(const GeometryData& g, AccelStruct* dst) {
        auto pb = prepareBlas(std::vector<const GeometryData*>{&g});
        pb->info.dstAccelerationStructure = dst->handle;
        pb->as = dst;
        submit({pb.get()});
    }
    Scene makeScene(Sharing sharing) {
        Scene sc;
        const size_t count = 9;
        const size_t blasCount = sharing == Sharing::Same ? 1 : sharing == Sharing::Different ? count : 3;
        for (size_t i = 0; i < blasCount; ++i) {
            sc.blases.push_back(trianglesBlas(0));
            sc.geometry.push_back(keep.back().get());
        }
        for (size_t i = 0; i < count; ++i) {
            Instance inst;
            inst.transform = translation(float(i % 3) * 3.0f, float(i / 3) * 3.0f, 0);
            inst.customIndex = uint32_t(i);
            inst.blas = sc.blases[sharing == Sharing::Mix ? (i * i) % blasCount : i % blasCount];
            sc.instances.push_back(inst);
        }
        sc.tlas = buildTlas(sc.instances);
        return sc;
    }
    size_t blasIndex(const Scene& sc, size_t instance) {
        return size_t(std::find(sc.blases.begin(), sc.blases.end(), sc.instances[instance].blas) - sc.blases.begin());
    }
    std::vector<std::vector<Hit>> traces(const AccelStruct* tlas, const std::vector<oracle::Ray>& rays) {
        std::vector<std::vector<Hit>> out;
        for (const auto& r : rays) out.push_back(traceAll(tlas->handle, r, 0, 0));
        return out;
    }
    void expectSame(const std::vector<std::vector<Hit>>& a, const std::vector<std::vector<Hit>>& b,
                    const std::vector<oracle::Ray>& rays) {
        size_t hits = 0;
        for (size_t i = 0; i < rays.size(); ++i) {
            bool same = a[i].size() == b[i].size();
            for (size_t k = 0; same && k < a[i].size(); ++k) same = identical(a[i][k], b[i][k]);
            ASSERT_TRUE(same) << "ray " << i << " " << describe(rays[i]);
            hits += a[i].back().type != 0;
        }
        EXPECT_GT(hits, rays.size() / 10);
    }
};

TEST_P(header_bottom_address, deep_serialization) {
    Scene sc = makeScene(GetParam());
    const size_t count = sc.instances.size();
    const auto rays = raysAt({-1.5f, -1.5f, -1.5f}, {7.5f, 7.5f, 1.5f}, 300);
    const auto before = traces(sc.tlas, rays);

    // Deep serialization: every bottom level, then the top level.
    std::vector<Blob> bottomBlobs;
    for (AccelStruct* b : sc.blases) bottomBlobs.push_back(serialize(b));
    Blob top = serialize(sc.tlas);
    ASSERT_EQ(top.handleCount(), count);
    EXPECT_EQ(queryValue(sc.tlas, VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_BOTTOM_LEVEL_POINTERS_KHR), count);
    for (size_t k = 0; k < count; ++k) EXPECT_EQ(top.handle(k), address(sc.instances[k].blas)) << "slot " << k;

    // Load the bottom levels into new structures; map old addresses to new ones through the application's own
    // table (old address -> original structure -> its copy), as the spec expects it to.
    std::vector<AccelStruct*> fresh;
    std::map<uint64_t, size_t> byOldAddress;
    for (size_t i = 0; i < sc.blases.size(); ++i) {
        fresh.push_back(deserialize(bottomBlobs[i], sc.blases[i]));
        byOldAddress[address(sc.blases[i])] = i;
    }
    for (size_t k = 0; k < count; ++k) {
        ASSERT_TRUE(byOldAddress.count(top.handle(k))) << "slot " << k;
        top.setHandle(k, address(fresh[byOldAddress[top.handle(k)]]));
    }
    // The originals go away before the top level is loaded: it can only be using the new bottom levels.
    for (AccelStruct* b : sc.blases) destroyAccelStruct(b);
    AccelStruct* tlas2 = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, top.deserializedSize(), {});
    ASSERT_EQ(deserializeInto(top, tlas2), VK_SUCCESS);
    expectSame(before, traces(tlas2, rays), rays);
    // Re-serializing the new top level gives the new bottom levels' addresses, one per instance, and the same
    // block and hash.
    Blob again = serialize(tlas2);
    ASSERT_EQ(again.handleCount(), count);
    for (size_t k = 0; k < count; ++k) EXPECT_EQ(again.handle(k), address(fresh[blasIndex(sc, k)])) << "slot " << k;
    EXPECT_EQ(0, std::memcmp(again.payload(), top.payload(), top.deserializedSize()));
    EXPECT_EQ(again.storedHash(), top.storedHash());
}

TEST_P(header_bottom_address, bottom_levels_built_after_the_top_level_is_loaded) {
    // Spec: the handles must name bottom levels "created before deserialization. These do not need to be built at
    // deserialize time, but must be created." The top level is loaded over empty new bottom levels, which are built
    // afterwards from the same geometry: it then traces exactly like the original.
    Scene sc = makeScene(GetParam());
    const auto rays = raysAt({-1.5f, -1.5f, -1.5f}, {7.5f, 7.5f, 1.5f}, 300);
    const auto before = traces(sc.tlas, rays);
    Blob top = serialize(sc.tlas);
    std::vector<AccelStruct*> fresh;
    std::map<uint64_t, size_t> byOldAddress;
    for (size_t i = 0; i < sc.blases.size(); ++i) {
        fresh.push_back(createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR,
                                          sc.blases[i]->sizes.accelerationStructureSize, {}));
        byOldAddress[address(sc.blases[i])] = i;
    }
    for (size_t k = 0; k < top.handleCount(); ++k) top.setHandle(k, address(fresh[byOldAddress.at(top.handle(k))]));
    AccelStruct* tlas2 = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, top.deserializedSize(), {});
    ASSERT_EQ(deserializeInto(top, tlas2), VK_SUCCESS);
    // Not built yet: every instance's bottom level is empty, so nothing is hit (and nothing crashes).
    for (const auto& r : rays) EXPECT_EQ(traceClosest(tlas2, r).type, uint32_t(VKAS_COMMITTED_INTERSECTION_NONE));
    // Now build each new bottom level from its original's geometry.
    for (size_t i = 0; i < sc.blases.size(); ++i) buildInto(*sc.geometry[i], fresh[i]);
    for (AccelStruct* b : sc.blases) destroyAccelStruct(b);
    expectSame(before, traces(tlas2, rays), rays);
}

INSTANTIATE_TEST_SUITE_P(, header_bottom_address, ::testing::Values(Sharing::Same, Sharing::Different, Sharing::Mix),
                         [](const ::testing::TestParamInfo<Sharing>& i) {
                             return i.param == Sharing::Same        ? "the_same_instances"
                                    : i.param == Sharing::Different ? "different_instances"
                                                                    : "mix_same_diff_instances";
                         });

class header_bottom_address_swap : public OperationsTest {};

TEST_F(header_bottom_address_swap, instances_hit_the_replacement) {
    // X and Y hold the same triangles in a different order (equal bounds): a top level serialized over X and loaded
    // over Y reports Y's primitive indices.
    Mesh m = icosphere(2);
    Mesh reversed = m;
    const size_t n = m.triangleCount();
    for (size_t t = 0; t < n; ++t)
        for (int j = 0; j < 3; ++j) reversed.indices[3 * t + j] = m.indices[3 * (n - 1 - t) + j];
    keep.push_back(makeGeometry(m, VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR));
    AccelStruct* x = buildBlas(*keep.back());
    keep.push_back(makeGeometry(reversed, VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR));
    AccelStruct* y = buildBlas(*keep.back());
    std::vector<Instance> instances = latticeInstances({x}, 8);
    AccelStruct* tlas = buildTlas(instances);
    Blob b = serialize(tlas);
    for (size_t k = 0; k < b.handleCount(); ++k)
        if (b.handle(k) != 0) b.setHandle(k, address(y));
    AccelStruct* loaded = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, b.deserializedSize(), {});
    ASSERT_EQ(deserializeInto(b, loaded), VK_SUCCESS);
    // The oracle: the same instances over Y.
    auto scene = std::make_shared<oracle::Scene>(*tlas->scene);
    for (auto& inst : scene->instances)
        if (inst.blas) {
            inst.blas = y->blas;
            inst.reference = y->reference();
        }
    loaded->scene = scene;
    const size_t hits = checkRays(loaded, latticeRays(300));
    EXPECT_GT(hits, 20u);
    size_t differing = 0;
    for (const auto& r : latticeRays(200)) {
        const Hit a = traceClosest(tlas, r), c = traceClosest(loaded, r);
        if (a.type && c.type) {
            EXPECT_EQ(c.primitiveIndex, int32_t(n - 1) - a.primitiveIndex);
            differing += a.primitiveIndex != c.primitiveIndex;
        }
    }
    EXPECT_GT(differing, 0u);
}

// ---- device_compability_khr ----------------------------------------------------------------------------------------
class device_compability_khr : public OperationsTest, public ::testing::WithParamInterface<bool> {};

TEST_P(device_compability_khr, serialized_headers) {
    const bool top = GetParam();
    AccelStruct* blas = trianglesBlas(VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR);
    AccelStruct* as = top ? buildTlas(latticeInstances({blas}, 5),
                                      {.flags = VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR})
                          : blas;
    AccelStruct* compacted = copyOf(as, VK_COPY_ACCELERATION_STRUCTURE_MODE_COMPACT_KHR);
    for (AccelStruct* s : {as, compacted}) {
        Blob b = serialize(s);
        VkAccelerationStructureVersionInfoKHR vi{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_VERSION_INFO_KHR};
        vi.pVersionData = b.data;
        VkAccelerationStructureCompatibilityKHR c = VK_ACCELERATION_STRUCTURE_COMPATIBILITY_MAX_ENUM_KHR;
        vk.vkGetDeviceAccelerationStructureCompatibilityKHR(device, &vi, &c);
        EXPECT_EQ(c, VK_ACCELERATION_STRUCTURE_COMPATIBILITY_COMPATIBLE_KHR);
        for (int byte : {0, 15, 16, 31}) {
            Blob bad = b;
            bad.data[byte] ^= 0x01;
            vi.pVersionData = bad.data;
            vk.vkGetDeviceAccelerationStructureCompatibilityKHR(device, &vi, &c);
            EXPECT_EQ(c, VK_ACCELERATION_STRUCTURE_COMPATIBILITY_INCOMPATIBLE_KHR) << "byte " << byte;
            EXPECT_EQ(deserializeInto(bad, compacted), VK_ERROR_INCOMPATIBLE_VERSION_KHR);
            EXPECT_TRUE(hasVuid(takeValidationErrors(), "VUID-VkCopyMemoryToAccelerationStructureInfoKHR-pInfo-03414"));
        }
    }
}
INSTANTIATE_TEST_SUITE_P(, device_compability_khr, ::testing::Values(true, false),
                         [](const ::testing::TestParamInfo<bool>& i) { return i.param ? "top" : "bottom"; });

// ---- query_pool_results ---------------------------------------------------------------------------------------------
class query_pool_results : public OperationsTest {};

TEST_F(query_pool_results, every_query_type_and_stride) {
    AccelStruct* b0 = trianglesBlas(VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR, 100);
    AccelStruct* b1 = aabbsBlas(VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR);
    std::vector<Instance> instances = latticeInstances({b0, b1}, 13);
    AccelStruct* t0 = buildTlas(instances, {.flags = VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR});
    const std::vector<AccelStruct*> all = {b0, b1, t0};
    std::vector<VkAccelerationStructureKHR> handles;
    for (auto* a : all) handles.push_back(a->handle);
    for (size_t stride : {size_t(8), size_t(16), size_t(24)}) {
        for (VkQueryType type : {VK_QUERY_TYPE_ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR,
                                 VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_SIZE_KHR,
                                 VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SIZE_KHR}) {
            std::vector<uint8_t> out(stride * all.size() + 8, 0x5A);
            uint8_t* p = out.data();
            ASSERT_EQ(reinterpret_cast<uintptr_t>(p) % 8, 0u);
            ASSERT_EQ(vk.vkWriteAccelerationStructuresPropertiesKHR(device, uint32_t(all.size()), handles.data(), type,
                                                                    stride * all.size(), p, stride),
                      VK_SUCCESS);
            for (size_t i = 0; i < all.size(); ++i) {
                const uint64_t used = usedSize(all[i]);
                const uint64_t n = i == 2 ? instances.size() : 0;
                const uint64_t expect =
                    type == VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_SIZE_KHR ? kHeader + 8 * n + 8 + used : used;
                EXPECT_EQ(load64(p + i * stride), expect) << "type " << type << " stride " << stride << " i " << i;
                for (size_t g = 8; g < stride; ++g) EXPECT_EQ(p[i * stride + g], 0x5A) << "gap written";
            }
            EXPECT_EQ(p[stride * all.size()], 0x5A);
        }
    }
    // The maintenance1 pointer count: the number of instances of a top level.
    EXPECT_EQ(queryValue(t0, VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_BOTTOM_LEVEL_POINTERS_KHR),
              instances.size());
    // Sizes of copies: a compacted copy reports the same sizes.
    AccelStruct* c = copyOf(t0, VK_COPY_ACCELERATION_STRUCTURE_MODE_COMPACT_KHR);
    EXPECT_EQ(queryValue(c, VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SIZE_KHR), usedSize(t0));
    EXPECT_EQ(queryValue(c, VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_BOTTOM_LEVEL_POINTERS_KHR),
              instances.size());
}

TEST_F(query_pool_results, valid_usage) {
    AccelStruct* plain = trianglesBlas(0);
    AccelStruct* compactable = trianglesBlas(VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR);
    alignas(8) uint64_t out[4] = {};
    auto expectVuid = [&](const char* vuid, std::vector<VkAccelerationStructureKHR> list, VkQueryType type,
                          size_t dataSize, void* data, size_t stride) {
        EXPECT_EQ(vk.vkWriteAccelerationStructuresPropertiesKHR(device, uint32_t(list.size()), list.data(), type,
                                                                dataSize, data, stride),
                  VK_ERROR_VALIDATION_FAILED_EXT)
            << vuid;
        const auto errors = takeValidationErrors();
        EXPECT_TRUE(hasVuid(errors, vuid)) << vuid << joined(errors);
    };
    expectVuid("VUID-vkWriteAccelerationStructuresPropertiesKHR-accelerationStructures-03431", {plain->handle},
               VK_QUERY_TYPE_ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR, 8, out, 8);
    expectVuid("VUID-vkWriteAccelerationStructuresPropertiesKHR-queryType-03448", {compactable->handle},
               VK_QUERY_TYPE_ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR, 8, out, 4);
    expectVuid("VUID-vkWriteAccelerationStructuresPropertiesKHR-queryType-03450", {compactable->handle},
               VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_SIZE_KHR, 12, out, 12);
    expectVuid("VUID-vkWriteAccelerationStructuresPropertiesKHR-queryType-06731", {plain->handle},
               VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SIZE_KHR, 8, out, 2);
    expectVuid("VUID-vkWriteAccelerationStructuresPropertiesKHR-queryType-06734", {plain->handle},
               VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_BOTTOM_LEVEL_POINTERS_KHR, 8,
               reinterpret_cast<uint8_t*>(out) + 4, 8);
    expectVuid("VUID-vkWriteAccelerationStructuresPropertiesKHR-pAccelerationStructures-12425", {plain->handle},
               VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_BOTTOM_LEVEL_POINTERS_KHR, 8, out, 8);
    expectVuid("VUID-vkWriteAccelerationStructuresPropertiesKHR-dataSize-03452", {plain->handle, compactable->handle},
               VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SIZE_KHR, 8, out, 8);
    expectVuid("VUID-vkWriteAccelerationStructuresPropertiesKHR-queryType-06742", {plain->handle},
               VK_QUERY_TYPE_OCCLUSION, 8, out, 8);
    AccelStruct* unbuilt = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, 4096, {});
    expectVuid("VUID-vkWriteAccelerationStructuresPropertiesKHR-pAccelerationStructures-11591", {unbuilt->handle},
               VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SIZE_KHR, 8, out, 8);
    // Nothing was written by the failed calls.
    for (uint64_t v : out) EXPECT_EQ(v, 0u);
}

// ---- Copy and serialization valid usage ---------------------------------------------------------------------------
class operations_validation : public OperationsTest {};

TEST_F(operations_validation, copy_rules) {
    AccelStruct* plain = trianglesBlas(0, 50);
    AccelStruct* compactable = trianglesBlas(VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR, 50);
    auto copy = [&](const AccelStruct* src, const AccelStruct* dst, VkCopyAccelerationStructureModeKHR mode,
                    const char* vuid, VkDeferredOperationKHR op = VK_NULL_HANDLE) {
        VkCopyAccelerationStructureInfoKHR info{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_INFO_KHR};
        info.src = src->handle;
        info.dst = dst->handle;
        info.mode = mode;
        EXPECT_EQ(vk.vkCopyAccelerationStructureKHR(device, op, &info), VK_ERROR_VALIDATION_FAILED_EXT) << vuid;
        const auto errors = takeValidationErrors();
        EXPECT_TRUE(hasVuid(errors, vuid)) << vuid << joined(errors);
    };
    AccelStruct* small = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, 256, {});
    AccelStruct* big = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, plain->size, {});
    copy(plain, big, VK_COPY_ACCELERATION_STRUCTURE_MODE_COMPACT_KHR, "VUID-VkCopyAccelerationStructureInfoKHR-src-03411");
    copy(plain, small, VK_COPY_ACCELERATION_STRUCTURE_MODE_CLONE_KHR, "VUID-VkCopyAccelerationStructureInfoKHR-mode-12418");
    copy(compactable, small, VK_COPY_ACCELERATION_STRUCTURE_MODE_COMPACT_KHR,
         "VUID-VkCopyAccelerationStructureInfoKHR-mode-12419");
    copy(plain, big, VK_COPY_ACCELERATION_STRUCTURE_MODE_SERIALIZE_KHR, "VUID-VkCopyAccelerationStructureInfoKHR-mode-03410");
    copy(small, big, VK_COPY_ACCELERATION_STRUCTURE_MODE_CLONE_KHR, "VUID-vkCopyAccelerationStructureKHR-src-11586");
    copy(plain, plain, VK_COPY_ACCELERATION_STRUCTURE_MODE_CLONE_KHR, "VUID-VkCopyAccelerationStructureInfoKHR-dst-07791");
    copy(plain, big, VK_COPY_ACCELERATION_STRUCTURE_MODE_CLONE_KHR,
         "VUID-vkCopyAccelerationStructureKHR-deferredOperation-parameter",
         reinterpret_cast<VkDeferredOperationKHR>(uintptr_t(0x1234)));
    // A clone into a structure of exactly the SIZE query's bytes is valid.
    copyOf(plain, VK_COPY_ACCELERATION_STRUCTURE_MODE_CLONE_KHR);
}

TEST_F(operations_validation, serialization_rules) {
    AccelStruct* blas = trianglesBlas(0);
    Blob b = serialize(blas);
    // Serialize: unaligned destination, wrong mode, unbuilt source.
    Blob out;
    out.allocate(b.size + 16);
    VkCopyAccelerationStructureToMemoryInfoKHR to{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_TO_MEMORY_INFO_KHR};
    to.src = blas->handle;
    to.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_SERIALIZE_KHR;
    auto expectTo = [&](const char* vuid) {
        EXPECT_EQ(vk.vkCopyAccelerationStructureToMemoryKHR(device, VK_NULL_HANDLE, &to), VK_ERROR_VALIDATION_FAILED_EXT);
        const auto errors = takeValidationErrors();
        EXPECT_TRUE(hasVuid(errors, vuid)) << vuid << joined(errors);
    };
    to.dst.hostAddress = out.data + 8;
    expectTo("VUID-vkCopyAccelerationStructureToMemoryKHR-pInfo-03751");
    to.dst.hostAddress = nullptr;
    expectTo("VUID-vkCopyAccelerationStructureToMemoryKHR-pInfo-03732");
    to.dst.hostAddress = out.data;
    to.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_CLONE_KHR;
    expectTo("VUID-VkCopyAccelerationStructureToMemoryInfoKHR-mode-03412");
    to.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_SERIALIZE_KHR;
    AccelStruct* unbuilt = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, 4096, {});
    to.src = unbuilt->handle;
    expectTo("VUID-VkCopyAccelerationStructureToMemoryInfoKHR-src-04959");

    // Deserialize: unaligned source, wrong mode, destination too small, unknown handles.
    VkCopyMemoryToAccelerationStructureInfoKHR from{VK_STRUCTURE_TYPE_COPY_MEMORY_TO_ACCELERATION_STRUCTURE_INFO_KHR};
    from.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_DESERIALIZE_KHR;
    AccelStruct* dst = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, b.deserializedSize(), {});
    from.dst = dst->handle;
    auto expectFrom = [&](const char* vuid) {
        EXPECT_EQ(vk.vkCopyMemoryToAccelerationStructureKHR(device, VK_NULL_HANDLE, &from), VK_ERROR_VALIDATION_FAILED_EXT);
        const auto errors = takeValidationErrors();
        EXPECT_TRUE(hasVuid(errors, vuid)) << vuid << joined(errors);
    };
    Blob shifted;
    shifted.allocate(b.size + 8);
    std::memcpy(shifted.data + 8, b.data, b.size);
    from.src.hostAddress = shifted.data + 8;
    expectFrom("VUID-vkCopyMemoryToAccelerationStructureKHR-pInfo-03750");
    from.src.hostAddress = nullptr;
    expectFrom("VUID-vkCopyMemoryToAccelerationStructureKHR-pInfo-03729");
    from.src.hostAddress = b.data;
    from.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_SERIALIZE_KHR;
    expectFrom("VUID-VkCopyMemoryToAccelerationStructureInfoKHR-mode-03413");
    from.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_DESERIALIZE_KHR;
    AccelStruct* tooSmall = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, b.deserializedSize() - 256, {});
    from.dst = tooSmall->handle;
    expectFrom("VUID-VkCopyMemoryToAccelerationStructureInfoKHR-dst-03746");
    // A top level whose handle array names no structure.
    AccelStruct* tlas = buildTlas(latticeInstances({blas}, 4));
    Blob t = serialize(tlas);
    const uint64_t original = t.handle(0);
    t.setHandle(0, 0x1234560);
    AccelStruct* tdst = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, t.deserializedSize(), {});
    from.dst = tdst->handle;
    from.src.hostAddress = t.data;
    expectFrom("VUID-VkCopyMemoryToAccelerationStructureInfoKHR-src-04960");
    // Layout 2 holds device addresses: a handle value of a live bottom level names nothing there.
    t.setHandle(0, blas->reference());
    expectFrom("VUID-VkCopyMemoryToAccelerationStructureInfoKHR-src-04960");
    // Nor does the address of a top level (bottom levels only).
    t.setHandle(0, address(tlas));
    expectFrom("VUID-VkCopyMemoryToAccelerationStructureInfoKHR-src-04960");
    t.setHandle(0, original);
    from.dst = tdst->handle;
    EXPECT_EQ(vk.vkCopyMemoryToAccelerationStructureKHR(device, VK_NULL_HANDLE, &from), VK_SUCCESS);
    // Valid: exactly the deserialized size.
    from.dst = dst->handle;
    from.src.hostAddress = b.data;
    EXPECT_EQ(vk.vkCopyMemoryToAccelerationStructureKHR(device, VK_NULL_HANDLE, &from), VK_SUCCESS);
}

// ---- Untrusted data: corrupted and truncated blobs, validation on and off ------------------------------------------
class operations_corrupt : public OperationsTest {
  protected:
    // A device without validation, with one structure of `size` bytes to deserialize into.
    struct RawDevice {
        VkDevice device = VK_NULL_HANDLE;
        Commands vk;
        ~RawDevice() {
            if (device) vkasDestroyDevice(device);
        }
        VkAccelerationStructureKHR create(VkDeviceSize size, VkAccelerationStructureTypeKHR type) {
            VkBufferCreateInfo bi{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
            bi.size = size;
            bi.usage = kAsBufferUsage;
            VkBuffer buffer;
            EXPECT_EQ(vk.vkCreateBuffer(device, &bi, nullptr, &buffer), VK_SUCCESS);
            VkMemoryRequirements req;
            vk.vkGetBufferMemoryRequirements(device, buffer, &req);
            VkMemoryAllocateFlagsInfo flagsInfo{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
            flagsInfo.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
            VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, &flagsInfo};
            ai.allocationSize = req.size;
            VkDeviceMemory memory;
            EXPECT_EQ(vk.vkAllocateMemory(device, &ai, nullptr, &memory), VK_SUCCESS);
            EXPECT_EQ(vk.vkBindBufferMemory(device, buffer, memory, 0), VK_SUCCESS);
            VkAccelerationStructureCreateInfoKHR ci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
            ci.buffer = buffer;
            ci.size = size;
            ci.type = type;
            VkAccelerationStructureKHR as = VK_NULL_HANDLE;
            EXPECT_EQ(vk.vkCreateAccelerationStructureKHR(device, &ci, nullptr, &as), VK_SUCCESS);
            return as;
        }
    };
    std::unique_ptr<RawDevice> raw;
    void SetUp() override {
        OperationsTest::SetUp();
        raw = std::make_unique<RawDevice>();
        VkasDeviceCreateInfo ci{};
        ci.disableValidation = VK_TRUE;
        ASSERT_EQ(vkasCreateDevice(&ci, &raw->device), VK_SUCCESS);
        raw->vk.load(raw->device);
    }
    void TearDown() override {
        raw.reset();
        OperationsTest::TearDown();
    }

    // Whether a raw-device structure holds a structure (the SIZE query gives 0 for one vkas has not constructed).
    bool constructedOnRaw(VkAccelerationStructureKHR as) {
        uint64_t v = ~0ull;
        raw->vk.vkWriteAccelerationStructuresPropertiesKHR(raw->device, 1, &as, VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SIZE_KHR,
                                                           sizeof v, &v, sizeof v);
        return v != 0;
    }
    // Loads `blas` (of the fixture's device) on the raw device and points every active entry of the top-level blob
    // `top` at that copy: the raw device's loads of `top` then succeed when nothing else is wrong.
    void rebindToRaw(const AccelStruct* blas, Blob& top) {
        const Blob bb = serialize(blas);
        const VkAccelerationStructureKHR copy = raw->create(bb.deserializedSize(), blas->type);
        ASSERT_EQ(deserializeOnRaw(bb, copy), VK_SUCCESS);
        VkAccelerationStructureDeviceAddressInfoKHR ai{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_DEVICE_ADDRESS_INFO_KHR};
        ai.accelerationStructure = copy;
        const uint64_t a = raw->vk.vkGetAccelerationStructureDeviceAddressKHR(raw->device, &ai);
        for (size_t k = 0; k < top.handleCount(); ++k)
            if (top.handle(k) != 0) top.setHandle(k, a);
    }
    VkResult deserializeOnRaw(const Blob& b, VkAccelerationStructureKHR dst) {
        VkCopyMemoryToAccelerationStructureInfoKHR info{VK_STRUCTURE_TYPE_COPY_MEMORY_TO_ACCELERATION_STRUCTURE_INFO_KHR};
        info.src.hostAddress = b.data;
        info.dst = dst;
        info.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_DESERIALIZE_KHR;
        return raw->vk.vkCopyMemoryToAccelerationStructureKHR(raw->device, VK_NULL_HANDLE, &info);
    }

    // Deserializes `b` with validation on (into a structure of `dstSize` bytes) and off; checks both results and
    // that the destination holds no structure afterwards (with validation off it held one before: a failed load
    // must not leave it in place).
    void expectRejected(const Blob& b, VkAccelerationStructureTypeKHR type, const char* what,
                        VkResult offResult = VK_ERROR_UNKNOWN, uint64_t dstSize = 1 << 20) {
        AccelStruct* dst = createAccelStruct(type, dstSize, {});
        const VkResult on = deserializeInto(b, dst);
        const auto errors = takeValidationErrors();
        if (offResult == VK_ERROR_INCOMPATIBLE_VERSION_KHR) {
            EXPECT_EQ(on, VK_ERROR_INCOMPATIBLE_VERSION_KHR) << what;
        } else {
            EXPECT_EQ(on, VK_ERROR_VALIDATION_FAILED_EXT) << what;
            EXPECT_TRUE(hasVuid(errors, "VUID-VkCopyMemoryToAccelerationStructureInfoKHR-src-04960") ||
                        hasVuid(errors, "VUID-VkCopyMemoryToAccelerationStructureInfoKHR-dst-03746"))
                << what << joined(errors);
        }
        // Not constructed: serializing it breaks VUID 04959 (validation on, so nothing is written).
        Blob out;
        out.allocate(64);
        VkCopyAccelerationStructureToMemoryInfoKHR to{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_TO_MEMORY_INFO_KHR};
        to.src = dst->handle;
        to.dst.hostAddress = out.data;
        to.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_SERIALIZE_KHR;
        EXPECT_EQ(vk.vkCopyAccelerationStructureToMemoryKHR(device, VK_NULL_HANDLE, &to), VK_ERROR_VALIDATION_FAILED_EXT);
        EXPECT_TRUE(hasVuid(takeValidationErrors(), "VUID-VkCopyAccelerationStructureToMemoryInfoKHR-src-04959"))
            << what << ": dst constructed";
        const VkAccelerationStructureKHR rawDst = raw->create(dstSize, type);
        EXPECT_EQ(deserializeOnRaw(b, rawDst), offResult) << what << " (validation off)";
        EXPECT_FALSE(constructedOnRaw(rawDst)) << what << " (validation off): dst constructed";
    }
    // A change of hashed bytes is caught by the hash; resealed, by the check that rule belongs to. Both must hold.
    void expectRejectedSealedOrNot(const Blob& b, VkAccelerationStructureTypeKHR type, const char* what) {
        expectRejected(b, type, what);
        Blob sealed = b;
        sealed.reseal();
        expectRejected(sealed, type, (std::string(what) + ", hash resealed").c_str());
    }
};

TEST_F(operations_corrupt, malformed_blobs_are_rejected) {
    AccelStruct* blas = trianglesBlas(0);  // several nodes
    ASSERT_GT(readBlockHeader(blas->data()).nodeCount, 1u);
    AccelStruct* tlas = buildTlas(latticeInstances({blas}, 12));
    const Blob bb = serialize(blas), tb = serialize(tlas);
    const auto BL = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, TL = VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR;
    auto mutated = [](const Blob& src, auto&& f) {
        Blob b = src;
        f(b);
        return b;
    };
    // UUIDs.
    expectRejected(mutated(bb, [](Blob& b) { b.data[3] ^= 0x20; }), BL, "driver UUID", VK_ERROR_INCOMPATIBLE_VERSION_KHR);
    expectRejected(mutated(bb, [](Blob& b) { b.data[20] ^= 0x01; }), BL, "compatibility UUID",
                   VK_ERROR_INCOMPATIBLE_VERSION_KHR);
    // Sizes.
    expectRejectedSealedOrNot(mutated(bb, [](Blob& b) { store64(b.data + 32, b.serializedSize() - 8); }), BL, "truncated");
    expectRejectedSealedOrNot(mutated(bb, [](Blob& b) { store64(b.data + 32, 40); }), BL, "shorter than the header");
    expectRejectedSealedOrNot(mutated(bb, [](Blob& b) { store64(b.data + 40, b.deserializedSize() + 64); }), BL, "deserialized size");
    expectRejectedSealedOrNot(mutated(bb, [](Blob& b) { store64(b.data + 48, 1); }), BL, "handle count of a bottom level");
    expectRejectedSealedOrNot(mutated(tb, [](Blob& b) { store64(b.data + 48, b.handleCount() - 1); }), TL, "handle count");
    expectRejectedSealedOrNot(mutated(tb, [](Blob& b) { store64(b.data + 48, ~0ull / 8); }), TL, "huge handle count");
    // The block's header.
    auto inBlock = [&](const Blob& src, size_t offset, uint64_t value, int bytes) {
        return mutated(src, [&](Blob& b) {
            if (bytes == 8) store64(b.payload() + offset, value);
            else store32(b.payload() + offset, uint32_t(value));
        });
    };
    const BlockHeader h = readBlockHeader(blas->data());
    expectRejectedSealedOrNot(inBlock(bb, 0, 0x12345678, 4), BL, "magic");
    expectRejectedSealedOrNot(inBlock(bb, 4, 3, 4), BL, "version");
    expectRejectedSealedOrNot(inBlock(bb, 4, 1, 4), BL, "version 1 under the compatibility UUID of format 2");
    expectRejectedSealedOrNot(inBlock(bb, 8, 7, 4), BL, "type");
    expectRejectedSealedOrNot(inBlock(bb, 16, h.usedSize + 64, 8), BL, "usedSize");
    expectRejectedSealedOrNot(inBlock(bb, 96, 2, 4), BL, "primitive type");
    expectRejectedSealedOrNot(inBlock(bb, 68, h.nodeCount + 1000, 4), BL, "node count");
    expectRejectedSealedOrNot(inBlock(bb, 64, h.recordCount + 1, 4), BL, "record count");
    expectRejectedSealedOrNot(inBlock(bb, 80, h.nodeOffset + 8, 8), BL, "misaligned nodes");
    expectRejectedSealedOrNot(inBlock(bb, 88, ~0ull - 63, 8), BL, "record offset overflow");
    expectRejectedSealedOrNot(inBlock(bb, 56, 1u << 30, 4), BL, "geometry count");
    // Sections out of order (found by the deserialization fuzzer: the size differences wrapped and passed, and the
    // geometry table or the nodes were read past usedSize): rejected by the rule that names it.
    for (const auto& [offset, value, what] :
         {std::tuple<size_t, uint64_t, const char*>{72, (h.usedSize - 8) & ~7ull, "geometry table after the nodes"},
          {80, h.recordOffset + 64, "nodes after the records"}}) {
        Blob b = inBlock(bb, offset, value, 8);
        expectRejectedSealedOrNot(b, BL, what);
        b.reseal();
        AccelStruct* dst = createAccelStruct(BL, 1 << 20, {});
        EXPECT_EQ(deserializeInto(b, dst), VK_ERROR_VALIDATION_FAILED_EXT);
        const std::string message = joined(takeValidationErrors());
        EXPECT_NE(message.find("not in the order geometry table, nodes, records"), std::string::npos) << what << message;
    }
    {
        // The fuzzer's minimized input (layout 1, no hash): 130 bytes, zero-filled to its serialized size of 568.
        const char* hex =
            "564b41532d4452495645522d464d5431564b41532d41532d464f524d41542d31380200000000000000020000000000000000000000"
            "000000564b415301000000010000000000000000020000000000000000004b483b9ee0e2004cc462ec10bfcdccccbe6766663f6766"
            "663f6766e63e010000000400000004000000000000000002";
        Blob f;
        f.allocate(568, 0);
        for (size_t i = 0; hex[2 * i]; ++i) f.data[i] = uint8_t(std::stoi(std::string(hex + 2 * i, 2), nullptr, 16));
        expectRejected(f, BL, "fuzzer input: sections out of order");
    }
    // The tree.
    const size_t child0 = h.nodeOffset + 192;  // node 0, child slot 0
    expectRejectedSealedOrNot(inBlock(bb, child0, (1ull << 62) | 0, 8), BL, "a cycle to the root");
    expectRejectedSealedOrNot(inBlock(bb, child0, (1ull << 62) | h.nodeCount, 8), BL, "a node outside the array");
    expectRejectedSealedOrNot(inBlock(bb, child0, (2ull << 62) | (uint64_t(4) << 40) | (h.recordCount - 1), 8), BL,
                   "a leaf past the records");
    expectRejectedSealedOrNot(inBlock(bb, child0, 3ull << 62, 8), BL, "an unknown reference kind");
    expectRejectedSealedOrNot(inBlock(bb, 24, (1ull << 62) | 1, 8), BL, "root not at node 0 (node 0 unreachable)");
    // Records.
    // Format 2 triangle leaves (docs/FORMAT.md): the leaf of triangle 0 has n lanes, its primitive indices at 36 n
    // and its geometry words at 40 n bytes from its start.
    uint64_t firstLeafLanes = 0;
    for (uint32_t k = 0; k < h.nodeCount && !firstLeafLanes; ++k)
        for (uint32_t c = 0; c < 8; ++c) {
            const uint64_t ref = load64(blas->data() + h.nodeOffset + 256ull * k + 192 + 8 * c);
            if ((ref >> 62) == 2 && (ref & 0xFF'FFFF'FFFFull) == 0) firstLeafLanes = (ref >> 40) & 0xFF;
        }
    ASSERT_NE(firstLeafLanes, 0u);
    expectRejectedSealedOrNot(inBlock(bb, h.recordOffset + 40 * firstLeafLanes, 5, 4), BL, "geometry index");
    expectRejectedSealedOrNot(inBlock(bb, h.recordOffset + 36 * firstLeafLanes, 1u << 20, 4), BL, "primitive index");
    const BlockHeader th = readBlockHeader(tlas->data());
    expectRejectedSealedOrNot(inBlock(tb, th.recordOffset + 112, 1000, 4), TL, "instanceId");
    expectRejectedSealedOrNot(inBlock(tb, th.recordOffset + 116, 1, 4), TL, "motion type of a static record");
    // The integrity hash itself, and the block's last byte (padding no check reads).
    expectRejected(mutated(bb, [](Blob& b) { b.hashField()[3] ^= 0x10; }), BL, "integrity hash");
    expectRejected(mutated(tb, [](Blob& b) { b.payload()[b.deserializedSize() - 1] ^= 0x01; }), TL, "last byte");
    // A destination smaller than the deserialized size: validation reports 03746; without validation nothing is
    // written and the result is VK_ERROR_UNKNOWN.
    expectRejected(bb, BL, "small destination", VK_ERROR_UNKNOWN, bb.deserializedSize() - 256);
    // The untouched blobs load on both devices.
    AccelStruct* ok = createAccelStruct(BL, bb.deserializedSize(), {});
    EXPECT_EQ(deserializeInto(bb, ok), VK_SUCCESS);
}

TEST_F(operations_corrupt, random_damage_never_crashes) {
    // Damage resealed with a matching hash (as a forger would), so that it reaches the structural checks: whatever
    // they let through must be safe to trace.
    AccelStruct* blas = trianglesBlas(0);
    AccelStruct* aabbs = aabbsBlas(0);
    AccelStruct* tlas = buildTlas(latticeInstances({blas, aabbs}, 12));
    const Blob blobs[3] = {serialize(blas), serialize(aabbs), serialize(tlas)};
    const VkAccelerationStructureTypeKHR types[3] = {VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR,
                                                     VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR,
                                                     VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR};
    VkAccelerationStructureKHR dst[3];
    for (int i = 0; i < 3; ++i) dst[i] = raw->create(blobs[i].deserializedSize() + 4096, types[i]);
    VkAccelerationStructureDeviceAddressInfoKHR ai{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_DEVICE_ADDRESS_INFO_KHR};
    size_t accepted = 0, rejected = 0;
    for (int round = 0; round < 600; ++round) {
        const int which = int(rng.below(3));
        Blob b = blobs[which];
        const int flips = 1 + int(rng.below(4));
        for (int f = 0; f < flips; ++f) {
            // Mostly the block's header, nodes and indices; sometimes anywhere.
            const size_t limit = rng.coin(0.7) ? std::min<size_t>(b.size, kHeader + 8 * b.handleCount() + 1024) : b.size;
            const size_t at = 32 + rng.below(uint32_t(limit - 32));
            b.data[at] ^= uint8_t(1u << rng.below(8));
        }
        b.reseal();
        if (deserializeOnRaw(b, dst[which]) != VK_SUCCESS) {
            ++rejected;
            EXPECT_FALSE(constructedOnRaw(dst[which]));
            continue;
        }
        ++accepted;
        if (which == 2) {
            // Loaded on the raw device only if its addresses name that device's bottom levels: they name this
            // fixture's device's, so only damage that zeroed them all can load; traversal must still be safe.
            for (int k = 0; k < 4; ++k) traceAll(dst[2], latticeRays(1)[0], 0, 0);
        } else {
            // A damaged bottom level that passed the checks, traced through an intact top level.
            Blob t = blobs[2];
            ai.accelerationStructure = dst[which];
            const uint64_t damaged = raw->vk.vkGetAccelerationStructureDeviceAddressKHR(raw->device, &ai);
            for (size_t k = 0; k < t.handleCount(); ++k)
                if (t.handle(k)) t.setHandle(k, damaged);
            ASSERT_EQ(deserializeOnRaw(t, dst[2]), VK_SUCCESS);
            for (const auto& ray : latticeRays(8)) traceAll(dst[2], ray, 0, 0);
        }
    }
    EXPECT_GT(rejected, 0u);
    std::cout << "  damaged and resealed blobs: " << accepted << " loaded, " << rejected << " rejected" << std::endl;
}

TEST_F(operations_corrupt, every_single_bit_flip_is_rejected) {
    // Every bit of small blobs of each kind, outside the handle array (which the application may rewrite), flipped
    // one at a time: each flip is rejected with validation off, and the destination, loaded before, holds no
    // structure afterwards. A sample is also checked with validation on (the VUID).
    keep.push_back(makeGeometry(grid(1, 1), VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR));
    AccelStruct* tri = buildBlas(*keep.back());
    AccelStruct* boxes = aabbsBlas(0);
    Instance one, two;
    one.blas = tri;
    two.blas = tri;
    two.transform = translation(3, 0, 0);
    AccelStruct* tlas = buildTlas({one, two});
    size_t flips = 0;
    for (AccelStruct* as : {tri, boxes, tlas}) {
        Blob b = serialize(as);
        const VkAccelerationStructureKHR dst = raw->create(b.deserializedSize(), as->type);
        if (as == tlas) rebindToRaw(tri, b);  // the raw device's own bottom level for the addresses
        ASSERT_EQ(deserializeOnRaw(b, dst), VK_SUCCESS);
        const size_t handlesBegin = kHeader, handlesEnd = kHeader + 8 * b.handleCount();
        AccelStruct* checked = createAccelStruct(as->type, b.deserializedSize(), {});
        for (size_t byte = 0; byte < b.size; ++byte) {
            if (byte >= handlesBegin && byte < handlesEnd) continue;
            for (int bit = 0; bit < 8; ++bit) {
                b.data[byte] ^= uint8_t(1u << bit);
                const VkResult r = deserializeOnRaw(b, dst);
                ASSERT_TRUE(r == VK_ERROR_UNKNOWN || r == VK_ERROR_INCOMPATIBLE_VERSION_KHR)
                    << "byte " << byte << " bit " << bit << " of " << b.size << ": result " << r;
                ASSERT_FALSE(constructedOnRaw(dst)) << "byte " << byte << " bit " << bit;
                if (byte % 61 == 0 && bit == 0) {
                    const VkResult on = deserializeInto(b, checked);
                    EXPECT_TRUE(on == VK_ERROR_VALIDATION_FAILED_EXT || on == VK_ERROR_INCOMPATIBLE_VERSION_KHR)
                        << "byte " << byte << ": " << on;
                    const auto errors = takeValidationErrors();
                    EXPECT_TRUE(hasVuid(errors, "VUID-VkCopyMemoryToAccelerationStructureInfoKHR-src-04960") ||
                                hasVuid(errors, "VUID-VkCopyMemoryToAccelerationStructureInfoKHR-pInfo-03414"))
                        << "byte " << byte << joined(errors);
                }
                b.data[byte] ^= uint8_t(1u << bit);
                ++flips;
            }
            // Restore the destination's structure for the next byte (each failure must undo it).
            if (byte % 97 == 0) {
                ASSERT_EQ(deserializeOnRaw(b, dst), VK_SUCCESS) << "byte " << byte;
            }
        }
        ASSERT_EQ(deserializeOnRaw(b, dst), VK_SUCCESS);
    }
    std::cout << "  " << flips << " single-bit flips, all rejected" << std::endl;
}

TEST_F(operations_corrupt, random_corruptions_of_large_blobs_are_rejected) {
    // Thousands of random multi-byte corruptions (1-16 bytes, each changed, anywhere outside the handle array) of
    // blobs of a large bottom level and a large top level: every one is rejected with validation off.
    keep.push_back(makeGeometry(triangleSoup(20000, rng, 0.05f), VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR));
    AccelStruct* big = buildBlas(*keep.back());
    AccelStruct* tlas = buildTlas(latticeInstances({big}, 40));
    for (AccelStruct* as : {big, tlas}) {
        Blob original = serialize(as);
        if (as == tlas) rebindToRaw(big, original);
        Blob b = original;
        const VkAccelerationStructureKHR dst = raw->create(b.deserializedSize(), as->type);
        ASSERT_EQ(deserializeOnRaw(b, dst), VK_SUCCESS);
        const size_t handlesEnd = kHeader + 8 * b.handleCount();
        const int rounds = 2000;
        for (int round = 0; round < rounds; ++round) {
            const int bytes = 1 + int(rng.below(16));
            const bool burst = rng.coin();  // contiguous bytes, or scattered ones
            size_t at = rng.below(uint32_t(b.size));
            std::vector<size_t> changed;
            for (int k = 0; k < bytes; ++k) {
                size_t p = burst ? (at + size_t(k)) % b.size : size_t(rng.below(uint32_t(b.size)));
                if (p >= kHeader && p < handlesEnd) p = handlesEnd + p % (b.size - handlesEnd);
                b.data[p] ^= uint8_t(1 + rng.below(255));  // a non-zero XOR: the byte changes
                changed.push_back(p);
            }
            const VkResult r = deserializeOnRaw(b, dst);
            ASSERT_TRUE(r == VK_ERROR_UNKNOWN || r == VK_ERROR_INCOMPATIBLE_VERSION_KHR)
                << "round " << round << ": " << bytes << " bytes from " << at << ", result " << r;
            for (size_t p : changed) b.data[p] = original.data[p];
        }
        ASSERT_EQ(0, std::memcmp(b.data, original.data, b.size));
        ASSERT_EQ(deserializeOnRaw(b, dst), VK_SUCCESS);
    }
}

// ---- The committed format-version-1 blobs ---------------------------------------------------------------------------
// tests/data/format_v1_{blas,tlas}.bin were written by format_v1_blob.DISABLED_generate from a fixed scene;
// format_v1_expected.txt holds the hits of fixed rays. Every later vkas must load them and give the same hits.
#ifndef VKAS_TEST_DATA_DIR
#define VKAS_TEST_DATA_DIR "tests/data"
#endif

// How a committed top-level blob's handle array is filled before it is loaded.
enum class Entries { Handles, Addresses };

class format_v1_blob : public OperationsTest {
  protected:
    static constexpr uint32_t kInstances = 4;
    // The fixed scene: a 6x6 grid mesh (72 triangles, z = 0, x and y in [0, 6]) under four instances.
    static VkTransformMatrixKHR instanceTransform(uint32_t i) {
        VkTransformMatrixKHR m = translation(float(i % 2) * 8.0f, float(i / 2) * 8.0f, float(i));
        return m;
    }
    static std::vector<oracle::Ray> fixedRays() {
        std::vector<oracle::Ray> rays;
        for (uint32_t i = 0; i < kInstances; ++i)
            for (int k = 0; k < 16; ++k) {
                oracle::Ray r;
                const float x = float(i % 2) * 8.0f + 0.3f + float(k % 4) * 1.45f;
                const float y = float(i / 2) * 8.0f + 0.6f + float(k / 4) * 1.37f;
                r.origin = {x, y, 10.0f};
                r.direction = {0, 0, -1};
                r.tMin = 0;
                r.tMax = 100;
                rays.push_back(r);
            }
        oracle::Ray miss;
        miss.origin = {-5, -5, 10};
        miss.direction = {0, 0, -1};
        miss.tMax = 100;
        rays.push_back(miss);
        return rays;
    }
    static std::string describeHit(const Hit& h) {
        std::ostringstream s;
        s << h.type << " " << h.instanceId << " " << h.customIndex << " " << h.geometryIndex << " " << h.primitiveIndex
          << " " << std::setprecision(9) << h.t << " " << h.bary[0] << " " << h.bary[1];
        return s.str();
    }
    void loadAndTrace(const std::string& blasFile, const std::string& tlasFile, Entries entries);
    static bool readFile(const std::string& path, Blob& b) {
        std::ifstream f(path, std::ios::binary);
        if (!f) return false;
        std::vector<char> bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
        b.allocate(bytes.size());
        std::memcpy(b.data, bytes.data(), bytes.size());
        return true;
    }
};

TEST_F(format_v1_blob, DISABLED_generate) {
    // Run with --gtest_also_run_disabled_tests and VKAS_WRITE_TEST_DATA=<dir> to write the files of the layout and
    // block format this vkas writes (layout 2, format 2: serialized_format2_*.bin). Older files are kept as they are:
    // format_v1_*.bin (layout 1, format 1) and serialized_layout2_*.bin (layout 2, format 1) were written by this
    // test before layout 2 and format 2 existed.
    const char* dir = std::getenv("VKAS_WRITE_TEST_DATA");
    ASSERT_NE(dir, nullptr) << "set VKAS_WRITE_TEST_DATA to the output directory";
    keep.push_back(makeGeometry(grid(6, 6), VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR));
    AccelStruct* blas = buildBlas(*keep.back(), {.flags = VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR});
    std::vector<Instance> instances;
    for (uint32_t i = 0; i < kInstances; ++i) {
        Instance inst;
        inst.transform = instanceTransform(i);
        inst.customIndex = 100 + i;
        inst.blas = blas;
        instances.push_back(inst);
    }
    AccelStruct* tlas = buildTlas(instances);
    const Blob bb = serialize(blas), tb = serialize(tlas);
    ASSERT_TRUE(bb.layout2());
    std::ofstream(std::string(dir) + "/serialized_format2_blas.bin", std::ios::binary)
        .write(reinterpret_cast<const char*>(bb.data), std::streamsize(bb.size));
    Blob t = tb;
    for (size_t k = 0; k < t.handleCount(); ++k) t.setHandle(k, 0);  // addresses mean nothing in a file
    std::ofstream(std::string(dir) + "/serialized_format2_tlas.bin", std::ios::binary)
        .write(reinterpret_cast<const char*>(t.data), std::streamsize(t.size));
    std::ofstream expected(std::string(dir) + "/format_v1_expected.txt");
    for (const auto& r : fixedRays()) expected << describeHit(traceClosest(tlas, r)) << "\n";
}

void format_v1_blob::loadAndTrace(const std::string& blasFile, const std::string& tlasFile, Entries entries) {
    const std::string dir = VKAS_TEST_DATA_DIR;
    Blob bb, tb;
    ASSERT_TRUE(readFile(dir + "/" + blasFile, bb)) << dir;
    ASSERT_TRUE(readFile(dir + "/" + tlasFile, tb)) << dir;
    ASSERT_EQ(bb.size, bb.serializedSize());
    ASSERT_EQ(tb.size, tb.serializedSize());
    VkAccelerationStructureVersionInfoKHR vi{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_VERSION_INFO_KHR};
    VkAccelerationStructureCompatibilityKHR c;
    for (const Blob* b : {&bb, &tb}) {
        vi.pVersionData = b->data;
        vk.vkGetDeviceAccelerationStructureCompatibilityKHR(device, &vi, &c);
        EXPECT_EQ(c, VK_ACCELERATION_STRUCTURE_COMPATIBILITY_COMPATIBLE_KHR);
    }
    AccelStruct* blas = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, bb.deserializedSize(), {});
    ASSERT_EQ(deserializeInto(bb, blas), VK_SUCCESS);
    // Whatever format the blob holds, the loaded structure is format 2 (docs/FORMAT.md): a format-1 block of the 72
    // grid triangles shrinks from 48 to 44 bytes a triangle plus the 4-byte tail.
    EXPECT_EQ(load32(blas->data() + 4), 2u) << "block format version";
    const bool format1 = std::memcmp(bb.data + 16, "VKAS-AS-FORMAT-1", 16) == 0;
    EXPECT_EQ(usedSize(blas), format1 ? bb.deserializedSize() - 4 * 72 + 4 : bb.deserializedSize());
    EXPECT_EQ(serialize(blas).deserializedSize(), usedSize(blas));
    ASSERT_EQ(tb.handleCount(), kInstances);
    for (size_t k = 0; k < kInstances; ++k)
        tb.setHandle(k, entries == Entries::Handles ? blas->reference() : address(blas));
    AccelStruct* tlas = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, tb.deserializedSize(), {});
    ASSERT_EQ(deserializeInto(tb, tlas), VK_SUCCESS);
    std::ifstream expected(dir + "/format_v1_expected.txt");
    ASSERT_TRUE(expected.good());
    size_t i = 0, hits = 0;
    for (const auto& r : fixedRays()) {
        std::string line;
        ASSERT_TRUE(std::getline(expected, line)) << "ray " << i;
        std::istringstream s(line);
        Hit want;
        s >> want.type >> want.instanceId >> want.customIndex >> want.geometryIndex >> want.primitiveIndex >> want.t >>
            want.bary[0] >> want.bary[1];
        const Hit got = traceClosest(tlas, r);
        EXPECT_EQ(got.type, want.type) << "ray " << i;
        EXPECT_EQ(got.instanceId, want.instanceId) << "ray " << i;
        EXPECT_EQ(got.customIndex, want.customIndex) << "ray " << i;
        EXPECT_EQ(got.primitiveIndex, want.primitiveIndex) << "ray " << i;
        EXPECT_NEAR(got.t, want.t, 1e-5f) << "ray " << i;
        EXPECT_NEAR(got.bary[0], want.bary[0], 1e-5f) << "ray " << i;
        EXPECT_NEAR(got.bary[1], want.bary[1], 1e-5f) << "ray " << i;
        hits += got.type != 0;
        ++i;
    }
    EXPECT_EQ(hits, size_t(16 * kInstances));
}

// Layout 1 (vkas wrote handle values into the array): entries are read as a device address first, else as a
// handle, so both an old application (handles) and one following the spec (addresses) load it.
TEST_F(format_v1_blob, loads_and_traces) { loadAndTrace("format_v1_blas.bin", "format_v1_tlas.bin", Entries::Handles); }
TEST_F(format_v1_blob, loads_and_traces_with_device_addresses) {
    loadAndTrace("format_v1_blas.bin", "format_v1_tlas.bin", Entries::Addresses);
}
// Format 2 (serialized layout 2): the blobs the current vkas writes.
TEST_F(format_v1_blob, format2_loads_and_traces) {
    loadAndTrace("serialized_format2_blas.bin", "serialized_format2_tlas.bin", Entries::Addresses);
}
// Layout 2 (device addresses, integrity hash), block format 1.
TEST_F(format_v1_blob, layout2_loads_and_traces) {
    loadAndTrace("serialized_layout2_blas.bin", "serialized_layout2_tlas.bin", Entries::Addresses);
}
