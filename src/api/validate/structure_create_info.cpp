#include "api/validate/structure_create_info.hpp"

#include "api/limits.hpp"
#include "api/validate/parameters.hpp"
#include "engine/util/pnext_chain.hpp"

namespace vkas {

namespace {
using ull = unsigned long long;
}  // namespace

void checkAccelerationStructureCreateInfo(Validator& v, const Device& dev,
                                          const VkAccelerationStructureCreateInfoKHR& ci) {
    v.check(ci.sType == VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR,
            "VUID-VkAccelerationStructureCreateInfoKHR-sType-sType", "pCreateInfo->sType is %d.",
            int(ci.sType));
    v.check(ci.type == VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR ||
                ci.type == VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR ||
                ci.type == VK_ACCELERATION_STRUCTURE_TYPE_GENERIC_KHR,
            "VUID-VkAccelerationStructureCreateInfoKHR-type-parameter", "pCreateInfo->type %d is not valid.",
            int(ci.type));
    checkNextChain(v, ci.pNext, {VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_MOTION_INFO_NV},
                   "VUID-VkAccelerationStructureCreateInfoKHR-pNext-pNext",
                   "VUID-VkAccelerationStructureCreateInfoKHR-sType-unique", "pCreateInfo");
    constexpr VkAccelerationStructureCreateFlagsKHR kKnownFlags =
        VK_ACCELERATION_STRUCTURE_CREATE_DEVICE_ADDRESS_CAPTURE_REPLAY_BIT_KHR |
        VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV;
    v.check((ci.createFlags & ~kKnownFlags) == 0, "VUID-VkAccelerationStructureCreateInfoKHR-createFlags-parameter",
            "pCreateInfo->createFlags 0x%x has bits that are not VkAccelerationStructureCreateFlagBitsKHR of an "
            "enabled extension.",
            ci.createFlags);
    // accelerationStructureCaptureReplay is not supported: a deviceAddress always breaks 03488, and 03612
    // or 03613 too (with or without the CAPTURE_REPLAY flag).
    v.check(ci.deviceAddress == 0, "VUID-vkCreateAccelerationStructureKHR-deviceAddress-03488",
            "pCreateInfo->deviceAddress is 0x%llx but accelerationStructureCaptureReplay is not enabled.",
            (ull)ci.deviceAddress);
    if (ci.deviceAddress != 0)
        v.check(ci.createFlags & VK_ACCELERATION_STRUCTURE_CREATE_DEVICE_ADDRESS_CAPTURE_REPLAY_BIT_KHR,
                "VUID-VkAccelerationStructureCreateInfoKHR-deviceAddress-03612",
                "pCreateInfo->deviceAddress is 0x%llx but createFlags lacks "
                "VK_ACCELERATION_STRUCTURE_CREATE_DEVICE_ADDRESS_CAPTURE_REPLAY_BIT_KHR.",
                (ull)ci.deviceAddress);
    v.check((ci.createFlags & VK_ACCELERATION_STRUCTURE_CREATE_DEVICE_ADDRESS_CAPTURE_REPLAY_BIT_KHR) == 0,
            "VUID-VkAccelerationStructureCreateInfoKHR-createFlags-03613",
            "createFlags has DEVICE_ADDRESS_CAPTURE_REPLAY but the feature is not enabled.");
    if ((ci.createFlags & VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV) &&
        ci.type == VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR) {  // [NV-motion]
        const VkAccelerationStructureMotionInfoNV* motionInfo = nullptr;
        // The last one, should the chain repeat it (sType-unique reports that).
        forEachInChain(ci.pNext, [&](const VkBaseInStructure* p) {
            if (p->sType == VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_MOTION_INFO_NV)
                motionInfo = reinterpret_cast<const VkAccelerationStructureMotionInfoNV*>(p);
        });
        if (v.check(motionInfo != nullptr, "VUID-VkAccelerationStructureCreateInfoKHR-createFlags-04954",
                    "createFlags has VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV and type is TOP_LEVEL, but "
                    "the pNext chain has no VkAccelerationStructureMotionInfoNV."))
            v.check(motionInfo->flags == 0, "VUID-VkAccelerationStructureMotionInfoNV-flags-zerobitmask",
                    "VkAccelerationStructureMotionInfoNV::flags is 0x%x.", motionInfo->flags);
    }
    v.check(ci.offset % limits::kAccelerationStructureOffsetAlignment == 0,
            "VUID-VkAccelerationStructureCreateInfoKHR-offset-03734",
            "pCreateInfo->offset %llu is not a multiple of 256.", (ull)ci.offset);
    if (const Buffer* b = checkHandle<Buffer>(v, dev, ci.buffer, ObjectMagic::Buffer,
                                              "VUID-VkAccelerationStructureCreateInfoKHR-buffer-parameter",
                                              nullptr, "pCreateInfo->buffer")) {
        v.check(b->usage & VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_STORAGE_BIT_KHR,
                "VUID-VkAccelerationStructureCreateInfoKHR-buffer-03614",
                "pCreateInfo->buffer lacks VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_STORAGE_BIT_KHR.");
        v.check(!(b->flags & VK_BUFFER_CREATE_SPARSE_RESIDENCY_BIT),
                "VUID-VkAccelerationStructureCreateInfoKHR-buffer-03615",
                "pCreateInfo->buffer was created with SPARSE_RESIDENCY.");
        v.check(ci.offset <= b->size && ci.size <= b->size - ci.offset,
                "VUID-VkAccelerationStructureCreateInfoKHR-offset-03616",
                "offset %llu + size %llu exceeds the buffer size %llu.", (ull)ci.offset, (ull)ci.size,
                (ull)b->size);
    }
}

}  // namespace vkas
