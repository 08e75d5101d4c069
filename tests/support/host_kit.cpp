#include "host_kit.hpp"

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstring>
#include <exception>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>

namespace hk {

void fail(const std::string& what) { throw Failure(what); }

void expect(VkResult got, VkResult want, const char* what) { expect(nullptr, got, want, what); }

void expect(Device* device, VkResult got, VkResult want, const char* what) {
    if (got == want) return;
    std::string msg = std::string(what) + " returned " + std::to_string(int(got)) + ", expected " + std::to_string(int(want));
    if (device)
        for (const auto& e : device->takeErrors()) msg += "\n  validation: " + e;
    fail(msg);
}

void parallel(uint32_t n, const std::function<void(uint32_t)>& fn) {
    std::mutex mutex;
    std::exception_ptr first;
    auto run = [&](uint32_t i) {
        try {
            fn(i);
        } catch (...) {
            std::lock_guard<std::mutex> lock(mutex);
            if (!first) first = std::current_exception();
        }
    };
    std::vector<std::thread> pool;
    for (uint32_t i = 1; i < n; ++i) pool.emplace_back(run, i);
    if (n > 0) run(0);
    for (auto& t : pool) t.join();
    if (first) std::rethrow_exception(first);
}

// ---- Device -----------------------------------------------------------------------------------------------------
VKAPI_ATTR VkBool32 VKAPI_CALL Device::messenger(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                 VkDebugUtilsMessageTypeFlagsEXT,
                                                 const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
    if (severity < VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT) return VK_FALSE;
    auto* self = static_cast<Device*>(user);
    std::string msg = std::string(data && data->pMessageIdName ? data->pMessageIdName : "") + ": " +
                      (data && data->pMessage ? data->pMessage : "");
    std::lock_guard<std::mutex> lock(self->mutex_);
    self->errors_.push_back(std::move(msg));
    return VK_FALSE;
}

Device::Device(uint32_t workerThreads) {
    vkas_kit::DeviceOptions options;
    options.validation = true;
    options.workerThreads = workerThreads;
    options.messenger = &Device::messenger;
    options.messengerUserData = this;
    try {
        device_.emplace(options);
    } catch (const vkas_kit::DeviceError& e) {
        expect(e.result(), VK_SUCCESS, "vkasCreateDevice");
    } catch (const vkas_kit::MissingCommand& e) {
        fail("vkasGetDeviceProcAddr(" + e.command() + ") is NULL");
    }
    handle = device_->handle();
    vk = device_->commands();
}

Device::~Device() = default;

std::vector<std::string> Device::takeErrors() {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<std::string> out;
    out.swap(errors_);
    return out;
}

void Device::checkNoErrors(const char* when) {
    auto errors = takeErrors();
    if (!errors.empty()) fail(std::string("validation error ") + when + ": " + errors.front());
}

// ---- Structures -------------------------------------------------------------------------------------------------
VkDeviceAddress Structure::address() const {
    VkAccelerationStructureDeviceAddressInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_DEVICE_ADDRESS_INFO_KHR};
    info.accelerationStructure = handle;
    return device->vk.vkGetAccelerationStructureDeviceAddressKHR(device->handle, &info);
}

Structure::~Structure() {
    if (!device) return;
    const auto& vk = device->vk;
    if (handle != VK_NULL_HANDLE) vk.vkDestroyAccelerationStructureKHR(device->handle, handle, nullptr);
    if (buffer != VK_NULL_HANDLE) vk.vkDestroyBuffer(device->handle, buffer, nullptr);
    if (memory != VK_NULL_HANDLE) {
        if (mapped) vk.vkUnmapMemory(device->handle, memory);
        vk.vkFreeMemory(device->handle, memory, nullptr);
    }
}

std::unique_ptr<Structure> createStructure(Device& d, VkAccelerationStructureTypeKHR type, VkDeviceSize size) {
    auto s = std::make_unique<Structure>();
    s->device = &d;
    s->type = type;
    s->size = size;
    const auto& vk = d.vk;
    VkBufferCreateInfo bi{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    bi.size = size;
    bi.usage = vt::kAsBufferUsage;
    bi.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    expect(&d, vk.vkCreateBuffer(d.handle, &bi, nullptr, &s->buffer), VK_SUCCESS, "vkCreateBuffer");
    VkMemoryRequirements req{};
    vk.vkGetBufferMemoryRequirements(d.handle, s->buffer, &req);
    VkMemoryAllocateFlagsInfo flagsInfo{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
    flagsInfo.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
    VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    ai.pNext = &flagsInfo;
    ai.allocationSize = req.size;
    ai.memoryTypeIndex = 0;
    expect(&d, vk.vkAllocateMemory(d.handle, &ai, nullptr, &s->memory), VK_SUCCESS, "vkAllocateMemory");
    expect(&d, vk.vkBindBufferMemory(d.handle, s->buffer, s->memory, 0), VK_SUCCESS, "vkBindBufferMemory");
    void* p = nullptr;
    expect(&d, vk.vkMapMemory(d.handle, s->memory, 0, VK_WHOLE_SIZE, 0, &p), VK_SUCCESS, "vkMapMemory");
    s->mapped = static_cast<uint8_t*>(p);
    VkAccelerationStructureCreateInfoKHR ci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
    ci.buffer = s->buffer;
    ci.size = size;
    ci.type = type;
    expect(&d, vk.vkCreateAccelerationStructureKHR(d.handle, &ci, nullptr, &s->handle), VK_SUCCESS,
           "vkCreateAccelerationStructureKHR");
    return s;
}

std::vector<uint8_t> structureBytes(const Structure& s) {
    uint64_t used = 0;
    std::memcpy(&used, s.mapped + 16, 8);
    used = std::min<uint64_t>(used, s.size);
    return std::vector<uint8_t>(s.mapped, s.mapped + used);
}

// ---- Geometry ---------------------------------------------------------------------------------------------------
void Geometry::refresh() {
    geometry = VkAccelerationStructureGeometryKHR{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
    geometry.flags = flags;
    if (isAabbs()) {
        geometry.geometryType = VK_GEOMETRY_TYPE_AABBS_KHR;
        auto& a = geometry.geometry.aabbs;
        a.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_AABBS_DATA_KHR;
        a.data.hostAddress = boxes.data();
        a.stride = sizeof(VkAabbPositionsKHR);
        range = {uint32_t(boxes.size()), 0, 0, 0};
    } else {
        geometry.geometryType = VK_GEOMETRY_TYPE_TRIANGLES_KHR;
        auto& t = geometry.geometry.triangles;
        t.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR;
        t.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
        t.vertexData.hostAddress = positions.data();
        t.vertexStride = 12;
        t.maxVertex = uint32_t(positions.size() / 3 ? positions.size() / 3 - 1 : 0);
        t.indexType = VK_INDEX_TYPE_UINT32;
        t.indexData.hostAddress = indices.data();
        range = {uint32_t(indices.size() / 3), 0, 0, 0};
    }
}

std::unique_ptr<Geometry> triangles(const vt::Mesh& mesh, VkGeometryFlagsKHR flags) {
    auto g = std::make_unique<Geometry>();
    for (const auto& p : mesh.positions) g->positions.insert(g->positions.end(), p.begin(), p.end());
    g->indices = mesh.indices;
    g->flags = flags;
    g->refresh();
    return g;
}

std::unique_ptr<Geometry> aabbs(std::vector<VkAabbPositionsKHR> boxes, VkGeometryFlagsKHR flags) {
    auto g = std::make_unique<Geometry>();
    g->boxes = std::move(boxes);
    g->flags = flags;
    g->refresh();
    return g;
}

std::vector<VkAabbPositionsKHR> randomBoxes(vt::Rng& rng, uint32_t count, float extent, float size) {
    std::vector<VkAabbPositionsKHR> out;
    for (uint32_t i = 0; i < count; ++i) {
        const float x = rng.uniformf(-extent, extent), y = rng.uniformf(-extent, extent), z = rng.uniformf(-extent, extent);
        out.push_back({x, y, z, x + rng.uniformf(0.01f, size), y + rng.uniformf(0.01f, size), z + rng.uniformf(0.01f, size)});
    }
    return out;
}

void jitter(Geometry& g, vt::Rng& rng, float amount) {
    for (float& v : g.positions) v += rng.uniformf(-amount, amount);
    for (auto& b : g.boxes) {
        const float dx = rng.uniformf(-amount, amount), dy = rng.uniformf(-amount, amount), dz = rng.uniformf(-amount, amount);
        b.minX += dx, b.maxX += dx, b.minY += dy, b.maxY += dy, b.minZ += dz, b.maxZ += dz;
    }
    g.refresh();
}

// ---- Deferred operations ----------------------------------------------------------------------------------------
void runDeferred(Device& d, uint32_t join, const std::function<VkResult(VkDeferredOperationKHR)>& command,
                 const char* what) {
    if (join == 0) {
        expect(&d, command(VK_NULL_HANDLE), VK_SUCCESS, what);
        return;
    }
    VkDeferredOperationKHR op = VK_NULL_HANDLE;
    expect(&d, d.vk.vkCreateDeferredOperationKHR(d.handle, nullptr, &op), VK_SUCCESS, "vkCreateDeferredOperationKHR");
    struct Guard {
        Device& d;
        VkDeferredOperationKHR op;
        ~Guard() { d.vk.vkDestroyDeferredOperationKHR(d.handle, op, nullptr); }
    } guard{d, op};
    const VkResult r = command(op);
    if (r == VK_OPERATION_NOT_DEFERRED_KHR || r == VK_SUCCESS) return;
    expect(&d, r, VK_OPERATION_DEFERRED_KHR, what);
    std::vector<VkResult> results(join, VK_ERROR_UNKNOWN);
    parallel(join, [&](uint32_t t) {
        VkResult j;
        while ((j = d.vk.vkDeferredOperationJoinKHR(d.handle, op)) == VK_THREAD_IDLE_KHR) std::this_thread::yield();
        results[t] = j;
    });
    uint32_t successes = 0;
    for (VkResult j : results) {
        if (j != VK_SUCCESS && j != VK_THREAD_DONE_KHR)
            fail(std::string(what) + ": vkDeferredOperationJoinKHR returned " + std::to_string(int(j)));
        successes += j == VK_SUCCESS;
    }
    if (successes == 0) fail(std::string(what) + ": no joined thread saw the operation complete");
    expect(&d, d.vk.vkGetDeferredOperationResultKHR(d.handle, op), VK_SUCCESS, what);
}

// ---- Builds -----------------------------------------------------------------------------------------------------
namespace {

std::shared_ptr<oracle::Blas> oracleBlas(const std::vector<const Geometry*>& geometries) {
    auto b = std::make_shared<oracle::Blas>();
    for (const auto* g : geometries) b->geometries.push_back(oracle::fetchGeometry(g->geometry, g->range));
    b->computeBounds();
    return b;
}

void packInstance(const InstanceDesc& in, uint8_t out[64]) {
    std::memcpy(out, &in.transform, 48);
    const uint32_t w0 = (in.customIndex & 0xFFFFFFu) | (in.mask << 24);
    const uint32_t w1 = (in.sbtOffset & 0xFFFFFFu) | (in.flags << 24);
    const uint64_t ref = in.blas ? in.blas->reference() : 0;
    std::memcpy(out + 48, &w0, 4);
    std::memcpy(out + 52, &w1, 4);
    std::memcpy(out + 56, &ref, 8);
}

struct InstanceData {
    std::vector<uint8_t> bytes;
    VkAccelerationStructureGeometryKHR geometry{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
    VkAccelerationStructureBuildRangeInfoKHR range{};
    std::shared_ptr<oracle::Scene> scene;
};

std::unique_ptr<InstanceData> instanceData(const std::vector<InstanceDesc>& instances) {
    auto data = std::make_unique<InstanceData>();
    data->bytes.assign(std::max<size_t>(64 * instances.size(), 64), 0);
    std::map<uint64_t, std::shared_ptr<const oracle::Blas>> blases;
    for (size_t i = 0; i < instances.size(); ++i) {
        packInstance(instances[i], data->bytes.data() + 64 * i);
        if (instances[i].blas) blases[instances[i].blas->reference()] = instances[i].blas->blas;
    }
    data->geometry.geometryType = VK_GEOMETRY_TYPE_INSTANCES_KHR;
    data->geometry.geometry.instances.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_INSTANCES_DATA_KHR;
    data->geometry.geometry.instances.data.hostAddress = data->bytes.data();
    data->range.primitiveCount = uint32_t(instances.size());
    data->scene = std::make_shared<oracle::Scene>();
    auto lookup = [&](uint64_t ref) -> std::shared_ptr<const oracle::Blas> {
        auto it = blases.find(ref);
        return it == blases.end() ? nullptr : it->second;
    };
    for (size_t i = 0; i < instances.size(); ++i)
        data->scene->instances.push_back(oracle::decodeInstance(data->bytes.data() + 64 * i, lookup));
    return data;
}

// One vkBuildAccelerationStructuresKHR: BUILD into a new structure (src null; returned) or UPDATE of src into dst
// (dst == src: in place).
std::unique_ptr<Structure> build(Device& d, VkAccelerationStructureTypeKHR type, VkBuildAccelerationStructureFlagsKHR flags,
                                 const std::vector<VkAccelerationStructureGeometryKHR>& geometries,
                                 const std::vector<VkAccelerationStructureBuildRangeInfoKHR>& ranges, Structure* src,
                                 bool inPlace, uint32_t join) {
    VkAccelerationStructureBuildGeometryInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
    info.type = type;
    info.flags = flags;
    info.mode = src ? VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR : VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR;
    info.geometryCount = uint32_t(geometries.size());
    info.pGeometries = geometries.data();
    std::vector<uint32_t> counts;
    for (const auto& r : ranges) counts.push_back(r.primitiveCount);
    VkAccelerationStructureBuildSizesInfoKHR sizes{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
    d.vk.vkGetAccelerationStructureBuildSizesKHR(d.handle, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info,
                                                 counts.data(), &sizes);
    std::unique_ptr<Structure> created;
    Structure* dst = src;
    if (!src || !inPlace) {
        created = createStructure(d, type, src ? src->size : sizes.accelerationStructureSize);
        dst = created.get();
    }
    dst->flags = flags;
    dst->updateScratchSize = sizes.updateScratchSize;
    info.srcAccelerationStructure = src ? src->handle : VK_NULL_HANDLE;
    info.dstAccelerationStructure = dst->handle;
    std::vector<uint64_t> scratch((size_t(src ? sizes.updateScratchSize : sizes.buildScratchSize) + 7) / 8 + 1);
    info.scratchData.hostAddress = scratch.data();
    const VkAccelerationStructureBuildRangeInfoKHR* rangePointer = ranges.data();
    runDeferred(d, join,
                [&](VkDeferredOperationKHR op) {
                    return d.vk.vkBuildAccelerationStructuresKHR(d.handle, op, 1, &info, &rangePointer);
                },
                src ? "vkBuildAccelerationStructuresKHR (update)" : "vkBuildAccelerationStructuresKHR");
    return created;
}

}  // namespace

std::unique_ptr<Structure> buildBlas(Device& d, const std::vector<const Geometry*>& geometries,
                                     VkBuildAccelerationStructureFlagsKHR flags, uint32_t join) {
    std::vector<VkAccelerationStructureGeometryKHR> g;
    std::vector<VkAccelerationStructureBuildRangeInfoKHR> r;
    for (const auto* x : geometries) g.push_back(x->geometry), r.push_back(x->range);
    auto s = build(d, VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, flags, g, r, nullptr, false, join);
    s->blas = oracleBlas(geometries);
    return s;
}

std::unique_ptr<Structure> updateBlas(Device& d, Structure& src, const std::vector<const Geometry*>& geometries,
                                      bool inPlace, uint32_t join) {
    std::vector<VkAccelerationStructureGeometryKHR> g;
    std::vector<VkAccelerationStructureBuildRangeInfoKHR> r;
    for (const auto* x : geometries) g.push_back(x->geometry), r.push_back(x->range);
    auto s = build(d, VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, src.flags, g, r, &src, inPlace, join);
    (s ? *s : src).blas = oracleBlas(geometries);
    return s;
}

std::unique_ptr<Structure> buildTlas(Device& d, const std::vector<InstanceDesc>& instances,
                                     VkBuildAccelerationStructureFlagsKHR flags, uint32_t join) {
    auto data = instanceData(instances);
    auto s = build(d, VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, flags, {data->geometry}, {data->range}, nullptr,
                   false, join);
    s->scene = data->scene;
    return s;
}

std::unique_ptr<Structure> updateTlas(Device& d, Structure& src, const std::vector<InstanceDesc>& instances,
                                      bool inPlace, uint32_t join) {
    auto data = instanceData(instances);
    auto s = build(d, VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, src.flags, {data->geometry}, {data->range}, &src,
                   inPlace, join);
    (s ? *s : src).scene = data->scene;
    return s;
}

// ---- Copies, queries, serialization -----------------------------------------------------------------------------
VkDeviceSize queryProperty(Device& d, const Structure& s, VkQueryType type) {
    uint64_t value = 0;
    expect(&d, d.vk.vkWriteAccelerationStructuresPropertiesKHR(d.handle, 1, &s.handle, type, sizeof value, &value,
                                                           sizeof value),
           VK_SUCCESS, "vkWriteAccelerationStructuresPropertiesKHR");
    return value;
}

namespace {
std::unique_ptr<Structure> copyInto(Device& d, const Structure& src, VkDeviceSize size, VkCopyAccelerationStructureModeKHR mode,
                                    uint32_t join) {
    auto dst = createStructure(d, src.type, size);
    dst->flags = src.flags;
    dst->updateScratchSize = src.updateScratchSize;
    VkCopyAccelerationStructureInfoKHR info{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_INFO_KHR};
    info.src = src.handle;
    info.dst = dst->handle;
    info.mode = mode;
    runDeferred(d, join, [&](VkDeferredOperationKHR op) { return d.vk.vkCopyAccelerationStructureKHR(d.handle, op, &info); },
                "vkCopyAccelerationStructureKHR");
    dst->blas = src.blas;
    dst->scene = src.scene;
    return dst;
}
}  // namespace

std::unique_ptr<Structure> cloneStructure(Device& d, const Structure& src, uint32_t join) {
    return copyInto(d, src, src.size, VK_COPY_ACCELERATION_STRUCTURE_MODE_CLONE_KHR, join);
}

std::unique_ptr<Structure> compactStructure(Device& d, const Structure& src, uint32_t join) {
    const VkDeviceSize size = queryProperty(d, src, VK_QUERY_TYPE_ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR);
    if (size == 0 || size > src.size) fail("compacted size " + std::to_string(size) + " of a structure of " + std::to_string(src.size));
    return copyInto(d, src, size, VK_COPY_ACCELERATION_STRUCTURE_MODE_COMPACT_KHR, join);
}

std::vector<uint8_t> serialize(Device& d, const Structure& src, uint32_t join) {
    const VkDeviceSize size = queryProperty(d, src, VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_SIZE_KHR);
    if (size < 56) fail("serialization size " + std::to_string(size));
    std::vector<uint64_t> storage(size_t(size + 7) / 8, 0);
    VkCopyAccelerationStructureToMemoryInfoKHR info{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_TO_MEMORY_INFO_KHR};
    info.src = src.handle;
    info.dst.hostAddress = storage.data();
    info.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_SERIALIZE_KHR;
    runDeferred(d, join,
                [&](VkDeferredOperationKHR op) { return d.vk.vkCopyAccelerationStructureToMemoryKHR(d.handle, op, &info); },
                "vkCopyAccelerationStructureToMemoryKHR");
    const auto* bytes = reinterpret_cast<const uint8_t*>(storage.data());
    return std::vector<uint8_t>(bytes, bytes + size);
}

VkAccelerationStructureCompatibilityKHR compatibility(Device& d, const std::vector<uint8_t>& blob) {
    VkAccelerationStructureVersionInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_VERSION_INFO_KHR};
    info.pVersionData = blob.data();
    VkAccelerationStructureCompatibilityKHR c = VK_ACCELERATION_STRUCTURE_COMPATIBILITY_MAX_ENUM_KHR;
    d.vk.vkGetDeviceAccelerationStructureCompatibilityKHR(d.handle, &info, &c);
    return c;
}

std::unique_ptr<Structure> deserialize(Device& d, const std::vector<uint8_t>& blob, VkAccelerationStructureTypeKHR type,
                                       uint32_t join) {
    if (blob.size() < 56) fail("blob too small to deserialize");
    uint64_t size = 0;
    std::memcpy(&size, blob.data() + 40, 8);
    auto dst = createStructure(d, type, size);
    std::vector<uint64_t> storage((blob.size() + 7) / 8, 0);  // 16-byte aligned source
    std::memcpy(storage.data(), blob.data(), blob.size());
    VkCopyMemoryToAccelerationStructureInfoKHR info{VK_STRUCTURE_TYPE_COPY_MEMORY_TO_ACCELERATION_STRUCTURE_INFO_KHR};
    info.src.hostAddress = storage.data();
    info.dst = dst->handle;
    info.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_DESERIALIZE_KHR;
    runDeferred(d, join,
                [&](VkDeferredOperationKHR op) { return d.vk.vkCopyMemoryToAccelerationStructureKHR(d.handle, op, &info); },
                "vkCopyMemoryToAccelerationStructureKHR");
    return dst;
}

std::vector<uint8_t> canonicalBlob(std::vector<uint8_t> blob) {
    if (blob.size() < 56) return blob;
    uint64_t n = 0;
    std::memcpy(&n, blob.data() + 48, 8);
    if (56 + 8 * n <= blob.size()) std::memset(blob.data() + 56, 0, size_t(8 * n));
    return blob;
}

// ---- Rays -------------------------------------------------------------------------------------------------------
std::vector<oracle::Ray> randomRays(const oracle::Scene& scene, vt::Rng& rng, size_t count) {
    std::vector<oracle::Ray> rays;
    std::vector<uint32_t> active;
    for (uint32_t i = 0; i < scene.instances.size(); ++i)
        if (scene.instances[i].blas) active.push_back(i);
    auto world = [](const oracle::Instance& inst, const oracle::Vec3& p) {
        oracle::Vec3 r;
        for (int k = 0; k < 3; ++k)
            r[k] = inst.toWorld[k][0] * p[0] + inst.toWorld[k][1] * p[1] + inst.toWorld[k][2] * p[2] + inst.toWorld[k][3];
        return r;
    };
    for (size_t n = 0; n < count; ++n) {
        oracle::Ray ray;
        oracle::Vec3 target{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)};
        if (!active.empty() && !rng.coin(0.15)) {
            const auto& inst = scene.instances[active[rng.below(uint32_t(active.size()))]];
            const auto& geoms = inst.blas->geometries;
            if (!geoms.empty()) {
                const auto& g = geoms[rng.below(uint32_t(geoms.size()))];
                if (!g.triangles.empty()) {
                    const auto& t = g.triangles[rng.below(uint32_t(g.triangles.size()))];
                    double a = rng.uniform(0.05, 0.9), b = rng.uniform(0.05, 0.9);
                    if (a + b > 0.95) a = 0.95 - a * 0.5, b = 0.95 - b * 0.5, a = std::max(a, 0.02), b = std::max(b, 0.02);
                    for (int k = 0; k < 3; ++k) target[k] = t.v[0][k] + a * (t.v[1][k] - t.v[0][k]) + b * (t.v[2][k] - t.v[0][k]);
                } else if (!g.aabbs.empty()) {
                    const auto& box = g.aabbs[rng.below(uint32_t(g.aabbs.size()))];
                    for (int k = 0; k < 3; ++k) target[k] = 0.5 * (box.lo[k] + box.hi[k]);
                }
                target = world(inst, target);
            }
        }
        // A direction on the sphere, the origin some distance back along it.
        double d[3], len = 0;
        do {
            len = 0;
            for (double& x : d) x = rng.uniform(-1, 1), len += x * x;
        } while (len < 1e-4 || len > 1);
        len = std::sqrt(len);
        const double dist = rng.uniform(0.5, 20.0), scale = rng.uniform(0.25, 4.0);
        for (int k = 0; k < 3; ++k) {
            ray.direction[k] = float(d[k] / len * scale);
            ray.origin[k] = float(target[k] - d[k] / len * dist);
        }
        ray.tMin = rng.coin(0.2) ? rng.uniformf(0.0f, 0.2f) : 0.0f;
        ray.tMax = rng.coin(0.2) ? rng.uniformf(1.0f, 10.0f) : 1e30f;
        rays.push_back(ray);
    }
    return rays;
}

std::vector<oracle::Result> expectedResults(const oracle::Scene& scene, const std::vector<oracle::Ray>& rays,
                                            uint32_t flags) {
    std::vector<oracle::Result> out;
    out.reserve(rays.size());
    for (const auto& r : rays) out.push_back(oracle::trace(scene, r, flags, 0xFF).withoutAabbs());
    return out;
}

std::vector<vt::Hit> rayQueries(VkAccelerationStructureKHR tlas, const std::vector<oracle::Ray>& rays, uint32_t flags) {
    std::vector<vt::Hit> hits;
    hits.reserve(rays.size());
    auto q = std::make_unique<VkasRayQuery>();  // 12 KiB: not on small thread stacks
    for (const auto& ray : rays) {
        vkasRayQueryInitialize(q.get(), tlas, flags, 0xFF, ray.origin.data(), ray.tMin, ray.direction.data(), ray.tMax);
        while (vkasRayQueryProceed(q.get()))
            if (vkasRayQueryGetIntersectionType(q.get(), VK_FALSE) == VKAS_CANDIDATE_INTERSECTION_TRIANGLE)
                vkasRayQueryConfirmIntersection(q.get());
        hits.push_back(vt::readHit(*q, true));
    }
    return hits;
}

std::vector<vt::Hit> batchTrace(Device& d, VkAccelerationStructureKHR tlas, const std::vector<oracle::Ray>& rays,
                                VkasTraceMode mode, uint32_t flags) {
    std::vector<VkasRay> in(rays.size());
    for (size_t i = 0; i < rays.size(); ++i) {
        std::memcpy(in[i].origin, rays[i].origin.data(), 12);
        std::memcpy(in[i].direction, rays[i].direction.data(), 12);
        in[i].tMin = rays[i].tMin;
        in[i].tMax = rays[i].tMax;
    }
    std::vector<VkasHit> out(rays.size());
    expect(&d, vkasTraceRays(d.handle, tlas, mode, flags, 0xFF, uint32_t(in.size()), in.data(), out.data()), VK_SUCCESS,
           "vkasTraceRays");
    std::vector<vt::Hit> hits;
    for (const auto& h : out) hits.push_back(vt::fromBatch(h));
    return hits;
}

size_t checkHits(const std::vector<oracle::Result>& expected, const std::vector<oracle::Ray>& rays,
                 const std::vector<vt::Hit>& hits, bool closest, const std::string& what) {
    if (expected.size() != rays.size() || hits.size() != rays.size()) fail(what + ": result counts differ");
    size_t count = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
        auto r = closest ? vt::matchesClosest(expected[i], rays[i], hits[i]) : vt::matchesAnyHit(expected[i], rays[i], hits[i]);
        if (!r) fail(what + ", ray " + std::to_string(i) + ": " + r.message());
        count += hits[i].type != VKAS_COMMITTED_INTERSECTION_NONE;
    }
    return count;
}

uint64_t residentBytes() {
    std::ifstream in("/proc/self/status");
    std::string line;
    while (std::getline(in, line))
        if (line.rfind("VmRSS:", 0) == 0) return std::strtoull(line.c_str() + 6, nullptr, 10) * 1024;
    return 0;
}

}  // namespace hk
