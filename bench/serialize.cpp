// What serialization and deserialization cost: a bumpy sphere (4 N^2 triangles) built once, then serialized
// (vkCopyAccelerationStructureToMemoryKHR) and deserialized (vkCopyMemoryToAccelerationStructureKHR) repeatedly
// into memory that was touched before (no page faults timed), with validation on and off; and the same for a top
// level of many instances of it. Prints the best and the median of the repetitions and the bandwidth.
// Usage: vkas_bench_serialize [N] [repetitions]   (default 512: 1,048,576 triangles; 9 repetitions)
#include <vkas/vkas.h>

#include "device_commands.hpp"  // kit/

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <vector>

namespace {

double msSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

using Vk = vkas_kit::Commands;

void check(VkResult r, const char* what) {
    if (r != VK_SUCCESS) {
        std::fprintf(stderr, "%s failed: %d\n", what, int(r));
        std::exit(1);
    }
}

// A structure of `size` bytes on its own buffer and memory (touched, so no first-use page faults are timed).
struct Structure {
    VkBuffer buffer = VK_NULL_HANDLE;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    VkAccelerationStructureKHR handle = VK_NULL_HANDLE;
};
Structure createStructure(const Vk& vk, VkDevice dev, VkDeviceSize size, VkAccelerationStructureTypeKHR type) {
    Structure s;
    VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    bci.size = size;
    bci.usage = VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_STORAGE_BIT_KHR | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT;
    check(vk.vkCreateBuffer(dev, &bci, nullptr, &s.buffer), "vkCreateBuffer");
    VkMemoryRequirements req;
    vk.vkGetBufferMemoryRequirements(dev, s.buffer, &req);
    VkMemoryAllocateFlagsInfo flags{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
    flags.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
    VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    mai.pNext = &flags;
    mai.allocationSize = req.size;
    check(vk.vkAllocateMemory(dev, &mai, nullptr, &s.memory), "vkAllocateMemory");
    check(vk.vkBindBufferMemory(dev, s.buffer, s.memory, 0), "vkBindBufferMemory");
    VkAccelerationStructureCreateInfoKHR ci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
    ci.buffer = s.buffer;
    ci.size = size;
    ci.type = type;
    check(vk.vkCreateAccelerationStructureKHR(dev, &ci, nullptr, &s.handle), "vkCreateAccelerationStructureKHR");
    return s;
}
void destroyStructure(const Vk& vk, VkDevice dev, const Structure& s) {
    vk.vkDestroyAccelerationStructureKHR(dev, s.handle, nullptr);
    vk.vkDestroyBuffer(dev, s.buffer, nullptr);
    vk.vkFreeMemory(dev, s.memory, nullptr);
}

Structure build(const Vk& vk, VkDevice dev, VkAccelerationStructureBuildGeometryInfoKHR info, uint32_t count) {
    VkAccelerationStructureBuildSizesInfoKHR sizes{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
    vk.vkGetAccelerationStructureBuildSizesKHR(dev, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info, &count,
                                               &sizes);
    Structure s = createStructure(vk, dev, sizes.accelerationStructureSize, info.type);
    std::vector<unsigned char> scratch(sizes.buildScratchSize + 1);
    info.dstAccelerationStructure = s.handle;
    info.scratchData.hostAddress = scratch.data();
    VkAccelerationStructureBuildRangeInfoKHR range{count, 0, 0, 0};
    const VkAccelerationStructureBuildRangeInfoKHR* pRange = &range;
    check(vk.vkBuildAccelerationStructuresKHR(dev, VK_NULL_HANDLE, 1, &info, &pRange), "build");
    return s;
}

uint64_t query(const Vk& vk, VkDevice dev, VkAccelerationStructureKHR as, VkQueryType type) {
    uint64_t v = 0;
    check(vk.vkWriteAccelerationStructuresPropertiesKHR(dev, 1, &as, type, sizeof v, &v, sizeof v), "query");
    return v;
}

struct Stats {
    double best, median;
};
Stats stats(std::vector<double> ms) {
    std::sort(ms.begin(), ms.end());
    return {ms.front(), ms[ms.size() / 2]};
}

// Serializes `src` and deserializes it `reps` times; prints best and median of each.
void measure(const Vk& vk, VkDevice dev, const char* name, VkAccelerationStructureKHR src,
             VkAccelerationStructureTypeKHR type, int reps, bool validation) {
    const uint64_t serialized = query(vk, dev, src, VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_SIZE_KHR);
    // 16-byte aligned blob, touched before timing.
    std::vector<unsigned char> storage(serialized + 16, 0);
    unsigned char* blob = storage.data() + (16 - reinterpret_cast<uintptr_t>(storage.data()) % 16) % 16;
    uint64_t deserializedSize;
    std::vector<double> ser, deser;
    VkCopyAccelerationStructureToMemoryInfoKHR to{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_TO_MEMORY_INFO_KHR};
    to.src = src;
    to.dst.hostAddress = blob;
    to.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_SERIALIZE_KHR;
    check(vk.vkCopyAccelerationStructureToMemoryKHR(dev, VK_NULL_HANDLE, &to), "serialize");  // warm-up
    std::memcpy(&deserializedSize, blob + 40, 8);
    Structure dst = createStructure(vk, dev, deserializedSize, type);
    VkCopyMemoryToAccelerationStructureInfoKHR from{VK_STRUCTURE_TYPE_COPY_MEMORY_TO_ACCELERATION_STRUCTURE_INFO_KHR};
    from.src.hostAddress = blob;
    from.dst = dst.handle;
    from.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_DESERIALIZE_KHR;
    check(vk.vkCopyMemoryToAccelerationStructureKHR(dev, VK_NULL_HANDLE, &from), "deserialize");  // warm-up
    for (int k = 0; k < reps; ++k) {
        auto t0 = std::chrono::steady_clock::now();
        check(vk.vkCopyAccelerationStructureToMemoryKHR(dev, VK_NULL_HANDLE, &to), "serialize");
        ser.push_back(msSince(t0));
        t0 = std::chrono::steady_clock::now();
        check(vk.vkCopyMemoryToAccelerationStructureKHR(dev, VK_NULL_HANDLE, &from), "deserialize");
        deser.push_back(msSince(t0));
    }
    const Stats s = stats(ser), d = stats(deser);
    const double mb = double(serialized) / (1 << 20);
    std::printf("  %-10s validation %-3s  %8.1f MiB  serialize best %7.2f median %7.2f ms (%5.2f GiB/s)"
                "  deserialize best %7.2f median %7.2f ms (%5.2f GiB/s)\n",
                name, validation ? "on" : "off", mb, s.best, s.median, mb / 1024 / (s.median / 1000), d.best,
                d.median, mb / 1024 / (d.median / 1000));
    destroyStructure(vk, dev, dst);
}

void run(bool validation, int n, int reps) {
    VkasDeviceCreateInfo dci{};
    dci.disableValidation = validation ? VK_FALSE : VK_TRUE;
    VkDevice dev;
    if (vkasCreateDevice(&dci, &dev) != VK_SUCCESS) std::exit(1);
    Vk vk;
    vk.load(dev);
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
            const uint32_t a = uint32_t(i * (2 * n + 1) + j), w = 2 * uint32_t(n);
            idx.insert(idx.end(), {a, a + 1, a + w + 2, a, a + w + 2, a + w + 1});
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
    info.geometryCount = 1;
    info.pGeometries = &g;
    const Structure blas = build(vk, dev, info, uint32_t(idx.size() / 3));
    measure(vk, dev, "bottom", blas.handle, VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, reps, validation);

    // A top level of 2^18 instances of it on a jittered grid.
    const uint32_t instanceCount = 1u << 18;
    std::vector<VkAccelerationStructureInstanceKHR> instances(instanceCount);
    for (uint32_t i = 0; i < instanceCount; ++i) {
        VkAccelerationStructureInstanceKHR& in = instances[i];
        std::memset(&in, 0, sizeof in);
        const float x = float(i % 512) * 3, y = float(i / 512) * 3;
        const float m[3][4] = {{1, 0, 0, x + u(rng)}, {0, 1, 0, y + u(rng)}, {0, 0, 1, u(rng)}};
        std::memcpy(in.transform.matrix, m, sizeof m);
        in.mask = 0xFF;
        in.instanceCustomIndex = i;
        in.accelerationStructureReference = reinterpret_cast<uint64_t>(blas.handle);
    }
    VkAccelerationStructureGeometryKHR ig{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
    ig.geometryType = VK_GEOMETRY_TYPE_INSTANCES_KHR;
    ig.geometry.instances.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_INSTANCES_DATA_KHR;
    ig.geometry.instances.data.hostAddress = instances.data();
    VkAccelerationStructureBuildGeometryInfoKHR tinfo{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
    tinfo.type = VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR;
    tinfo.geometryCount = 1;
    tinfo.pGeometries = &ig;
    const Structure tlas = build(vk, dev, tinfo, instanceCount);
    measure(vk, dev, "top", tlas.handle, VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, reps, validation);
    destroyStructure(vk, dev, tlas);
    destroyStructure(vk, dev, blas);
    vkasDestroyDevice(dev);
}

}  // namespace

int main(int argc, char** argv) {
    const int n = argc > 1 ? std::atoi(argv[1]) : 512;
    const int reps = argc > 2 ? std::max(1, std::atoi(argv[2])) : 9;
    std::printf("bottom level: %d triangles; top level: 262144 instances of it; one thread, %d repetitions\n",
                4 * n * n, reps);
    run(false, n, reps);
    run(true, n, reps);
    return 0;
}
