#include "api/validate/micromap_create_info.hpp"

#include "api/validate/parameters.hpp"

namespace vkas {

namespace {
using ull = unsigned long long;
constexpr uint64_t kMicromapOffsetAlignment = 256;  // VkMicromapCreateInfoEXT::offset
}  // namespace

void checkMicromapCreateInfo(Validator& v, const Device& dev, const VkMicromapCreateInfoEXT& ci) {
    v.check(ci.sType == VK_STRUCTURE_TYPE_MICROMAP_CREATE_INFO_EXT, "VUID-VkMicromapCreateInfoEXT-sType-sType",
            "pCreateInfo->sType is %d.", int(ci.sType));
    v.check(ci.pNext == nullptr, "VUID-VkMicromapCreateInfoEXT-pNext-pNext", "pCreateInfo->pNext is not NULL.");
    v.check((ci.createFlags & ~VkMicromapCreateFlagsEXT(VK_MICROMAP_CREATE_DEVICE_ADDRESS_CAPTURE_REPLAY_BIT_EXT)) == 0,
            "VUID-VkMicromapCreateInfoEXT-createFlags-parameter",
            "pCreateInfo->createFlags 0x%x has bits that are not VkMicromapCreateFlagBitsEXT.", ci.createFlags);
    // DISPLACEMENT_MICROMAP_NV belongs to VK_NV_displacement_micromap, which vkas does not support.
    v.check(ci.type == VK_MICROMAP_TYPE_OPACITY_MICROMAP_EXT, "VUID-VkMicromapCreateInfoEXT-type-parameter",
            "pCreateInfo->type %d is not a VkMicromapTypeEXT of an enabled extension.", int(ci.type));
    // Spec: "If deviceAddress is not zero, createFlags must include
    // VK_MICROMAP_CREATE_DEVICE_ADDRESS_CAPTURE_REPLAY_BIT_EXT".
    if (ci.deviceAddress != 0)
        v.check(ci.createFlags & VK_MICROMAP_CREATE_DEVICE_ADDRESS_CAPTURE_REPLAY_BIT_EXT,
                "VUID-VkMicromapCreateInfoEXT-deviceAddress-07433",
                "pCreateInfo->deviceAddress is 0x%llx but createFlags lacks "
                "VK_MICROMAP_CREATE_DEVICE_ADDRESS_CAPTURE_REPLAY_BIT_EXT.",
                (ull)ci.deviceAddress);
    // Spec: "If createFlags includes VK_MICROMAP_CREATE_DEVICE_ADDRESS_CAPTURE_REPLAY_BIT_EXT,
    // VkPhysicalDeviceOpacityMicromapFeaturesEXT::micromapCaptureReplay must be VK_TRUE"; vkas reports VK_FALSE.
    v.check((ci.createFlags & VK_MICROMAP_CREATE_DEVICE_ADDRESS_CAPTURE_REPLAY_BIT_EXT) == 0,
            "VUID-VkMicromapCreateInfoEXT-micromapCaptureReplay-11616",
            "createFlags has DEVICE_ADDRESS_CAPTURE_REPLAY but micromapCaptureReplay is not supported.");
    // Spec: "offset ... must be a multiple of 256."
    v.check(ci.offset % kMicromapOffsetAlignment == 0,
            "VUID-VkMicromapCreateInfoEXT-offset-07438", "pCreateInfo->offset %llu is not a multiple of 256.",
            (ull)ci.offset);
    if (const Buffer* b = checkHandle<Buffer>(v, dev, ci.buffer, ObjectMagic::Buffer,
                                              "VUID-VkMicromapCreateInfoEXT-buffer-parameter", nullptr,
                                              "pCreateInfo->buffer")) {
        v.check(b->usage & VK_BUFFER_USAGE_MICROMAP_STORAGE_BIT_EXT, "VUID-VkMicromapCreateInfoEXT-buffer-07435",
                "pCreateInfo->buffer lacks VK_BUFFER_USAGE_MICROMAP_STORAGE_BIT_EXT.");
        v.check(!(b->flags & VK_BUFFER_CREATE_SPARSE_RESIDENCY_BIT), "VUID-VkMicromapCreateInfoEXT-buffer-07436",
                "pCreateInfo->buffer was created with SPARSE_RESIDENCY.");
        v.check(ci.offset <= b->size && ci.size <= b->size - ci.offset, "VUID-VkMicromapCreateInfoEXT-offset-07437",
                "offset %llu + size %llu exceeds the buffer size %llu.", (ull)ci.offset, (ull)ci.size, (ull)b->size);
    }
}

}  // namespace vkas
