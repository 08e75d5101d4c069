// vkas._core's array checks and ray inputs, shared by the translation units: arrayData (dtype, shape, contiguity and
// alignment of an array handed to the extension), the ray inputs with their checks and packing (defined in
// rays.cpp) and parallelChunks, the chunked loop of batch calls over the device's threads.
#pragma once

#include <atomic>
#include <thread>

#include "core.hpp"

namespace vkas_python {

// ------------------------------------------------------------------------------------------------------------------
// Array checks (the Python layer has converted already; these keep the extension safe on its own)

template <class T>
const T* arrayData(const py::array& a, const char* name, std::initializer_list<py::ssize_t> shape) {
    if (!py::isinstance<py::array_t<T>>(a) || !a.dtype().is(py::dtype::of<T>()))
        throw py::type_error(std::string(name) + ": wrong dtype for vkas._core");
    if (!(a.flags() & py::array::c_style)) throw py::value_error(std::string(name) + ": not C-contiguous");
    if (reinterpret_cast<uintptr_t>(a.data()) % alignof(T) != 0)
        throw py::value_error(std::string(name) + ": not aligned to " + std::to_string(alignof(T)) + " bytes");
    if (size_t(a.ndim()) != shape.size()) throw py::value_error(std::string(name) + ": wrong number of dimensions");
    size_t k = 0;
    for (py::ssize_t s : shape) {
        if (s >= 0 && a.shape(k) != s) throw py::value_error(std::string(name) + ": wrong shape");
        ++k;
    }
    return static_cast<const T*>(a.data());
}

// ------------------------------------------------------------------------------------------------------------------
// Rays

struct RayError {
    int64_t index = -1;
    int kind = 0;  // 1 origin, 2 direction, 3 tmin/tmax NaN, 4 negative, 5 tmin > tmax
    float values[3] = {0, 0, 0};
};

struct RayInputs {
    const float* origins = nullptr;
    const float* directions = nullptr;
    const float* tmin = nullptr;
    const float* tmax = nullptr;
    size_t tminStride = 0, tmaxStride = 0;  // 0 for a scalar
    size_t count = 0;
};

RayInputs rayInputs(const py::array& origins, const py::array& directions, const py::array& tmin,
                    const py::array& tmax);
bool checkRays(const RayInputs& in, size_t first, size_t last, VkasRay* out, RayError& err);
[[noreturn]] void throwRayError(const RayError& e);
void packRays(const DeviceImpl& d, const RayInputs& in, VkasRay* rays);
void checkFlags(DeviceImpl& d, VkAccelerationStructureKHR tlas, uint32_t flags, uint32_t mask);

// Runs fn(first, last) over [0, n) in chunks on `threads` threads (the calling one included).
template <class Fn>
void parallelChunks(size_t n, size_t chunk, unsigned threads, Fn&& fn) {
    const size_t chunks = (n + chunk - 1) / chunk;
    if (threads <= 1 || chunks <= 1) {
        for (size_t c = 0; c < chunks; ++c) fn(c, c * chunk, std::min(n, (c + 1) * chunk));
        return;
    }
    std::atomic<size_t> next{0};
    std::exception_ptr error;
    std::mutex errorMutex;
    auto work = [&] {
        try {
            for (size_t c; (c = next.fetch_add(1)) < chunks;) fn(c, c * chunk, std::min(n, (c + 1) * chunk));
        } catch (...) {
            std::lock_guard<std::mutex> lock(errorMutex);
            if (!error) error = std::current_exception();
            next = chunks;
        }
    };
    std::vector<std::thread> pool;
    const unsigned extra = unsigned(std::min<size_t>(threads, chunks)) - 1;
    pool.reserve(extra);
    for (unsigned k = 0; k < extra; ++k) pool.emplace_back(work);
    work();
    for (auto& t : pool) t.join();
    if (error) std::rethrow_exception(error);
}

}  // namespace vkas_python
