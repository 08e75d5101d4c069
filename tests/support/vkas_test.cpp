#include "vkas_test.hpp"

#include <algorithm>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <limits>
#include <set>
#include <sstream>
#include <tuple>

namespace vt {

uint64_t chooseSeed() {
    if (const char* env = std::getenv("VKAS_TEST_SEED"); env && *env) return std::strtoull(env, nullptr, 0);
    std::random_device rd;
    return (uint64_t(rd()) << 32) ^ uint64_t(rd());
}

// ---- Math -------------------------------------------------------------------------------------------------------
std::vector<uint8_t> triangleRecordsOf(const uint8_t* block) {
    auto load32 = [](const uint8_t* p) { uint32_t v; std::memcpy(&v, p, 4); return v; };
    auto load64 = [](const uint8_t* p) { uint64_t v; std::memcpy(&v, p, 8); return v; };
    const uint32_t recordCount = load32(block + 64), nodeCount = load32(block + 68);
    const uint64_t nodeOffset = load64(block + 80), recordOffset = load64(block + 88);
    std::vector<uint8_t> out(48ull * recordCount, 0);
    auto unpack = [&](uint64_t ref) {
        if ((ref >> 62) != 2) return;
        const uint64_t first = ref & 0xFF'FFFF'FFFFull;
        const uint32_t n = uint32_t(ref >> 40) & 0xFF;
        const uint8_t* leaf = block + recordOffset + 44 * first;
        for (uint32_t l = 0; l < n && first + l < recordCount; ++l) {
            uint8_t* r = out.data() + 48 * (first + l);
            for (uint32_t row = 0; row < 9; ++row) std::memcpy(r + 4 * row, leaf + 4 * (row * n + l), 4);
            const uint32_t primitive = load32(leaf + 4 * (9 * n + l)), gf = load32(leaf + 4 * (10 * n + l));
            const uint32_t geometry = gf & 0xFFFFFFu, flags = gf >> 24;
            std::memcpy(r + 36, &geometry, 4), std::memcpy(r + 40, &primitive, 4), std::memcpy(r + 44, &flags, 4);
        }
    };
    unpack(load64(block + 24));
    for (uint32_t k = 0; k < nodeCount; ++k)
        for (uint32_t c = 0; c < 8; ++c) unpack(load64(block + nodeOffset + 256ull * k + 192 + 8 * c));
    return out;
}

VkTransformMatrixKHR identityTransform() {
    VkTransformMatrixKHR m{};
    m.matrix[0][0] = m.matrix[1][1] = m.matrix[2][2] = 1.0f;
    return m;
}

VkTransformMatrixKHR translation(float x, float y, float z) {
    VkTransformMatrixKHR m = identityTransform();
    m.matrix[0][3] = x;
    m.matrix[1][3] = y;
    m.matrix[2][3] = z;
    return m;
}

VkTransformMatrixKHR compose(const VkTransformMatrixKHR& a, const VkTransformMatrixKHR& b) {
    VkTransformMatrixKHR r{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 4; ++j) {
            double s = j == 3 ? a.matrix[i][3] : 0.0;
            for (int k = 0; k < 3; ++k) s += double(a.matrix[i][k]) * b.matrix[k][j];
            r.matrix[i][j] = float(s);
        }
    return r;
}

VkTransformMatrixKHR randomTransform(Rng& rng, float minScale, float maxScale, bool mirror, float maxTranslation) {
    // Uniform random rotation (Shoemake).
    const double u1 = rng.uniform(0, 1), u2 = rng.uniform(0, 2 * M_PI), u3 = rng.uniform(0, 2 * M_PI);
    const double a = std::sqrt(1 - u1), b = std::sqrt(u1);
    const double x = a * std::sin(u2), y = a * std::cos(u2), z = b * std::sin(u3), w = b * std::cos(u3);
    const double R[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)},
                            {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)},
                            {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)}};
    double s[3];
    for (double& v : s) v = rng.uniform(minScale, maxScale);
    if (mirror) s[rng.below(3)] *= -1.0;
    VkTransformMatrixKHR m{};
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) m.matrix[i][j] = float(R[i][j] * s[j]);
        m.matrix[i][3] = rng.uniformf(-maxTranslation, maxTranslation);
    }
    return m;
}

Float3 transformPoint(const VkTransformMatrixKHR& m, const Float3& p) {
    Float3 r;
    for (int i = 0; i < 3; ++i)
        r[i] = float(double(m.matrix[i][0]) * p[0] + double(m.matrix[i][1]) * p[1] + double(m.matrix[i][2]) * p[2] +
                     m.matrix[i][3]);
    return r;
}

std::string describe(const oracle::Ray& r) {
    char buf[512];
    std::snprintf(buf, sizeof buf, "origin (%a, %a, %a) dir (%a, %a, %a) tMin %a tMax %a  [~ (%g %g %g) (%g %g %g) %g %g]",
                  r.origin[0], r.origin[1], r.origin[2], r.direction[0], r.direction[1], r.direction[2], r.tMin,
                  r.tMax, r.origin[0], r.origin[1], r.origin[2], r.direction[0], r.direction[1], r.direction[2],
                  r.tMin, r.tMax);
    return buf;
}

// ---- Meshes -----------------------------------------------------------------------------------------------------
std::unique_ptr<GeometryData> makeGeometry(const Mesh& mesh, VkIndexType indexType, VkGeometryFlagsKHR flags,
                                           const VkTransformMatrixKHR* transform) {
    auto g = std::make_unique<GeometryData>();
    const size_t triCount = mesh.triangleCount();
    auto& tri = g->geometry.geometry.triangles;
    g->geometry.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR;
    g->geometry.geometryType = VK_GEOMETRY_TYPE_TRIANGLES_KHR;
    g->geometry.flags = flags;
    tri.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR;
    tri.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
    tri.vertexStride = 12;
    tri.indexType = indexType;
    if (indexType == VK_INDEX_TYPE_NONE_KHR) {
        g->vertices.resize(std::max<size_t>(triCount * 36, 1));
        for (size_t i = 0; i < triCount * 3; ++i)
            std::memcpy(g->vertices.data() + 12 * i, mesh.positions[mesh.indices[i]].data(), 12);
        tri.maxVertex = uint32_t(triCount ? triCount * 3 - 1 : 0);
    } else {
        g->vertices.resize(std::max<size_t>(mesh.positions.size() * 12, 1));
        if (!mesh.positions.empty()) std::memcpy(g->vertices.data(), mesh.positions.data(), mesh.positions.size() * 12);
        tri.maxVertex = uint32_t(mesh.positions.empty() ? 0 : mesh.positions.size() - 1);
        if (indexType == VK_INDEX_TYPE_UINT16) {
            if (mesh.positions.size() > 65536) throw std::invalid_argument("mesh too large for 16-bit indices");
            g->indices.resize(std::max<size_t>(mesh.indices.size() * 2, 2));
            for (size_t i = 0; i < mesh.indices.size(); ++i) {
                const uint16_t v = uint16_t(mesh.indices[i]);
                std::memcpy(g->indices.data() + 2 * i, &v, 2);
            }
        } else {
            g->indices.resize(std::max<size_t>(mesh.indices.size() * 4, 4));
            if (!mesh.indices.empty()) std::memcpy(g->indices.data(), mesh.indices.data(), mesh.indices.size() * 4);
        }
        tri.indexData.hostAddress = g->indices.data();
    }
    tri.vertexData.hostAddress = g->vertices.data();
    if (transform) {
        g->transform.resize(sizeof(VkTransformMatrixKHR));
        std::memcpy(g->transform.data(), transform, sizeof(VkTransformMatrixKHR));
        tri.transformData.hostAddress = g->transform.data();
    }
    g->range.primitiveCount = uint32_t(triCount);
    return g;
}

void packInstance(const Instance& in, uint8_t out[64]) {
    std::memcpy(out, &in.transform, 48);
    const uint32_t w0 = (in.customIndex & 0xFFFFFFu) | (in.mask << 24);
    const uint32_t w1 = (in.sbtOffset & 0xFFFFFFu) | (in.flags << 24);
    const uint64_t ref = in.blas ? in.blas->reference() : 0;
    std::memcpy(out + 48, &w0, 4);
    std::memcpy(out + 52, &w1, 4);
    std::memcpy(out + 56, &ref, 8);
}

// ---- Results ----------------------------------------------------------------------------------------------------
std::string Hit::str() const {
    if (type == VKAS_COMMITTED_INTERSECTION_NONE && instanceId < 0) return "miss";
    char buf[256];
    std::snprintf(buf, sizeof buf, "type %u t %.9g inst %d custom %d sbt %u geom %d prim %d bary (%.6g %.6g) %s", type,
                  t, instanceId, customIndex, sbtOffset, geometryIndex, primitiveIndex, bary[0], bary[1],
                  frontFace ? "front" : "back");
    return buf;
}

Hit readHit(const VkasRayQuery& q, bool committed) {
    const VkBool32 c = committed ? VK_TRUE : VK_FALSE;
    Hit h;
    h.type = vkasRayQueryGetIntersectionType(&q, c);
    if (committed && h.type == VKAS_COMMITTED_INTERSECTION_NONE) return h;
    h.t = vkasRayQueryGetIntersectionT(&q, c);
    h.instanceId = vkasRayQueryGetIntersectionInstanceId(&q, c);
    h.customIndex = vkasRayQueryGetIntersectionInstanceCustomIndex(&q, c);
    h.geometryIndex = vkasRayQueryGetIntersectionGeometryIndex(&q, c);
    h.primitiveIndex = vkasRayQueryGetIntersectionPrimitiveIndex(&q, c);
    h.sbtOffset = vkasRayQueryGetIntersectionInstanceShaderBindingTableRecordOffset(&q, c);
    vkasRayQueryGetIntersectionBarycentrics(&q, c, h.bary);
    h.frontFace = vkasRayQueryGetIntersectionFrontFace(&q, c) == VK_TRUE;
    vkasRayQueryGetIntersectionObjectRayOrigin(&q, c, h.objectOrigin);
    vkasRayQueryGetIntersectionObjectRayDirection(&q, c, h.objectDirection);
    if (!committed && h.type == VKAS_CANDIDATE_INTERSECTION_AABB)
        h.aabbOpaque = vkasRayQueryGetIntersectionCandidateAABBOpaque(&q) == VK_TRUE;
    return h;
}

bool identical(const Hit& a, const Hit& b) {
    if (a.type != b.type) return false;
    if (a.type == VKAS_COMMITTED_INTERSECTION_NONE) return true;
    return std::memcmp(&a.t, &b.t, 4) == 0 && a.instanceId == b.instanceId && a.customIndex == b.customIndex &&
           a.geometryIndex == b.geometryIndex && a.primitiveIndex == b.primitiveIndex && a.sbtOffset == b.sbtOffset &&
           std::memcmp(a.bary, b.bary, 8) == 0 && a.frontFace == b.frontFace;
}

Hit fromBatch(const VkasHit& b) {
    Hit h;
    h.type = b.type;
    if (h.type == VKAS_COMMITTED_INTERSECTION_NONE) return h;
    h.t = b.t;
    h.instanceId = b.instanceId;
    h.customIndex = b.instanceCustomIndex;
    h.geometryIndex = b.geometryIndex;
    h.primitiveIndex = b.primitiveIndex;
    h.sbtOffset = b.instanceShaderBindingTableRecordOffset;
    h.bary[0] = b.barycentrics[0];
    h.bary[1] = b.barycentrics[1];
    h.frontFace = b.frontFace == VK_TRUE;
    return h;
}

namespace {
std::string listCandidates(const oracle::Result& r) {
    std::vector<const oracle::Candidate*> v;
    for (const auto& c : r.candidates) v.push_back(&c);
    std::sort(v.begin(), v.end(), [](auto* a, auto* b) { return a->t < b->t; });
    std::ostringstream s;
    s << r.candidates.size() << " oracle candidate(s)";
    for (size_t i = 0; i < v.size() && i < 8; ++i) {
        const auto* c = v[i];
        char buf[256];
        if (c->aabb)
            std::snprintf(buf, sizeof buf, "\n    AABB t %.9g..%.9g (tol %.3g) inst %d geom %d prim %d %s%s", c->t, c->tExit,
                          c->tTolerance, c->instanceId, c->geometryIndex, c->primitiveIndex,
                          c->opaque ? "opaque" : "non-opaque", c->optional ? " (optional)" : "");
        else
            std::snprintf(buf, sizeof buf, "\n    t %.9g (tol %.3g) inst %d geom %d prim %d bary (%.6g %.6g, tol %.3g) %s %s%s", c->t,
                          c->tTolerance, c->instanceId, c->geometryIndex, c->primitiveIndex, c->bary[0], c->bary[1], c->baryTolerance,
                          c->frontFace ? "front" : "back", c->opaque ? "opaque" : "non-opaque",
                          c->optional ? " (optional)" : "");
        s << buf;
    }
    return s.str();
}

::testing::AssertionResult compare(const oracle::Result& expected, const oracle::Ray& ray, const Hit& got,
                                   bool closest) {
    auto fail = [&](const std::string& why) {
        return ::testing::AssertionFailure() << why << "\n  ray " << describe(ray) << "\n  vkas:   " << got.str()
                                             << "\n  oracle: " << listCandidates(expected);
    };
    if (got.type == VKAS_COMMITTED_INTERSECTION_NONE) {
        if (expected.requiredCount() == 0) return ::testing::AssertionSuccess();
        return fail("vkas missed, the oracle has a hit");
    }
    if (got.type != VKAS_COMMITTED_INTERSECTION_TRIANGLE && got.type != VKAS_COMMITTED_INTERSECTION_GENERATED)
        return fail("committed type is neither TRIANGLE nor GENERATED");
    const oracle::Candidate* c = expected.find(got.instanceId, got.geometryIndex, got.primitiveIndex);
    if (!c) return fail("vkas reports a primitive that the oracle does not hit");
    if (c->aabb != (got.type == VKAS_COMMITTED_INTERSECTION_GENERATED))
        return fail(c->aabb ? "an AABB hit is not committed as GENERATED" : "a triangle hit is not committed as TRIANGLE");
    if (c->aabb && (got.bary[0] != 0 || got.bary[1] != 0 || got.frontFace))
        return fail("a generated hit reports barycentrics or a front face");
    const double tol = std::max(1e-4 * std::max(std::fabs(double(got.t)), std::fabs(c->t)), 10 * c->tTolerance);
    if (!(std::fabs(double(got.t) - c->t) <= tol)) return fail("t differs from the oracle's t for this primitive");
    if (closest) {
        const oracle::Candidate* best = expected.closestRequired();
        if (best && double(got.t) > best->t + std::max(tol, 1e-4 * std::fabs(best->t) + 10 * best->tTolerance))
            return fail("vkas's hit is not the closest");
    }
    if (got.customIndex != int32_t(c->customIndex)) return fail("instance custom index differs");
    if (got.sbtOffset != c->sbtOffset) return fail("SBT record offset differs");
    if (!c->facingAmbiguous && got.frontFace != c->frontFace) return fail("front face differs");
    if (std::isfinite(c->baryTolerance)) {
        const double btol = std::max(2e-3, 10 * c->baryTolerance);
        if (!(std::fabs(got.bary[0] - c->bary[0]) <= btol && std::fabs(got.bary[1] - c->bary[1]) <= btol))
            return fail("barycentrics differ");
    }
    return ::testing::AssertionSuccess();
}
}  // namespace

::testing::AssertionResult matchesClosest(const oracle::Result& expected, const oracle::Ray& ray, const Hit& got) {
    return compare(expected, ray, got, true);
}
::testing::AssertionResult matchesAnyHit(const oracle::Result& expected, const oracle::Ray& ray, const Hit& got) {
    return compare(expected, ray, got, false);
}

// ---- Fixture ----------------------------------------------------------------------------------------------------
VKAPI_ATTR VkBool32 VKAPI_CALL VkasTest::messenger(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                   VkDebugUtilsMessageTypeFlagsEXT,
                                                   const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
    auto* self = static_cast<VkasTest*>(user);
    std::string msg = std::string(data && data->pMessageIdName ? data->pMessageIdName : "") + ": " +
                      (data && data->pMessage ? data->pMessage : "");
    if (severity >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT) {
        std::lock_guard<std::mutex> lock(self->messagesMutex_);
        self->errors_.push_back(msg);
    } else if (severity >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT) {
        std::fprintf(stderr, "[vkas warning] %s\n", msg.c_str());
    }
    return VK_FALSE;
}

std::vector<std::string> VkasTest::takeValidationErrors() {
    std::lock_guard<std::mutex> lock(messagesMutex_);
    std::vector<std::string> out;
    out.swap(errors_);
    return out;
}

std::vector<HostBuffer*> VkasTest::allBuffers() {
    std::vector<HostBuffer*> out;
    for (auto& b : buffers_) out.push_back(b.get());
    return out;
}

void VkasTest::SetUp() {
    seed = chooseSeed();
    rng = Rng(seed);
    std::cout << "[   SEED   ] VKAS_TEST_SEED=" << seed << std::endl;
    RecordProperty("VKAS_TEST_SEED", std::to_string(seed));
    VkasDeviceCreateInfo ci{};
    ci.disableValidation = VK_FALSE;
    ci.pfnMessenger = &VkasTest::messenger;
    ci.pMessengerUserData = this;
    ci.workerThreadCount = 2;
    if (const VkAllocationCallbacks* allocator = deviceAllocator())
        ASSERT_EQ(vkasCreateDeviceWithAllocator(&ci, allocator, &device), VK_SUCCESS);
    else
        ASSERT_EQ(vkasCreateDevice(&ci, &device), VK_SUCCESS);
    ASSERT_NE(device, VK_NULL_HANDLE);
    try {
        vk.load(device);
    } catch (const vkas_kit::MissingCommand& e) {
        FAIL() << "vkasGetDeviceProcAddr(" << e.command() << ") is NULL";
    }
}

void VkasTest::TearDown() {
    if (device != VK_NULL_HANDLE) {
        for (auto& as : structures_)
            if (as->handle != VK_NULL_HANDLE && vk.vkDestroyAccelerationStructureKHR)
                vk.vkDestroyAccelerationStructureKHR(device, as->handle, nullptr);
        structures_.clear();
        for (auto& b : buffers_) {
            if (b->buffer != VK_NULL_HANDLE && vk.vkDestroyBuffer) vk.vkDestroyBuffer(device, b->buffer, nullptr);
            if (b->memory != VK_NULL_HANDLE && vk.vkFreeMemory) {
                if (b->mapped && vk.vkUnmapMemory) vk.vkUnmapMemory(device, b->memory);
                vk.vkFreeMemory(device, b->memory, nullptr);
            }
        }
        buffers_.clear();
        vkasDestroyDevice(device);
        device = VK_NULL_HANDLE;
    }
    const auto errors = takeValidationErrors();
    for (const auto& e : errors)
        if (!(ignoreLeaksAtTeardown && e.find("VUID-vkDestroyDevice-device-05137") != std::string::npos))
            ADD_FAILURE() << "unexpected validation error: " << e;
    if (HasFailure()) std::cout << "[   SEED   ] replay with VKAS_TEST_SEED=" << seed << std::endl;
}

HostBuffer* VkasTest::createBuffer(VkDeviceSize size, VkBufferUsageFlags usage, bool bind, uint8_t poison) {
    auto b = std::make_unique<HostBuffer>();
    b->size = size;
    VkBufferCreateInfo ci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    ci.size = size;
    ci.usage = usage;
    ci.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    EXPECT_EQ(vk.vkCreateBuffer(device, &ci, nullptr, &b->buffer), VK_SUCCESS);
    vk.vkGetBufferMemoryRequirements(device, b->buffer, &b->requirements);
    buffers_.push_back(std::move(b));
    HostBuffer* out = buffers_.back().get();
    if (bind) bindBuffer(out, poison);
    return out;
}

void VkasTest::bindBuffer(HostBuffer* b, uint8_t poison) {
    EXPECT_TRUE(b->requirements.memoryTypeBits & 1u) << "memory type 0 must be usable for every buffer";
    VkMemoryAllocateFlagsInfo flagsInfo{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
    flagsInfo.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
    VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    ai.pNext = &flagsInfo;
    ai.allocationSize = b->requirements.size;
    ai.memoryTypeIndex = 0;
    EXPECT_EQ(vk.vkAllocateMemory(device, &ai, nullptr, &b->memory), VK_SUCCESS);
    EXPECT_EQ(vk.vkBindBufferMemory(device, b->buffer, b->memory, 0), VK_SUCCESS);
    void* p = nullptr;
    EXPECT_EQ(vk.vkMapMemory(device, b->memory, 0, VK_WHOLE_SIZE, 0, &p), VK_SUCCESS);
    b->mapped = static_cast<uint8_t*>(p);
    if (b->mapped) std::memset(b->mapped, poison, b->size);
}

AccelStruct* VkasTest::createAccelStruct(VkAccelerationStructureTypeKHR type, VkDeviceSize size,
                                         const BuildOptions& opt) {
    auto as = std::make_unique<AccelStruct>();
    as->type = type;
    as->offset = opt.asOffset;
    as->size = size;
    as->poison = opt.memoryPoison;
    as->buffer = createBuffer(opt.asOffset + size + 256, kAsBufferUsage, !opt.bindAfterCreate, opt.memoryPoison);
    VkAccelerationStructureCreateInfoKHR ci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
    ci.buffer = as->buffer->buffer;
    ci.offset = opt.asOffset;
    ci.size = size;
    ci.type = opt.createGeneric ? VK_ACCELERATION_STRUCTURE_TYPE_GENERIC_KHR : type;
    ci.createFlags = opt.createFlags;
    VkAccelerationStructureMotionInfoNV motionInfo{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_MOTION_INFO_NV};
    motionInfo.maxInstances = opt.motionMaxInstances;
    if ((opt.createFlags & VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV) && type == VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR)
        ci.pNext = &motionInfo;
    EXPECT_EQ(vk.vkCreateAccelerationStructureKHR(device, &ci, nullptr, &as->handle), VK_SUCCESS);
    EXPECT_NE(as->handle, VK_NULL_HANDLE);
    if (opt.bindAfterCreate) bindBuffer(as->buffer, opt.memoryPoison);
    structures_.push_back(std::move(as));
    return structures_.back().get();
}

void VkasTest::destroyAccelStruct(AccelStruct* as) {
    if (as->handle != VK_NULL_HANDLE) vk.vkDestroyAccelerationStructureKHR(device, as->handle, nullptr);
    blasRegistry.erase(as->reference());
    as->handle = VK_NULL_HANDLE;
}

std::unique_ptr<PreparedBuild> VkasTest::prepareBlas(
    const std::vector<VkAccelerationStructureGeometryKHR>& geometries,
    const std::vector<VkAccelerationStructureBuildRangeInfoKHR>& ranges, const BuildOptions& opt) {
    auto pb = std::make_unique<PreparedBuild>();
    pb->geometries = geometries;
    pb->ranges = ranges;
    for (const auto& g : pb->geometries) pb->geometryPointers.push_back(&g);
    auto& info = pb->info;
    info.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR;
    info.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
    info.flags = opt.flags;
    info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR;
    info.geometryCount = uint32_t(pb->geometries.size());
    if (info.geometryCount) {
        if (opt.usePointers)
            info.ppGeometries = pb->geometryPointers.data();
        else
            info.pGeometries = pb->geometries.data();
    }
    std::vector<uint32_t> maxCounts;
    for (const auto& r : ranges) maxCounts.push_back(r.primitiveCount + opt.extraMaxPrimitives);
    VkAccelerationStructureBuildSizesInfoKHR sizes{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
    vk.vkGetAccelerationStructureBuildSizesKHR(device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info,
                                               maxCounts.empty() ? nullptr : maxCounts.data(), &sizes);
    EXPECT_GT(sizes.accelerationStructureSize, 0u);
    pb->as = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, sizes.accelerationStructureSize, opt);
    pb->as->sizes = sizes;
    info.dstAccelerationStructure = pb->as->handle;
    pb->scratch.assign(sizes.buildScratchSize, opt.scratchPoison);
    info.scratchData.hostAddress = pb->scratch.empty() ? nullptr : pb->scratch.data();
    // The oracle reads the same application buffers.
    pb->blas = std::make_shared<oracle::Blas>();
    for (size_t i = 0; i < geometries.size(); ++i)
        pb->blas->geometries.push_back(oracle::fetchGeometry(geometries[i], ranges[i]));
    pb->blas->computeBounds();
    return pb;
}

std::unique_ptr<PreparedBuild> VkasTest::prepareBlas(const std::vector<const GeometryData*>& geometries,
                                                     const BuildOptions& opt) {
    std::vector<VkAccelerationStructureGeometryKHR> g;
    std::vector<VkAccelerationStructureBuildRangeInfoKHR> r;
    for (const auto* d : geometries) {
        g.push_back(d->geometry);
        r.push_back(d->range);
    }
    return prepareBlas(g, r, opt);
}

std::unique_ptr<PreparedBuild> VkasTest::prepareTlas(const std::vector<Instance>& instances,
                                                     const BuildOptions& opt) {
    auto pb = std::make_unique<PreparedBuild>();
    const size_t n = instances.size();
    const uint32_t off = opt.instancePrimitiveOffset;
    pb->instanceBytes.assign(std::max<size_t>(off + 64 * n, 1), 0xAA);
    for (size_t i = 0; i < n; ++i) packInstance(instances[i], pb->instanceBytes.data() + (opt.usePointers ? 0 : off) + 64 * i);
    if (opt.usePointers) {
        // Pointers to the instances, in reverse memory order to make sure the pointers are followed.
        std::vector<uint8_t> reordered(std::max<size_t>(64 * n, 1));
        pb->instancePointerBytes.assign(std::max<size_t>(off + 8 * n, 1), 0xAA);
        for (size_t i = 0; i < n; ++i) {
            uint8_t* dst = reordered.data() + 64 * (n - 1 - i);
            std::memcpy(dst, pb->instanceBytes.data() + 64 * i, 64);
        }
        pb->instanceBytes.swap(reordered);
        for (size_t i = 0; i < n; ++i) {
            const void* p = pb->instanceBytes.data() + 64 * (n - 1 - i);
            std::memcpy(pb->instancePointerBytes.data() + off + 8 * i, &p, 8);
        }
    }
    VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
    g.geometryType = VK_GEOMETRY_TYPE_INSTANCES_KHR;
    g.geometry.instances.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_INSTANCES_DATA_KHR;
    g.geometry.instances.arrayOfPointers = opt.usePointers ? VK_TRUE : VK_FALSE;
    g.geometry.instances.data.hostAddress =
        opt.usePointers ? pb->instancePointerBytes.data() : pb->instanceBytes.data();
    pb->geometries.push_back(g);
    pb->geometryPointers.push_back(&pb->geometries[0]);
    VkAccelerationStructureBuildRangeInfoKHR range{};
    range.primitiveCount = uint32_t(n);
    range.primitiveOffset = off;
    pb->ranges.push_back(range);
    auto& info = pb->info;
    info.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR;
    info.type = VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR;
    info.flags = opt.flags;
    info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR;
    info.geometryCount = 1;
    info.pGeometries = pb->geometries.data();
    const uint32_t maxCount = uint32_t(n) + opt.extraMaxPrimitives;
    VkAccelerationStructureBuildSizesInfoKHR sizes{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
    vk.vkGetAccelerationStructureBuildSizesKHR(device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info,
                                               &maxCount, &sizes);
    EXPECT_GT(sizes.accelerationStructureSize, 0u);
    pb->as = createAccelStruct(VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, sizes.accelerationStructureSize, opt);
    pb->as->sizes = sizes;
    info.dstAccelerationStructure = pb->as->handle;
    pb->scratch.assign(sizes.buildScratchSize, opt.scratchPoison);
    info.scratchData.hostAddress = pb->scratch.empty() ? nullptr : pb->scratch.data();
    // Oracle: decode the application's instance bytes (through the pointers when arrayOfPointers).
    pb->scene = std::make_shared<oracle::Scene>();
    auto lookup = [this](uint64_t ref) -> std::shared_ptr<const oracle::Blas> {
        auto it = blasRegistry.find(ref);
        return it == blasRegistry.end() ? nullptr : it->second;
    };
    for (size_t i = 0; i < n; ++i) {
        const uint8_t* p;
        if (opt.usePointers)
            std::memcpy(&p, pb->instancePointerBytes.data() + off + 8 * i, 8);
        else
            p = pb->instanceBytes.data() + off + 64 * i;
        pb->scene->instances.push_back(oracle::decodeInstance(p, lookup));
    }
    return pb;
}

void VkasTest::submit(const std::vector<PreparedBuild*>& builds) {
    std::vector<VkAccelerationStructureBuildGeometryInfoKHR> infos;
    std::vector<const VkAccelerationStructureBuildRangeInfoKHR*> ranges;
    for (auto* b : builds) {
        infos.push_back(b->info);
        ranges.push_back(b->ranges.data());
    }
    const VkResult r = vk.vkBuildAccelerationStructuresKHR(device, VK_NULL_HANDLE, uint32_t(infos.size()),
                                                           infos.data(), ranges.data());
    EXPECT_EQ(r, VK_SUCCESS) << "vkBuildAccelerationStructuresKHR";
    for (auto* b : builds) {
        AccelStruct* as = b->as;
        // Everything outside [offset, offset + size) of the buffer must be untouched.
        const uint8_t* m = as->buffer->mapped;
        size_t bad = 0;
        for (VkDeviceSize i = 0; i < as->offset; ++i) bad += m[i] != as->poison;
        for (VkDeviceSize i = as->offset + as->size; i < as->buffer->size; ++i) bad += m[i] != as->poison;
        EXPECT_EQ(bad, 0u) << "the build wrote outside [offset, offset + size) of the structure's buffer";
        if (b->blas) {
            as->blas = b->blas;
            blasRegistry[as->reference()] = b->blas;
        }
        if (b->scene) as->scene = b->scene;
    }
}

AccelStruct* VkasTest::buildBlas(const std::vector<VkAccelerationStructureGeometryKHR>& geometries,
                                 const std::vector<VkAccelerationStructureBuildRangeInfoKHR>& ranges,
                                 const BuildOptions& opt) {
    auto pb = prepareBlas(geometries, ranges, opt);
    submit({pb.get()});
    return pb->as;
}

AccelStruct* VkasTest::buildBlas(const std::vector<const GeometryData*>& geometries, const BuildOptions& opt) {
    auto pb = prepareBlas(geometries, opt);
    submit({pb.get()});
    return pb->as;
}

AccelStruct* VkasTest::buildBlas(const GeometryData& geometry, const BuildOptions& opt) {
    return buildBlas(std::vector<const GeometryData*>{&geometry}, opt);
}

AccelStruct* VkasTest::buildTlas(const std::vector<Instance>& instances, const BuildOptions& opt) {
    auto pb = prepareTlas(instances, opt);
    submit({pb.get()});
    return pb->as;
}

AccelStruct* VkasTest::buildSingleInstanceTlas(const AccelStruct* blas, const BuildOptions& opt) {
    Instance inst;
    inst.blas = blas;
    return buildTlas({inst}, opt);
}

namespace {
// The box an AABB candidate names, or null when its ids name none.
const oracle::Aabb* findBox(const oracle::Scene& scene, const Hit& c) {
    if (c.instanceId < 0 || size_t(c.instanceId) >= scene.instances.size()) return nullptr;
    const auto& blas = scene.instances[size_t(c.instanceId)].blas;
    if (!blas || c.geometryIndex < 0 || size_t(c.geometryIndex) >= blas->geometries.size()) return nullptr;
    const oracle::Geometry& g = blas->geometries[size_t(c.geometryIndex)];
    if (g.type != VK_GEOMETRY_TYPE_AABBS_KHR || c.primitiveIndex < 0 || size_t(c.primitiveIndex) >= g.aabbs.size())
        return nullptr;
    return &g.aabbs[size_t(c.primitiveIndex)];
}
}  // namespace

QueryTrace VkasTest::query(VkAccelerationStructureKHR tlas, const oracle::Ray& ray, uint32_t flags,
                           uint32_t cullMask, Confirm confirm, const oracle::Scene* scene) {
    QueryTrace out;
    std::ostringstream problems;
    VkasRayQuery q;
    vkasRayQueryInitialize(&q, tlas, flags, cullMask, ray.origin.data(), ray.tMin, ray.direction.data(), ray.tMax);
    if (vkasRayQueryGetRayTMin(&q) != ray.tMin) problems << "GetRayTMin differs; ";
    if (vkasRayQueryGetRayFlags(&q) != flags) problems << "GetRayFlags differs; ";
    float o[3], d[3];
    vkasRayQueryGetWorldRayOrigin(&q, o);
    vkasRayQueryGetWorldRayDirection(&q, d);
    for (int k = 0; k < 3; ++k)
        if (o[k] != ray.origin[k] || d[k] != ray.direction[k]) problems << "GetWorldRayOrigin/Direction differ; ";
    if (vkasRayQueryGetIntersectionType(&q, VK_TRUE) != VKAS_COMMITTED_INTERSECTION_NONE)
        problems << "committed type is not NONE after Initialize; ";
    std::set<std::tuple<int32_t, int32_t, int32_t>> seenAabbs;
    size_t guard = 0;
    while (vkasRayQueryProceed(&q)) {
        if (++guard > 10000000) {
            problems << "Proceed never returned false; ";
            break;
        }
        Hit c = readHit(q, false);
        const bool hasCommitted = vkasRayQueryGetIntersectionType(&q, VK_TRUE) != VKAS_COMMITTED_INTERSECTION_NONE;
        const float curMax = hasCommitted ? vkasRayQueryGetIntersectionT(&q, VK_TRUE) : ray.tMax;
        out.candidates.push_back(c);
        const uint32_t primitiveType = vkasRayQueryGetIntersectionPrimitiveType(&q, VK_FALSE);
        if (c.type == VKAS_CANDIDATE_INTERSECTION_AABB ? primitiveType != VKAS_INTERSECTION_PRIMITIVE_AABB
                                                       : primitiveType != VKAS_INTERSECTION_PRIMITIVE_TRIANGLE &&
                                                             primitiveType != VKAS_INTERSECTION_PRIMITIVE_SPHERE &&
                                                             primitiveType != VKAS_INTERSECTION_PRIMITIVE_LSS)
            problems << "candidate primitive type " << primitiveType << " does not fit candidate type " << c.type << "; ";
        if (c.type == VKAS_CANDIDATE_INTERSECTION_TRIANGLE) {
            if (!(c.t > ray.tMin) || !(c.t <= curMax))
                problems << "candidate t " << c.t << " outside (tMin " << ray.tMin << ", current tMax " << curMax << "]; ";
            if (confirm != Confirm::All) continue;
            vkasRayQueryConfirmIntersection(&q);
            Hit after = readHit(q, true);
            if (after.type != VKAS_COMMITTED_INTERSECTION_TRIANGLE || after.t != c.t ||
                after.instanceId != c.instanceId || after.geometryIndex != c.geometryIndex ||
                after.primitiveIndex != c.primitiveIndex || after.customIndex != c.customIndex ||
                after.sbtOffset != c.sbtOffset || after.frontFace != c.frontFace || after.bary[0] != c.bary[0] ||
                after.bary[1] != c.bary[1])
                problems << "committed values after ConfirmIntersection differ from the candidate's (" << after.str()
                         << " vs " << c.str() << "); ";
            continue;
        }
        if (c.type != VKAS_CANDIDATE_INTERSECTION_AABB) {
            problems << "candidate type " << c.type << " is neither TRIANGLE nor AABB; ";
            continue;
        }
        // An AABB candidate: the ray meets the box within [tMin, current tMax] (inclusive).
        if (!(c.t >= ray.tMin) || !(c.t <= curMax))
            problems << "AABB candidate t " << c.t << " outside [tMin " << ray.tMin << ", current tMax " << curMax << "]; ";
        if (!seenAabbs.insert({c.instanceId, c.geometryIndex, c.primitiveIndex}).second)
            problems << "AABB candidate " << c.str() << " reported twice; ";
        if (c.bary[0] != 0 || c.bary[1] != 0 || c.frontFace)
            problems << "AABB candidate " << c.str() << " has barycentrics or a front face; ";
        float oo[3], od[3];
        vkasRayQueryGetIntersectionObjectRayOrigin(&q, VK_FALSE, oo);
        vkasRayQueryGetIntersectionObjectRayDirection(&q, VK_FALSE, od);
        const oracle::Aabb* box = scene ? findBox(*scene, c) : nullptr;
        if (!box || !box->valid()) {
            problems << "AABB candidate " << c.str() << (scene ? " names no valid box of the scene; " : " without a scene; ");
            continue;
        }
        if (confirm != Confirm::All) continue;
        // What an intersection shader for the box itself computes: the entry point, from the object ray.
        double t0, t1;
        if (!oracle::boxInterval({oo[0], oo[1], oo[2]}, {od[0], od[1], od[2]}, box->lo, box->hi, t0, t1)) continue;
        const double entry = std::max(t0, double(ray.tMin));
        if (!(entry <= double(curMax)) || t1 < double(ray.tMin)) continue;
        const float tHit = float(entry);
        vkasRayQueryGenerateIntersection(&q, tHit);
        Hit after = readHit(q, true);
        float co[3], cd[3];
        vkasRayQueryGetIntersectionObjectRayOrigin(&q, VK_TRUE, co);
        vkasRayQueryGetIntersectionObjectRayDirection(&q, VK_TRUE, cd);
        if (after.type != VKAS_COMMITTED_INTERSECTION_GENERATED || after.t != tHit ||
            after.instanceId != c.instanceId || after.geometryIndex != c.geometryIndex ||
            after.primitiveIndex != c.primitiveIndex || after.customIndex != c.customIndex ||
            after.sbtOffset != c.sbtOffset || after.frontFace || after.bary[0] != 0 || after.bary[1] != 0 ||
            std::memcmp(co, oo, sizeof co) != 0 || std::memcmp(cd, od, sizeof cd) != 0)
            problems << "committed values after GenerateIntersection(" << tHit << ") differ from the candidate's ("
                     << after.str() << " vs " << c.str() << "); ";
    }
    out.committed = readHit(q, true);
    const uint32_t committedPrimitive = vkasRayQueryGetIntersectionPrimitiveType(&q, VK_TRUE);
    const bool fits = out.committed.type == VKAS_COMMITTED_INTERSECTION_NONE
                          ? committedPrimitive == VKAS_INTERSECTION_PRIMITIVE_NONE
                      : out.committed.type == VKAS_COMMITTED_INTERSECTION_GENERATED
                          ? committedPrimitive == VKAS_INTERSECTION_PRIMITIVE_AABB
                          : committedPrimitive != VKAS_INTERSECTION_PRIMITIVE_NONE &&
                                committedPrimitive != VKAS_INTERSECTION_PRIMITIVE_AABB;
    if (!fits)
        problems << "committed primitive type " << committedPrimitive << " does not fit committed type "
                 << out.committed.type << "; ";
    if (vkasRayQueryGetIntersectionPrimitiveType(&q, VK_FALSE) != VKAS_INTERSECTION_PRIMITIVE_NONE)
        problems << "a candidate primitive type after Proceed returned false; ";
    out.problems = problems.str();
    return out;
}

Hit VkasTest::traceClosest(const AccelStruct* tlas, const oracle::Ray& ray, uint32_t flags, uint32_t cullMask) {
    QueryTrace tr = query(tlas ? tlas->handle : VK_NULL_HANDLE, ray, flags, cullMask);
    EXPECT_EQ(tr.problems, "") << describe(ray);
    return tr.committed;
}

std::vector<oracle::Ray> VkasTest::randomRays(const oracle::Scene& scene, size_t count) {
    // World bounds and the list of (instance, geometry, primitive) targets.
    double lo[3] = {1e30, 1e30, 1e30}, hi[3] = {-1e30, -1e30, -1e30};
    std::vector<size_t> activeInstances;
    for (size_t i = 0; i < scene.instances.size(); ++i) {
        const auto& inst = scene.instances[i];
        if (!inst.blas || inst.blas->lo[0] > inst.blas->hi[0]) continue;
        activeInstances.push_back(i);
        for (int c = 0; c < 8; ++c) {
            const double p[3] = {c & 1 ? inst.blas->hi[0] : inst.blas->lo[0], c & 2 ? inst.blas->hi[1] : inst.blas->lo[1],
                                 c & 4 ? inst.blas->hi[2] : inst.blas->lo[2]};
            for (int r = 0; r < 3; ++r) {
                const double w = inst.toWorld[r][0] * p[0] + inst.toWorld[r][1] * p[1] + inst.toWorld[r][2] * p[2] +
                                 inst.toWorld[r][3];
                lo[r] = std::min(lo[r], w);
                hi[r] = std::max(hi[r], w);
            }
        }
    }
    if (activeInstances.empty())
        for (int r = 0; r < 3; ++r) lo[r] = -1, hi[r] = 1;
    double center[3], radius = 0;
    for (int r = 0; r < 3; ++r) {
        center[r] = 0.5 * (lo[r] + hi[r]);
        radius += (hi[r] - lo[r]) * (hi[r] - lo[r]) / 4;
    }
    radius = std::max(std::sqrt(radius), 1e-3);
    auto unitVector = [&]() {
        std::array<double, 3> v;
        do {
            for (double& x : v) x = rng.uniform(-1, 1);
        } while (v[0] * v[0] + v[1] * v[1] + v[2] * v[2] > 1 || v[0] * v[0] + v[1] * v[1] + v[2] * v[2] < 1e-4);
        const double l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        for (double& x : v) x /= l;
        return v;
    };
    auto trianglePoint = [&](std::array<double, 3>& out) -> bool {
        if (activeInstances.empty()) return false;
        const auto& inst = scene.instances[activeInstances[rng.below(uint32_t(activeInstances.size()))]];
        std::vector<size_t> geoms;
        for (size_t g = 0; g < inst.blas->geometries.size(); ++g)
            if (!inst.blas->geometries[g].triangles.empty() || !inst.blas->geometries[g].aabbs.empty()) geoms.push_back(g);
        if (geoms.empty()) return false;
        const oracle::Geometry& geom = inst.blas->geometries[geoms[rng.below(uint32_t(geoms.size()))]];
        double p[3];
        if (geom.type == VK_GEOMETRY_TYPE_AABBS_KHR) {  // a random point of a random box
            const oracle::Aabb& box = geom.aabbs[rng.below(uint32_t(geom.aabbs.size()))];
            if (!box.valid()) return false;
            for (int k = 0; k < 3; ++k) p[k] = box.lo[k] + rng.uniform(0, 1) * (box.hi[k] - box.lo[k]);
        } else {
            const auto& tris = geom.triangles;
            const auto& tri = tris[rng.below(uint32_t(tris.size()))];
            double b1 = rng.uniform(0, 1), b2 = rng.uniform(0, 1);
            if (b1 + b2 > 1) b1 = 1 - b1, b2 = 1 - b2;
            for (int k = 0; k < 3; ++k) p[k] = tri.v[0][k] + b1 * (tri.v[1][k] - tri.v[0][k]) + b2 * (tri.v[2][k] - tri.v[0][k]);
        }
        for (int r = 0; r < 3; ++r)
            out[r] = inst.toWorld[r][0] * p[0] + inst.toWorld[r][1] * p[1] + inst.toWorld[r][2] * p[2] + inst.toWorld[r][3];
        return std::isfinite(out[0]) && std::isfinite(out[1]) && std::isfinite(out[2]);
    };
    std::vector<oracle::Ray> rays;
    while (rays.size() < count) {
        const uint32_t kind = rng.below(100);
        std::array<double, 3> origin, target;
        oracle::Ray ray;
        ray.tMin = 0;
        ray.tMax = std::numeric_limits<float>::infinity();
        double dirScale = std::exp(rng.uniform(std::log(0.25), std::log(4.0)));
        if (kind < 15) {  // from inside the bounds, random direction
            for (int r = 0; r < 3; ++r) origin[r] = rng.uniform(lo[r], hi[r]);
            auto u = unitVector();
            for (int r = 0; r < 3; ++r) ray.direction[r] = float(u[r] * dirScale);
        } else {
            const auto u = unitVector();
            for (int r = 0; r < 3; ++r) origin[r] = center[r] + u[r] * radius * rng.uniform(1.2, 3.0);
            if (kind < 40 || !trianglePoint(target))
                for (int r = 0; r < 3; ++r) target[r] = rng.uniform(lo[r], hi[r]);
            if (kind >= 85) {  // axis-aligned direction through the target
                const int axis = int(rng.below(3));
                for (int r = 0; r < 3; ++r) origin[r] = target[r];
                origin[axis] = target[axis] + (rng.coin() ? 1 : -1) * radius * rng.uniform(1.2, 3.0);
            }
            for (int r = 0; r < 3; ++r) ray.direction[r] = float((target[r] - origin[r]) * dirScale);
            if (kind >= 70 && kind < 85) {  // a [tMin, tMax] window around the target (t = 1 / dirScale)
                const double tt = 1.0 / dirScale;
                ray.tMin = float(rng.uniform(0, tt));
                ray.tMax = float(rng.coin(0.7) ? rng.uniform(tt, 2 * tt) : rng.uniform(ray.tMin, tt));
            }
        }
        for (int r = 0; r < 3; ++r) ray.origin[r] = float(origin[r]);
        if (ray.direction[0] == 0 && ray.direction[1] == 0 && ray.direction[2] == 0) continue;
        rays.push_back(ray);
    }
    return rays;
}

std::vector<oracle::Ray> VkasTest::targetedRays(const oracle::Scene& scene, size_t maxRays) {
    struct Target {
        size_t inst, geom, prim;
    };
    std::vector<Target> targets;
    for (size_t i = 0; i < scene.instances.size(); ++i) {
        const auto& inst = scene.instances[i];
        if (!inst.blas) continue;
        for (size_t g = 0; g < inst.blas->geometries.size(); ++g) {
            for (size_t p = 0; p < inst.blas->geometries[g].triangles.size(); ++p)
                if (inst.blas->geometries[g].triangles[p].active) targets.push_back({i, g, p});
            for (size_t p = 0; p < inst.blas->geometries[g].aabbs.size(); ++p)
                if (inst.blas->geometries[g].aabbs[p].valid()) targets.push_back({i, g, p});
        }
    }
    std::shuffle(targets.begin(), targets.end(), rng.gen);
    if (targets.size() > maxRays) targets.resize(maxRays);
    std::vector<oracle::Ray> rays;
    for (const Target& tg : targets) {
        const auto& inst = scene.instances[tg.inst];
        const oracle::Geometry& geom = inst.blas->geometries[tg.geom];
        double p[3], w[3];
        if (geom.type == VK_GEOMETRY_TYPE_AABBS_KHR) {  // an interior point of the box
            const oracle::Aabb& box = geom.aabbs[tg.prim];
            for (int k = 0; k < 3; ++k) p[k] = box.lo[k] + rng.uniform(0.05, 0.95) * (box.hi[k] - box.lo[k]);
        } else {
            const auto& tri = geom.triangles[tg.prim];
            double b1 = rng.uniform(0.05, 0.9), b2 = rng.uniform(0.05, 0.9);
            if (b1 + b2 > 0.95) b1 = 0.95 - b1 * 0.5, b2 = 0.95 - b1 - 0.02;
            for (int k = 0; k < 3; ++k) p[k] = tri.v[0][k] + b1 * (tri.v[1][k] - tri.v[0][k]) + b2 * (tri.v[2][k] - tri.v[0][k]);
        }
        for (int r = 0; r < 3; ++r)
            w[r] = inst.toWorld[r][0] * p[0] + inst.toWorld[r][1] * p[1] + inst.toWorld[r][2] * p[2] + inst.toWorld[r][3];
        double d[3], len;
        do {
            for (double& x : d) x = rng.uniform(-1, 1);
            len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        } while (len > 1 || len < 0.1);
        const double dist = rng.uniform(0.5, 3.0), scale = std::exp(rng.uniform(-1.0, 1.0));
        oracle::Ray ray;
        for (int k = 0; k < 3; ++k) {
            ray.origin[k] = float(w[k] + d[k] / len * dist);
            ray.direction[k] = float(-d[k] / len * scale);
        }
        ray.tMin = 0;
        ray.tMax = std::numeric_limits<float>::infinity();
        rays.push_back(ray);
    }
    return rays;
}

size_t VkasTest::checkRays(const AccelStruct* tlas, const std::vector<oracle::Ray>& rays, uint32_t flags,
                           uint32_t cullMask, bool alsoBatch) {
    const oracle::Scene empty;
    const oracle::Scene& scene = tlas && tlas->scene ? *tlas->scene : empty;
    const VkAccelerationStructureKHR handle = tlas ? tlas->handle : VK_NULL_HANDLE;
    size_t hits = 0, failures = 0;
    std::vector<oracle::Result> expected;
    std::vector<Hit> queryHits;
    expected.reserve(rays.size());
    for (const auto& ray : rays) {
        expected.push_back(oracle::trace(scene, ray, flags, cullMask));
        const oracle::Result& ex = expected.back();
        QueryTrace tr = query(handle, ray, flags, cullMask, Confirm::All, &scene);
        queryHits.push_back(tr.committed);
        if (tr.committed.type != VKAS_COMMITTED_INTERSECTION_NONE) ++hits;
        std::string extra = tr.problems;
        for (const Hit& c : tr.candidates) {
            const oracle::Candidate* oc = ex.find(c.instanceId, c.geometryIndex, c.primitiveIndex);
            const bool aabb = c.type == VKAS_CANDIDATE_INTERSECTION_AABB;
            if (!oc || oc->aabb != aabb)
                extra += "candidate " + c.str() + " is not an oracle candidate; ";
            else if (!aabb && oc->opaque && !oc->opacityAmbiguous)
                extra += "Proceed returned an opaque candidate " + c.str() + "; ";
            else if (aabb && c.aabbOpaque != oc->opaque)
                extra += "CandidateAABBOpaque of " + c.str() + " differs from the oracle's opacity; ";
        }
        const bool terminate = flags & VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT;
        auto res = terminate ? matchesAnyHit(ex, ray, tr.committed) : matchesClosest(ex, ray, tr.committed);
        if ((!res || !extra.empty()) && ++failures <= 10) {
            ADD_FAILURE() << "ray query (flags 0x" << std::hex << flags << " cullMask 0x" << cullMask << std::dec
                          << "): " << res.message() << "\n  " << extra << "\n  seed " << seed;
        }
    }
    if (alsoBatch && !rays.empty()) {
        std::vector<VkasRay> batch(rays.size());
        for (size_t i = 0; i < rays.size(); ++i) {
            for (int k = 0; k < 3; ++k) {
                batch[i].origin[k] = rays[i].origin[k];
                batch[i].direction[k] = rays[i].direction[k];
            }
            batch[i].tMin = rays[i].tMin;
            batch[i].tMax = rays[i].tMax;
        }
        for (VkasTraceMode mode : {VKAS_TRACE_MODE_CLOSEST_HIT, VKAS_TRACE_MODE_ANY_HIT}) {
            std::vector<VkasHit> out(rays.size());
            std::memset(out.data(), 0xAA, out.size() * sizeof(VkasHit));
            EXPECT_EQ(vkasTraceRays(device, handle, mode, flags, cullMask, uint32_t(rays.size()), batch.data(), out.data()),
                      VK_SUCCESS);
            for (size_t i = 0; i < rays.size(); ++i) {
                const Hit h = fromBatch(out[i]);
                const bool anyHit = mode == VKAS_TRACE_MODE_ANY_HIT || (flags & VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT);
                // No intersection shader: AABBs never become hits in a batch.
                const oracle::Result batchExpected = expected[i].withoutAabbs();
                auto res = anyHit ? matchesAnyHit(batchExpected, rays[i], h) : matchesClosest(batchExpected, rays[i], h);
                auto zeroOrMinusOne = [](int32_t v) { return v == 0 || v == -1; };
                if (h.type == VKAS_COMMITTED_INTERSECTION_NONE &&
                    !(zeroOrMinusOne(out[i].instanceId) && zeroOrMinusOne(out[i].primitiveIndex) &&
                      zeroOrMinusOne(out[i].geometryIndex) && zeroOrMinusOne(out[i].instanceCustomIndex)))
                    res = ::testing::AssertionFailure() << "a batch miss must report 0/-1 fields, got instance "
                                                        << out[i].instanceId << " geometry " << out[i].geometryIndex
                                                        << " primitive " << out[i].primitiveIndex;
                // Closest-hit batches agree with the query loop wherever the oracle sees no ambiguity (and no AABB,
                // which only the query loop can hit).
                const bool unambiguous = std::none_of(expected[i].candidates.begin(), expected[i].candidates.end(),
                                                      [](const oracle::Candidate& c) { return c.optional || c.aabb; });
                if (res && mode == VKAS_TRACE_MODE_CLOSEST_HIT && !(flags & VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT) &&
                    unambiguous &&
                    (h.type != queryHits[i].type ||
                     std::fabs(h.t - queryHits[i].t) > 1e-4f * std::max(std::fabs(h.t), std::fabs(queryHits[i].t))))
                    res = ::testing::AssertionFailure() << "vkasTraceRays closest (" << h.str()
                                                        << ") disagrees with the query loop (" << queryHits[i].str()
                                                        << ") for " << describe(rays[i]);
                if (!res && ++failures <= 10)
                    ADD_FAILURE() << "vkasTraceRays " << (mode == VKAS_TRACE_MODE_CLOSEST_HIT ? "closest" : "any-hit")
                                  << " (flags 0x" << std::hex << flags << " cullMask 0x" << cullMask << std::dec
                                  << "): " << res.message() << "\n  seed " << seed;
            }
        }
    }
    if (failures > 10) ADD_FAILURE() << failures << " failures in total (first 10 shown), seed " << seed;
    return hits;
}

}  // namespace vt
