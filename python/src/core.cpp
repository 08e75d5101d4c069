// vkas._core: the pybind11 extension behind the vkas Python package (docs/PYTHON.md).
//
// It uses the public C API only (include/vkas/vkas.h): a device with a debug messenger, the Vulkan commands from
// vkasGetDeviceProcAddr for buffers, builds, copies, serialization and queries, vkasTraceRays for batches of rays and
// the vkasRayQuery* functions for intersect_all. The Python layer (vkas/__init__.py) checks and converts the
// arguments; this file still checks every array it is given (dtype, shape, contiguity) so that nothing it is handed
// can make it read out of bounds. Builds and traces run with the GIL released.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <exception>
#include <limits>
#include <memory>
#include <mutex>
#include <new>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "vkas/vkas.h"

namespace py = pybind11;

namespace {

// ------------------------------------------------------------------------------------------------------------------
// Validation messages: vkas reports each broken valid-usage rule through the device's messenger. Every command this
// module issues runs inside a Capture on the calling thread; what it collected becomes a vkas.ValidationError.

struct Message {
    std::string vuid, text;
};

thread_local std::vector<Message>* tlCapture = nullptr;

VKAPI_ATTR VkBool32 VKAPI_CALL messenger(VkDebugUtilsMessageSeverityFlagBitsEXT, VkDebugUtilsMessageTypeFlagsEXT,
                                         const VkDebugUtilsMessengerCallbackDataEXT* data, void*) {
    const char* id = data && data->pMessageIdName ? data->pMessageIdName : "";
    const char* text = data && data->pMessage ? data->pMessage : "";
    if (tlCapture) {
        try {
            tlCapture->push_back({id, text});
        } catch (...) {
        }
    } else {
        std::fprintf(stderr, "vkas: %s\n", text);
    }
    return VK_FALSE;
}

struct ValidationFailure : std::exception {
    std::vector<Message> messages;
    explicit ValidationFailure(std::vector<Message> m) : messages(std::move(m)) {}
    const char* what() const noexcept override { return "vkas validation error"; }
};

const char* resultName(VkResult r) {
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

    DeviceImpl(bool validate, uint32_t threadCount) : validation(validate), requestedThreads(threadCount) {
        VkasDeviceCreateInfo ci{};
        ci.disableValidation = validate ? VK_FALSE : VK_TRUE;
        ci.pfnMessenger = &messenger;
        ci.workerThreadCount = threadCount;
        Capture capture;
        capture.check(vkasCreateDevice(&ci, &device), "vkasCreateDevice");
#define CORE_LOAD(name)                                                                                               \
    name = reinterpret_cast<PFN_##name>(vkasGetDeviceProcAddr(device, #name));                                        \
    if (!name) throw std::runtime_error("vkasGetDeviceProcAddr(" #name ") returned NULL");
        CORE_COMMANDS(CORE_LOAD)
#undef CORE_LOAD
        const unsigned hw = std::max(1u, std::thread::hardware_concurrency());
        threads = threadCount == 0 ? hw : threadCount;
    }
    ~DeviceImpl() {
        if (device) vkasDestroyDevice(device);
    }
    DeviceImpl(const DeviceImpl&) = delete;
    DeviceImpl& operator=(const DeviceImpl&) = delete;
};

// Host memory aligned to 16 bytes (the copy commands' pointer rule for serialized data).
struct Aligned {
    struct alignas(16) Chunk {
        unsigned char b[16];
    };
    std::unique_ptr<Chunk[]> chunks;
    size_t size = 0;
    explicit Aligned(size_t n) : chunks(new Chunk[(n + 15) / 16 + 1]), size(n) {}
    unsigned char* data() { return chunks[0].b; }
};

// One acceleration structure with its own buffer and memory.
struct Structure {
    std::shared_ptr<DeviceImpl> d;
    VkBuffer buffer = VK_NULL_HANDLE;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    VkAccelerationStructureKHR as = VK_NULL_HANDLE;
    VkDeviceSize size = 0;
    const unsigned char* mapped = nullptr;

    Structure(std::shared_ptr<DeviceImpl> dev, VkAccelerationStructureTypeKHR type, VkDeviceSize bytes)
        : d(std::move(dev)), size(std::max<VkDeviceSize>(bytes, 256)) {
        Capture capture;
        VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
        bci.size = size;
        bci.usage = VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_STORAGE_BIT_KHR | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT;
        try {
            capture.check(d->vkCreateBuffer(d->device, &bci, nullptr, &buffer), "vkCreateBuffer");
            VkMemoryRequirements req{};
            d->vkGetBufferMemoryRequirements(d->device, buffer, &req);
            VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
            mai.allocationSize = req.size;
            mai.memoryTypeIndex = 0;
            VkMemoryAllocateFlagsInfo flags{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
            flags.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
            mai.pNext = &flags;
            capture.check(d->vkAllocateMemory(d->device, &mai, nullptr, &memory), "vkAllocateMemory");
            capture.check(d->vkBindBufferMemory(d->device, buffer, memory, 0), "vkBindBufferMemory");
            void* p = nullptr;
            capture.check(d->vkMapMemory(d->device, memory, 0, VK_WHOLE_SIZE, 0, &p), "vkMapMemory");
            mapped = static_cast<const unsigned char*>(p);
            VkAccelerationStructureCreateInfoKHR ci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
            ci.buffer = buffer;
            ci.size = size;
            ci.type = type;
            capture.check(d->vkCreateAccelerationStructureKHR(d->device, &ci, nullptr, &as),
                          "vkCreateAccelerationStructureKHR");
        } catch (...) {
            release();
            throw;
        }
    }
    ~Structure() { release(); }
    Structure(const Structure&) = delete;
    Structure& operator=(const Structure&) = delete;

    void release() {
        Capture capture;  // nothing should be reported; whatever is, is dropped with the object
        if (as) d->vkDestroyAccelerationStructureKHR(d->device, as, nullptr);
        if (buffer) d->vkDestroyBuffer(d->device, buffer, nullptr);
        if (memory) d->vkFreeMemory(d->device, memory, nullptr);
        as = VK_NULL_HANDLE, buffer = VK_NULL_HANDLE, memory = VK_NULL_HANDLE, mapped = nullptr;
    }

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

    uint64_t address() const {
        VkAccelerationStructureDeviceAddressInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_DEVICE_ADDRESS_INFO_KHR};
        info.accelerationStructure = as;
        Capture capture;
        const uint64_t a = d->vkGetAccelerationStructureDeviceAddressKHR(d->device, &info);
        capture.check("vkGetAccelerationStructureDeviceAddressKHR");
        return a;
    }

    py::bytes read(uint64_t offset, uint64_t count) const {
        const uint64_t used = std::min<uint64_t>(usedSize(), size);
        if (!constructed() || offset > used || count > used - offset)
            throw py::value_error("read: [" + std::to_string(offset) + ", +" + std::to_string(count) +
                                  ") is outside the structure's " + std::to_string(used) + " bytes");
        return py::bytes(reinterpret_cast<const char*>(mapped + offset), size_t(count));
    }

    uint64_t query(VkQueryType type) const {
        uint64_t value = 0;
        Capture capture;
        capture.check(d->vkWriteAccelerationStructuresPropertiesKHR(d->device, 1, &as, type, sizeof value, &value,
                                                                      sizeof value),
                      "vkWriteAccelerationStructuresPropertiesKHR");
        return value;
    }
};

using StructurePtr = std::shared_ptr<Structure>;

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

struct GeometryInputs {
    std::vector<VkAccelerationStructureGeometryKHR> geometries;
    std::vector<VkAccelerationStructureGeometrySpheresDataNV> spheres;
    std::vector<VkAccelerationStructureBuildRangeInfoKHR> ranges;
    std::vector<uint32_t> counts;
    std::vector<py::array> keep;  // the arrays read by the build
    uint64_t primitives = 0;
};

// geometries: a list of (0, vertices (N,3) f32, indices (M,3) u16/u32 or None, transform (3,4) f32 or None, opaque)
// and (1, centers (N,3) f32, radii (N,) f32, opaque).
GeometryInputs parseGeometries(const py::list& list) {
    GeometryInputs in;
    const size_t n = list.size();
    in.geometries.reserve(n);
    in.spheres.reserve(n);
    for (size_t i = 0; i < n; ++i) {
        py::tuple t = list[i].cast<py::tuple>();
        const int kind = t[0].cast<int>();
        VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
        // Every primitive is reported at most once to intersect_all's ray queries.
        g.flags = VK_GEOMETRY_NO_DUPLICATE_ANY_HIT_INVOCATION_BIT_KHR;
        uint32_t count = 0;
        if (kind == 0) {
            if (t.size() != 5) throw py::value_error("vkas._core: a triangle geometry is a 5-tuple");
            py::array v = t[1].cast<py::array>();
            const float* vp = arrayData<float>(v, "vertices", {-1, 3});
            const py::ssize_t nv = v.shape(0);
            in.keep.push_back(v);
            g.geometryType = VK_GEOMETRY_TYPE_TRIANGLES_KHR;
            auto& tr = g.geometry.triangles;
            tr.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR;
            tr.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
            tr.vertexData.hostAddress = vp;
            tr.vertexStride = 12;
            tr.maxVertex = nv > 0 ? uint32_t(nv - 1) : 0;
            if (t[2].is_none()) {
                tr.indexType = VK_INDEX_TYPE_NONE_KHR;
                count = uint32_t(nv / 3);
            } else {
                py::array idx = t[2].cast<py::array>();
                in.keep.push_back(idx);
                if (idx.dtype().is(py::dtype::of<uint16_t>())) {
                    tr.indexType = VK_INDEX_TYPE_UINT16;
                    tr.indexData.hostAddress = arrayData<uint16_t>(idx, "indices", {-1, 3});
                } else {
                    tr.indexType = VK_INDEX_TYPE_UINT32;
                    tr.indexData.hostAddress = arrayData<uint32_t>(idx, "indices", {-1, 3});
                }
                count = uint32_t(idx.shape(0));
            }
            if (!t[3].is_none()) {
                py::array xf = t[3].cast<py::array>();
                in.keep.push_back(xf);
                tr.transformData.hostAddress = arrayData<float>(xf, "transform", {3, 4});
            }
            if (t[4].cast<bool>()) g.flags |= VK_GEOMETRY_OPAQUE_BIT_KHR;
        } else if (kind == 1) {
            if (t.size() != 4) throw py::value_error("vkas._core: a sphere geometry is a 4-tuple");
            py::array c = t[1].cast<py::array>(), r = t[2].cast<py::array>();
            const float* cp = arrayData<float>(c, "centers", {-1, 3});
            const float* rp = arrayData<float>(r, "radii", {c.shape(0)});
            in.keep.push_back(c);
            in.keep.push_back(r);
            VkAccelerationStructureGeometrySpheresDataNV sp{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_SPHERES_DATA_NV};
            sp.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
            sp.vertexData.hostAddress = cp;
            sp.vertexStride = 12;
            sp.radiusFormat = VK_FORMAT_R32_SFLOAT;
            sp.radiusData.hostAddress = rp;
            sp.radiusStride = 4;
            sp.indexType = VK_INDEX_TYPE_NONE_KHR;
            in.spheres.push_back(sp);
            g.pNext = &in.spheres.back();  // reserved above: no reallocation
            g.geometryType = VK_GEOMETRY_TYPE_SPHERES_NV;
            count = uint32_t(c.shape(0));
            if (t[3].cast<bool>()) g.flags |= VK_GEOMETRY_OPAQUE_BIT_KHR;
        } else {
            throw py::value_error("vkas._core: unknown geometry kind " + std::to_string(kind));
        }
        in.geometries.push_back(g);
        in.ranges.push_back({count, 0, 0, 0});
        in.counts.push_back(count);
        in.primitives += count;
    }
    return in;
}

// Runs one build (or update). With more than one thread and enough primitives, through a deferred operation joined
// by the device's threads: the bytes are the same either way (docs/API.md, section 7).
void runBuild(DeviceImpl& d, const VkAccelerationStructureBuildGeometryInfoKHR& info,
              const VkAccelerationStructureBuildRangeInfoKHR* ranges, uint64_t primitives) {
    Capture capture;
    const VkAccelerationStructureBuildRangeInfoKHR* pRanges = ranges;
    const unsigned threads = primitives >= 16384 ? d.threads : 1;
    if (threads <= 1 || info.mode == VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR) {
        capture.check(d.vkBuildAccelerationStructuresKHR(d.device, VK_NULL_HANDLE, 1, &info, &pRanges),
                      "vkBuildAccelerationStructuresKHR");
        return;
    }
    VkDeferredOperationKHR op = VK_NULL_HANDLE;
    capture.check(d.vkCreateDeferredOperationKHR(d.device, nullptr, &op), "vkCreateDeferredOperationKHR");
    struct OpGuard {
        DeviceImpl& d;
        VkDeferredOperationKHR op;
        ~OpGuard() { d.vkDestroyDeferredOperationKHR(d.device, op, nullptr); }
    } guard{d, op};
    const VkResult r = d.vkBuildAccelerationStructuresKHR(d.device, op, 1, &info, &pRanges);
    if (r != VK_OPERATION_DEFERRED_KHR) {
        capture.check(r, "vkBuildAccelerationStructuresKHR");
        return;
    }
    auto join = [&] {
        while (d.vkDeferredOperationJoinKHR(d.device, op) == VK_THREAD_IDLE_KHR) std::this_thread::yield();
    };
    std::vector<std::thread> pool;
    for (unsigned k = 1; k < threads; ++k) pool.emplace_back(join);
    join();
    for (auto& t : pool) t.join();
    capture.check(d.vkGetDeferredOperationResultKHR(d.device, op), "vkBuildAccelerationStructuresKHR (deferred)");
}

VkAccelerationStructureBuildGeometryInfoKHR buildInfo(VkAccelerationStructureTypeKHR type, uint32_t flags,
                                                      const std::vector<VkAccelerationStructureGeometryKHR>& g) {
    VkAccelerationStructureBuildGeometryInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
    info.type = type;
    info.flags = flags;
    info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR;
    info.geometryCount = uint32_t(g.size());
    info.pGeometries = g.data();
    return info;
}

StructurePtr buildNew(const std::shared_ptr<DeviceImpl>& d, VkAccelerationStructureTypeKHR type, uint32_t flags,
                      const std::vector<VkAccelerationStructureGeometryKHR>& geometries,
                      const std::vector<VkAccelerationStructureBuildRangeInfoKHR>& ranges,
                      const std::vector<uint32_t>& counts, uint64_t primitives) {
    VkAccelerationStructureBuildGeometryInfoKHR info = buildInfo(type, flags, geometries);
    VkAccelerationStructureBuildSizesInfoKHR sizes{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
    {
        Capture capture;
        d->vkGetAccelerationStructureBuildSizesKHR(d->device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info,
                                                   counts.data(), &sizes);
        capture.check("vkGetAccelerationStructureBuildSizesKHR");
    }
    if (sizes.accelerationStructureSize == 0) throw std::runtime_error("vkGetAccelerationStructureBuildSizesKHR gave 0");
    auto s = std::make_shared<Structure>(d, type, sizes.accelerationStructureSize);
    std::unique_ptr<unsigned char[]> scratch(new unsigned char[std::max<VkDeviceSize>(sizes.buildScratchSize, 16)]);
    info.dstAccelerationStructure = s->as;
    info.scratchData.hostAddress = scratch.get();
    runBuild(*d, info, ranges.data(), primitives);
    return s;
}

void updateInPlace(const std::shared_ptr<DeviceImpl>& d, Structure& s, VkAccelerationStructureTypeKHR type,
                   uint32_t flags, const std::vector<VkAccelerationStructureGeometryKHR>& geometries,
                   const std::vector<VkAccelerationStructureBuildRangeInfoKHR>& ranges) {
    VkAccelerationStructureBuildGeometryInfoKHR info = buildInfo(type, flags, geometries);
    info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR;
    info.srcAccelerationStructure = info.dstAccelerationStructure = s.as;
    unsigned char scratch[16];  // updateScratchSize is 0
    info.scratchData.hostAddress = scratch;
    runBuild(*d, info, ranges.data(), 0);
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

std::string fmt(float v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.9g", double(v));
    return b;
}

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

// ------------------------------------------------------------------------------------------------------------------
// Python-facing device

class Device {
public:
    std::shared_ptr<DeviceImpl> d;

    Device(bool validation, uint32_t threads) : d(std::make_shared<DeviceImpl>(validation, threads)) {}

    StructurePtr buildBottom(const py::list& geometries, uint32_t flags) {
        GeometryInputs in = parseGeometries(geometries);
        py::gil_scoped_release release;
        return buildNew(d, VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, flags, in.geometries, in.ranges, in.counts,
                        in.primitives);
    }

    void updateBottom(const StructurePtr& s, const py::list& geometries, uint32_t flags) {
        GeometryInputs in = parseGeometries(geometries);
        py::gil_scoped_release release;
        updateInPlace(d, *s, VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, flags, in.geometries, in.ranges);
    }

    // records: the VkAccelerationStructureInstanceKHR array, as a bytes-like object of 64 * count bytes.
    static VkAccelerationStructureGeometryKHR instanceGeometry(const py::buffer_info& b, uint32_t& count) {
        if (b.size * b.itemsize % 64 != 0) throw py::value_error("records: not a whole number of 64-byte records");
        count = uint32_t(b.size * b.itemsize / 64);
        VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
        g.geometryType = VK_GEOMETRY_TYPE_INSTANCES_KHR;
        g.geometry.instances.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_INSTANCES_DATA_KHR;
        g.geometry.instances.arrayOfPointers = VK_FALSE;
        g.geometry.instances.data.hostAddress = b.ptr;
        return g;
    }

    StructurePtr buildTop(const py::buffer& records, uint32_t flags) {
        py::buffer_info b = records.request();
        uint32_t count = 0;
        std::vector<VkAccelerationStructureGeometryKHR> g{instanceGeometry(b, count)};
        std::vector<VkAccelerationStructureBuildRangeInfoKHR> ranges{{count, 0, 0, 0}};
        std::vector<uint32_t> counts{count};
        py::gil_scoped_release release;
        return buildNew(d, VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, flags, g, ranges, counts, count);
    }

    void updateTop(const StructurePtr& s, const py::buffer& records, uint32_t flags) {
        py::buffer_info b = records.request();
        uint32_t count = 0;
        std::vector<VkAccelerationStructureGeometryKHR> g{instanceGeometry(b, count)};
        std::vector<VkAccelerationStructureBuildRangeInfoKHR> ranges{{count, 0, 0, 0}};
        py::gil_scoped_release release;
        updateInPlace(d, *s, VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, flags, g, ranges);
    }

    // A copy of `src` (COMPACT or CLONE) into a structure of exactly the size the copy needs.
    StructurePtr copy(const StructurePtr& src, bool compact) {
        py::gil_scoped_release release;
        const uint64_t bytes = src->query(compact ? VK_QUERY_TYPE_ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR
                                                  : VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SIZE_KHR);
        auto dst = std::make_shared<Structure>(d, VkAccelerationStructureTypeKHR(src->type()), bytes);
        VkCopyAccelerationStructureInfoKHR info{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_INFO_KHR};
        info.src = src->as;
        info.dst = dst->as;
        info.mode = compact ? VK_COPY_ACCELERATION_STRUCTURE_MODE_COMPACT_KHR : VK_COPY_ACCELERATION_STRUCTURE_MODE_CLONE_KHR;
        Capture capture;
        capture.check(d->vkCopyAccelerationStructureKHR(d->device, VK_NULL_HANDLE, &info), "vkCopyAccelerationStructureKHR");
        return dst;
    }

    py::bytes serialize(const StructurePtr& s) {
        std::unique_ptr<Aligned> out;
        {
            py::gil_scoped_release release;
            const uint64_t bytes = s->query(VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_SIZE_KHR);
            out = std::make_unique<Aligned>(size_t(bytes));
            VkCopyAccelerationStructureToMemoryInfoKHR info{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_TO_MEMORY_INFO_KHR};
            info.src = s->as;
            info.dst.hostAddress = out->data();
            info.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_SERIALIZE_KHR;
            Capture capture;
            capture.check(d->vkCopyAccelerationStructureToMemoryKHR(d->device, VK_NULL_HANDLE, &info),
                          "vkCopyAccelerationStructureToMemoryKHR");
        }
        return py::bytes(reinterpret_cast<const char*>(out->data()), out->size);
    }

    // blob: a serialized structure. With replace, bottoms gives the handle array to write: one structure per entry
    // (its device address; null for 0, an inactive instance); without, the blob must have no entries.
    StructurePtr deserialize(const py::buffer& blob, const std::vector<StructurePtr>& bottoms, bool replace) {
        py::buffer_info b = blob.request();
        // The bytes are read as one run from b.ptr: a strided view (a reversed memoryview) would be read outside it.
        py::ssize_t expected = b.itemsize;
        for (py::ssize_t k = b.ndim - 1; k >= 0; --k) {
            if (b.shape[size_t(k)] > 1 && b.strides[size_t(k)] != expected)
                throw py::value_error("blob: not C-contiguous: pass bytes(blob)");
            expected *= b.shape[size_t(k)];
        }
        const uint64_t n = uint64_t(b.size) * uint64_t(b.itemsize);
        if (n < 64) throw py::value_error("blob: " + std::to_string(n) + " bytes is too short for a serialized structure");
        auto load = [&](size_t off) {
            uint64_t v;
            std::memcpy(&v, static_cast<const unsigned char*>(b.ptr) + off, 8);
            return v;
        };
        const uint64_t serialized = load(32), deserialized = load(40), handles = load(48);
        if (serialized > n)
            throw py::value_error("blob: truncated: " + std::to_string(n) + " bytes, its header says " +
                                  std::to_string(serialized));
        if (deserialized > serialized || handles > (serialized - 56) / 8)
            throw py::value_error("blob: corrupted: the sizes in its header disagree");
        if (replace && bottoms.size() != handles)
            throw py::value_error("bottom_levels: the blob's top level has " + std::to_string(handles) +
                                  " instances, " + std::to_string(bottoms.size()) + " bottom levels were given");
        if (!replace && handles != 0)
            throw py::value_error("bottom_levels: the blob is a top level with " + std::to_string(handles) +
                                  " instances: give the bottom level of each (None for an inactive one)");
        Aligned copy{size_t(serialized)};
        std::memcpy(copy.data(), b.ptr, size_t(serialized));
        for (uint64_t k = 0; k < handles; ++k) {
            const uint64_t a = bottoms[k] ? bottoms[k]->address() : 0;
            std::memcpy(copy.data() + 56 + 8 * k, &a, 8);
        }
        py::gil_scoped_release release;
        auto dst = std::make_shared<Structure>(d, VK_ACCELERATION_STRUCTURE_TYPE_GENERIC_KHR, deserialized);
        VkCopyMemoryToAccelerationStructureInfoKHR info{VK_STRUCTURE_TYPE_COPY_MEMORY_TO_ACCELERATION_STRUCTURE_INFO_KHR};
        info.src.hostAddress = copy.data();
        info.dst = dst->as;
        info.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_DESERIALIZE_KHR;
        Capture capture;
        const VkResult r = d->vkCopyMemoryToAccelerationStructureKHR(d->device, VK_NULL_HANDLE, &info);
        if (r == VK_ERROR_UNKNOWN && capture.messages.empty())  // validation off: the data is checked all the same
            throw py::value_error("blob: not a valid serialized structure (corrupted, malformed or truncated; "
                                  "vkCopyMemoryToAccelerationStructureKHR: VK_ERROR_UNKNOWN)");
        if (r == VK_ERROR_INCOMPATIBLE_VERSION_KHR && capture.messages.empty())
            throw py::value_error("blob: serialized by an incompatible vkas (VK_ERROR_INCOMPATIBLE_VERSION_KHR)");
        capture.check(r, "vkCopyMemoryToAccelerationStructureKHR");
        return dst;
    }

    void checkRayFlags(const StructurePtr& tlas, uint32_t flags, uint32_t mask) {
        checkFlags(*d, tlas ? tlas->as : VK_NULL_HANDLE, flags, mask);
    }

    // intersect (anyHit false) and occluded (anyHit true).
    py::object trace(const StructurePtr& tlas, const py::array& origins, const py::array& directions,
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

    // Every hit along each ray (candidates of ray queries with NoOpaque, none confirmed, so none shortens the ray),
    // sorted by t, then instance, geometry and primitive; at most maxHits a ray (0: all).
    py::tuple traceAll(const StructurePtr& tlas, const py::array& origins, const py::array& directions,
                       const py::array& tmin, const py::array& tmax, uint32_t flags, uint32_t mask, uint32_t maxHits) {
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

    // For the overhead bench: vkasTraceRays alone on rays packed beforehand (pack_rays), best of `repeats` runs.
    double timeTraceRays(const StructurePtr& tlas, const py::array& packed, uint32_t flags, uint32_t mask,
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

    py::array packRaysForBench(const py::array& origins, const py::array& directions, const py::array& tmin,
                               const py::array& tmax) {
        const RayInputs in = rayInputs(origins, directions, tmin, tmax);
        py::array_t<float> out({py::ssize_t(in.count), py::ssize_t(8)});
        static_assert(sizeof(VkasRay) == 32);
        packRays(*d, in, reinterpret_cast<VkasRay*>(out.mutable_data()));
        return out;
    }
};

}  // namespace

PYBIND11_MODULE(_core, m) {
    m.doc() = "vkas._core: the C API binding behind the vkas package (use the vkas package itself)";
    m.attr("VERSION") = py::make_tuple(VKAS_VERSION_MAJOR, VKAS_VERSION_MINOR, VKAS_VERSION_PATCH);
    m.attr("RAY_QUERY_SIZE") = VKAS_RAY_QUERY_SIZE;

    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const ValidationFailure& e) {
            py::object cls = py::module_::import("vkas._errors").attr("ValidationError");
            py::list all;
            for (const Message& msg : e.messages) all.append(py::make_tuple(msg.vuid, msg.text));
            py::object exc = cls(e.messages.front().vuid, e.messages.front().text, all);
            PyErr_SetObject(cls.ptr(), exc.ptr());
        }
    });

    py::class_<Structure, StructurePtr>(m, "Structure")
        .def_property_readonly("handle", [](const Structure& s) { return uint64_t(reinterpret_cast<uintptr_t>(s.as)); })
        .def_property_readonly("address", &Structure::address)
        .def_property_readonly("size", [](const Structure& s) { return uint64_t(s.size); })
        .def_property_readonly("constructed", &Structure::constructed)
        .def_property_readonly("type", &Structure::type)
        .def_property_readonly("build_flags", &Structure::buildFlags)
        .def_property_readonly("used_size", &Structure::usedSize)
        .def("read", &Structure::read, py::arg("offset"), py::arg("count"))
        .def("query", [](const Structure& s, uint32_t type) {
            py::gil_scoped_release release;
            return s.query(VkQueryType(type));
        });

    py::class_<Device>(m, "Device")
        .def(py::init<bool, uint32_t>(), py::arg("validation"), py::arg("threads"))
        .def_property_readonly("validation", [](const Device& d) { return d.d->validation; })
        .def_property_readonly("threads", [](const Device& d) { return d.d->threads; })
        .def_property_readonly("requested_threads", [](const Device& d) { return d.d->requestedThreads; })
        .def("build_bottom", &Device::buildBottom)
        .def("update_bottom", &Device::updateBottom)
        .def("build_top", &Device::buildTop)
        .def("update_top", &Device::updateTop)
        .def("copy", &Device::copy)
        .def("serialize", &Device::serialize)
        .def("deserialize", &Device::deserialize)
        .def("check_ray_flags", &Device::checkRayFlags)
        .def("trace", &Device::trace)
        .def("trace_all", &Device::traceAll)
        .def("time_trace_rays", &Device::timeTraceRays)
        .def("pack_rays", &Device::packRaysForBench);
}
