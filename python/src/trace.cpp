// vkas._core's tracing through vkasTraceRays: the Device's intersect and occluded (rays packed from the arrays into
// the device's pooled batch buffers, hits unpacked into numpy arrays), the ray-flag check, and the two hooks of the
// overhead bench (pack_rays, time_trace_rays).
#include <chrono>
#include <limits>

#include "arrays.hpp"

namespace vkas_python {

void Device::checkRayFlags(const StructurePtr& tlas, uint32_t flags, uint32_t mask) {
    checkFlags(*d, tlas ? tlas->as : VK_NULL_HANDLE, flags, mask);
}

// intersect (anyHit false) and occluded (anyHit true).
py::object Device::trace(const StructurePtr& tlas, const py::array& origins, const py::array& directions,
                         const py::array& tmin, const py::array& tmax, uint32_t flags, uint32_t mask, bool anyHit) {
    const RayInputs in = rayInputs(origins, directions, tmin, tmax);
    const VkAccelerationStructureKHR as = tlas ? tlas->as : VK_NULL_HANDLE;
    const size_t n = in.count;
    struct Lease {
        DeviceImpl& d;
        std::unique_ptr<DeviceImpl::Batch> b;
        ~Lease() { d.giveBatch(std::move(b)); }
    } lease{*d, d->takeBatch(n)};
    VkasRay* rays = lease.b->rays.get();
    const VkasHit* hits = lease.b->hits.get();
    packRays(*d, in, rays);
    {
        Capture capture;
        VkResult r;
        {
            py::gil_scoped_release release;
            r = vkasTraceRays(d->device, as, anyHit ? VKAS_TRACE_MODE_ANY_HIT : VKAS_TRACE_MODE_CLOSEST_HIT, flags,
                              mask, uint32_t(n), rays, lease.b->hits.get());
        }
        capture.check(r, "vkasTraceRays");
    }
    if (anyHit) {
        py::array_t<bool> out{py::ssize_t(n)};
        bool* o = out.mutable_data();
        py::gil_scoped_release release;
        parallelChunks(n, 1 << 16, d->threads, [&](size_t, size_t a, size_t b) {
            for (size_t i = a; i < b; ++i) o[i] = hits[i].type != VKAS_COMMITTED_INTERSECTION_NONE;
        });
        return out;
    }
    const py::ssize_t sn = py::ssize_t(n);
    py::array_t<float> t(sn);
    py::array_t<int32_t> prim(sn), geom(sn), inst(sn), custom(sn);
    py::array_t<float> bary({sn, py::ssize_t(2)});
    py::array_t<bool> front(sn);
    float* pt = t.mutable_data();
    int32_t *pp = prim.mutable_data(), *pg = geom.mutable_data(), *pi = inst.mutable_data(),
            *pc = custom.mutable_data();
    float* pb = bary.mutable_data();
    bool* pf = front.mutable_data();
    {
        py::gil_scoped_release release;
        parallelChunks(n, 1 << 16, d->threads, [&](size_t, size_t a, size_t b) {
            const float inf = std::numeric_limits<float>::infinity();
            for (size_t i = a; i < b; ++i) {
                const VkasHit& h = hits[i];
                if (h.type == VKAS_COMMITTED_INTERSECTION_NONE) {
                    pt[i] = inf;
                    pp[i] = pg[i] = pi[i] = pc[i] = -1;
                    pb[2 * i] = pb[2 * i + 1] = 0.0f;
                    pf[i] = false;
                } else {
                    pt[i] = h.t;
                    pp[i] = h.primitiveIndex, pg[i] = h.geometryIndex, pi[i] = h.instanceId;
                    pc[i] = h.instanceCustomIndex;
                    pb[2 * i] = h.barycentrics[0], pb[2 * i + 1] = h.barycentrics[1];
                    pf[i] = h.frontFace != VK_FALSE;
                }
            }
        });
    }
    return py::make_tuple(t, prim, geom, inst, custom, bary, front);
}

// For the overhead bench: vkasTraceRays alone on rays packed beforehand (pack_rays), best of `repeats` runs.
double Device::timeTraceRays(const StructurePtr& tlas, const py::array& packed, uint32_t flags, uint32_t mask,
                             bool anyHit, int repeats) {
    const float* p = arrayData<float>(packed, "packed", {-1, 8});
    const size_t n = size_t(packed.shape(0));
    // The device's pooled hit buffer, as intersect uses it (warm memory on both sides).
    struct Lease {
        DeviceImpl& d;
        std::unique_ptr<DeviceImpl::Batch> b;
        ~Lease() { d.giveBatch(std::move(b)); }
    } lease{*d, d->takeBatch(n)};
    VkasHit* hits = lease.b->hits.get();
    double best = 1e300;
    Capture capture;
    VkResult r = VK_SUCCESS;
    {
        py::gil_scoped_release release;
        for (int k = 0; k < std::max(repeats, 1) && r == VK_SUCCESS; ++k) {
            const auto t0 = std::chrono::steady_clock::now();
            r = vkasTraceRays(d->device, tlas ? tlas->as : VK_NULL_HANDLE,
                              anyHit ? VKAS_TRACE_MODE_ANY_HIT : VKAS_TRACE_MODE_CLOSEST_HIT, flags, mask,
                              uint32_t(n), reinterpret_cast<const VkasRay*>(p), hits);
            best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
        }
    }
    capture.check(r, "vkasTraceRays");
    return best;
}

py::array Device::packRaysForBench(const py::array& origins, const py::array& directions, const py::array& tmin,
                                   const py::array& tmax) {
    const RayInputs in = rayInputs(origins, directions, tmin, tmax);
    py::array_t<float> out({py::ssize_t(in.count), py::ssize_t(8)});
    static_assert(sizeof(VkasRay) == 32);
    packRays(*d, in, reinterpret_cast<VkasRay*>(out.mutable_data()));
    return out;
}

}  // namespace vkas_python
