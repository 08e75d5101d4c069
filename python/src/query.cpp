// vkas._core's ray queries: the Device's intersect_all, every hit along each ray through the vkasRayQuery* functions
// (candidates collected, none confirmed), sorted and gathered into numpy arrays.
#include <algorithm>

#include "arrays.hpp"

namespace vkas_python {

// Every hit along each ray (candidates of ray queries with NoOpaque, none confirmed, so none shortens the ray),
// sorted by t, then instance, geometry and primitive; at most maxHits a ray (0: all).
py::tuple Device::traceAll(const StructurePtr& tlas, const py::array& origins, const py::array& directions,
                           const py::array& tmin, const py::array& tmax, uint32_t flags, uint32_t mask,
                           uint32_t maxHits) {
    const RayInputs in = rayInputs(origins, directions, tmin, tmax);
    const VkAccelerationStructureKHR as = tlas ? tlas->as : VK_NULL_HANDLE;
    {
        // Only the checks: the rays are read in place below.
        RayError err;
        bool ok;
        {
            py::gil_scoped_release release;
            ok = checkRays(in, 0, in.count, nullptr, err);
        }
        if (!ok) throwRayError(err);
    }
    checkFlags(*d, as, flags, mask);
    struct AllHit {
        uint32_t ray;
        float t;
        int32_t inst, custom, geom, prim;
        float b0, b1;
        bool front;
    };
    constexpr size_t kChunk = 512;
    const size_t n = in.count;
    const size_t chunks = (n + kChunk - 1) / kChunk;
    std::vector<std::vector<AllHit>> found(chunks);
    {
        py::gil_scoped_release release;
        parallelChunks(n, kChunk, d->threads, [&](size_t c, size_t a, size_t b) {
            auto q = std::make_unique<VkasRayQuery>();
            std::vector<AllHit>& out = found[c];
            for (size_t i = a; i < b; ++i) {
                const float* o = in.origins + 3 * i;
                const float* dir = in.directions + 3 * i;
                vkasRayQueryInitialize(q.get(), as, flags, mask, o, in.tmin[i * in.tminStride], dir,
                                       in.tmax[i * in.tmaxStride]);
                const size_t start = out.size();
                while (vkasRayQueryProceed(q.get())) {
                    if (vkasRayQueryGetIntersectionType(q.get(), VK_FALSE) != VKAS_CANDIDATE_INTERSECTION_TRIANGLE)
                        continue;  // AABBs: no intersection shader here
                    AllHit h;
                    h.ray = uint32_t(i);
                    h.t = vkasRayQueryGetIntersectionT(q.get(), VK_FALSE);
                    h.inst = vkasRayQueryGetIntersectionInstanceId(q.get(), VK_FALSE);
                    h.custom = vkasRayQueryGetIntersectionInstanceCustomIndex(q.get(), VK_FALSE);
                    h.geom = vkasRayQueryGetIntersectionGeometryIndex(q.get(), VK_FALSE);
                    h.prim = vkasRayQueryGetIntersectionPrimitiveIndex(q.get(), VK_FALSE);
                    float bc[2];
                    vkasRayQueryGetIntersectionBarycentrics(q.get(), VK_FALSE, bc);
                    h.b0 = bc[0], h.b1 = bc[1];
                    h.front = vkasRayQueryGetIntersectionFrontFace(q.get(), VK_FALSE) != VK_FALSE;
                    out.push_back(h);
                }
                std::sort(out.begin() + std::ptrdiff_t(start), out.end(), [](const AllHit& x, const AllHit& y) {
                    if (x.t != y.t) return x.t < y.t;
                    if (x.inst != y.inst) return x.inst < y.inst;
                    if (x.geom != y.geom) return x.geom < y.geom;
                    return x.prim < y.prim;
                });
                if (maxHits && out.size() - start > maxHits) out.resize(start + maxHits);
            }
        });
    }
    size_t total = 0;
    for (const auto& v : found) total += v.size();
    const py::ssize_t sn = py::ssize_t(total);
    py::array_t<int64_t> ray(sn);
    py::array_t<float> t(sn);
    py::array_t<int32_t> prim(sn), geom(sn), inst(sn), custom(sn);
    py::array_t<float> bary({sn, py::ssize_t(2)});
    py::array_t<bool> front(sn);
    int64_t* pr = ray.mutable_data();
    float* pt = t.mutable_data();
    int32_t *pp = prim.mutable_data(), *pg = geom.mutable_data(), *pi = inst.mutable_data(),
            *pc = custom.mutable_data();
    float* pb = bary.mutable_data();
    bool* pf = front.mutable_data();
    {
        py::gil_scoped_release release;
        size_t k = 0;
        for (const auto& v : found)
            for (const AllHit& h : v) {
                pr[k] = h.ray, pt[k] = h.t, pp[k] = h.prim, pg[k] = h.geom, pi[k] = h.inst, pc[k] = h.custom;
                pb[2 * k] = h.b0, pb[2 * k + 1] = h.b1, pf[k] = h.front;
                ++k;
            }
    }
    return py::make_tuple(ray, t, prim, geom, inst, custom, bary, front);
}

}  // namespace vkas_python
