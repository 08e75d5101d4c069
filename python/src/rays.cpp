// vkas._core's ray inputs: the origins, directions, tmin and tmax arrays read in place, the value rules of
// OpRayQueryInitializeKHR checked ray by ray (with the ValueError naming the first bad ray), rays packed into VkasRay
// records, and the ray-flag rules checked through vkasTraceRays.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>

#include "arrays.hpp"

namespace vkas_python {

RayInputs rayInputs(const py::array& origins, const py::array& directions, const py::array& tmin,
                    const py::array& tmax) {
    RayInputs in;
    in.origins = arrayData<float>(origins, "origins", {-1, 3});
    in.count = size_t(origins.shape(0));
    in.directions = arrayData<float>(directions, "directions", {py::ssize_t(in.count), 3});
    auto tArray = [&](const py::array& a, const char* name, const float*& p, size_t& stride) {
        if (a.ndim() == 0) {
            p = arrayData<float>(a, name, {});
            stride = 0;
        } else {
            p = arrayData<float>(a, name, {py::ssize_t(in.count)});
            stride = 1;
        }
    };
    tArray(tmin, "tmin", in.tmin, in.tminStride);
    tArray(tmax, "tmax", in.tmax, in.tmaxStride);
    if (in.count > std::numeric_limits<uint32_t>::max())
        throw py::value_error("origins: at most 2**32 - 1 rays a call");
    return in;
}

// Checks the ray rules of OpRayQueryInitializeKHR that concern values (finite origin and direction, tMin and tMax
// not NaN, non-negative, tMin <= tMax) for rays [first, last) and packs them into VkasRay records when out is set.
bool checkRays(const RayInputs& in, size_t first, size_t last, VkasRay* out, RayError& err) {
    for (size_t i = first; i < last; ++i) {
        const float* o = in.origins + 3 * i;
        const float* dir = in.directions + 3 * i;
        const float t0 = in.tmin[i * in.tminStride], t1 = in.tmax[i * in.tmaxStride];
        int kind = 0;
        if (!(std::isfinite(o[0]) && std::isfinite(o[1]) && std::isfinite(o[2])))
            kind = 1;
        else if (!(std::isfinite(dir[0]) && std::isfinite(dir[1]) && std::isfinite(dir[2])))
            kind = 2;
        else if (std::isnan(t0) || std::isnan(t1))
            kind = 3;
        else if (t0 < 0.0f || t1 < 0.0f)
            kind = 4;
        else if (t0 > t1)
            kind = 5;
        if (kind) {
            err.index = int64_t(i);
            err.kind = kind;
            const float* v = kind == 1 ? o : kind == 2 ? dir : nullptr;
            if (v) std::memcpy(err.values, v, sizeof err.values);
            else err.values[0] = t0, err.values[1] = t1;
            return false;
        }
        if (out) {
            VkasRay& r = out[i];
            r.origin[0] = o[0], r.origin[1] = o[1], r.origin[2] = o[2];
            r.tMin = t0;
            r.direction[0] = dir[0], r.direction[1] = dir[1], r.direction[2] = dir[2];
            r.tMax = t1;
        }
    }
    return true;
}

namespace {

std::string fmt(float v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.9g", double(v));
    return b;
}

}  // namespace

[[noreturn]] void throwRayError(const RayError& e) {
    const std::string i = std::to_string(e.index);
    const float* v = e.values;
    switch (e.kind) {
        case 1:
            throw py::value_error("origins: ray " + i + " has a non-finite origin (" + fmt(v[0]) + ", " + fmt(v[1]) +
                                  ", " + fmt(v[2]) + "); origins must be finite (VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06348)");
        case 2:
            throw py::value_error("directions: ray " + i + " has a non-finite direction (" + fmt(v[0]) + ", " +
                                  fmt(v[1]) + ", " + fmt(v[2]) +
                                  "); directions must be finite (VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06348)");
        case 3:
            throw py::value_error(std::string(std::isnan(v[0]) ? "tmin" : "tmax") + ": ray " + i + " has tmin " +
                                  fmt(v[0]) + ", tmax " + fmt(v[1]) +
                                  "; they must not be NaN (VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06351)");
        case 4:
            throw py::value_error(std::string(v[0] < 0 ? "tmin" : "tmax") + ": ray " + i + " has tmin " + fmt(v[0]) +
                                  ", tmax " + fmt(v[1]) +
                                  "; they must be >= 0 (VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06349)");
        default:
            throw py::value_error("tmin: ray " + i + " has tmin " + fmt(v[0]) + " > tmax " + fmt(v[1]) +
                                  " (VUID-RuntimeSpirv-OpRayQueryInitializeKHR-06350)");
    }
}

// Packs and checks rays (in parallel for big batches) into rays; throws ValueError for the first bad ray.
void packRays(const DeviceImpl& d, const RayInputs& in, VkasRay* rays) {
    constexpr size_t kChunk = 1 << 16;
    const size_t chunks = (in.count + kChunk - 1) / kChunk;
    std::vector<RayError> errors(std::max<size_t>(chunks, 1));
    {
        py::gil_scoped_release release;
        parallelChunks(in.count, kChunk, d.threads,
                       [&](size_t c, size_t a, size_t b) { checkRays(in, a, b, rays, errors[c]); });
    }
    for (const RayError& e : errors)
        if (e.kind) throwRayError(e);  // the first bad ray: chunks are in ray order
}

// The ray-flag rules (06889-06891) and the top level (06352), as vkasTraceRays checks them: with zero rays, on the
// calling thread, so that the messages reach the Capture.
void checkFlags(DeviceImpl& d, VkAccelerationStructureKHR tlas, uint32_t flags, uint32_t mask) {
    Capture capture;
    capture.check(vkasTraceRays(d.device, tlas, VKAS_TRACE_MODE_CLOSEST_HIT, flags, mask, 0, nullptr, nullptr),
                  "vkasTraceRays");
}

}  // namespace vkas_python
