// Shared pieces of the vkas fuzz targets (docs/FUZZING.md): devices created once per process through the public
// API, buffers and acceleration structures made the way an application makes them, a few real structures that
// fuzzed data may reference, and a tracer that runs ray queries and batch traces over whatever was accepted.
// Everything goes through <vkas/vkas.h> and vkasGetDeviceProcAddr (the device and its commands: vkas_kit, kit/);
// nothing here includes vkas's sources.
#pragma once

#include <vkas/vkas.h>

#include "device.hpp"  // kit/

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <vector>

namespace fz {

// Stops the process so that libFuzzer records the input as a crash.
[[noreturn]] void fail(const char* format, ...) __attribute__((format(printf, 1, 2)));
// FZ_CHECK(condition, "printf format", args...): fail() with the place and the condition when it is false.
#define FZ_CHECK(cond, fmt, ...)                                                                               \
    do {                                                                                                       \
        if (!(cond)) ::fz::fail("%s:%d: check `%s` failed: " fmt "\n", __FILE__, __LINE__, #cond, ##__VA_ARGS__); \
    } while (0)

struct Buffer {
    VkBuffer buffer = VK_NULL_HANDLE;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    uint8_t* data = nullptr;
    VkDeviceSize size = 0;  // the memory's size (the buffer size rounded up to 256)
};

struct Structure {
    VkAccelerationStructureKHR handle = VK_NULL_HANDLE;
    Buffer buffer;
    VkDeviceSize offset = 0, size = 0;
    uint8_t* block() const { return buffer.data + offset; }
};

// Host memory owned by the harness, allocated with its exact size (so that AddressSanitizer sees any read past
// the end) and 16-byte aligned.
struct Region {
    uint8_t* data = nullptr;
    size_t size = 0;
    Region() = default;
    explicit Region(size_t n, uint8_t fill = 0);
    Region(const Region&) = delete;
    Region& operator=(const Region&) = delete;
    Region(Region&& o) noexcept : data(o.data), size(o.size) { o.data = nullptr, o.size = 0; }
    Region& operator=(Region&& o) noexcept;
    ~Region();
};

// The commands (vkCreateBuffer etc.) are vkas_kit::Commands'.
class Device : public vkas_kit::Commands {
public:
    explicit Device(bool validation);
    ~Device();
    Device(const Device&) = delete;
    Device& operator=(const Device&) = delete;

    VkDevice device = VK_NULL_HANDLE;
    const bool validation;

    // Validation messages reported by this device so far (every one counted; printed when VKAS_FUZZ_VERBOSE is set).
    uint64_t messages() const { return messages_.load(); }

    Buffer createBuffer(VkDeviceSize size, uint8_t poison = 0xAA);
    void destroyBuffer(Buffer& b);
    // A structure of `size` bytes at `offset` (a multiple of 256) of a new buffer of at least offset + size + 256
    // bytes (bufferSize when larger), poisoned with 0xAA. createFlags with VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV
    // chain a VkAccelerationStructureMotionInfoNV (maxInstances: motionMaxInstances) for every type but BOTTOM_LEVEL.
    Structure createStructure(VkAccelerationStructureTypeKHR type, VkDeviceSize size, VkDeviceSize offset = 0,
                              VkDeviceSize bufferSize = 0, VkAccelerationStructureCreateFlagsKHR createFlags = 0,
                              uint32_t motionMaxInstances = 64);
    void destroyStructure(Structure& s);
    uint64_t address(const Structure& s);
    // The SIZE query of a constructed structure (usedSize).
    VkDeviceSize usedSize(const Structure& s);

    // Real structures built at start-up (valid builds of each kind), that fuzzed data may reference.
    Structure blasTriangles, blasAabbs, blasSpheres, blasLss, tlas;
    // [NV-motion] Motion structures: motion triangles, and a motion top level of static, matrix and SRT instances
    // (of blasTriangles, blasMotion, blasAabbs, blasSpheres, blasLss, and an inactive one).
    Structure blasMotion, tlasMotion;
    Structure unbuilt;  // created, never built
    uint64_t deadHandle = 0;  // a structure handle that was destroyed

    // Builds one geometry into a new structure (valid input; fails the process otherwise). flags with
    // VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV create the structure with VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV.
    Structure buildSimple(VkAccelerationStructureTypeKHR type, const VkAccelerationStructureGeometryKHR& geometry,
                          uint32_t primitiveCount, VkBuildAccelerationStructureFlagsKHR flags = 0);
    // A top level of one identity instance of `blas` (flags: instance flags). motionType 0, 1 or 2: a motion top level
    // of one VkAccelerationStructureMotionInstanceNV of that type (static, matrix motion, SRT motion) instead.
    Structure buildSingleInstanceTlas(const Structure& blas, uint32_t instanceFlags = 0, int motionType = -1);

private:
    static VKAPI_ATTR VkBool32 VKAPI_CALL messenger(VkDebugUtilsMessageSeverityFlagBitsEXT,
                                                    VkDebugUtilsMessageTypeFlagsEXT,
                                                    const VkDebugUtilsMessengerCallbackDataEXT* data, void* user);
    std::atomic<uint64_t> messages_{0};
    bool verbose_ = false;
    std::optional<vkas_kit::Device> kit_;  // created last: the messenger may run while it is created
};

// The two devices of a fuzz process, created on first use: validation on (messages counted) and off.
Device& validatingDevice();
Device& plainDevice();

// Runs a few rays through `topLevel` (a top-level structure of `device`): ray queries that call every getter and
// confirm or generate every candidate (some through vkasRayQueryInitializeMotion at times 0.25, 1 and one from the
// seed, which may be outside [0, 1]), vkasTraceRays and vkasTraceRaysProcedural. `seed` bytes choose extra rays and
// ray flags. `bounds` (lower xyz, upper xyz), when finite, aims rays at the scene.
void traceProbe(Device& device, VkAccelerationStructureKHR topLevel, const float bounds[6], const uint8_t* seed,
                size_t seedSize);

// A small deterministic generator (splitmix64).
struct Rng {
    uint64_t s;
    explicit Rng(uint64_t seed) : s(seed) {}
    uint64_t next() {
        uint64_t z = (s += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }
    float uniform(float a, float b) { return a + (b - a) * float(next() >> 40) * (1.0f / 16777216.0f); }
};

uint64_t hashBytes(const uint8_t* data, size_t size);

// The header's buildFlags (docs/FORMAT.md) has VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV.
inline bool builtWithMotion(const uint8_t* block) {
    uint32_t flags;
    std::memcpy(&flags, block + 12, 4);
    return (flags & VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV) != 0;
}

}  // namespace fz
