// What a refit (VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR) costs against a build: a bumpy sphere (4 N^2
// triangles) built with ALLOW_UPDATE, then refitted in place with every vertex moved, with validation on and off.
// Usage: vkas_bench_refit [N [REFITS]]   (default 512: 1,048,576 triangles; 3 refits, the best printed)
#include <vkas/vkas.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

namespace {

double msSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// Builds once and refits `refits` times on a device with validation on or off; prints the best refit.
void measure(bool validation, int n, int refits) {
    VkasDeviceCreateInfo dci{};
    dci.disableValidation = validation ? VK_FALSE : VK_TRUE;
    VkDevice dev;
    if (vkasCreateDevice(&dci, &dev) != VK_SUCCESS) std::exit(1);
#define GET(name) auto name = reinterpret_cast<PFN_##name>(vkasGetDeviceProcAddr(dev, #name))
    GET(vkCreateBuffer);
    GET(vkGetBufferMemoryRequirements);
    GET(vkAllocateMemory);
    GET(vkBindBufferMemory);
    GET(vkGetAccelerationStructureBuildSizesKHR);
    GET(vkCreateAccelerationStructureKHR);
    GET(vkBuildAccelerationStructuresKHR);
    GET(vkDestroyAccelerationStructureKHR);
    GET(vkDestroyBuffer);
    GET(vkFreeMemory);
#undef GET
    std::vector<float> v, moved;
    std::vector<uint32_t> idx;
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> u(0, 1);
    for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= 2 * n; ++j) {
            const float th = float(M_PI) * i / n, ph = 2 * float(M_PI) * j / (2 * n), r = 1 + 0.02f * u(rng);
            v.insert(v.end(), {r * std::sin(th) * std::cos(ph), r * std::sin(th) * std::sin(ph), r * std::cos(th)});
        }
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < 2 * n; ++j) {
            const uint32_t a = uint32_t(i * (2 * n + 1) + j), w = 2 * uint32_t(n);
            idx.insert(idx.end(), {a, a + 1, a + w + 2, a, a + w + 2, a + w + 1});
        }
    moved = v;
    for (float& c : moved) c *= 1.0f + 0.01f * u(rng);
    VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
    g.geometryType = VK_GEOMETRY_TYPE_TRIANGLES_KHR;
    g.flags = VK_GEOMETRY_OPAQUE_BIT_KHR;
    auto& t = g.geometry.triangles;
    t.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR;
    t.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
    t.vertexData.hostAddress = v.data();
    t.vertexStride = 12;
    t.maxVertex = uint32_t(v.size() / 3 - 1);
    t.indexType = VK_INDEX_TYPE_UINT32;
    t.indexData.hostAddress = idx.data();
    VkAccelerationStructureBuildGeometryInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
    info.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
    info.flags = VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR;
    info.geometryCount = 1;
    info.pGeometries = &g;
    uint32_t count = uint32_t(idx.size() / 3);
    VkAccelerationStructureBuildSizesInfoKHR sizes{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
    vkGetAccelerationStructureBuildSizesKHR(dev, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info, &count, &sizes);
    VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    bci.size = sizes.accelerationStructureSize;
    bci.usage = VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_STORAGE_BIT_KHR;
    VkBuffer buf;
    vkCreateBuffer(dev, &bci, nullptr, &buf);
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(dev, buf, &req);
    VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    mai.allocationSize = req.size;
    VkDeviceMemory mem;
    vkAllocateMemory(dev, &mai, nullptr, &mem);
    vkBindBufferMemory(dev, buf, mem, 0);
    VkAccelerationStructureCreateInfoKHR ci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
    ci.buffer = buf;
    ci.size = sizes.accelerationStructureSize;
    ci.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
    VkAccelerationStructureKHR as;
    vkCreateAccelerationStructureKHR(dev, &ci, nullptr, &as);
    std::vector<unsigned char> scratch(sizes.buildScratchSize + 1);
    info.dstAccelerationStructure = as;
    info.scratchData.hostAddress = scratch.data();
    VkAccelerationStructureBuildRangeInfoKHR range{count, 0, 0, 0};
    const VkAccelerationStructureBuildRangeInfoKHR* pRange = &range;
    auto t0 = std::chrono::steady_clock::now();
    if (vkBuildAccelerationStructuresKHR(dev, VK_NULL_HANDLE, 1, &info, &pRange) != VK_SUCCESS) std::exit(1);
    const double buildMs = msSince(t0);
    // Refit in place (updateScratchSize is 0): alternate between the moved and the original vertices.
    info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR;
    info.srcAccelerationStructure = as;
    info.scratchData.hostAddress = nullptr;
    double best = 1e300;
    for (int k = 0; k < refits; ++k) {
        t.vertexData.hostAddress = (k % 2 == 0) ? moved.data() : v.data();
        t0 = std::chrono::steady_clock::now();
        if (vkBuildAccelerationStructuresKHR(dev, VK_NULL_HANDLE, 1, &info, &pRange) != VK_SUCCESS) std::exit(1);
        best = std::min(best, msSince(t0));
    }
    std::printf("  validation %-3s  build %8.1f ms (%5.2f Mtris/s)  refit %7.1f ms (%5.2f Mtris/s)  refit/build %.3f\n",
                validation ? "on" : "off", buildMs, count / buildMs / 1000, best, count / best / 1000, best / buildMs);
    vkDestroyAccelerationStructureKHR(dev, as, nullptr);
    vkDestroyBuffer(dev, buf, nullptr);
    vkFreeMemory(dev, mem, nullptr);
    vkasDestroyDevice(dev);
}

}  // namespace

int main(int argc, char** argv) {
    const int n = argc > 1 ? std::atoi(argv[1]) : 512;
    const int refits = argc > 2 ? std::max(1, std::atoi(argv[2])) : 3;
    std::printf("%d triangles, one thread\n", 4 * n * n);
    measure(false, n, refits);
    measure(true, n, refits);
    return 0;
}
