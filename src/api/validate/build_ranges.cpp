#include "engine/util/host_memory.hpp"
#include "api/validate/build_ranges.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "api/limits.hpp"
#include "engine/format/motion.hpp"
#include "engine/input/aabbs.hpp"
#include "engine/input/build_inputs.hpp"
#include "engine/input/instances.hpp"
#include "engine/input/motion_inputs.hpp"
#include "engine/input/triangles.hpp"
#include "engine/input/vertex_format.hpp"

namespace vkas {

namespace {

using ull = unsigned long long;

constexpr VkGeometryInstanceFlagsKHR kKnownInstanceFlags =
    VK_GEOMETRY_INSTANCE_TRIANGLE_FACING_CULL_DISABLE_BIT_KHR | VK_GEOMETRY_INSTANCE_TRIANGLE_FLIP_FACING_BIT_KHR |
    VK_GEOMETRY_INSTANCE_FORCE_OPAQUE_BIT_KHR | VK_GEOMETRY_INSTANCE_FORCE_NO_OPAQUE_BIT_KHR |
    VK_GEOMETRY_INSTANCE_FORCE_OPACITY_MICROMAP_2_STATE_EXT | VK_GEOMETRY_INSTANCE_DISABLE_OPACITY_MICROMAPS_EXT;

// The left 3x3 of a VkTransformMatrixKHR is invertible (VUID-VkTransformMatrixKHR-matrix-03799).
bool invertible3x3(const float m[3][4]) {
    const double det = double(m[0][0]) * (double(m[1][1]) * m[2][2] - double(m[1][2]) * m[2][1]) -
                       double(m[0][1]) * (double(m[1][0]) * m[2][2] - double(m[1][2]) * m[2][0]) +
                       double(m[0][2]) * (double(m[1][0]) * m[2][1] - double(m[1][1]) * m[2][0]);
    return det != 0.0 && std::isfinite(det);
}

// An instance's rules (the VkAccelerationStructureInstanceKHR, or the static member of a motion instance): flags and
// an invertible transform. `flagsVuid` names the structure the flags belong to.
void checkInstanceBody(Validator& v, const float transform[3][4], uint32_t sbtOffsetAndFlags, const char* flagsVuid,
                       const char* where, uint32_t k) {
    const uint32_t flags = sbtOffsetAndFlags >> 24;
    v.check((flags & ~kKnownInstanceFlags) == 0, flagsVuid,
            "%s: instance %u has flags 0x%x, with bits that are not VkGeometryInstanceFlagBitsKHR of an enabled "
            "extension.",
            where, k, flags);
    if (transform)
        v.check(invertible3x3(transform), "VUID-VkTransformMatrixKHR-matrix-03799",
                "%s: the transform of instance %u is not invertible (its first three columns).", where, k);
}

}  // namespace

void checkAabbRange(Validator& v, const VkAccelerationStructureGeometryAabbsDataKHR& a,
                    const VkAccelerationStructureBuildRangeInfoKHR& r, const char* where, uint32_t g) {
    v.check(r.primitiveOffset % 8 == 0, "VUID-VkAccelerationStructureBuildRangeInfoKHR-primitiveOffset-03659",
            "%s geometry %u: primitiveOffset %u is not a multiple of 8.", where, g, r.primitiveOffset);
    if (r.primitiveCount == 0) return;
    if (!v.check(a.data.hostAddress != nullptr, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03774",
                 "%s geometry %u: aabbs.data.hostAddress is NULL.", where, g))
        return;
    if (v.failureCount() != 0) return;  // read the boxes only through a range that passed its rules
    // VkAabbPositionsKHR needs min <= max on each axis; inactive boxes (minX NaN) are exempt. One message per
    // axis, naming the first box that breaks it.
    static const char* const kAxisVuids[3] = {"VUID-VkAabbPositionsKHR-minX-03546",
                                              "VUID-VkAabbPositionsKHR-minY-03547",
                                              "VUID-VkAabbPositionsKHR-minZ-03548"};
    static const char kAxisNames[3] = {'X', 'Y', 'Z'};
    int64_t firstBad[3] = {-1, -1, -1};
    float badMin[3] = {}, badMax[3] = {};
    AabbSource source(a, r);
    for (uint32_t i = 0; i < r.primitiveCount; ++i) {
        float lower[3], upper[3];
        if (!source.fetch(i, lower, upper)) continue;
        for (int axis = 0; axis < 3; ++axis)
            if (firstBad[axis] < 0 && !(lower[axis] <= upper[axis])) {
                firstBad[axis] = i;
                badMin[axis] = lower[axis];
                badMax[axis] = upper[axis];
            }
    }
    for (int axis = 0; axis < 3; ++axis)
        if (firstBad[axis] >= 0)
            v.fail(kAxisVuids[axis], "%s geometry %u: AABB %lld has min%c %g greater than max%c %g.", where, g,
                   (long long)firstBad[axis], kAxisNames[axis], double(badMin[axis]), kAxisNames[axis],
                   double(badMax[axis]));
}

void checkTrianglesRange(Validator& v, const VkAccelerationStructureGeometryTrianglesDataKHR& t,
                         const VkAccelerationStructureBuildRangeInfoKHR& r, const char* where, uint32_t g) {
    const VertexFormatInfo* fmt = vertexFormatInfo(t.vertexFormat);
    const bool indexed = t.indexType != VK_INDEX_TYPE_NONE_KHR;
    if (r.primitiveCount != 0) {
        v.check(t.vertexData.hostAddress != nullptr, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03771",
                "%s geometry %u: triangles.vertexData.hostAddress is NULL.", where, g);
        if (indexed)
            v.check(t.indexData.hostAddress != nullptr, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03772",
                    "%s geometry %u: triangles.indexData.hostAddress is NULL with indexType %d.", where, g,
                    int(t.indexType));
    }
    if (indexed) {
        uint32_t indexSize = t.indexType == VK_INDEX_TYPE_UINT16 ? 2 : 4;
        v.check(r.primitiveOffset % indexSize == 0,
                "VUID-VkAccelerationStructureBuildRangeInfoKHR-primitiveOffset-03656",
                "%s geometry %u: primitiveOffset %u is not a multiple of the index size %u.", where, g,
                r.primitiveOffset, indexSize);
    } else if (fmt) {
        uint32_t unit = fmt->packed ? fmt->size : fmt->componentSize;
        v.check(r.primitiveOffset % unit == 0,
                "VUID-VkAccelerationStructureBuildRangeInfoKHR-primitiveOffset-03657",
                "%s geometry %u: primitiveOffset %u is not a multiple of %u.", where, g, r.primitiveOffset,
                unit);
    }
    if (t.transformData.hostAddress != nullptr &&
        v.check(r.transformOffset % 16 == 0,
                "VUID-VkAccelerationStructureBuildRangeInfoKHR-transformOffset-03658",
                "%s geometry %u: transformOffset %u is not a multiple of 16.", where, g, r.transformOffset)) {
        float m[3][4];
        std::memcpy(m, static_cast<const std::byte*>(t.transformData.hostAddress) + r.transformOffset,
                    sizeof m);
        v.check(invertible3x3(m), "VUID-VkTransformMatrixKHR-matrix-03799",
                "%s geometry %u: the transform at transformData + %u is not invertible.", where, g,
                r.transformOffset);
    }
    if (const auto* motionData = motion::findMotionTriangles(t))
        v.check(motionData->vertexData.hostAddress != nullptr,
                "VUID-vkBuildAccelerationStructuresKHR-pInfos-11820",
                "%s geometry %u: VkAccelerationStructureGeometryMotionTrianglesDataNV::vertexData.hostAddress "
                "is NULL.",
                where, g);
    // maxVertex against the vertices actually read.
    if (r.primitiveCount != 0 && t.vertexData.hostAddress && (!indexed || t.indexData.hostAddress) &&
        v.failureCount() == 0) {
        if (!indexed) {
            uint64_t last = uint64_t(r.firstVertex) + 3ull * r.primitiveCount - 1;
            v.check(last <= t.maxVertex, "VUID-VkAccelerationStructureBuildRangeInfoKHR-None-10775",
                    "%s geometry %u: firstVertex %u + 3 * primitiveCount %u - 1 = %llu exceeds maxVertex %u.",
                    where, g, r.firstVertex, r.primitiveCount, (ull)last, t.maxVertex);
        } else {
            TriangleSource source(t, r);
            uint64_t maxIndex = 0;
            for (uint32_t p = 0; p < r.primitiveCount; ++p)
                for (uint32_t j = 0; j < 3; ++j) maxIndex = std::max(maxIndex, source.vertexIndex(p, j));
            uint64_t last = uint64_t(r.firstVertex) + maxIndex;
            v.check(last <= t.maxVertex, "VUID-VkAccelerationStructureBuildRangeInfoKHR-maxVertex-10774",
                    "%s geometry %u: firstVertex %u + the largest index %llu exceeds maxVertex %u.", where, g,
                    r.firstVertex, (ull)maxIndex, t.maxVertex);
        }
    }
}

bool checkInstancesRange(Validator& v, const Device& dev, const VkAccelerationStructureGeometryInstancesDataKHR& inst,
                         const VkAccelerationStructureBuildRangeInfoKHR& r,
                         VkBuildAccelerationStructureFlagsKHR buildFlags, const char* where,
                         HostVector<const AccelerationStructure*>& referenced) {
    v.check(r.primitiveOffset % 16 == 0, "VUID-VkAccelerationStructureBuildRangeInfoKHR-primitiveOffset-03660",
            "%s: primitiveOffset %u is not a multiple of 16.", where, r.primitiveOffset);
    if (!v.check(r.primitiveCount <= limits::kMaxInstanceCount,
                 "VUID-vkBuildAccelerationStructuresKHR-pInfos-03801",
                 "%s: primitiveCount %u exceeds maxInstanceCount.", where, r.primitiveCount))
        return false;  // nothing is read from a build that large
    if (r.primitiveCount != 0 && motion::isMotionBuild(buildFlags) && inst.data.hostAddress != nullptr &&
        r.primitiveOffset % 16 == 0) {
        // [NV-motion] VkAccelerationStructureMotionInstanceNV records (or typed pointers to their members).
        motion::MotionInstanceSource source(inst, r);
        for (uint32_t k = 0; k < r.primitiveCount; ++k) {
            if (inst.arrayOfPointers &&
                !v.check((source.rawAddress(k) & ~uintptr_t(0xF)) != 0,
                         "VUID-vkBuildAccelerationStructuresKHR-pInfos-03778",
                         "%s: instance pointer %u is NULL.", where, k))
                continue;
            motion::RawMotionInstance mi;
            source.fetch(k, mi);
            if (!v.check(mi.type <= motion::kSrt, "VUID-VkAccelerationStructureMotionInstanceNV-type-parameter",
                         "%s: motion instance %u has type %u, not a VkAccelerationStructureMotionInstanceTypeNV.",
                         where, k, mi.type))
                continue;
            v.check(mi.flags == 0, "VUID-VkAccelerationStructureMotionInstanceNV-flags-zerobitmask",
                    "%s: motion instance %u has flags 0x%x.", where, k, mi.flags);
            static const char* const kFlagVuids[3] = {
                "VUID-VkAccelerationStructureInstanceKHR-flags-parameter",
                "VUID-VkAccelerationStructureMatrixMotionInstanceNV-flags-parameter",
                "VUID-VkAccelerationStructureSRTMotionInstanceNV-flags-parameter"};
            checkInstanceBody(v, mi.type == motion::kStatic ? mi.staticTransform : nullptr,
                              mi.sbtOffsetAndFlags, kFlagVuids[mi.type], where, k);
            if (mi.reference == 0) continue;
            const auto* blas = dev.live<AccelerationStructure>(reinterpret_cast<const void*>(mi.reference),
                                                               ObjectMagic::AccelerationStructure);
            if (!v.check(blas != nullptr, "VUID-vkBuildAccelerationStructuresKHR-pInfos-04930",
                         "%s: motion instance %u references 0x%llx, which is not a live "
                         "VkAccelerationStructureKHR.",
                         where, k, (ull)mi.reference))
                continue;
            v.check(blas->buffer->memory != nullptr, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03709",
                    "%s: instance %u references a structure whose buffer is not bound to memory.", where, k);
            referenced.push_back(blas);
            if (v.failureCount() > 16) break;  // enough said
        }
    } else if (r.primitiveCount != 0 &&
        v.check(inst.data.hostAddress != nullptr, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03778",
                "%s: instances.data.hostAddress is NULL.", where) &&
        r.primitiveOffset % 16 == 0) {
        InstanceSource source(inst, r);
        for (uint32_t k = 0; k < r.primitiveCount; ++k) {
            if (inst.arrayOfPointers &&
                !v.check(loadUnaligned<const void*>(static_cast<const std::byte*>(inst.data.hostAddress) +
                                                   r.primitiveOffset + 8ull * k) != nullptr,
                         "VUID-vkBuildAccelerationStructuresKHR-pInfos-03778",
                         "%s: instance pointer %u is NULL.", where, k))
                continue;
            RawInstance ri = source.fetch(k);
            checkInstanceBody(v, ri.transform, ri.sbtOffsetAndFlags,
                              "VUID-VkAccelerationStructureInstanceKHR-flags-parameter", where, k);
            if (ri.reference == 0) continue;
            const auto* blas = dev.live<AccelerationStructure>(reinterpret_cast<const void*>(ri.reference),
                                                               ObjectMagic::AccelerationStructure);
            if (!v.check(blas != nullptr, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03779",
                         "%s: instance %u references 0x%llx, which is not a live VkAccelerationStructureKHR.",
                         where, k, (ull)ri.reference))
                continue;
            v.check(blas->buffer->memory != nullptr, "VUID-vkBuildAccelerationStructuresKHR-pInfos-03709",
                    "%s: instance %u references a structure whose buffer is not bound to memory.", where, k);
            referenced.push_back(blas);
            if (v.failureCount() > 16) break;  // enough said
        }
    }
    return true;
}

}  // namespace vkas
