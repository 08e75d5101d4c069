#include "vkas_side.hpp"

#include <vkas/vkas.h>
#include <vkas/vkas_compat.h>
#include <vkas_test.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <mutex>
#include <stdexcept>

namespace diff {

namespace {

void check(VkResult r, const char* what) {
    if (r != VK_SUCCESS) throw std::runtime_error(std::string("vkas: ") + what + " returned " + std::to_string(r));
}

// A buffer bound to host memory that is mapped for its whole life; the memory starts as 0xAA.
struct HostAllocation {
    VkBuffer buffer = VK_NULL_HANDLE;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    uint8_t* mapped = nullptr;
};

}  // namespace

struct VkasSide::Impl {
    VkDevice device = VK_NULL_HANDLE;
    vt::Commands vk;  // the commands of kit/device_commands.hpp
    std::mutex messagesMutex;
    std::string messages;

    static VKAPI_ATTR VkBool32 VKAPI_CALL messenger(VkDebugUtilsMessageSeverityFlagBitsEXT,
                                                    VkDebugUtilsMessageTypeFlagsEXT,
                                                    const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
        auto* self = static_cast<Impl*>(user);
        std::lock_guard<std::mutex> lock(self->messagesMutex);
        self->messages += std::string(data->pMessageIdName ? data->pMessageIdName : "?") + ": " +
                          (data->pMessage ? data->pMessage : "") + "\n";
        return VK_FALSE;
    }

    HostAllocation allocate(VkDeviceSize size) {
        HostAllocation a;
        VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
        bci.size = std::max<VkDeviceSize>(size, 1);
        bci.usage = VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_STORAGE_BIT_KHR | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT;
        check(vk.vkCreateBuffer(device, &bci, nullptr, &a.buffer), "vkCreateBuffer");
        VkMemoryRequirements req;
        vk.vkGetBufferMemoryRequirements(device, a.buffer, &req);
        // SHADER_DEVICE_ADDRESS buffers need memory allocated with DEVICE_ADDRESS (VUID-vkBindBufferMemory-bufferDeviceAddress-03339).
        VkMemoryAllocateFlagsInfo flagsInfo{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
        flagsInfo.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
        VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, &flagsInfo};
        mai.allocationSize = req.size;
        mai.memoryTypeIndex = 0;
        check(vk.vkAllocateMemory(device, &mai, nullptr, &a.memory), "vkAllocateMemory");
        check(vk.vkBindBufferMemory(device, a.buffer, a.memory, 0), "vkBindBufferMemory");
        void* p = nullptr;
        check(vk.vkMapMemory(device, a.memory, 0, VK_WHOLE_SIZE, 0, &p), "vkMapMemory");
        a.mapped = static_cast<uint8_t*>(p);
        std::memset(a.mapped, 0xAA, size_t(req.size));
        return a;
    }

    void release(HostAllocation& a) {
        vk.vkDestroyBuffer(device, a.buffer, nullptr);
        vk.vkFreeMemory(device, a.memory, nullptr);
        a = {};
    }

    // Builds one structure into a fresh allocation; returns its handle.
    VkAccelerationStructureKHR build(VkAccelerationStructureBuildGeometryInfoKHR& info,
                                     const std::vector<VkAccelerationStructureBuildRangeInfoKHR>& ranges,
                                     std::vector<HostAllocation>& allocations,
                                     std::vector<VkAccelerationStructureKHR>& structures) {
        std::vector<uint32_t> counts;
        for (const auto& r : ranges) counts.push_back(r.primitiveCount);
        VkAccelerationStructureBuildSizesInfoKHR sizes{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
        vk.vkGetAccelerationStructureBuildSizesKHR(device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info,
                                                   counts.data(), &sizes);
        allocations.push_back(allocate(sizes.accelerationStructureSize));
        VkAccelerationStructureCreateInfoKHR ci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
        ci.buffer = allocations.back().buffer;
        ci.size = sizes.accelerationStructureSize;
        ci.type = info.type;
        VkAccelerationStructureKHR as = VK_NULL_HANDLE;
        check(vk.vkCreateAccelerationStructureKHR(device, &ci, nullptr, &as), "vkCreateAccelerationStructureKHR");
        structures.push_back(as);
        std::vector<uint8_t> scratch(size_t(sizes.buildScratchSize) + 1, 0xAA);
        info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR;
        info.dstAccelerationStructure = as;
        info.scratchData.hostAddress = scratch.data();
        const VkAccelerationStructureBuildRangeInfoKHR* pRanges = ranges.data();
        check(vk.vkBuildAccelerationStructuresKHR(device, VK_NULL_HANDLE, 1, &info, &pRanges),
              "vkBuildAccelerationStructuresKHR");
        return as;
    }
};

VkasSide::VkasSide(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

VkasSide::~VkasSide() {
    if (impl_ && impl_->device) vkasDestroyDevice(impl_->device);
}

std::unique_ptr<VkasSide> VkasSide::create(std::string* why) {
    auto impl = std::make_unique<Impl>();
    VkasDeviceCreateInfo info{};
    info.pfnMessenger = &Impl::messenger;
    info.pMessengerUserData = impl.get();
    if (VkResult r = vkasCreateDevice(&info, &impl->device); r != VK_SUCCESS) {
        if (why) *why = "vkasCreateDevice returned " + std::to_string(r);
        return nullptr;
    }
try {
        impl->vk.load(impl->device);
    } catch (const vkas_kit::MissingCommand& e) {
        if (why) *why = "vkasGetDeviceProcAddr returned NULL for " + e.command();
        vkasDestroyDevice(impl->device);
        return nullptr;
    }
    return std::unique_ptr<VkasSide>(new VkasSide(std::move(impl)));
}

namespace {

// The ray program of diff_case.hpp, on one ray.
Result runProgram(VkAccelerationStructureKHR tlas, const Ray& ray, const ProceduralTables& tables) {
    Result out;
    std::memset(&out, 0, sizeof out);
    VkasRayQuery q;
    vkasRayQueryInitialize(&q, tlas, ray.flags, ray.cullMask, ray.origin, ray.tMin, ray.direction, ray.tMax);
    while (vkasRayQueryProceed(&q)) {
        const uint32_t type = vkasRayQueryGetIntersectionType(&q, VK_FALSE);
        const uint32_t instanceId = uint32_t(vkasRayQueryGetIntersectionInstanceId(&q, VK_FALSE));
        const uint32_t geometryIndex = uint32_t(vkasRayQueryGetIntersectionGeometryIndex(&q, VK_FALSE));
        const uint32_t primitiveIndex = uint32_t(vkasRayQueryGetIntersectionPrimitiveIndex(&q, VK_FALSE));
        if (out.candidateCount < kMaxRecordedCandidates)
            out.candidates[out.candidateCount] = {type, instanceId, geometryIndex, primitiveIndex};
        ++out.candidateCount;
        if (ray.mode == kModeCount) continue;
        if (type == VKAS_CANDIDATE_INTERSECTION_TRIANGLE) {
            if (confirmRule(instanceId, geometryIndex, primitiveIndex)) vkasRayQueryConfirmIntersection(&q);
            continue;
        }
        float o[3], d[3];
        vkasRayQueryGetIntersectionObjectRayOrigin(&q, VK_FALSE, o);
        vkasRayQueryGetIntersectionObjectRayDirection(&q, VK_FALSE, d);
        const uint32_t blas = tables.instanceBlas[instanceId];
        const float* box = &tables.boxes[8 * size_t(tables.geometryFirstBox[tables.blasFirstGeometry[blas] + geometryIndex] +
                                                     primitiveIndex)];
        float tNear = -INFINITY, tFar = INFINITY;
        for (int c = 0; c < 3; ++c) {
            const float t0 = (box[c] - o[c]) / d[c], t1 = (box[4 + c] - o[c]) / d[c];
            tNear = std::max(tNear, std::min(t0, t1));
            tFar = std::min(tFar, std::max(t0, t1));
        }
        const float tHit = std::max(tNear, ray.tMin);
        const float limit = vkasRayQueryGetIntersectionType(&q, VK_TRUE) == VKAS_COMMITTED_INTERSECTION_NONE
                                ? ray.tMax
                                : vkasRayQueryGetIntersectionT(&q, VK_TRUE);
        if (generateRule(instanceId, geometryIndex, primitiveIndex) && tHit <= tFar && tHit <= limit)
            vkasRayQueryGenerateIntersection(&q, tHit);
    }
    out.committedType = vkasRayQueryGetIntersectionType(&q, VK_TRUE);
    if (out.committedType == VKAS_COMMITTED_INTERSECTION_NONE) return out;
    out.instanceId = uint32_t(vkasRayQueryGetIntersectionInstanceId(&q, VK_TRUE));
    out.customIndex = uint32_t(vkasRayQueryGetIntersectionInstanceCustomIndex(&q, VK_TRUE));
    out.sbtOffset = vkasRayQueryGetIntersectionInstanceShaderBindingTableRecordOffset(&q, VK_TRUE);
    out.geometryIndex = uint32_t(vkasRayQueryGetIntersectionGeometryIndex(&q, VK_TRUE));
    out.primitiveIndex = uint32_t(vkasRayQueryGetIntersectionPrimitiveIndex(&q, VK_TRUE));
    out.t = vkasRayQueryGetIntersectionT(&q, VK_TRUE);
    if (out.committedType == VKAS_COMMITTED_INTERSECTION_TRIANGLE) {
        out.frontFace = vkasRayQueryGetIntersectionFrontFace(&q, VK_TRUE) ? 1 : 0;
        vkasRayQueryGetIntersectionBarycentrics(&q, VK_TRUE, out.barycentrics);
        if (tables.blasFlags[tables.instanceBlas[out.instanceId]] & 1u) {
            float p[3][3];
            vkasRayQueryGetIntersectionTriangleVertexPositions(&q, VK_TRUE, p);
            for (int i = 0; i < 3; ++i)
                for (int c = 0; c < 3; ++c) out.positions[i][c] = p[i][c];
            out.positionsValid = 1;
        }
    }
    return out;
}

}  // namespace

std::vector<Result> VkasSide::run(const Scene& scene, const std::vector<Ray>& rays) {
    Impl& s = *impl_;
    {
        std::lock_guard<std::mutex> lock(s.messagesMutex);
        s.messages.clear();
    }
    std::vector<HostAllocation> allocations;
    std::vector<VkAccelerationStructureKHR> structures;
    auto cleanup = [&] {
        for (auto as : structures) s.vk.vkDestroyAccelerationStructureKHR(s.device, as, nullptr);
        for (auto& a : allocations) s.release(a);
    };
    try {
        // The application data, at a 256-byte aligned address so the blob's offsets keep their alignment.
        allocations.push_back(s.allocate(scene.blob.size() + 256));
        uint8_t* blob = allocations.back().mapped;
        blob += (256 - reinterpret_cast<uintptr_t>(blob) % 256) % 256;
        std::memcpy(blob, scene.blob.data(), scene.blob.size());

        std::vector<VkAccelerationStructureKHR> blases;
        for (const Blas& b : scene.blases) {
            std::vector<VkAccelerationStructureGeometryKHR> geometries;
            std::vector<VkAccelerationStructureBuildRangeInfoKHR> ranges;
            for (const Geometry& g : b.geometries) {
                geometries.push_back(vulkanGeometry(g, uint64_t(reinterpret_cast<uintptr_t>(blob))));
                ranges.push_back(g.range);
            }
            VkAccelerationStructureBuildGeometryInfoKHR info{
                VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
            info.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
            info.flags = b.buildFlags;
            info.geometryCount = uint32_t(geometries.size());
            info.pGeometries = geometries.data();
            blases.push_back(s.build(info, ranges, allocations, structures));
        }

        std::vector<uint8_t> instances(std::max<size_t>(64, 64 * scene.instances.size()), 0xAA);
        for (size_t i = 0; i < scene.instances.size(); ++i) {
            const Instance& in = scene.instances[i];
            packInstance(in, in.blas < 0 ? 0 : uint64_t(blases[size_t(in.blas)]), instances.data() + 64 * i);
        }
        VkAccelerationStructureGeometryKHR geom{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
        geom.geometryType = VK_GEOMETRY_TYPE_INSTANCES_KHR;
        geom.geometry.instances.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_INSTANCES_DATA_KHR;
        geom.geometry.instances.data.hostAddress = instances.data();
        VkAccelerationStructureBuildGeometryInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
        info.type = VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR;
        info.flags = scene.tlasFlags;
        info.geometryCount = 1;
        info.pGeometries = &geom;
        VkAccelerationStructureBuildRangeInfoKHR range{};
        range.primitiveCount = uint32_t(scene.instances.size());
        VkAccelerationStructureKHR tlas = s.build(info, {range}, allocations, structures);

        const ProceduralTables tables = makeProceduralTables(scene);
        std::vector<Result> results;
        results.reserve(rays.size());
        for (const Ray& ray : rays) results.push_back(runProgram(tlas, ray, tables));

        std::string messages;
        {
            std::lock_guard<std::mutex> lock(s.messagesMutex);
            messages.swap(s.messages);
        }
        if (!messages.empty()) throw std::runtime_error("vkas reported validation messages:\n" + messages);
        cleanup();
        return results;
    } catch (...) {
        cleanup();
        throw;
    }
}

}  // namespace diff
