// vkasTraceRays: many rays, each traced as a ray query run to completion would trace it, spread over the worker
// threads.
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>

#include "api/device.hpp"
#include "api/command_memory.hpp"
#include "api/exception_result.hpp"
#include "api/validate/batch_trace_calls.hpp"
#include "engine/trace/batch_kernel.hpp"
#include "engine/trace/batch_schedule.hpp"
#include "engine/trace/packet_gather.hpp"
#include "engine/trace/ray_query.hpp"

namespace {

void writeHit(const vkas::QueryHit& h, VkasHit& out) {
    out.type = h.type;
    out.t = h.t;
    if (h.type == vkas::kCommittedNone) {
        out.instanceId = out.instanceCustomIndex = out.geometryIndex = out.primitiveIndex = -1;
        out.barycentrics[0] = out.barycentrics[1] = 0.0f;
        out.instanceShaderBindingTableRecordOffset = 0;
        out.frontFace = VK_FALSE;
        return;
    }
    out.instanceId = int32_t(h.instance->instanceId);
    out.instanceCustomIndex = int32_t(h.instance->customIndexAndMask & 0xFFFFFFu);
    out.instanceShaderBindingTableRecordOffset = h.instance->sbtOffsetAndFlags & 0xFFFFFFu;
    out.geometryIndex = vkas::hitGeometryIndex(h);
    out.primitiveIndex = vkas::hitPrimitiveIndex(h);
    out.barycentrics[0] = h.barycentrics[0];
    out.barycentrics[1] = h.barycentrics[1];
    out.frontFace = h.frontFace ? VK_TRUE : VK_FALSE;
}

// Runs one query to completion the way a pipeline without any-hit shaders would: non-opaque triangles are
// accepted, and AABB candidates go to the intersection callback (none: never a hit).
void runQuery(vkas::RayQueryState& q, uint32_t rayIndex, PFN_vkasIntersectAabb intersect, void* userData) {
    if (!intersect) {
        vkas::queryRunToCompletion(q);
        return;
    }
    while (vkas::queryProceed(q)) {
        const vkas::QueryHit& c = q.candidate;
        if (c.type != vkas::kCandidateAabb) {
            vkas::queryConfirm(q);
            continue;
        }
        VkasAabbCandidate info{};
        info.rayIndex = rayIndex;
        info.instanceId = int32_t(c.instance->instanceId);
        info.instanceCustomIndex = int32_t(c.instance->customIndexAndMask & 0xFFFFFFu);
        info.geometryIndex = vkas::hitGeometryIndex(c);
        info.primitiveIndex = vkas::hitPrimitiveIndex(c);
        std::memcpy(info.objectRayOrigin, c.objectOrigin, sizeof info.objectRayOrigin);
        std::memcpy(info.objectRayDirection, c.objectDirection, sizeof info.objectRayDirection);
        info.tMin = q.tMin;
        info.tMax = q.tMax;
        info.opaque = c.aabbOpaque ? VK_TRUE : VK_FALSE;
        float tHit = 0.0f;
        if (intersect(userData, &info, &tHit) && tHit >= q.tMin && tHit <= q.tMax) vkas::queryGenerate(q, tHit);
    }
}

VkResult traceBatch(VkDevice device, VkAccelerationStructureKHR topLevel, VkasTraceMode mode, uint32_t rayFlags,
                    uint32_t cullMask, uint32_t rayCount, const VkasRay* pRays, VkasHit* pHits,
                    PFN_vkasIntersectAabb intersect, void* userData, const vkas::TraceVuids& vuids) {
    vkas::Device* dev = vkas::Device::fromHandle(device);
    vkas::Validator v(dev, vuids.command);
    if (!vkas::checkTraceDevice(v, dev, vuids)) return VK_ERROR_VALIDATION_FAILED_EXT;
    const vkas::AccelerationStructure* tlas = nullptr;
    if (topLevel != VK_NULL_HANDLE) {
        tlas = dev->validationEnabled()
                   ? dev->live<vkas::AccelerationStructure>(topLevel, vkas::ObjectMagic::AccelerationStructure)
                   : vkas::fromHandle<vkas::AccelerationStructure>(topLevel);
    }
    if (!vkas::checkTraceBatch(v, topLevel, tlas, mode, rayFlags, rayCount, pRays, pHits, vuids))
        return VK_ERROR_VALIDATION_FAILED_EXT;
    const std::byte* block = tlas ? tlas->block() : nullptr;
    // Without an intersection step an AABB candidate never becomes a hit, so AABB instances are skipped
    // outright; the flag only ever removes candidates that would be dropped anyway.
    const uint32_t flags = rayFlags | (intersect ? 0u : VKAS_RAY_FLAG_SKIP_AABBS) |
                           (mode == VKAS_TRACE_MODE_ANY_HIT ? VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT : 0u);
    const uint64_t tasks = (uint64_t(rayCount) + vkas::kRaysPerTask - 1) / vkas::kRaysPerTask;
    // Without an intersection callback the engine's schedule (engine/trace/batch_schedule.hpp) traces the rays with
    // the batch kernels, coherent closest-hit rays as packets; a ray they do not cover (motion, spheres, LSS) and
    // every ray of vkasTraceRaysProcedural run as ray queries here. All give the same hits.
    vkas::BatchSchedule schedule(block, vkas::resolveAccelerationStructure,
                                 intersect ? vkas::PacketPolicy::Off : vkas::packetPolicy());
    dev->workers().parallelFor(tasks, [&](uint64_t task) {
        // 11 KiB and more: kept off small worker stacks, in the command's host memory (the pool's workers run with it).
        vkas::HostUnique<vkas::PacketScratch> scratch;
        vkas::HostUnique<vkas::RayQueryState> q;
        const uint64_t first = task * vkas::kRaysPerTask;
        const uint32_t n = uint32_t(std::min<uint64_t>(rayCount, first + vkas::kRaysPerTask) - first);
        auto traceAsQuery = [&](uint32_t k) {
            const uint64_t i = first + k;
            const VkasRay& r = pRays[i];
            if (!q) q = vkas::makeHostUnique<vkas::RayQueryState>();
            vkas::queryInitialize(*q, block, vkas::resolveAccelerationStructure, flags, cullMask, r.origin, r.tMin,
                                  r.direction, r.tMax);
            vkas::queryWithoutKernel(*q);  // the kernel declined this ray, or AABB candidates go to `intersect`
            runQuery(*q, uint32_t(i), intersect, userData);
            writeHit(q->committed, pHits[i]);
        };
        if (intersect) {
            for (uint32_t k = 0; k < n; ++k) traceAsQuery(k);
            return;
        }
        scratch = vkas::makeHostUniqueForOverwrite<vkas::PacketScratch>();
        vkas::KernelRay rays[vkas::kRaysPerTask];
        for (uint32_t k = 0; k < n; ++k) {
            const VkasRay& r = pRays[first + k];
            rays[k] = {{r.origin[0], r.origin[1], r.origin[2]}, {r.direction[0], r.direction[1], r.direction[2]},
                       r.tMin, r.tMax, flags, cullMask};
        }
        vkas::traceBatchTask(
            schedule, rays, n, *scratch,
            [&](uint32_t k, const vkas::QueryHit& hit) { writeHit(hit, pHits[first + k]); }, traceAsQuery);
    });
    return VK_SUCCESS;
}

}  // namespace

extern "C" VKAS_API VkResult vkasTraceRays(VkDevice device, VkAccelerationStructureKHR topLevel, VkasTraceMode mode,
                                           uint32_t rayFlags, uint32_t cullMask, uint32_t rayCount,
                                           const VkasRay* pRays, VkasHit* pHits) {
    vkas::CommandHostMemory<VkDevice> memory(device);
    return vkas::guarded([&] {
        return traceBatch(device, topLevel, mode, rayFlags, cullMask, rayCount, pRays, pHits, nullptr, nullptr,
                          vkas::kTraceRaysVuids);
    });
}

extern "C" VKAS_API VkResult vkasTraceRaysProcedural(VkDevice device, VkAccelerationStructureKHR topLevel,
                                                     VkasTraceMode mode, uint32_t rayFlags, uint32_t cullMask,
                                                     uint32_t rayCount, const VkasRay* pRays, VkasHit* pHits,
                                                     PFN_vkasIntersectAabb pfnIntersect, void* pUserData) {
    vkas::CommandHostMemory<VkDevice> memory(device);
    return vkas::guarded([&] {
        return traceBatch(device, topLevel, mode, rayFlags, cullMask, rayCount, pRays, pHits, pfnIntersect,
                          pUserData, vkas::kTraceRaysProceduralVuids);
    });
}
