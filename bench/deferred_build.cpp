// How a bottom-level build scales over the threads joined to a deferred operation (VK_KHR_deferred_host_operations):
// one build of a bumpy sphere (4 N^2 triangles) without deferral, then deferred and joined by 1, 2, 4, 8, ... threads.
// Prints the time, the speed-up over the build without deferral, and whether the bytes are identical (they must be).
// Usage: vkas_bench_deferred_build [N] [max threads] [build flags]   (default 500: 1,000,000 triangles; hardware
// threads; PREFER_FAST_TRACE = 1, e.g. 8 for PREFER_FAST_BUILD, 0 for the default)
#include <vkas/vkas.h>

#include "device_commands.hpp"  // kit/

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <thread>
#include <vector>

namespace {

double msSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) {
    const int n = argc > 1 ? std::atoi(argv[1]) : 500;
    const unsigned maxThreads = argc > 2 ? unsigned(std::atoi(argv[2])) : std::thread::hardware_concurrency();
    const auto buildFlags = argc > 3 ? VkBuildAccelerationStructureFlagsKHR(std::atoi(argv[3]))
                                     : VkBuildAccelerationStructureFlagsKHR(VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR);
    VkDevice dev;
    if (vkasCreateDevice(nullptr, &dev) != VK_SUCCESS) return 1;
    vkas_kit::Commands vk;
    vk.load(dev);

    // A bumpy sphere: (n + 1) x (2n + 1) vertices, 4 n^2 triangles.
    std::vector<float> v;
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
            const uint32_t a = uint32_t(i * (2 * n + 1) + j);
            idx.insert(idx.end(), {a, a + 1, a + 2 * uint32_t(n) + 2, a, a + 2 * uint32_t(n) + 2, a + 2 * uint32_t(n) + 1});
        }
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
    info.flags = buildFlags;
    info.geometryCount = 1;
    info.pGeometries = &g;
    uint32_t count = uint32_t(idx.size() / 3);
    VkAccelerationStructureBuildSizesInfoKHR sizes{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
    vk.vkGetAccelerationStructureBuildSizesKHR(dev, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info, &count, &sizes);

    // One structure per run, so each build starts from fresh memory.
    struct Structure {
        VkAccelerationStructureKHR as;
        VkBuffer buffer;
        VkDeviceMemory memory;
    };
    std::vector<Structure> structures;
    auto makeStructure = [&]() -> const Structure& {
        VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
        bci.size = sizes.accelerationStructureSize;
        bci.usage = VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_STORAGE_BIT_KHR;
        VkBuffer buf;
        vk.vkCreateBuffer(dev, &bci, nullptr, &buf);
        VkMemoryRequirements req;
        vk.vkGetBufferMemoryRequirements(dev, buf, &req);
        VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
        mai.allocationSize = req.size;
        VkDeviceMemory mem;
        vk.vkAllocateMemory(dev, &mai, nullptr, &mem);
        vk.vkBindBufferMemory(dev, buf, mem, 0);
        VkAccelerationStructureCreateInfoKHR ci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
        ci.buffer = buf;
        ci.size = sizes.accelerationStructureSize;
        ci.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
        VkAccelerationStructureKHR as;
        vk.vkCreateAccelerationStructureKHR(dev, &ci, nullptr, &as);
        structures.push_back({as, buf, mem});
        return structures.back();
    };
    auto bytesOf = [&](VkDeviceMemory mem) {
        void* p = nullptr;
        vk.vkMapMemory(dev, mem, 0, VK_WHOLE_SIZE, 0, &p);
        uint64_t used;
        std::memcpy(&used, static_cast<unsigned char*>(p) + 16, sizeof used);  // Header::usedSize
        return std::vector<unsigned char>(static_cast<unsigned char*>(p), static_cast<unsigned char*>(p) + used);
    };
    std::vector<unsigned char> scratch(sizes.buildScratchSize);
    info.scratchData.hostAddress = scratch.data();
    VkAccelerationStructureBuildRangeInfoKHR range{count, 0, 0, 0};
    const VkAccelerationStructureBuildRangeInfoKHR* pRange = &range;

    const Structure serial = makeStructure();
    info.dstAccelerationStructure = serial.as;
    auto t0 = std::chrono::steady_clock::now();
    vk.vkBuildAccelerationStructuresKHR(dev, VK_NULL_HANDLE, 1, &info, &pRange);
    const double serialMs = msSince(t0);
    const std::vector<unsigned char> expected = bytesOf(serial.memory);
    std::printf("%u triangles, %u hardware threads\n", count, std::thread::hardware_concurrency());
    std::printf("  %-28s %9.1f ms  %6.2f Mtris/s\n", "no deferral (1 thread)", serialMs, count / serialMs / 1000);

    VkDeferredOperationKHR op;
    vk.vkCreateDeferredOperationKHR(dev, nullptr, &op);
    for (unsigned threads = 1; threads <= maxThreads; threads *= 2) {
        const Structure run = makeStructure();
        info.dstAccelerationStructure = run.as;
        t0 = std::chrono::steady_clock::now();
        if (vk.vkBuildAccelerationStructuresKHR(dev, op, 1, &info, &pRange) != VK_OPERATION_DEFERRED_KHR) return 1;
        auto join = [&] {
            while (vk.vkDeferredOperationJoinKHR(dev, op) == VK_THREAD_IDLE_KHR) std::this_thread::yield();
        };
        std::vector<std::thread> pool;
        for (unsigned k = 1; k < threads; ++k) pool.emplace_back(join);
        join();
        for (auto& th : pool) th.join();
        const double ms = msSince(t0);
        const bool same = bytesOf(run.memory) == expected;
        std::printf("  deferred, %2u joined threads  %9.1f ms  %6.2f Mtris/s  speed-up %5.2f  bytes %s\n", threads, ms,
                    count / ms / 1000, serialMs / ms, same ? "identical" : "DIFFERENT");
        if (!same || vk.vkGetDeferredOperationResultKHR(dev, op) != VK_SUCCESS) return 1;
    }
    vk.vkDestroyDeferredOperationKHR(dev, op, nullptr);
    for (const Structure& st : structures) {
        vk.vkDestroyAccelerationStructureKHR(dev, st.as, nullptr);
        vk.vkDestroyBuffer(dev, st.buffer, nullptr);
        vk.vkFreeMemory(dev, st.memory, nullptr);
    }
    vkasDestroyDevice(dev);
    return 0;
}
