// vkas_kit's command table: every Vulkan command the tool, the benchmarks, the fuzzers and the host kit fetch with
// vkasGetDeviceProcAddr, in one X-macro list, and the struct that holds and resolves them. Public header only
// (<vkas/vkas.h>); not part of vkas's API and not installed.
#pragma once

#include <stdexcept>
#include <string>

#include <vkas/vkas.h>

// The commands every vkas device has: Commands::load throws when one is missing.
#define VKAS_KIT_COMMANDS(X)                            \
    X(vkCreateBuffer)                                   \
    X(vkDestroyBuffer)                                  \
    X(vkGetBufferMemoryRequirements)                    \
    X(vkAllocateMemory)                                 \
    X(vkFreeMemory)                                     \
    X(vkBindBufferMemory)                               \
    X(vkMapMemory)                                      \
    X(vkUnmapMemory)                                    \
    X(vkGetBufferDeviceAddress)                         \
    X(vkGetAccelerationStructureBuildSizesKHR)          \
    X(vkCreateAccelerationStructureKHR)                 \
    X(vkDestroyAccelerationStructureKHR)                \
    X(vkGetAccelerationStructureDeviceAddressKHR)       \
    X(vkBuildAccelerationStructuresKHR)                 \
    X(vkWriteAccelerationStructuresPropertiesKHR)       \
    X(vkCopyAccelerationStructureKHR)                   \
    X(vkCopyAccelerationStructureToMemoryKHR)           \
    X(vkCopyMemoryToAccelerationStructureKHR)           \
    X(vkGetDeviceAccelerationStructureCompatibilityKHR) \
    X(vkCreateDeferredOperationKHR)                     \
    X(vkDestroyDeferredOperationKHR)                    \
    X(vkGetDeferredOperationMaxConcurrencyKHR)          \
    X(vkGetDeferredOperationResultKHR)                  \
    X(vkDeferredOperationJoinKHR)

// Commands a caller may do without (VK_EXT_opacity_micromap): Commands::load leaves a missing one NULL.
#define VKAS_KIT_OPTIONAL_COMMANDS(X)      \
    X(vkCreateMicromapEXT)                 \
    X(vkDestroyMicromapEXT)                \
    X(vkGetMicromapBuildSizesEXT)          \
    X(vkBuildMicromapsEXT)                 \
    X(vkCopyMicromapEXT)                   \
    X(vkCopyMicromapToMemoryEXT)           \
    X(vkCopyMemoryToMicromapEXT)           \
    X(vkWriteMicromapsPropertiesEXT)       \
    X(vkGetDeviceMicromapCompatibilityEXT)

namespace vkas_kit {

// A command of VKAS_KIT_COMMANDS that vkasGetDeviceProcAddr returned NULL for.
class MissingCommand : public std::runtime_error {
public:
    explicit MissingCommand(const char* command);
    const std::string& command() const { return command_; }

private:
    std::string command_;
};

struct Commands {
#define VKAS_KIT_DECLARE(name) PFN_##name name = nullptr;
    VKAS_KIT_COMMANDS(VKAS_KIT_DECLARE)
    VKAS_KIT_OPTIONAL_COMMANDS(VKAS_KIT_DECLARE)
#undef VKAS_KIT_DECLARE

    // Resolves every command of both lists; throws MissingCommand for the first missing one of VKAS_KIT_COMMANDS.
    void load(VkDevice device);
    // Every command of VKAS_KIT_OPTIONAL_COMMANDS (the micromap commands) is there.
    bool hasMicromaps() const;
};

}  // namespace vkas_kit
