#include "engine/as_build.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "engine/build_sizes.hpp"
#include "engine/bvh_builder.hpp"
#include "engine/format.hpp"
#include "engine/geometry_fetch.hpp"
#include "engine/motion.hpp"
#include "engine/refit.hpp"
#include "engine/sphere_fetch.hpp"

namespace vkas {

using namespace format;

const VkAccelerationStructureGeometryKHR& buildGeometry(const VkAccelerationStructureBuildGeometryInfoKHR& info,
                                                        uint32_t i) {
    return info.pGeometries ? info.pGeometries[i] : *info.ppGeometries[i];
}

bool usesMotionRecords(const VkAccelerationStructureBuildGeometryInfoKHR& info) {
    if (!motion::isMotionBuild(info.flags)) return false;
    if (info.type == VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR) return true;
    if (info.geometryCount == 0 || (!info.pGeometries && !info.ppGeometries)) return false;
    return buildGeometry(info, 0).geometryType == VK_GEOMETRY_TYPE_TRIANGLES_KHR;
}

namespace {

std::byte* alignedScratch(const VkAccelerationStructureBuildGeometryInfoKHR& info) {
    auto p = reinterpret_cast<uintptr_t>(info.scratchData.hostAddress);
    p = (p + kScratchAlignment - 1) & ~uintptr_t(kScratchAlignment - 1);
    return reinterpret_cast<std::byte*>(p);
}

void setRef(PrimRef& ref, uint32_t index, const Aabb& b) {
    ref.lower[0] = b.lower.x, ref.lower[1] = b.lower.y, ref.lower[2] = b.lower.z;
    ref.upper[0] = b.upper.x, ref.upper[1] = b.upper.y, ref.upper[2] = b.upper.z;
    ref.index = index;
    ref.pad = 0;
}

void writeHeader(std::byte* dst, StructureType type, VkGeometryTypeKHR primitiveType,
                 const VkAccelerationStructureBuildGeometryInfoKHR& info, uint64_t primitiveCount,
                 const BvhBuildResult& tree, uint32_t recordCount, const StructureLayout& layout) {
    Header h;
    std::memset(&h, 0, sizeof h);
    h.magic = kMagic;
    h.version = kVersion;
    h.type = uint32_t(type);
    h.buildFlags = info.flags;
    h.usedSize = layout.end;
    h.root = tree.root;
    h.bounds[0] = tree.bounds.lower.x, h.bounds[1] = tree.bounds.lower.y, h.bounds[2] = tree.bounds.lower.z;
    h.bounds[3] = tree.bounds.upper.x, h.bounds[4] = tree.bounds.upper.y, h.bounds[5] = tree.bounds.upper.z;
    h.geometryCount = info.geometryCount;
    h.primitiveCount = uint32_t(primitiveCount);
    h.recordCount = recordCount;
    h.nodeCount = tree.nodeCount;
    h.geometryOffset = layout.geometryOffset;
    h.nodeOffset = layout.nodeOffset;
    h.recordOffset = layout.recordOffset;
    h.primitiveType = primitiveType;
    std::memcpy(dst, &h, sizeof h);
}

// Zeroes the alignment gaps between sections so that every byte of [0, usedSize) depends only on the inputs.
void clearGaps(std::byte* dst, uint32_t geometryCount, uint64_t nodeCount, const StructureLayout& layout) {
    uint64_t geometryEnd = layout.geometryOffset + uint64_t(geometryCount) * sizeof(GeometryDesc);
    std::memset(dst + geometryEnd, 0, layout.nodeOffset - geometryEnd);
    uint64_t nodeEnd = layout.nodeOffset + nodeCount * sizeof(Node);
    std::memset(dst + nodeEnd, 0, layout.recordOffset - nodeEnd);
}

void writeGeometryDescs(std::byte* dst, const BuildJob& job) {
    const auto& info = *job.info;
    for (uint32_t g = 0; g < info.geometryCount; ++g) {
        const auto& geom = buildGeometry(info, g);
        GeometryDesc d;
        std::memset(&d, 0, sizeof d);
        d.geometryType = geom.geometryType;
        d.flags = geom.flags;
        d.primitiveCount = job.ranges[g].primitiveCount;
        if (geom.geometryType == VK_GEOMETRY_TYPE_TRIANGLES_KHR) {
            d.vertexFormat = geom.geometry.triangles.vertexFormat;
            d.indexType = geom.geometry.triangles.indexType;
            d.maxVertex = geom.geometry.triangles.maxVertex;
            d.hasTransform = geom.geometry.triangles.transformData.hostAddress != nullptr;
            // What an update must compare its index values against (VUID 03768).
            if ((info.flags & VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR) &&
                geom.geometry.triangles.indexType != VK_INDEX_TYPE_NONE_KHR)
                d.indexHash = referencedIndexHash(geom.geometry.triangles, job.ranges[g]);
        }
        std::memcpy(dst + sizeof(Header) + g * sizeof(GeometryDesc), &d, sizeof d);
    }
}


Aabb instanceWorldBounds(const RawInstance& inst, const std::byte* blas) {
    const Header* h = header(blas);
    Affine3x4d m = affineFromFloat(inst.transform);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    bool empty = !(h->bounds[0] <= h->bounds[3] && h->bounds[1] <= h->bounds[4] && h->bounds[2] <= h->bounds[5]);
    if (empty) {  // a degenerate instance: a point at the instance origin
        for (int c = 0; c < 3; ++c) lo[c] = hi[c] = m.m[c][3];
    } else {
        for (int corner = 0; corner < 8; ++corner) {
            double p[3] = {h->bounds[(corner & 1) ? 3 : 0], h->bounds[(corner & 2) ? 4 : 1],
                           h->bounds[(corner & 4) ? 5 : 2]};
            double q[3];
            applyAffine(m, p, q);
            for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], q[c]), hi[c] = std::max(hi[c], q[c]);
        }
    }
    Aabb b;
    b.lower = {roundDown(lo[0]), roundDown(lo[1]), roundDown(lo[2])};
    b.upper = {roundUp(hi[0]), roundUp(hi[1]), roundUp(hi[2])};
    return b;
}

// Fetches the active triangles of every triangle geometry into temp[] and refs[]; returns how many.
// Triangle number k of the build (geometries in order) is fetched into temp[k] by chunks, on several threads when
// the job has a ParallelFor; then the refs of the kept triangles are packed in order. refs[j].index names the
// triangle's temp slot, so the output does not depend on the chunking.
uint32_t gatherTriangles(const BuildJob& job, PrimRef* refs, TriangleRecord* temp) {
    const auto& info = *job.info;
    const bool keepDegenerate = (info.flags & VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR) != 0;
    struct Chunk {
        uint32_t geometry, begin, end;
        uint64_t base;  // build-wide number of the geometry's first triangle
    };
    constexpr uint32_t kChunk = 16384;
    std::vector<Chunk> chunks;
    uint64_t base = 0;
    for (uint32_t g = 0; g < info.geometryCount; ++g) {
        const uint32_t count = job.ranges[g].primitiveCount;
        if (buildGeometry(info, g).geometryType == VK_GEOMETRY_TYPE_TRIANGLES_KHR)
            for (uint32_t b = 0; b < count; b += kChunk) chunks.push_back({g, b, std::min(count, b + kChunk), base});
        base += count;
    }
    auto fetchChunk = [&](uint32_t c) {
        const Chunk& ch = chunks[c];
        const auto& geom = buildGeometry(info, ch.geometry);
        TriangleSource source(geom.geometry.triangles, job.ranges[ch.geometry]);
        uint32_t flags = 0;
        if (geom.flags & VK_GEOMETRY_OPAQUE_BIT_KHR) flags |= kTriangleOpaque;
        if (geom.flags & VK_GEOMETRY_NO_DUPLICATE_ANY_HIT_INVOCATION_BIT_KHR) flags |= kTriangleNoDuplicateAnyHit;
        // The reader specialised for the geometry's index type, vertex format and transform (no per-vertex dispatch).
        source.visit([&](auto reader) {
            for (uint32_t i = ch.begin; i < ch.end; ++i) {
                const uint64_t k = ch.base + i;
                TriangleRecord& rec = temp[k];
                refs[k].pad = 0;  // not kept
                if (!reader.fetch(i, rec.v)) continue;  // inactive: never hit, never updated back to life
                rec.geometryIndex = ch.geometry;
                rec.primitiveIndex = i;
                rec.flags = flags;
                if (isDegenerateTriangle(rec.v)) {
                    if (!keepDegenerate) continue;
                    rec.flags |= kTriangleDegenerate;
                }
                Aabb b;
                for (auto& v : rec.v) b.extend(Vec3{v[0], v[1], v[2]});
                setRef(refs[k], uint32_t(k), b);
                refs[k].pad = 1;  // kept
            }
        });
    };
    if (job.parallel && chunks.size() > 1)
        (*job.parallel)(uint32_t(chunks.size()), fetchChunk);
    else
        for (uint32_t c = 0; c < chunks.size(); ++c) fetchChunk(c);
    // Pack the refs of the kept triangles in order. The leading chunks whose triangles were all kept (usually all of
    // them) stay in place and only clear their flags, in parallel; the rest is packed serially.
    std::vector<uint8_t> whole(chunks.size());
    auto checkChunk = [&](uint32_t c) {
        const Chunk& ch = chunks[c];
        bool all = true;
        for (uint64_t k = ch.base + ch.begin; k < ch.base + ch.end; ++k) all = all && refs[k].pad != 0;
        if (all)
            for (uint64_t k = ch.base + ch.begin; k < ch.base + ch.end; ++k) refs[k].pad = 0;
        whole[c] = all;
    };
    if (job.parallel && chunks.size() > 1)
        (*job.parallel)(uint32_t(chunks.size()), checkChunk);
    else
        for (uint32_t c = 0; c < chunks.size(); ++c) checkChunk(c);
    uint32_t n = 0;
    size_t c = 0;
    for (; c < chunks.size() && whole[c] && chunks[c].base + chunks[c].begin == n; ++c)
        n += chunks[c].end - chunks[c].begin;
    for (; c < chunks.size(); ++c) {
        const Chunk& ch = chunks[c];
        for (uint64_t k = ch.base + ch.begin; k < ch.base + ch.end; ++k)
            if (whole[c] || refs[k].pad) {
                refs[n] = refs[k];
                refs[n++].pad = 0;
            }
    }
    return n;
}

// [NV-motion] gatherTriangles for a motion bottom level: every triangle geometry gives its time-0 positions
// (vertexData) and time-1 positions (VkAccelerationStructureGeometryMotionTrianglesDataNV::vertexData, same format,
// stride, indexing and geometry transform; a geometry without it does not move). A triangle is inactive when a
// vertex X is NaN at either time. Degenerate triangles are always kept: a triangle can be degenerate at some
// times only, and the intersection test rejects zero-area triangles anyway. The box is the union of both times'
// boxes, which holds the linear interpolation in between (interpolated coordinates never leave [v0, v1]).
uint32_t gatherMotionTriangles(const BuildJob& job, PrimRef* refs, MotionTriangleRecord* temp) {
    const auto& info = *job.info;
    uint32_t n = 0;
    for (uint32_t g = 0; g < info.geometryCount; ++g) {
        const auto& geom = buildGeometry(info, g);
        if (geom.geometryType != VK_GEOMETRY_TYPE_TRIANGLES_KHR) continue;
        TriangleSource source(geom.geometry.triangles, job.ranges[g]);
        VkAccelerationStructureGeometryTrianglesDataKHR atOne = geom.geometry.triangles;
        const auto* m = motion::findMotionTriangles(geom.geometry.triangles);
        if (m && m->vertexData.hostAddress) atOne.vertexData = m->vertexData;  // NULL: invalid, treated as static
        TriangleSource source1(atOne, job.ranges[g]);
        uint32_t flags = kTriangleMotion;
        if (geom.flags & VK_GEOMETRY_OPAQUE_BIT_KHR) flags |= kTriangleOpaque;
        if (geom.flags & VK_GEOMETRY_NO_DUPLICATE_ANY_HIT_INVOCATION_BIT_KHR) flags |= kTriangleNoDuplicateAnyHit;
        for (uint32_t i = 0; i < source.primitiveCount(); ++i) {
            MotionTriangleRecord rec;
            std::memset(&rec, 0, sizeof rec);
            const bool active0 = source.fetch(i, rec.base.v);
            const bool active1 = source1.fetch(i, rec.v1);
            if (!active0 || !active1) continue;  // inactive: never hit, never updated back to life
            rec.base.geometryIndex = g;
            rec.base.primitiveIndex = i;
            rec.base.flags = flags;
            Aabb b;
            for (auto& v : rec.base.v) b.extend(Vec3{v[0], v[1], v[2]});
            for (auto& v : rec.v1) b.extend(Vec3{v[0], v[1], v[2]});
            temp[n] = rec;
            setRef(refs[n], n, b);
            ++n;
        }
    }
    return n;
}

// Fetches the active AABBs of every AABB geometry into temp[] and refs[]; returns how many. The tree bounds
// each box exactly: the inputs are floats already.
uint32_t gatherAabbs(const BuildJob& job, PrimRef* refs, AabbRecord* temp) {
    const auto& info = *job.info;
    uint32_t n = 0;
    for (uint32_t g = 0; g < info.geometryCount; ++g) {
        const auto& geom = buildGeometry(info, g);
        if (geom.geometryType != VK_GEOMETRY_TYPE_AABBS_KHR) continue;
        AabbSource source(geom.geometry.aabbs, job.ranges[g]);
        uint32_t flags = 0;
        if (geom.flags & VK_GEOMETRY_OPAQUE_BIT_KHR) flags |= kAabbOpaque;
        if (geom.flags & VK_GEOMETRY_NO_DUPLICATE_ANY_HIT_INVOCATION_BIT_KHR) flags |= kAabbNoDuplicateAnyHit;
        for (uint32_t i = 0; i < source.primitiveCount(); ++i) {
            AabbRecord rec;
            std::memset(&rec, 0, sizeof rec);
            if (!source.fetch(i, rec.lower, rec.upper)) continue;  // inactive (minX NaN): still counts in indices
            if (isInvertedAabb(rec.lower, rec.upper)) continue;    // invalid input (VUIDs 03546-03548): never hit
            rec.geometryIndex = g;
            rec.primitiveIndex = i;
            rec.flags = flags;
            Aabb b;
            b.extend(Vec3{rec.lower[0], rec.lower[1], rec.lower[2]});
            b.extend(Vec3{rec.upper[0], rec.upper[1], rec.upper[2]});
            temp[n] = rec;
            setRef(refs[n], n, b);
            ++n;
        }
    }
    return n;
}

VkResult buildBottomLevel(const BuildJob& job) {
    const auto& info = *job.info;
    uint64_t total = 0;
    for (uint32_t g = 0; g < info.geometryCount; ++g) total += job.ranges[g].primitiveCount;
    const bool motion = usesMotionRecords(info);  // [NV-motion] triangles: MotionTriangleRecords
    auto worst = structureSizes(StructureType::BottomLevel, info.geometryCount, total, motion);
    if (worst.structureSize > job.dstSize) return VK_ERROR_UNKNOWN;

    // All geometries of a bottom-level structure have one type (VUID 03792): geometry 0 names it.
    VkGeometryTypeKHR primitiveType = VK_GEOMETRY_TYPE_TRIANGLES_KHR;
    if (info.geometryCount != 0) {
        const VkGeometryTypeKHR first = buildGeometry(info, 0).geometryType;
        if (first == VK_GEOMETRY_TYPE_AABBS_KHR || first == VK_GEOMETRY_TYPE_SPHERES_NV ||
            first == VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV)
            primitiveType = first;
    }
    const size_t kRecordSize = motion ? sizeof(MotionTriangleRecord) : sizeof(TriangleRecord);  // == sizeof(AabbRecord), SphereRecord, LssRecord
    PrimRef* refs = nullptr;
    std::byte* temp = nullptr;
    if (total != 0) {
        refs = reinterpret_cast<PrimRef*>(alignedScratch(info));
        temp = reinterpret_cast<std::byte*>(refs + total);
    }
    const uint32_t n = primitiveType == VK_GEOMETRY_TYPE_AABBS_KHR
                           ? gatherAabbs(job, refs, reinterpret_cast<AabbRecord*>(temp))
                       : primitiveType == VK_GEOMETRY_TYPE_SPHERES_NV
                           ? gatherSpheres(job, refs, reinterpret_cast<SphereRecord*>(temp))
                       : primitiveType == VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV
                           ? gatherLss(job, refs, reinterpret_cast<LssRecord*>(temp))
                           : motion ? gatherMotionTriangles(job, refs, reinterpret_cast<MotionTriangleRecord*>(temp))
                           : gatherTriangles(job, refs, reinterpret_cast<TriangleRecord*>(temp));
    StructureLayout pre = structureLayout(StructureType::BottomLevel, info.geometryCount, 0, 0);
    auto* nodes = reinterpret_cast<Node*>(job.dst + pre.nodeOffset);
    const BvhBuildSettings settings = buildSettingsFor(maxLeafSize(StructureType::BottomLevel), info.flags);
    BvhBuildResult tree = buildWideBvh(refs, n, settings, nodes, job.parallel);
    StructureLayout layout =
        structureLayout(StructureType::BottomLevel, info.geometryCount, tree.nodeCount, n, motion);
    std::byte* records = job.dst + layout.recordOffset;
    auto copyRecords = [&](uint32_t begin, uint32_t end) {
        for (uint32_t i = begin; i < end; ++i)
            std::memcpy(records + uint64_t(i) * kRecordSize, temp + uint64_t(refs[i].index) * kRecordSize,
                        kRecordSize);
    };
    constexpr uint32_t kCopyChunk = 65536;
    if (job.parallel && n > 2 * kCopyChunk)
        (*job.parallel)((n + kCopyChunk - 1) / kCopyChunk, [&](uint32_t c) {
            copyRecords(c * kCopyChunk, std::min(n, (c + 1) * kCopyChunk));
        });
    else
        copyRecords(0, n);
    writeGeometryDescs(job.dst, job);
    clearGaps(job.dst, info.geometryCount, tree.nodeCount, layout);
    writeHeader(job.dst, StructureType::BottomLevel, primitiveType, info, total, tree, n, layout);
    return VK_SUCCESS;
}

// [NV-motion] A top level built with VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV: the instances are
// VkAccelerationStructureMotionInstanceNV (or pointers to their members, the type in the low 4 bits), stored as
// MotionInstanceRecords whose boxes hold the instance over the whole time range [0, 1].
VkResult buildMotionTopLevel(const BuildJob& job) {
    const auto& info = *job.info;
    uint64_t total = info.geometryCount ? job.ranges[0].primitiveCount : 0;
    auto worst = structureSizes(StructureType::TopLevel, info.geometryCount, total, true);
    if (worst.structureSize > job.dstSize) return VK_ERROR_UNKNOWN;

    PrimRef* refs = nullptr;
    MotionInstanceRecord* temp = nullptr;
    if (total != 0) {
        refs = reinterpret_cast<PrimRef*>(alignedScratch(info));
        temp = reinterpret_cast<MotionInstanceRecord*>(refs + total);
    }
    uint32_t n = 0;
    if (total != 0) {
        motion::MotionInstanceSource source(buildGeometry(info, 0).geometry.instances, job.ranges[0]);
        for (uint32_t i = 0; i < source.count(); ++i) {
            motion::RawMotionInstance inst;
            if (!source.fetch(i, inst) || inst.reference == 0) continue;  // inactive: still counted in instance ids
            const std::byte* blas = job.resolver ? job.resolver(inst.reference) : nullptr;
            if (!blas) continue;  // not a structure (invalid usage, reported by validation)
            MotionInstanceRecord rec;
            Aabb b;
            makeMotionInstanceRecord(inst, i, blas, rec, b);
            temp[n] = rec;
            setRef(refs[n], n, b);
            ++n;
        }
    }
    StructureLayout pre = structureLayout(StructureType::TopLevel, info.geometryCount, 0, 0, true);
    auto* nodes = reinterpret_cast<Node*>(job.dst + pre.nodeOffset);
    const BvhBuildSettings settings = buildSettingsFor(maxLeafSize(StructureType::TopLevel), info.flags);
    BvhBuildResult tree = buildWideBvh(refs, n, settings, nodes, job.parallel);
    StructureLayout layout = structureLayout(StructureType::TopLevel, info.geometryCount, tree.nodeCount, n, true);
    auto* records = reinterpret_cast<MotionInstanceRecord*>(job.dst + layout.recordOffset);
    for (uint32_t i = 0; i < n; ++i) records[i] = temp[refs[i].index];
    writeGeometryDescs(job.dst, job);
    clearGaps(job.dst, info.geometryCount, tree.nodeCount, layout);
    writeHeader(job.dst, StructureType::TopLevel, VK_GEOMETRY_TYPE_INSTANCES_KHR, info, total, tree, n, layout);
    return VK_SUCCESS;
}

VkResult buildTopLevel(const BuildJob& job) {
    const auto& info = *job.info;
    if (motion::isMotionBuild(info.flags)) return buildMotionTopLevel(job);
    uint64_t total = info.geometryCount ? job.ranges[0].primitiveCount : 0;
    auto worst = structureSizes(StructureType::TopLevel, info.geometryCount, total);
    if (worst.structureSize > job.dstSize) return VK_ERROR_UNKNOWN;

    PrimRef* refs = nullptr;
    InstanceRecord* temp = nullptr;
    if (total != 0) {
        refs = reinterpret_cast<PrimRef*>(alignedScratch(info));
        temp = reinterpret_cast<InstanceRecord*>(refs + total);
    }
    uint32_t n = 0;
    if (total != 0) {
        InstanceSource source(buildGeometry(info, 0).geometry.instances, job.ranges[0]);
        for (uint32_t i = 0; i < source.count(); ++i) {
            RawInstance inst = source.fetch(i);
            if (inst.reference == 0) continue;  // inactive instance: still counted in instance ids
            const std::byte* blas = job.resolver ? job.resolver(inst.reference) : nullptr;
            if (!blas) continue;  // not a structure (invalid usage, reported by validation)
            InstanceRecord rec;
            Aabb b;
            makeInstanceRecord(inst, i, blas, rec, b);
            temp[n] = rec;
            setRef(refs[n], n, b);
            ++n;
        }
    }
    StructureLayout pre = structureLayout(StructureType::TopLevel, info.geometryCount, 0, 0);
    auto* nodes = reinterpret_cast<Node*>(job.dst + pre.nodeOffset);
    const BvhBuildSettings settings = buildSettingsFor(maxLeafSize(StructureType::TopLevel), info.flags);
    BvhBuildResult tree = buildWideBvh(refs, n, settings, nodes, job.parallel);
    StructureLayout layout = structureLayout(StructureType::TopLevel, info.geometryCount, tree.nodeCount, n);
    auto* records = reinterpret_cast<InstanceRecord*>(job.dst + layout.recordOffset);
    for (uint32_t i = 0; i < n; ++i) records[i] = temp[refs[i].index];
    writeGeometryDescs(job.dst, job);
    clearGaps(job.dst, info.geometryCount, tree.nodeCount, layout);
    writeHeader(job.dst, StructureType::TopLevel, VK_GEOMETRY_TYPE_INSTANCES_KHR, info, total, tree, n, layout);
    return VK_SUCCESS;
}

}  // namespace

void makeInstanceRecord(const RawInstance& inst, uint32_t instanceId, const std::byte* blas, InstanceRecord& rec,
                        Aabb& box) {
    std::memset(&rec, 0, sizeof rec);
    std::memcpy(rec.objectToWorld, inst.transform, sizeof rec.objectToWorld);
    Affine3x4d inv;
    invertAffine(affineFromFloat(inst.transform), inv);
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) rec.worldToObject[r][c] = float(inv.m[r][c]);
    rec.customIndexAndMask = inst.customIndexAndMask;
    rec.sbtOffsetAndFlags = inst.sbtOffsetAndFlags;
    rec.reference = inst.reference;
    rec.instanceId = instanceId;
    box = instanceWorldBounds(inst, blas);
}

void makeMotionInstanceRecord(const motion::RawMotionInstance& inst, uint32_t instanceId, const std::byte* blas,
                              MotionInstanceRecord& rec, Aabb& box) {
    std::memset(&rec, 0, sizeof rec);
    if (inst.type == motion::kStatic) {
        std::memcpy(rec.base.objectToWorld, inst.staticTransform, sizeof rec.base.objectToWorld);
        Affine3x4d inv;
        invertAffine(affineFromFloat(inst.staticTransform), inv);
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c) rec.base.worldToObject[r][c] = float(inv.m[r][c]);
    } else {
        rec.base.motionType = inst.type;
        std::memcpy(rec.motion, inst.motion, sizeof rec.motion);
        if (inst.type == motion::kMatrix) std::memset(rec.motion + 24, 0, 8 * sizeof(float));
        motion::instanceTransformsAt(rec.base, 0.0f, rec.base.objectToWorld, rec.base.worldToObject);
    }
    rec.base.customIndexAndMask = inst.customIndexAndMask;
    rec.base.sbtOffsetAndFlags = inst.sbtOffsetAndFlags;
    rec.base.reference = inst.reference;
    rec.base.instanceId = instanceId;
    // The bottom level's bounds; an empty one is a point at the object-space origin (degenerate instance).
    const Header* h = header(blas);
    double boxLo[3] = {0, 0, 0}, boxHi[3] = {0, 0, 0};
    if (h->bounds[0] <= h->bounds[3] && h->bounds[1] <= h->bounds[4] && h->bounds[2] <= h->bounds[5])
        for (int c = 0; c < 3; ++c) boxLo[c] = h->bounds[c], boxHi[c] = h->bounds[3 + c];
    double lo[3], hi[3];
    motion::instanceBounds(inst.type, inst.staticTransform, inst.motion, boxLo, boxHi, lo, hi);
    box.lower = {roundDown(lo[0]), roundDown(lo[1]), roundDown(lo[2])};
    box.upper = {roundUp(hi[0]), roundUp(hi[1]), roundUp(hi[2])};
}

VkResult buildAccelerationStructure(const BuildJob& job) {
    if (job.info->type == VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR) return buildTopLevel(job);
    return buildBottomLevel(job);
}

}  // namespace vkas
