// vkas._core's shared declarations: the pybind11 extension behind the vkas Python package (docs/PYTHON.md).
//
// It uses the public C API only (include/vkas/vkas.h): a device with a debug messenger, the Vulkan commands from
// vkasGetDeviceProcAddr for buffers, builds, copies, serialization and queries, vkasTraceRays for batches of rays and
// the vkasRayQuery* functions for intersect_all. The Python layer (vkas/*.py) checks and converts the arguments;
// the extension still checks every array it is given (dtype, shape, contiguity, arrays.hpp) so that nothing it is
// handed can make it read out of bounds. Builds and traces run with the GIL released.
//
// This header owns what every translation unit shares: the validation-message Capture, DeviceImpl (the device, its
// commands and batch buffers), Structure (one acceleration structure) and the Python-facing Device. They are defined
// by concern in module.cpp (the module, the device), structures.cpp (structures, copies, serialization), builds.cpp
// (builds and updates), rays.cpp (ray inputs), trace.cpp (vkasTraceRays) and query.cpp (ray queries).
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cstring>
#include <exception>
#include <memory>
#include <mutex>
#include <new>
#include <stdexcept>
#include <string>
#include <vector>

#include "vkas/vkas.h"

namespace py = pybind11;

namespace vkas_python {

// ------------------------------------------------------------------------------------------------------------------
// Validation messages: vkas reports each broken valid-usage rule through the device's messenger. Every command this
// module issues runs inside a Capture on the calling thread; what it collected becomes a vkas.ValidationError.

struct Message {
    std::string vuid, text;
};

inline thread_local std::vector<Message>* tlCapture = nullptr;

struct ValidationFailure : std::exception {
    std::vector<Message> messages;
    explicit ValidationFailure(std::vector<Message> m) : messages(std::move(m)) {}
    const char* what() const noexcept override { return "vkas validation error"; }
};

inline const char* resultName(VkResult r) {
    switch (int(r)) {
        case VK_SUCCESS: return "VK_SUCCESS";
        case VK_ERROR_OUT_OF_HOST_MEMORY: return "VK_ERROR_OUT_OF_HOST_MEMORY";
        case VK_ERROR_OUT_OF_DEVICE_MEMORY: return "VK_ERROR_OUT_OF_DEVICE_MEMORY";
        case VK_ERROR_VALIDATION_FAILED_EXT: return "VK_ERROR_VALIDATION_FAILED_EXT";
        case VK_ERROR_UNKNOWN: return "VK_ERROR_UNKNOWN";
        case VK_ERROR_INCOMPATIBLE_VERSION_KHR: return "VK_ERROR_INCOMPATIBLE_VERSION_KHR";
        default: return "an error";
    }
}

struct Capture {
    std::vector<Message> messages;
    std::vector<Message>* previous;
    Capture() : previous(tlCapture) { tlCapture = &messages; }
    ~Capture() { tlCapture = previous; }
    Capture(const Capture&) = delete;
    Capture& operator=(const Capture&) = delete;
    // Throws for collected messages (vkas.ValidationError) or a failed result.
    void check(VkResult r, const char* what) {
        if (!messages.empty()) throw ValidationFailure(std::move(messages));
        if (r == VK_ERROR_OUT_OF_HOST_MEMORY || r == VK_ERROR_OUT_OF_DEVICE_MEMORY) throw std::bad_alloc();
        if (r != VK_SUCCESS)
            throw std::runtime_error(std::string(what) + " failed: " + resultName(r) + " (" + std::to_string(int(r)) +
                                     ")");
    }
    void check(const char* what) { check(VK_SUCCESS, what); }
};

// ------------------------------------------------------------------------------------------------------------------
// The device

#define CORE_COMMANDS(X)                                                                                              \
    X(vkCreateBuffer)                                                                                                 \
    X(vkDestroyBuffer)                                                                                                \
    X(vkGetBufferMemoryRequirements)                                                                                  \
    X(vkAllocateMemory)                                                                                               \
    X(vkFreeMemory)                                                                                                   \
    X(vkBindBufferMemory)                                                                                             \
    X(vkMapMemory)                                                                                                    \
    X(vkGetAccelerationStructureBuildSizesKHR)                                                                        \
    X(vkCreateAccelerationStructureKHR)                                                                               \
    X(vkDestroyAccelerationStructureKHR)                                                                              \
    X(vkGetAccelerationStructureDeviceAddressKHR)                                                                     \
    X(vkBuildAccelerationStructuresKHR)                                                                               \
    X(vkCopyAccelerationStructureKHR)                                                                                 \
    X(vkCopyAccelerationStructureToMemoryKHR)                                                                         \
    X(vkCopyMemoryToAccelerationStructureKHR)                                                                         \
    X(vkWriteAccelerationStructuresPropertiesKHR)                                                                     \
    X(vkCreateDeferredOperationKHR)                                                                                   \
    X(vkDestroyDeferredOperationKHR)                                                                                  \
    X(vkDeferredOperationJoinKHR)                                                                                     \
    X(vkGetDeferredOperationResultKHR)

struct DeviceImpl {
    VkDevice device = VK_NULL_HANDLE;
    bool validation = true;
    uint32_t requestedThreads = 0;
    uint32_t threads = 1;  // resolved: what builds and intersect_all use; vkasTraceRays has its own workers
#define CORE_MEMBER(name) PFN_##name name = nullptr;
    CORE_COMMANDS(CORE_MEMBER)
#undef CORE_MEMBER

    // Batch buffers (packed rays and hits), kept for the next call: fresh memory costs page faults, a large part of
    // a batch's time otherwise. One per concurrent call; at most kPoolKeep kept.
    struct Batch {
        std::unique_ptr<VkasRay[]> rays;
        std::unique_ptr<VkasHit[]> hits;
        size_t capacity = 0;
        void reserve(size_t n) {
            if (n <= capacity) return;
            rays.reset();
            hits.reset();
            rays.reset(new VkasRay[n]);
            hits.reset(new VkasHit[n]);
            capacity = n;
        }
    };
    static constexpr size_t kPoolKeep = 4;
    std::mutex poolMutex;
    std::vector<std::unique_ptr<Batch>> pool;
    std::unique_ptr<Batch> takeBatch(size_t n) {
        std::unique_ptr<Batch> b;
        {
            std::lock_guard<std::mutex> lock(poolMutex);
            if (!pool.empty()) {
                b = std::move(pool.back());
                pool.pop_back();
            }
        }
        if (!b) b = std::make_unique<Batch>();
        b->reserve(std::max<size_t>(n, 1));
        return b;
    }
    void giveBatch(std::unique_ptr<Batch> b) {
        std::lock_guard<std::mutex> lock(poolMutex);
        if (pool.size() < kPoolKeep) pool.push_back(std::move(b));
    }

    DeviceImpl(bool validate, uint32_t threadCount);
    ~DeviceImpl();
    DeviceImpl(const DeviceImpl&) = delete;
    DeviceImpl& operator=(const DeviceImpl&) = delete;
};

// One acceleration structure with its own buffer and memory.
struct Structure {
    std::shared_ptr<DeviceImpl> d;
    VkBuffer buffer = VK_NULL_HANDLE;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    VkAccelerationStructureKHR as = VK_NULL_HANDLE;
    VkDeviceSize size = 0;
    const unsigned char* mapped = nullptr;

    Structure(std::shared_ptr<DeviceImpl> dev, VkAccelerationStructureTypeKHR type, VkDeviceSize bytes);
    ~Structure() { release(); }
    Structure(const Structure&) = delete;
    Structure& operator=(const Structure&) = delete;

    void release();

    template <class T>
    T field(size_t offset) const {
        T v{};
        if (mapped && offset + sizeof(T) <= size) std::memcpy(&v, mapped + offset, sizeof v);
        return v;
    }
    // The block header (docs/FORMAT.md, "Header").
    bool constructed() const { return field<uint32_t>(0) == 0x53414B56u; }
    uint32_t type() const { return field<uint32_t>(8); }
    uint32_t buildFlags() const { return field<uint32_t>(12); }
    uint64_t usedSize() const { return field<uint64_t>(16); }

    uint64_t address() const;
    py::bytes read(uint64_t offset, uint64_t count) const;
    uint64_t query(VkQueryType type) const;
};

using StructurePtr = std::shared_ptr<Structure>;

// ------------------------------------------------------------------------------------------------------------------
// Python-facing device

class Device {
public:
    std::shared_ptr<DeviceImpl> d;

    Device(bool validation, uint32_t threads) : d(std::make_shared<DeviceImpl>(validation, threads)) {}

    // builds.cpp
    StructurePtr buildBottom(const py::list& geometries, uint32_t flags);
    void updateBottom(const StructurePtr& s, const py::list& geometries, uint32_t flags);
    static VkAccelerationStructureGeometryKHR instanceGeometry(const py::buffer_info& b, uint32_t& count);
    StructurePtr buildTop(const py::buffer& records, uint32_t flags);
    void updateTop(const StructurePtr& s, const py::buffer& records, uint32_t flags);

    // structures.cpp
    StructurePtr copy(const StructurePtr& src, bool compact);
    py::bytes serialize(const StructurePtr& s);
    StructurePtr deserialize(const py::buffer& blob, const std::vector<StructurePtr>& bottoms, bool replace);

    // trace.cpp
    void checkRayFlags(const StructurePtr& tlas, uint32_t flags, uint32_t mask);
    py::object trace(const StructurePtr& tlas, const py::array& origins, const py::array& directions,
                     const py::array& tmin, const py::array& tmax, uint32_t flags, uint32_t mask, bool anyHit);
    double timeTraceRays(const StructurePtr& tlas, const py::array& packed, uint32_t flags, uint32_t mask,
                         bool anyHit, int repeats);
    py::array packRaysForBench(const py::array& origins, const py::array& directions, const py::array& tmin,
                               const py::array& tmax);

    // query.cpp
    py::tuple traceAll(const StructurePtr& tlas, const py::array& origins, const py::array& directions,
                       const py::array& tmin, const py::array& tmax, uint32_t flags, uint32_t mask, uint32_t maxHits);
};

}  // namespace vkas_python
