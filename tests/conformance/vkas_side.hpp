// The vkas side of a differential case: builds the scene with vkas's host commands (vkBuildAccelerationStructuresKHR
// through vkasGetDeviceProcAddr, memory poisoned with 0xAA) and runs the ray program with vkas's host ray queries.
#pragma once

#include <vulkan/vulkan_core.h>

#include <memory>
#include <string>
#include <vector>

#include "diff_case.hpp"

namespace diff {

class VkasSide {
  public:
    // Returns null and sets *why when the vkas device cannot be created.
    static std::unique_ptr<VkasSide> create(std::string* why);
    ~VkasSide();
    VkasSide(const VkasSide&) = delete;
    VkasSide& operator=(const VkasSide&) = delete;

    // Throws std::runtime_error on a failed command or a validation message (a valid case must produce none).
    std::vector<Result> run(const Scene& scene, const std::vector<Ray>& rays);

  private:
    struct Impl;
    explicit VkasSide(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
};

}  // namespace diff
