#include "fuzz_common.hpp"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <new>

namespace fz {

void fail(const char* format, ...) {
    va_list args;
    va_start(args, format);
    std::fputs("vkas fuzz: ", stderr);
    std::vfprintf(stderr, format, args);
    va_end(args);
    std::fflush(stderr);
    std::abort();
}

uint64_t hashBytes(const uint8_t* data, size_t size) {
    uint64_t h = 0xCBF29CE484222325ull;  // FNV-1a
    for (size_t i = 0; i < size; ++i) h = (h ^ data[i]) * 0x100000001B3ull;
    return h;
}

// ---- Region -----------------------------------------------------------------------------------------------------
Region::Region(size_t n, uint8_t fill) : size(n) {
    data = static_cast<uint8_t*>(::operator new(std::max<size_t>(n, 1), std::align_val_t(16)));
    std::memset(data, fill, n);
}
Region& Region::operator=(Region&& o) noexcept {
    if (this != &o) {
        this->~Region();
        data = o.data, size = o.size;
        o.data = nullptr, o.size = 0;
    }
    return *this;
}
Region::~Region() {
    if (data) ::operator delete(data, std::align_val_t(16));
}

// ---- Device -----------------------------------------------------------------------------------------------------
VkBool32 Device::messenger(VkDebugUtilsMessageSeverityFlagBitsEXT, VkDebugUtilsMessageTypeFlagsEXT,
                           const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
    auto* self = static_cast<Device*>(user);
    self->messages_.fetch_add(1);
    if (self->verbose_) std::fprintf(stderr, "  [vkas] %s\n", data && data->pMessage ? data->pMessage : "?");
    return VK_FALSE;
}

Device::Device(bool validation_) : validation(validation_) {
    verbose_ = std::getenv("VKAS_FUZZ_VERBOSE") != nullptr;
    vkas_kit::DeviceOptions options;
    options.validation = validation;
    options.workerThreads = 1;
    options.messenger = &Device::messenger;
    options.messengerUserData = this;
    try {
        kit_.emplace(options);
    } catch (const vkas_kit::DeviceError& e) {
        fail("vkasCreateDevice returned %d\n", int(e.result()));
    } catch (const vkas_kit::MissingCommand& e) {
        fail("vkasGetDeviceProcAddr(%s) returned NULL\n", e.command().c_str());
    }
    device = kit_->handle();
    static_cast<vkas_kit::Commands&>(*this) = kit_->commands();

    // Real structures of every kind, for references in fuzzed data.
    {
        std::vector<float> v;
        std::vector<uint32_t> idx;
        const int n = 4;
        for (int y = 0; y <= n; ++y)
            for (int x = 0; x <= n; ++x) v.insert(v.end(), {-1.0f + 2.0f * x / n, -1.0f + 2.0f * y / n, 0.1f * x});
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const uint32_t a = uint32_t(y * (n + 1) + x), b = a + 1, c = a + n + 1, d = c + 1;
                idx.insert(idx.end(), {a, b, d, a, d, c});
            }
        VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
        g.geometryType = VK_GEOMETRY_TYPE_TRIANGLES_KHR;
        auto& t = g.geometry.triangles;
        t.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR;
        t.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
        t.vertexData.hostAddress = v.data();
        t.vertexStride = 12;
        t.maxVertex = uint32_t(v.size() / 3 - 1);
        t.indexType = VK_INDEX_TYPE_UINT32;
        t.indexData.hostAddress = idx.data();
        blasTriangles = buildSimple(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, g, uint32_t(idx.size() / 3),
                                    VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_DATA_ACCESS_KHR);
        // [NV-motion] The same grid as motion triangles: at time 1 each vertex moves by (0.1 y, -0.2 x, 0.5).
        std::vector<float> v1(v);
        for (size_t k = 0; k < v1.size(); k += 3) {
            const float x = v1[k], y = v1[k + 1];
            v1[k] += 0.1f * y, v1[k + 1] -= 0.2f * x, v1[k + 2] += 0.5f;
        }
        VkAccelerationStructureGeometryMotionTrianglesDataNV m{
            VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_MOTION_TRIANGLES_DATA_NV};
        m.vertexData.hostAddress = v1.data();
        t.pNext = &m;
        blasMotion = buildSimple(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, g, uint32_t(idx.size() / 3),
                                 VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV |
                                     VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR);
    }
    {
        const VkAabbPositionsKHR boxes[4] = {{-1, -1, -1, 0, 0, 0}, {0, 0, 0, 1, 1, 1}, {-1, 0, -1, 0, 1, 0},
                                             {0.25f, -1, 0.25f, 0.75f, -0.5f, 0.75f}};
        VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
        g.geometryType = VK_GEOMETRY_TYPE_AABBS_KHR;
        g.geometry.aabbs.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_AABBS_DATA_KHR;
        g.geometry.aabbs.data.hostAddress = boxes;
        g.geometry.aabbs.stride = sizeof(VkAabbPositionsKHR);
        blasAabbs = buildSimple(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, g, 4);
    }
    {
        const float centers[4][3] = {{-0.5f, -0.5f, 0}, {0.5f, -0.5f, 0}, {0.5f, 0.5f, 0}, {-0.5f, 0.5f, 0.2f}};
        const float radii[4] = {0.3f, 0.2f, 0.4f, 0.25f};
        VkAccelerationStructureGeometrySpheresDataNV s{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_SPHERES_DATA_NV};
        s.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
        s.vertexData.hostAddress = centers;
        s.vertexStride = 12;
        s.radiusFormat = VK_FORMAT_R32_SFLOAT;
        s.radiusData.hostAddress = radii;
        s.radiusStride = 4;
        s.indexType = VK_INDEX_TYPE_NONE_KHR;
        VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
        g.pNext = &s;
        g.geometryType = VK_GEOMETRY_TYPE_SPHERES_NV;
        g.flags = VK_GEOMETRY_OPAQUE_BIT_KHR;
        blasSpheres = buildSimple(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, g, 4);

        VkAccelerationStructureGeometryLinearSweptSpheresDataNV l{
            VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_LINEAR_SWEPT_SPHERES_DATA_NV};
        l.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
        l.vertexData.hostAddress = centers;
        l.vertexStride = 12;
        l.radiusFormat = VK_FORMAT_R32_SFLOAT;
        l.radiusData.hostAddress = radii;
        l.radiusStride = 4;
        const uint32_t chain[3] = {0, 1, 2};
        l.indexType = VK_INDEX_TYPE_UINT32;
        l.indexData.hostAddress = chain;
        l.indexStride = 4;
        l.indexingMode = VK_RAY_TRACING_LSS_INDEXING_MODE_SUCCESSIVE_NV;
        l.endCapsMode = VK_RAY_TRACING_LSS_PRIMITIVE_END_CAPS_MODE_CHAINED_NV;
        g.pNext = &l;
        g.geometryType = VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV;
        g.flags = 0;
        blasLss = buildSimple(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, g, 3);
    }
    {
        VkAccelerationStructureInstanceKHR inst[5]{};
        const Structure* b[5] = {&blasTriangles, &blasAabbs, &blasSpheres, &blasLss, nullptr};
        for (int i = 0; i < 5; ++i) {
            inst[i].transform.matrix[0][0] = inst[i].transform.matrix[1][1] = inst[i].transform.matrix[2][2] = 1;
            inst[i].transform.matrix[0][3] = float(i % 2) * 3.0f;
            inst[i].transform.matrix[1][3] = float(i / 2) * 3.0f;
            inst[i].instanceCustomIndex = uint32_t(10 + i);
            inst[i].mask = 0xFF;
            inst[i].accelerationStructureReference = b[i] ? uint64_t(b[i]->handle) : 0;
        }
        inst[2].flags = VK_GEOMETRY_INSTANCE_FORCE_NO_OPAQUE_BIT_KHR;
        VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
        g.geometryType = VK_GEOMETRY_TYPE_INSTANCES_KHR;
        g.geometry.instances.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_INSTANCES_DATA_KHR;
        g.geometry.instances.data.hostAddress = inst;
        tlas = buildSimple(VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, g, 5);
    }
    {
        // [NV-motion] A motion top level: one instance of each type and of each bottom level, one inactive.
        VkAccelerationStructureMotionInstanceNV inst[6];
        std::memset(inst, 0, sizeof inst);
        const Structure* b[6] = {&blasTriangles, &blasMotion, &blasAabbs, &blasSpheres, &blasLss, nullptr};
        for (int i = 0; i < 6; ++i) {
            const uint32_t type = uint32_t(i % 3);
            inst[i].type = VkAccelerationStructureMotionInstanceTypeNV(type);
            const uint64_t ref = b[i] ? uint64_t(b[i]->handle) : 0;
            const float tx = float(i % 3) * 3.0f, ty = float(i / 3) * 3.0f;
            if (type == 0) {
                auto& s = inst[i].data.staticInstance;
                s.transform.matrix[0][0] = s.transform.matrix[1][1] = s.transform.matrix[2][2] = 1;
                s.transform.matrix[0][3] = tx, s.transform.matrix[1][3] = ty;
                s.instanceCustomIndex = uint32_t(20 + i), s.mask = 0xFF, s.accelerationStructureReference = ref;
            } else if (type == 1) {
                auto& mm = inst[i].data.matrixMotionInstance;
                for (auto* t : {&mm.transformT0, &mm.transformT1}) {
                    t->matrix[0][0] = t->matrix[1][1] = t->matrix[2][2] = 1;
                    t->matrix[0][3] = tx, t->matrix[1][3] = ty;
                }
                mm.transformT1.matrix[2][3] = 1.5f;
                mm.transformT1.matrix[0][1] = 0.25f;
                mm.instanceCustomIndex = uint32_t(20 + i), mm.mask = 0xFF, mm.accelerationStructureReference = ref;
                mm.flags = VK_GEOMETRY_INSTANCE_TRIANGLE_FACING_CULL_DISABLE_BIT_KHR;
            } else {
                auto& sm = inst[i].data.srtMotionInstance;
                for (auto* t : {&sm.transformT0, &sm.transformT1}) {
                    t->sx = t->sy = t->sz = 1;
                    t->qw = 1;
                    t->tx = tx, t->ty = ty;
                }
                sm.transformT1.qz = 0.7071068f, sm.transformT1.qw = 0.7071068f;  // 90 degrees about z at time 1
                sm.transformT1.sx = 1.5f, sm.transformT1.a = 0.2f, sm.transformT1.pvx = 0.5f;
                sm.instanceCustomIndex = uint32_t(20 + i), sm.mask = 0xFF, sm.accelerationStructureReference = ref;
            }
        }
        Region arr(160 * 6);
        for (int i = 0; i < 6; ++i) std::memcpy(arr.data + 160 * i, &inst[i], sizeof inst[i]);
        VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
        g.geometryType = VK_GEOMETRY_TYPE_INSTANCES_KHR;
        g.geometry.instances.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_INSTANCES_DATA_KHR;
        g.geometry.instances.data.hostAddress = arr.data;
        tlasMotion = buildSimple(VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, g, 6,
                                 VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV);
    }
    unbuilt = createStructure(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, 4096);
    Structure dead = createStructure(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, 256);
    deadHandle = uint64_t(dead.handle);
    destroyStructure(dead);
    FZ_CHECK(messages() == 0, "validation reported %llu message(s) while the harness set up its device",
             (unsigned long long)messages());
}

Device::~Device() {
    for (Structure* s : {&blasTriangles, &blasAabbs, &blasSpheres, &blasLss, &tlas, &blasMotion, &tlasMotion, &unbuilt})
        destroyStructure(*s);
}

Buffer Device::createBuffer(VkDeviceSize size, uint8_t poison) {
    Buffer b;
    VkBufferCreateInfo ci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    ci.size = std::max<VkDeviceSize>(size, 1);
    ci.usage = VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_STORAGE_BIT_KHR | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT;
    FZ_CHECK(vkCreateBuffer(device, &ci, nullptr, &b.buffer) == VK_SUCCESS, "vkCreateBuffer");
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(device, b.buffer, &req);
    VkMemoryAllocateFlagsInfo flags{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
    flags.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
    VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    ai.pNext = &flags;
    ai.allocationSize = req.size;
    ai.memoryTypeIndex = 0;
    FZ_CHECK(vkAllocateMemory(device, &ai, nullptr, &b.memory) == VK_SUCCESS, "vkAllocateMemory");
    FZ_CHECK(vkBindBufferMemory(device, b.buffer, b.memory, 0) == VK_SUCCESS, "vkBindBufferMemory");
    void* p = nullptr;
    FZ_CHECK(vkMapMemory(device, b.memory, 0, VK_WHOLE_SIZE, 0, &p) == VK_SUCCESS, "vkMapMemory");
    b.data = static_cast<uint8_t*>(p);
    b.size = req.size;
    std::memset(b.data, poison, b.size);
    return b;
}

void Device::destroyBuffer(Buffer& b) {
    if (b.buffer) vkDestroyBuffer(device, b.buffer, nullptr);
    if (b.memory) vkFreeMemory(device, b.memory, nullptr);
    b = Buffer{};
}

Structure Device::createStructure(VkAccelerationStructureTypeKHR type, VkDeviceSize size, VkDeviceSize offset,
                                  VkDeviceSize bufferSize, VkAccelerationStructureCreateFlagsKHR createFlags,
                                  uint32_t motionMaxInstances) {
    Structure s;
    s.offset = offset;
    s.size = size;
    s.buffer = createBuffer(std::max(offset + size + 256, bufferSize));
    VkAccelerationStructureCreateInfoKHR ci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
    ci.buffer = s.buffer.buffer;
    ci.offset = offset;
    ci.size = size;
    ci.type = type;
    ci.createFlags = createFlags;
    VkAccelerationStructureMotionInfoNV motionInfo{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_MOTION_INFO_NV};
    motionInfo.maxInstances = motionMaxInstances;
    if ((createFlags & VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV) && type != VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR)
        ci.pNext = &motionInfo;
    FZ_CHECK(vkCreateAccelerationStructureKHR(device, &ci, nullptr, &s.handle) == VK_SUCCESS,
             "vkCreateAccelerationStructureKHR");
    return s;
}

void Device::destroyStructure(Structure& s) {
    if (s.handle) vkDestroyAccelerationStructureKHR(device, s.handle, nullptr);
    destroyBuffer(s.buffer);
    s = Structure{};
}

uint64_t Device::address(const Structure& s) {
    VkAccelerationStructureDeviceAddressInfoKHR ai{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_DEVICE_ADDRESS_INFO_KHR};
    ai.accelerationStructure = s.handle;
    return vkGetAccelerationStructureDeviceAddressKHR(device, &ai);
}

VkDeviceSize Device::usedSize(const Structure& s) {
    VkDeviceSize size = ~VkDeviceSize(0);
    FZ_CHECK(vkWriteAccelerationStructuresPropertiesKHR(device, 1, &s.handle, VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SIZE_KHR,
                                                        sizeof size, &size, sizeof size) == VK_SUCCESS,
             "vkWriteAccelerationStructuresPropertiesKHR(SIZE)");
    return size;
}

Structure Device::buildSimple(VkAccelerationStructureTypeKHR type, const VkAccelerationStructureGeometryKHR& geometry,
                              uint32_t primitiveCount, VkBuildAccelerationStructureFlagsKHR flags) {
    VkAccelerationStructureBuildGeometryInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
    info.type = type;
    info.flags = flags;
    info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR;
    info.geometryCount = 1;
    info.pGeometries = &geometry;
    VkAccelerationStructureBuildSizesInfoKHR sizes{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
    vkGetAccelerationStructureBuildSizesKHR(device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info,
                                            &primitiveCount, &sizes);
    const bool motion = (flags & VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV) != 0;
    Structure s = createStructure(type, (sizes.accelerationStructureSize + 255) / 256 * 256, 0, 0,
                                  motion ? VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV : 0, primitiveCount);
    Region scratch(sizes.buildScratchSize);
    info.dstAccelerationStructure = s.handle;
    info.scratchData.hostAddress = scratch.data;
    VkAccelerationStructureBuildRangeInfoKHR range{};
    range.primitiveCount = primitiveCount;
    const VkAccelerationStructureBuildRangeInfoKHR* ranges[] = {&range};
    FZ_CHECK(vkBuildAccelerationStructuresKHR(device, VK_NULL_HANDLE, 1, &info, ranges) == VK_SUCCESS,
             "a valid build of the harness failed");
    return s;
}

Structure Device::buildSingleInstanceTlas(const Structure& blas, uint32_t instanceFlags, int motionType) {
    VkAccelerationStructureInstanceKHR inst{};
    inst.transform.matrix[0][0] = inst.transform.matrix[1][1] = inst.transform.matrix[2][2] = 1;
    inst.mask = 0xFF;
    inst.flags = instanceFlags & 0x0F;  // the core VkGeometryInstanceFlagBitsKHR
    inst.accelerationStructureReference = uint64_t(blas.handle);
    VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
    g.geometryType = VK_GEOMETRY_TYPE_INSTANCES_KHR;
    g.geometry.instances.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_INSTANCES_DATA_KHR;
    g.geometry.instances.data.hostAddress = &inst;
    if (motionType < 0) return buildSimple(VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, g, 1);
    // [NV-motion] One motion instance: the identity at time 0, moved (and for SRT rotated) at time 1.
    VkAccelerationStructureMotionInstanceNV mi;
    std::memset(&mi, 0, sizeof mi);
    mi.type = VkAccelerationStructureMotionInstanceTypeNV(motionType % 3);
    if (mi.type == VK_ACCELERATION_STRUCTURE_MOTION_INSTANCE_TYPE_STATIC_NV) {
        mi.data.staticInstance = inst;
    } else if (mi.type == VK_ACCELERATION_STRUCTURE_MOTION_INSTANCE_TYPE_MATRIX_MOTION_NV) {
        auto& m = mi.data.matrixMotionInstance;
        m.transformT0 = m.transformT1 = inst.transform;
        m.transformT1.matrix[0][3] = 0.5f, m.transformT1.matrix[1][0] = 0.1f;
        m.mask = 0xFF, m.flags = inst.flags, m.accelerationStructureReference = inst.accelerationStructureReference;
    } else {
        auto& s = mi.data.srtMotionInstance;
        for (auto* t : {&s.transformT0, &s.transformT1}) t->sx = t->sy = t->sz = 1, t->qw = 1;
        s.transformT1.qx = 0.5f, s.transformT1.qw = 0.8660254f, s.transformT1.ty = 0.5f;
        s.mask = 0xFF, s.flags = inst.flags, s.accelerationStructureReference = inst.accelerationStructureReference;
    }
    g.geometry.instances.data.hostAddress = &mi;
    return buildSimple(VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, g, 1, VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV);
}

Device& validatingDevice() {
    static Device* d = new Device(true);  // never destroyed: lives as long as the fuzz process
    return *d;
}
Device& plainDevice() {
    static Device* d = new Device(false);
    return *d;
}

// ---- Tracing ----------------------------------------------------------------------------------------------------
namespace {

float loadFloat(const uint8_t* p) {
    float f;
    std::memcpy(&f, p, 4);
    return f;
}

VkBool32 VKAPI_PTR intersectAtEntry(void*, const VkasAabbCandidate* c, float* tHit) {
    *tHit = c->tMin;
    return (c->primitiveIndex & 1) == 0 ? VK_TRUE : VK_FALSE;
}

// time: NULL for vkasRayQueryInitialize, else vkasRayQueryInitializeMotion at *time.
void runQuery(VkAccelerationStructureKHR topLevel, uint32_t flags, const VkasRay& r, uint32_t variant,
              const float* time = nullptr) {
    alignas(16) static thread_local VkasRayQuery q;
    if (time) vkasRayQueryInitializeMotion(&q, topLevel, flags, 0xFF, r.origin, r.tMin, r.direction, r.tMax, *time);
    else vkasRayQueryInitialize(&q, topLevel, flags, 0xFF, r.origin, r.tMin, r.direction, r.tMax);
    uint64_t stops = 0;
    float tmp[4][4];
    while (vkasRayQueryProceed(&q)) {
        FZ_CHECK(++stops < (1u << 20), "a ray query did not end");
        const uint32_t type = vkasRayQueryGetIntersectionType(&q, VK_FALSE);
        // Every getter on the candidate.
        (void)vkasRayQueryGetIntersectionT(&q, VK_FALSE);
        (void)vkasRayQueryGetIntersectionInstanceCustomIndex(&q, VK_FALSE);
        (void)vkasRayQueryGetIntersectionInstanceId(&q, VK_FALSE);
        (void)vkasRayQueryGetIntersectionInstanceShaderBindingTableRecordOffset(&q, VK_FALSE);
        (void)vkasRayQueryGetIntersectionGeometryIndex(&q, VK_FALSE);
        (void)vkasRayQueryGetIntersectionPrimitiveIndex(&q, VK_FALSE);
        vkasRayQueryGetIntersectionBarycentrics(&q, VK_FALSE, tmp[0]);
        (void)vkasRayQueryGetIntersectionFrontFace(&q, VK_FALSE);
        (void)vkasRayQueryGetIntersectionCandidateAABBOpaque(&q);
        vkasRayQueryGetIntersectionObjectRayOrigin(&q, VK_FALSE, tmp[0]);
        vkasRayQueryGetIntersectionObjectRayDirection(&q, VK_FALSE, tmp[0]);
        vkasRayQueryGetIntersectionObjectToWorld(&q, VK_FALSE, reinterpret_cast<float(*)[4]>(tmp));
        vkasRayQueryGetIntersectionWorldToObject(&q, VK_FALSE, reinterpret_cast<float(*)[4]>(tmp));
        vkasRayQueryGetIntersectionTriangleVertexPositions(&q, VK_FALSE, reinterpret_cast<float(*)[3]>(tmp));
        (void)vkasRayQueryIsSphereHit(&q, VK_FALSE);
        (void)vkasRayQueryIsLssHit(&q, VK_FALSE);
        vkasRayQueryGetIntersectionSpherePosition(&q, VK_FALSE, tmp[0]);
        (void)vkasRayQueryGetIntersectionSphereRadius(&q, VK_FALSE);
        vkasRayQueryGetIntersectionLssPositions(&q, VK_FALSE, reinterpret_cast<float(*)[3]>(tmp));
        vkasRayQueryGetIntersectionLssRadii(&q, VK_FALSE, tmp[0]);
        (void)vkasRayQueryGetIntersectionLssHitValue(&q, VK_FALSE);
        (void)vkasRayQueryGetIntersectionPrimitiveType(&q, VK_FALSE);
        if (type == VKAS_CANDIDATE_INTERSECTION_TRIANGLE) {
            if ((stops + variant) % 3 != 0) vkasRayQueryConfirmIntersection(&q);
        } else {
            const float tMin = vkasRayQueryGetRayTMin(&q);
            const float t = vkasRayQueryGetIntersectionT(&q, VK_FALSE);
            vkasRayQueryGenerateIntersection(&q, (stops + variant) % 2 ? t : tMin);
        }
        if (variant == 3 && stops == 5) vkasRayQueryTerminate(&q);
    }
    (void)vkasRayQueryGetRayFlags(&q);
    vkasRayQueryGetWorldRayOrigin(&q, tmp[0]);
    vkasRayQueryGetWorldRayDirection(&q, tmp[0]);
    if (vkasRayQueryGetIntersectionType(&q, VK_TRUE) != VKAS_COMMITTED_INTERSECTION_NONE) {
        (void)vkasRayQueryGetIntersectionT(&q, VK_TRUE);
        (void)vkasRayQueryGetIntersectionInstanceId(&q, VK_TRUE);
        (void)vkasRayQueryGetIntersectionPrimitiveIndex(&q, VK_TRUE);
        vkasRayQueryGetIntersectionBarycentrics(&q, VK_TRUE, tmp[0]);
        vkasRayQueryGetIntersectionObjectToWorld(&q, VK_TRUE, reinterpret_cast<float(*)[4]>(tmp));
        vkasRayQueryGetIntersectionTriangleVertexPositions(&q, VK_TRUE, reinterpret_cast<float(*)[3]>(tmp));
        vkasRayQueryGetIntersectionLssPositions(&q, VK_TRUE, reinterpret_cast<float(*)[3]>(tmp));
        (void)vkasRayQueryGetIntersectionSphereRadius(&q, VK_TRUE);
    }
}

}  // namespace

void traceProbe(Device& device, VkAccelerationStructureKHR topLevel, const float bounds[6], const uint8_t* seed,
                size_t seedSize) {
    float c[3] = {0, 0, 0}, extent = 1;
    bool finite = bounds != nullptr;
    for (int k = 0; finite && k < 6; ++k) finite = std::isfinite(bounds[k]) && std::fabs(bounds[k]) < 1e18f;
    if (finite) {
        for (int k = 0; k < 3; ++k) {
            c[k] = 0.5f * (bounds[k] + bounds[k + 3]);
            extent = std::max(extent, bounds[k + 3] - bounds[k]);
        }
    }
    std::vector<VkasRay> rays;
    for (int axis = 0; axis < 3; ++axis)
        for (float sign : {-1.0f, 1.0f}) {
            VkasRay r{};
            float d[3] = {0.01f, 0.02f, 0.03f};
            d[axis] = sign;
            for (int k = 0; k < 3; ++k) {
                r.origin[k] = c[k] - d[k] * 2 * extent;
                r.direction[k] = d[k];
            }
            r.tMin = 0;
            r.tMax = 4 * extent + 1;
            rays.push_back(r);
        }
    // A ray from the inside, and a few from the seed (raw floats: some break the ray rules, which validation reports).
    VkasRay inside{{c[0], c[1], c[2]}, 0.0f, {0.3f, -0.5f, 0.8f}, 1e30f};
    rays.push_back(inside);
    for (size_t off = 0; off + 32 <= seedSize && rays.size() < 11; off += 32) {
        VkasRay r{};
        for (int k = 0; k < 3; ++k) {
            r.origin[k] = loadFloat(seed + off + 4 * k);
            r.direction[k] = loadFloat(seed + off + 12 + 4 * k);
        }
        r.tMin = std::fabs(loadFloat(seed + off + 24));
        r.tMax = std::fabs(loadFloat(seed + off + 28));
        rays.push_back(r);
    }
    uint32_t extraFlags = seedSize >= 2 ? uint32_t(seed[0] | (seed[1] << 8)) & 0x3FF : 0;
    const uint32_t flagSets[] = {0, VKAS_RAY_FLAG_OPAQUE, extraFlags};
    for (uint32_t f = 0; f < 3; ++f)
        for (size_t i = 0; i < rays.size(); ++i) runQuery(topLevel, flagSets[f], rays[i], uint32_t(i + f));
    // [NV-motion] Each ray once more at one of three ray times (a time outside [0, 1], NaN included, is reported and
    // traces nothing).
    const float times[3] = {0.25f, 1.0f, seedSize >= 6 ? loadFloat(seed + 2) : 0.75f};
    for (size_t i = 0; i < rays.size(); ++i)
        runQuery(topLevel, i % 3 == 2 ? extraFlags : 0, rays[i], uint32_t(i), &times[i % 3]);
    std::vector<VkasHit> hits(rays.size());
    const uint32_t n = uint32_t(rays.size());
    for (VkasTraceMode mode : {VKAS_TRACE_MODE_CLOSEST_HIT, VKAS_TRACE_MODE_ANY_HIT}) {
        (void)vkasTraceRays(device.device, topLevel, mode, 0, 0xFF, n, rays.data(), hits.data());
        (void)vkasTraceRaysProcedural(device.device, topLevel, mode, extraFlags, 0xFF, n, rays.data(), hits.data(),
                                      &intersectAtEntry, nullptr);
    }
}

}  // namespace fz
