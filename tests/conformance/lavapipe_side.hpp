// The lavapipe side of a differential case: the same scene built by a real Vulkan driver, Mesa's lavapipe, with
// device commands (vkCmdBuildAccelerationStructuresKHR), and the ray program run by a compute shader with
// GL_EXT_ray_query (shaders/ray_program.comp). Select lavapipe with VK_ICD_FILENAMES and VK_DRIVER_FILES set to its
// ICD manifest (lvp_icd.json); without them the loader offers every installed driver and create() picks lavapipe.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "diff_case.hpp"

namespace diff {

class LavapipeSide {
  public:
    // Creates a VkInstance (API 1.2) and a device on lavapipe with VK_KHR_acceleration_structure, VK_KHR_ray_query,
    // VK_KHR_deferred_host_operations, bufferDeviceAddress and, when available, VK_KHR_ray_tracing_position_fetch.
    // Returns null and sets *why when impossible.
    static std::unique_ptr<LavapipeSide> create(std::string* why);
    ~LavapipeSide();
    LavapipeSide(const LavapipeSide&) = delete;
    LavapipeSide& operator=(const LavapipeSide&) = delete;

    // The device name and driver information, e.g. "llvmpipe (LLVM 15.0.6, 256 bits), Mesa 25.0.7 (LLVM 15.0.6)".
    std::string deviceDescription() const;
    // Whether rayTracingPositionFetch is enabled: otherwise Result::positionsValid is always 0.
    bool hasPositionFetch() const;
    // Whether the device exposes VK_EXT_opacity_micromap with its micromap feature. Mesa 25.0.7's lavapipe does
    // not, so the differential test has no micromap cases (docs/CONFORMANCE.md).
    bool hasOpacityMicromap() const;

    // The vertex formats with VK_FORMAT_FEATURE_ACCELERATION_STRUCTURE_VERTEX_BUFFER_BIT_KHR.
    std::vector<VkFormat> vertexFormats() const;

    // Known lavapipe defects that run() avoids by giving lavapipe an input that is equivalent by the spec
    // (docs/CONFORMANCE.md shows the evidence; test_lavapipe_side.cpp keeps checking that each one still exists).
    struct Workarounds {
        // Mesa 25.0.7 applies VkAccelerationStructureBuildRangeInfoKHR::firstVertex twice: fold it into the vertex
        // address instead (vertexData + firstVertex * vertexStride, maxVertex - firstVertex, firstVertex = 0).
        bool foldFirstVertex = true;
    };
    void setWorkarounds(const Workarounds& workarounds);
    // Triangle geometries that run() has given lavapipe with firstVertex folded into the address, in total.
    size_t foldedFirstVertexGeometries() const;

    // Builds every BLAS, then the TLAS, on the device; runs the ray program over all rays; returns one Result per
    // ray. Throws std::runtime_error on any Vulkan failure.
    std::vector<Result> run(const Scene& scene, const std::vector<Ray>& rays);

  private:
    struct Impl;
    explicit LavapipeSide(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
};

}  // namespace diff
